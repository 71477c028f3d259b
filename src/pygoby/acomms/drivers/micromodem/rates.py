"""Micro-Modem data rates (spec acomms.md §7.6): frames per packet and bytes per frame."""

RATE_NUM_FRAMES = (1, 3, 3, 2, 2, 8)
RATE_FRAME_BYTES = (32, 64, 64, 256, 256, 256)


def check_rate(rate: int) -> None:
    # Quirk A4 (sane): only 0-5 exist in the driver's tables.
    if not 0 <= rate < len(RATE_NUM_FRAMES):
        raise ValueError(f"Micro-Modem rate must be 0-5, not {rate}")
