"""DCCL field codecs: one class per field kind and codec version, looked up by name in a registry."""

from pygoby.dccl.codecs.base import FieldCodec, FieldInfo, FixedWidthCodec
from pygoby.dccl.codecs.boolean import BoolCodec
from pygoby.dccl.codecs.enum import EnumCodec, EnumCodecV2
from pygoby.dccl.codecs.numeric import NumericCodec
from pygoby.dccl.codecs.presence import PresenceCodec
from pygoby.dccl.codecs.static import StaticCodec
from pygoby.dccl.codecs.strings import (
    FixedBytesCodec,
    LengthPrefixedStringCodec,
    StringCodecV2,
    StringCodecV3,
    VarBytesCodec,
)
from pygoby.dccl.codecs.time import TimeCodec

__all__ = [
    "BoolCodec",
    "EnumCodec",
    "EnumCodecV2",
    "FieldCodec",
    "FieldInfo",
    "FixedBytesCodec",
    "FixedWidthCodec",
    "LengthPrefixedStringCodec",
    "NumericCodec",
    "PresenceCodec",
    "StaticCodec",
    "StringCodecV2",
    "StringCodecV3",
    "TimeCodec",
    "VarBytesCodec",
]
