"""Upstream shared-library names in users' configurations, and what pygoby uses instead.

Goby missions name compiled C++ libraries: `load_shared_library: "libgoby_moos.so"` (messages),
`load_shared_library: ".../libdccl_ccl_compat.so"` (DCCL codecs),
`IFRONTSEAT_DRIVER_LIBRARY=libgoby_frontseat_bluefin.so.30` (a driver),
`PACOMMSHANDLER_PLUGINS=libmy_driver.so`. pygoby cannot load those; every such name goes through
`builtin_for(name)`, this one table of what stands for it:

    builtin_for("/usr/lib/libgoby_moos.so.30")         -> Builtin(MESSAGES, "")
    builtin_for("libgoby_frontseat_abc.so.30")          -> Builtin(FRONTSEAT_DRIVER, "abc")
    builtin_for("/x/libdccl_ccl_compat.so.31")          -> Builtin(DCCL_CODECS, "dccl_ccl_compat")
    builtin_for("libgobyexample_protobuf.so")           -> None

Kinds: MESSAGES (the library's protobuf messages are built into pygoby: nothing to load),
DCCL_CODECS (`name` is the library in pygoby.dccl.libraries, which says which DCCL libraries
pygoby has and loads them into a Codec), FRONTSEAT_DRIVER (`name` is the iFrontSeat driver
entry point). `unavailable(name)` is the one sentence for a name pygoby has nothing for.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import PurePath

MESSAGES = "messages"
DCCL_CODECS = "DCCL codecs"
FRONTSEAT_DRIVER = "frontseat driver"

_SHARED_LIBRARY = re.compile(r"^(?:lib)?(?P<stem>[\w.+-]+?)(?:\.so(?:\.\d+)*|\.dylib|\.dll)$")

# The library stem (file name without directory, `lib`, suffix and version) -> (kind, name).
# `{stem}` or a `{name}` group in the name is filled from the match. First match wins.
_TABLE: list[tuple[re.Pattern[str], str, str]] = [
    (re.compile(r"goby_frontseat_(?P<name>\w+)"), FRONTSEAT_DRIVER, "{name}"),
    # goby3's (libgoby, libgoby_moos, ...) and Goby 2's (libgoby_acomms, libgoby_util, ...)
    # message libraries: pygoby has their messages built in.
    (re.compile(r"goby(?:_(?:moos|acomms|util|common|pb|middleware|zeromq))?"), MESSAGES, ""),
    # DCCL and its codec libraries (dccl, dccl_ccl_compat, dccl_arithmetic, ...)
    (re.compile(r"dccl(?:_\w+)?"), DCCL_CODECS, "{stem}"),
]

NOT_PROVIDED = (
    "pygoby cannot load compiled C++ libraries; use load_proto_file with the .proto file(s) "
    "the library was built from instead"
)


@dataclass(frozen=True)
class Builtin:
    kind: str
    name: str  # entry point or library name; "" when there is nothing to load


def library_stem(name: str) -> str | None:
    """`/usr/lib/libgoby_moos.so.30.0.1` -> `goby_moos`; None unless `name` is a shared
    library file name (`[lib]*.so[.N...]`, `.dylib`, `.dll`)."""
    match = _SHARED_LIBRARY.match(PurePath(name.strip()).name)
    return match.group("stem") if match else None


def is_shared_library(name: str) -> bool:
    return library_stem(name) is not None


def builtin_for(name: str) -> Builtin | None:
    """What stands for the shared library `name`; None when pygoby has nothing (or `name` is
    not a shared library name)."""
    stem = library_stem(name)
    if stem is None:
        return None
    for pattern, kind, target in _TABLE:
        match = pattern.fullmatch(stem)
        if match is not None:
            return Builtin(kind, target.format(stem=stem, **match.groupdict()))
    return None


def unavailable(name: str, wanted: str = MESSAGES) -> str:
    """Why `name` cannot be used where a library of the kind `wanted` is expected: one
    sentence saying what to do instead."""
    builtin = builtin_for(name)
    if builtin is None:
        return NOT_PROVIDED
    if builtin.kind == DCCL_CODECS and wanted in (MESSAGES, DCCL_CODECS):
        return "pygoby has no built-in equivalent of this DCCL codec library"
    return f"this library is a {builtin.kind}, not {wanted}"
