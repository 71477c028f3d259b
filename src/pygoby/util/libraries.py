"""Upstream shared-library names in users' configurations, and what pygoby uses instead.

Goby missions name compiled C++ libraries: `load_shared_library: "libgoby_moos.so"` (messages
and DCCL codecs), `IFRONTSEAT_DRIVER_LIBRARY=libgoby_frontseat_bluefin.so.30` (a driver),
`PACOMMSHANDLER_PLUGINS=libmy_driver.so`. pygoby cannot load those; every such name goes through
`builtin_for(name)`, one table that says which of pygoby's built-ins stands for it:

    builtin_for("/usr/lib/libgoby_moos.so.30")        -> Builtin(MESSAGES, "")
    builtin_for("libgoby_frontseat_abc.so.30")         -> Builtin(FRONTSEAT_DRIVER, "abc")
    builtin_for("libdccl_arithmetic.so")               -> Builtin(DCCL_CODECS, <module or "">)
    builtin_for("libgobyexample_protobuf.so")          -> None  (see NOT_PROVIDED)

Kinds: MESSAGES (the library's protobuf messages are built into pygoby: nothing to load),
DCCL_CODECS (import `name`, a module whose import registers the codecs; "" while pygoby has
no equivalent), FRONTSEAT_DRIVER (`name` is the iFrontSeat driver entry point).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import PurePath

MESSAGES = "messages"
DCCL_CODECS = "DCCL codecs"
FRONTSEAT_DRIVER = "frontseat driver"

_SHARED_LIBRARY = re.compile(r"(?P<stem>lib[\w.+-]*?)\.(?:so(?:\.\d+)*|dylib)")

# The library stem (file name without directory, `.so` and version) -> (kind, name). A `{name}`
# group in a pattern is copied into the name. First match wins.
_TABLE: list[tuple[re.Pattern[str], str, str]] = [
    (re.compile(r"libgoby_frontseat_(?P<name>\w+)"), FRONTSEAT_DRIVER, "{name}"),
    # goby3's (libgoby, libgoby_moos, ...) and Goby 2's (libgoby_acomms, libgoby_util, ...)
    # message libraries and DCCL's own: pygoby has their messages and codecs built in.
    (re.compile(r"libgoby(?:_(?:moos|acomms|util|common|pb|middleware|zeromq))?"), MESSAGES, ""),
    (re.compile(r"libdccl"), MESSAGES, ""),
    # DCCL's optional codec libraries: the name is the pygoby.dccl module whose import registers
    # the same codecs. "" = no built-in yet (legacy CCL and arithmetic are being added to
    # pygoby.dccl; put their modules here when they land).
    (re.compile(r"libdccl_ccl_compat"), DCCL_CODECS, ""),
    (re.compile(r"libdccl_arithmetic"), DCCL_CODECS, ""),
]

NOT_PROVIDED = (
    "pygoby cannot load compiled C++ libraries; use load_proto_file with the .proto file(s) "
    "the library was built from instead"
)


@dataclass(frozen=True)
class Builtin:
    kind: str
    name: str  # entry point or module; "" when there is nothing to load


def library_stem(name: str) -> str | None:
    """`/usr/lib/libgoby_moos.so.30.0.1` -> `libgoby_moos`; None unless `name` is a shared
    library file name (`lib*.so[.N...]` or `lib*.dylib`)."""
    match = _SHARED_LIBRARY.fullmatch(PurePath(name.strip()).name)
    return match.group("stem") if match else None


def is_shared_library(name: str) -> bool:
    return library_stem(name) is not None


def builtin_for(name: str) -> Builtin | None:
    """The built-in that stands for the shared library `name`; None when pygoby has none (or
    `name` is not a shared library name)."""
    stem = library_stem(name)
    if stem is None:
        return None
    for pattern, kind, target in _TABLE:
        match = pattern.fullmatch(stem)
        if match is None:
            continue
        return Builtin(kind, target.format(**match.groupdict()))
    return None
