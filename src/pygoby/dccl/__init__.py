"""DCCL: the Dynamic Compact Control Language, byte-compatible with the C++ DCCL library.

    from pygoby.dccl import Codec
    codec = Codec()
    Status = codec.load_proto("status.proto", "my.Status", include_dirs=["."])
    data = codec.encode(Status(depth=12))
    msg = codec.decode(data)
"""

from pygoby.dccl.codec import Codec, CompiledType
from pygoby.dccl.codecs.base import FieldCodec, FieldInfo, FixedWidthCodec
from pygoby.dccl.errors import DcclDecodeError, DcclEncodeError, DcclError, DcclLoadError
from pygoby.dccl.registry import DEFAULT_REGISTRY, CodecRegistry, register_codec

__all__ = [
    "DEFAULT_REGISTRY",
    "Codec",
    "CodecRegistry",
    "CompiledType",
    "DcclDecodeError",
    "DcclEncodeError",
    "DcclError",
    "DcclLoadError",
    "FieldCodec",
    "FieldInfo",
    "FixedWidthCodec",
    "register_codec",
]
