"""DCCL1: Goby 1.1's DCCL wire format for XML message sets (byte-identical with Goby 1.1.2).

    from pygoby.dccl.xml import load_message_set
    from pygoby.dccl.dccl1 import Dccl1Codec, stitch, unstitch

    codec = Dccl1Codec(passphrase=None, modem_id=1)   # 1.1 encrypts even without a passphrase
    codec.load(load_message_set("simple_status.xml"))
    data = codec.encode("SIMPLE_STATUS", {"nav_x": "100", "Speed": "1.5"}, dest=0)
    codec.decode(data).values

`pygoby.dccl.xml` (the Goby 2 transitional form, DCCL v2 bytes) reads the same XML files.
"""

from pygoby.dccl.dccl1.codec import (
    DCCL1_FIRST_BYTE,
    Dccl1Codec,
    Dccl1Decoded,
    Dccl1Field,
    Dccl1Header,
    Dccl1Message,
    unix_time,
)
from pygoby.dccl.dccl1.frames import FramePart, is_dccl1_frame, stitch, unstitch

__all__ = [
    "DCCL1_FIRST_BYTE",
    "Dccl1Codec",
    "Dccl1Decoded",
    "Dccl1Field",
    "Dccl1Header",
    "Dccl1Message",
    "FramePart",
    "is_dccl1_frame",
    "stitch",
    "unix_time",
    "unstitch",
]
