"""Identifier codecs: the ID at the start of every encoding and the legacy CCL one.

* `dccl.default.id`: 1 byte `id << 1` for ids 0..127, 2 bytes `(id << 1) | 1` up to 32767.
* `dccl.ccl.id` (C++ DCCL's libdccl_ccl_compat): lets REMUS CCL frames and DCCL messages share a
  link. A CCL type (id 0x0CC1xxxx) is sent as the one byte xx, the CCL mode; any other DCCL
  message is the byte 0x20 followed by its default ID. A Codec switches to it when a CCL type
  is loaded (as loading the C++ library does).
"""

from __future__ import annotations

from pygoby.dccl.errors import DcclDecodeError, DcclLoadError

CCL_ID_PREFIX = 0x0CC10000
DCCL_CCL_HEADER = 0x20  # the first byte of a DCCL message among CCL frames
MAX_DEFAULT_ID = 32767


def is_ccl_id(dccl_id: int | None) -> bool:
    return dccl_id is not None and dccl_id & 0xFFFF0000 == CCL_ID_PREFIX


class DefaultIdCodec:
    name = "dccl.default.id"

    def encode(self, dccl_id: int, where: str = "") -> tuple[int, int]:
        """(raw, bits) of an id; raises DcclLoadError for an id this codec cannot send."""
        if not 0 <= dccl_id <= MAX_DEFAULT_ID:
            raise DcclLoadError(f"{where}: id {dccl_id} is outside 0..{MAX_DEFAULT_ID}")
        if dccl_id < 128:
            return dccl_id << 1, 8
        return dccl_id << 1 | 1, 16

    def decode(self, data: bytes) -> tuple[int, int]:
        """(id, bits) from the first bytes of an encoding."""
        if not data:
            raise DcclDecodeError("no bytes to read a DCCL ID from")
        first = data[0]
        if not first & 1:
            return first >> 1, 8
        if len(data) < 2:
            raise DcclDecodeError("the long-form DCCL ID needs two bytes, got one")
        return (first | data[1] << 8) >> 1, 16


class CclIdCodec(DefaultIdCodec):
    name = "dccl.ccl.id"

    def encode(self, dccl_id: int, where: str = "") -> tuple[int, int]:
        if is_ccl_id(dccl_id):
            mode = dccl_id & 0xFFFF
            if mode > 0xFF:
                raise DcclLoadError(f"{where}: CCL id {dccl_id:#x} has a mode above 0xff")
            return mode, 8
        raw, bits = super().encode(dccl_id, where)
        return DCCL_CCL_HEADER | raw << 8, bits + 8

    def decode(self, data: bytes) -> tuple[int, int]:
        if not data:
            raise DcclDecodeError("no bytes to read a CCL mode or DCCL ID from")
        if data[0] != DCCL_CCL_HEADER:
            return CCL_ID_PREFIX + data[0], 8
        dccl_id, bits = super().decode(data[1:])
        return dccl_id, bits + 8


ID_CODECS = {codec.name: codec for codec in (DefaultIdCodec(), CclIdCodec())}


def id_codec(name: str) -> DefaultIdCodec:
    try:
        return ID_CODECS[name]
    except KeyError:
        raise DcclLoadError(
            f"unknown identifier codec {name!r} (known: {', '.join(ID_CODECS)})"
        ) from None
