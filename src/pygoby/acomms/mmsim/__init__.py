"""Micro-Modem emulator: a sans-I/O modem model, pluggable acoustic channels, asyncio servers."""

from pygoby.acomms.mmsim.channel import (
    AcousticPacket,
    Channel,
    ChannelEndpoint,
    LoopbackChannel,
    PacketKind,
    Reception,
)
from pygoby.acomms.mmsim.model import MicroModemModel

__all__ = [
    "AcousticPacket",
    "Channel",
    "ChannelEndpoint",
    "LoopbackChannel",
    "MicroModemModel",
    "PacketKind",
    "Reception",
]
