"""Packet-level acoustic channel for the netsim simulator.

The physics are pure functions in small modules (`soundspeed`, `absorption`, `levels`,
`geometry`, `frame_errors`, `timing`); `model.Channel` combines them into the sans-I/O channel the
modem emulators call (its API is documented in `pygoby.netsim.channel.model`).
"""

from pygoby.netsim.channel.frame_errors import (
    LogisticModel,
    RateErrorModels,
    TableModel,
    ThresholdModel,
)
from pygoby.netsim.channel.geometry import NavFix
from pygoby.netsim.channel.model import (
    Band,
    Channel,
    ChannelConfig,
    Detection,
    Outcome,
    PacketKind,
    Reception,
    Transmission,
)

__all__ = [
    "Band",
    "Channel",
    "ChannelConfig",
    "Detection",
    "LogisticModel",
    "NavFix",
    "Outcome",
    "PacketKind",
    "RateErrorModels",
    "Reception",
    "TableModel",
    "ThresholdModel",
    "Transmission",
]
