"""Legacy REMUS CCL (Compact Control Language) support.

* `pygoby.dccl.ccl.fields`: the CCL field encodings as plain functions (lat/lon, time/date,
  heading, depth, speed, ...), for building CCL frames without DCCL.
* `pygoby.dccl.ccl.codecs`: the same as DCCL field codecs (`_ccl_*`), registered by default.
* `pygoby.dccl.ccl.remus`: the 32-byte REMUS frames (State, Redirect, Ranger, Position, Alert,
  Alert2) as typed objects with `encode()` / `decode(data)`, built on `fields`.
* The message set `dccl.legacyccl.protobuf.CCLMDAT*` ships as `dccl/ccl/protobuf/ccl.proto`;
  loading one of its types switches a Codec to the CCL identifier codec
  (`pygoby.dccl.identifier`).
"""

from pygoby.dccl.ccl.remus import CCLEncodeError, CCLFrameError

CCL_PROTO = "dccl/ccl/protobuf/ccl.proto"
CCL_MESSAGES = tuple(
    f"dccl.legacyccl.protobuf.CCLMDAT{name}"
    for name in ("Empty", "Redirect", "Bathy", "CTD", "State", "Command", "Error")
)

__all__ = [
    "CCL_MESSAGES",
    "CCL_PROTO",
    "CCLEncodeError",
    "CCLFrameError",
    "codecs",
    "fields",
    "remus",
]
