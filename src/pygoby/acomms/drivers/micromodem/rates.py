"""Micro-Modem data rates: frames per packet and bytes per frame."""

RATE_NUM_FRAMES = (1, 3, 3, 2, 2, 8)
RATE_FRAME_BYTES = (32, 64, 64, 256, 256, 256)


def check_rate(rate: int) -> None:
    # only 0-5 exist in the driver's tables (goby3 indexes past them: QUIRKS.md Q-ACOMMS-4)
    if not 0 <= rate < len(RATE_NUM_FRAMES):
        raise ValueError(f"Micro-Modem rate must be 0-5, not {rate}")
