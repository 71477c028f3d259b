"""DCCL: the Dynamic Compact Control Language, byte-compatible with the C++ DCCL library.

    from pygoby.dccl import Codec
    codec = Codec()
    Status = codec.load_proto("status.proto", "my.Status", include_dirs=["."])
    data = codec.encode(Status(depth=12))
    msg = codec.decode(data)

Debugging: `codec.compiled(Status).source` (or `pygoby dccl analyze --source`) is the Python
generated for the type, whose lines tracebacks show; `Codec(trace=True)` logs each field's value
and bits to the `pygoby.dccl.trace` logger at DEBUG.
"""

from pygoby.dccl.codec import Codec
from pygoby.dccl.codecs.base import FieldCodec, FieldInfo, FixedWidthCodec
from pygoby.dccl.compiled import CompiledType
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
