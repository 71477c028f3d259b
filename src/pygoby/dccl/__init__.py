"""DCCL: the Dynamic Compact Control Language, byte-compatible with the C++ DCCL library.

    from pygoby.dccl import Codec
    codec = Codec()
    Status = codec.load_proto("status.proto", "my.Status", include_dirs=["."])
    data = codec.encode(Status(depth=12))
    msg = codec.decode(data)

Add-ons of C++ DCCL are built in: legacy CCL (`pygoby.dccl.ccl`), `dccl.arithmetic`
(`codec.set_arithmetic_model`, `load_model_file`), `dccl.native_protobuf`, dynamic conditions
(Lua, via lupa) and `dccl.hash`; `builtin_library("libdccl_ccl_compat.so")` maps a C++ library
name (as missions give it to load_shared_library) to its pygoby built-in.

Debugging: `codec.compiled(Status).source` (or `pygoby dccl analyze --source`) is the Python
generated for the type, whose lines tracebacks show; `Codec(trace=True)` logs each field's value
and bits to the `pygoby.dccl.trace` logger at DEBUG.
"""

from pygoby.dccl.arithmetic import load_model_file
from pygoby.dccl.codec import Codec
from pygoby.dccl.codecs.base import FieldCodec, FieldInfo, FixedWidthCodec, RepeatedFieldCodec
from pygoby.dccl.compiled import CompiledType
from pygoby.dccl.errors import DcclDecodeError, DcclEncodeError, DcclError, DcclLoadError
from pygoby.dccl.libraries import builtin_library
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
    "RepeatedFieldCodec",
    "builtin_library",
    "load_model_file",
    "register_codec",
]
