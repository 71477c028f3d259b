"""Micro-Modem receive statistics ($CACST / ReceiveStatistics) synthesized for a reception.
The mapping of the channel's numbers onto the modem's fields follows
ros_acomms; fields the model has no physics for get plausible values inside goby3's DCCL ranges.
These are modelling choices, not measured modem behaviour.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

from pygoby.netsim.channel.model import Outcome, PacketKind, Reception
from pygoby.protobuf.goby.acomms.protobuf.mm_receive_statistics_pb2 import ReceiveStatistics


def receive_statistics_class() -> type[ReceiveStatistics]:
    return ReceiveStatistics


def _clamp(value: float, low: int, high: int) -> int:
    return int(min(max(round(value), low), high))


def receive_statistics(
    reception: Reception,
    *,
    source_id: int,
    dest_id: int,
    carrier_hz: float = 25000.0,
    bandwidth_hz: float = 5000.0,
    clock_mode: str = "NO_SYNC_TO_PPS_AND_CCCLK_GOOD",
    flexible_data_packet: bool = False,
) -> ReceiveStatistics | None:
    """The $CACST a modem would report for this reception, or None if it reports nothing
    (the packet was never detected, or the receiver was busy with another one)."""
    link = link_statistics(reception, carrier_hz, bandwidth_hz)
    if link is None:
        return None
    tx = reception.transmission
    if reception.outcome is Outcome.HALF_DUPLEX:
        mode, psk_error = "PACKET_TIMEOUT", "MISSED_START_OF_PSK_PACKET"
    elif reception.outcome is Outcome.GOOD:
        mode, psk_error = "RECEIVE_GOOD", "NO_ERROR"
    else:
        mode, psk_error = "BAD_CRC", "BAD_CRC_AT_LEAST_ONE_FRAME"
    if flexible_data_packet:
        packet_type = "FLEXIBLE_DATA_PACKET"
    elif tx.kind is PacketKind.MINI:
        packet_type = "FSK_MINI" if tx.rate == 0 else "PSK_MINI"
    else:
        packet_type = "FSK" if tx.rate == 0 else "PSK"
    # (enum fields given by name, as protobuf's constructors take them)
    fields: dict[str, Any] = dict(
        mode=mode,
        time=round(reception.arrival * 1e6),
        clock_mode=clock_mode,
        shf_agn=250,
        rate=_clamp(tx.rate, -1, 6),
        source=_clamp(source_id, 0, 127),
        dest=_clamp(dest_id, 0, 127),
        psk_error_code=psk_error,
        packet_type=packet_type,
        number_frames=_clamp(tx.frames, 0, 8),
        number_bad_frames=_clamp(reception.bad_frames, 0, 8),
        version=6,
        **link,
    )
    return receive_statistics_class()(**fields)


def link_statistics(
    reception: Reception, carrier_hz: float = 25000.0, bandwidth_hz: float = 5000.0
) -> dict[str, float] | None:
    """The $CACST fields the physics decides (levels, SNRs, Doppler, band) for a reception, or
    None if the modem reports nothing for it (see `receive_statistics`)."""
    if reception.outcome in (Outcome.NOT_DETECTED, Outcome.RECEIVER_BUSY):
        return None
    fields = dict(
        _level_statistics(
            reception.sinr,
            reception.received_level,
            reception.noise_level,
            carrier_hz,
            bandwidth_hz,
        )
    )
    fields["doppler"] = min(max(round(reception.closing_speed, 1), -3.0), 3.0)
    return fields


# A link's levels recur (fixed nodes, steady noise): their integer fields are computed once.
# (Every field here is rounded to an integer, so a key of -0.0 and 0.0 give the same values;
# the Doppler, which keeps the sign of a zero, is computed every time.)
@lru_cache(maxsize=1 << 16)  # (a 100-node network has 9,900 links)
def _level_statistics(
    snr: float, received_level: float, noise_level: float, carrier_hz: float, bandwidth_hz: float
) -> dict[str, float]:
    return {
        "mfd_power": _clamp(snr / 2, -30, 40),
        "mfd_ratio": _clamp(10 ** (min(snr, 40) / 10) * 10, 0, 16383),
        "spl": round(received_level),
        "snr_rss": _clamp(received_level - noise_level, 0, 255),
        "snr_in": _clamp(snr, -10, 30),
        "snr_out": _clamp(snr + 10, 0, 25),
        "snr_symbols": _clamp(snr + 10, 0, 30),
        "mse_equalizer": _clamp(-snr, -30, 5),
        "data_quality_factor": _clamp(snr * 10, 0, 255),
        "doppler": 0.0,  # (set by link_statistics: keeps the fields in $CACST order)
        "stddev_noise": _clamp(noise_level - 40, 0, 255),
        "carrier_freq": _clamp(carrier_hz, 100, 30000),
        "bandwidth": _clamp(bandwidth_hz, 1000, 5000),
    }
