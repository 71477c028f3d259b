"""Micro-Modem emulator: a sans-I/O modem model, pluggable acoustic channels, asyncio servers."""

from pygoby.acomms.mmsim.channel import (
    AcousticPacket,
    ChannelEndpoint,
    LoopbackChannel,
    ModemChannel,
    ModemPacketKind,
    ModemReception,
)
from pygoby.acomms.mmsim.model import MicroModemModel

__all__ = [
    "AcousticPacket",
    "ChannelEndpoint",
    "LoopbackChannel",
    "MicroModemModel",
    "ModemChannel",
    "ModemPacketKind",
    "ModemReception",
]
