"""C++ DCCL codec libraries named in configuration, mapped to pygoby's built-ins.

goby3 and Goby 2 missions load DCCL add-ons with `load_shared_library: ".../libdccl_ccl_compat.so"`
(or `libdccl_arithmetic.so`, `libdccl_native_protobuf.so`). pygoby has these codecs built in:
`builtin_library(name)` says what such a name stands for, and `.apply(codec)` does to a Codec
what loading the C++ library does (the legacy CCL one also loads its seven message types and
switches the Codec to the CCL identifier codec). Names go through pygoby.util.libraries, the
one table of the upstream library names pygoby stands in for; any other shared library is C++
code pygoby cannot run: the error says to give its messages' .proto files (`load_proto_file`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import Any

from pygoby.dccl.ccl import CCL_MESSAGES, CCL_PROTO
from pygoby.dccl.errors import DcclLoadError
from pygoby.util.libraries import DCCL_CODECS, builtin_for, unavailable


@dataclass(frozen=True)
class BuiltinLibrary:
    """What a C++ DCCL codec library provides, and how to give it to a Codec."""

    name: str  # the library's name without "lib" and suffix, e.g. "dccl_ccl_compat"
    provides: str  # for logs: what it stands for
    proto_files: tuple[str, ...] = ()  # our .proto files defining its messages and options
    messages: tuple[str, ...] = ()  # message types it loads into a codec (C++ dccl3_load)
    id_codec: str | None = None

    def apply(self, codec: Any) -> list[type]:
        """Load into `codec` (a pygoby.dccl.Codec) what the C++ library loads; returns the
        message classes loaded."""
        for proto in self.proto_files:
            codec.loader.load_file(proto)
        if self.id_codec is not None:
            codec.set_id_codec(self.id_codec)
        return [codec.load(codec.loader.message_class(name)) for name in self.messages]


BUILTIN_LIBRARIES = {
    lib.name: lib
    for lib in (
        BuiltinLibrary(
            "dccl_ccl_compat",
            "legacy REMUS CCL messages and field codecs (pygoby.dccl.ccl)",
            proto_files=(CCL_PROTO,),
            messages=CCL_MESSAGES,
            id_codec="dccl.ccl.id",
        ),
        BuiltinLibrary(
            "dccl_arithmetic",
            "the dccl.arithmetic codec (pygoby.dccl.arithmetic)",
            proto_files=("dccl/arithmetic/protobuf/arithmetic_extensions.proto",),
        ),
        BuiltinLibrary("dccl_native_protobuf", "the dccl.native_protobuf codec (built in)"),
        BuiltinLibrary("dccl", "DCCL itself (built in)"),
    )
}


def builtin_library(name: str) -> BuiltinLibrary:
    """The pygoby built-in standing for a C++ DCCL library (path or file name, any version
    suffix). Raises DcclLoadError, saying what to use instead, for any other library."""
    builtin = builtin_for(name)
    library = None
    if builtin is not None and builtin.kind == DCCL_CODECS:
        library = BUILTIN_LIBRARIES.get(builtin.name)
    if library is None:
        known = ", ".join(f"lib{n}.so" for n in BUILTIN_LIBRARIES)
        raise DcclLoadError(f'"{name}": {unavailable(name, DCCL_CODECS)} (built in: {known})')
    return library


def split_libraries(
    names: Iterable[str], error: Callable[[str, str], Exception] | None = None
) -> tuple[list[BuiltinLibrary], list[str]]:
    """A `load_shared_library` list as (pygoby built-ins for its C++ DCCL codec libraries, the
    other names: Python modules or .py files of generated message code, and other upstream
    libraries, which the app's MessageTypes accepts or refuses). An unknown DCCL library is a
    DcclLoadError saying what to use instead, or `error(reason, name)` when given (an app's
    located ConfigError)."""
    libraries, others = [], []
    for name in names:
        builtin = builtin_for(name)
        if builtin is None or builtin.kind != DCCL_CODECS:
            others.append(name)
            continue
        try:
            libraries.append(builtin_library(name))
        except DcclLoadError as err:
            if error is None:
                raise
            raise error(str(err), name) from None
    return libraries, others
