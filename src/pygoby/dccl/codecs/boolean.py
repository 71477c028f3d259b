"""Bool codec: 1 bit required; 2 bits optional (0 unset, 1 false, 2 true)."""

from __future__ import annotations

from pygoby.dccl.codecs.base import FieldInfo, FixedWidthCodec


class BoolCodec(FixedWidthCodec):
    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)
        if info.required:
            self.bits = 1
            self.to_raw = lambda v, strict: 1 if v else 0
            self.from_raw = bool
        else:
            self.bits = 2
            self.to_raw = lambda v, strict: 0 if v is None else (2 if v else 1)
            self.from_raw = lambda raw: None if raw == 0 else raw != 1
