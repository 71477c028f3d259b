"""DCCL1: Goby 1.1's DCCL wire format for XML message sets, byte for byte as Goby 1.1.2 writes
and reads it.

Message = 6 header bytes + body. All bit fields are written most significant first: each field
shifts what is already there left by its width and fills the low bits.

* Header (48 bits): 0x20 (8) | DCCL id (9) | time of day in seconds (17) | source (5) |
  destination (5) | multi-message flag (1) | broadcast flag (1) | unused (2).
* Body: the <layout> variables in order, in ceil(bits / 8) bytes (so the padding is in the first
  bits); trailing zero bytes are dropped. An array sends elements 1..n-1 then element 0; with
  <max_delta> elements 1..n-1 travel as differences from element 0.
* The body is always AES-256-CTR encrypted: key SHA-256(passphrase), SHA-256("") when none is
  set; IV the first 16 bytes of SHA-256 of the 6 header bytes.
* The decoder drops every trailing zero byte of the whole message before decrypting (a 1.1
  defect kept for compatibility: a body whose ciphertext ends in 0x00 decodes differently).

Libdccl 1.1 applies no <algorithm>s itself (pAcommsHandler 1.1 runs them around the codec), so
neither does this codec.
"""

from __future__ import annotations

import math
import time as _time
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

from pygoby.dccl.crypto import BodyCipher
from pygoby.dccl.dccl1.values import (
    Value,
    as_bool,
    as_double,
    as_long,
    as_string,
    to_unsigned_long,
    unbiased_round,
)
from pygoby.dccl.errors import DcclDecodeError, DcclEncodeError, DcclLoadError
from pygoby.dccl.xml.model import Var, XmlMessage

DCCL1_FIRST_BYTE = 0x20
HEADER_BYTES = 6
HEADER_BITS = 48
# Header parts in wire order: (name of the part when the XML does not rename it, width in bits).
HEADER_LAYOUT = (
    ("_ccl_id", 8),
    ("_id", 9),
    ("_time", 17),
    ("_src_id", 5),
    ("_dest_id", 5),
    ("_multimessage_flag", 1),
    ("_broadcast_flag", 1),
    ("_unused", 2),
)
SECONDS_PER_DAY = 86400
BROADCAST_ID = 0

Values = Mapping[str, Value | Sequence[Value]]


def _width(span: float, precision: float) -> int:
    """Bits for a number with `span` * 10^precision steps plus "unset": 1.1's formula."""
    return math.ceil(math.log(span * math.pow(10.0, precision) + 2) / math.log(2))


@dataclass
class Dccl1Field:
    """One <layout> variable with its DCCL1 widths."""

    var: Var
    array_length: int

    @property
    def name(self) -> str:
        return self.var.name

    @property
    def kind(self) -> str:
        return self.var.kind

    @property
    def is_number(self) -> bool:
        return self.kind in ("int", "float")

    @property
    def precision(self) -> int:
        return self.var.precision if self.kind == "float" else 0

    @property
    def bounds(self) -> tuple[float, float]:
        low, high = float(self.var.min or 0), float(self.var.max or 0)
        return (high, low) if high < low else (low, high)

    @property
    def uses_delta(self) -> bool:
        return self.is_number and self.var.max_delta is not None

    def key_bits(self) -> int:
        kind = self.kind
        if self.is_number:
            low, high = self.bounds
            return _width(high - low, self.precision)
        if kind == "bool":
            return 2
        if kind == "enum":
            return math.ceil(math.log(len(self.var.enum_values) + 1) / math.log(2))
        if kind == "string":
            return 8 * (self.var.max_length or 0)
        if kind == "hex":
            return 8 * (self.var.num_bytes or 0)
        return 0  # static

    def delta_bits(self) -> int:
        if not self.uses_delta:
            return self.key_bits()
        return _width(2 * float(self.var.max_delta or 0), self.precision)

    def total_bits(self) -> int:
        return self.key_bits() + (self.array_length - 1) * self.delta_bits()

    # -- one element ---------------------------------------------------------------------------
    def encode_element(self, value: Value, key: Value, is_delta: bool) -> int:
        """The element's bits (not yet masked to the width)."""
        kind = self.kind
        if self.is_number:
            number = as_double(value)
            low, high = self.bounds
            if number is None or number < low or number > high:
                return 0
            if is_delta:
                max_delta = float(self.var.max_delta or 0)
                key_number = as_double(key)
                number += max_delta - (math.nan if key_number is None else key_number)
                if number > 2 * max_delta or number < 0:
                    return 0
            else:
                number -= low
            return to_unsigned_long(number * math.pow(10.0, self.precision)) + 1
        if kind == "bool":
            flag = as_bool(value)
            return 0 if flag is None else int(flag) + 1
        if kind == "enum":
            text = as_string(value)
            values = self.var.enum_values
            return values.index(text) + 1 if text in values else 0
        if kind == "string":
            return _string_bits(as_string(value).encode(), self.var.max_length or 0)
        if kind == "hex":
            return _hex_bits(self.name, as_string(value), self.var.num_bytes or 0)
        return 0  # static: no bits

    def decode_element(self, bits: int, key: object, is_delta: bool) -> object:
        kind = self.kind
        if self.is_number:
            if not bits:
                return None
            number = float(bits - 1) / math.pow(10.0, self.precision)
            if is_delta:
                if key is None:
                    return None  # 1.1 adds the delta to "no value" and gets NaN
                number += float(key) - float(self.var.max_delta or 0)  # type: ignore[arg-type]
            else:
                number += self.bounds[0]
            if kind == "int":
                return int(number)
            return round(number, self.precision)
        if kind == "bool":
            return None if not bits else bits == 2
        if kind == "enum":
            values = self.var.enum_values
            return values[bits - 1] if 0 < bits <= len(values) else None
        if kind == "string":
            length = self.var.max_length or 0
            text = bits.to_bytes(length, "big").split(b"\0", 1)[0]
            return text.decode("latin-1") or None
        if kind == "hex":
            return bits.to_bytes(self.var.num_bytes or 0, "big").hex()
        return self.var.static_value


def _string_bits(text: bytes, max_length: int) -> int:
    """1.1 packs a string one char at a time, each a *signed* char widened to 64 bits: a byte
    >= 0x80 also sets the 56 bits above it (within the field), overwriting earlier chars."""
    mask = (1 << (8 * max_length)) - 1
    padded = text + bytes(max_length)
    bits = 0
    for byte in padded[:max_length]:
        widened = byte if byte < 0x80 else (byte - 256) & (2**64 - 1)
        bits = ((bits << 8) | widened) & mask
    return bits


def _hex_bits(name: str, text: str, num_bytes: int) -> int:
    if len(text) != 2 * num_bytes:
        size = "short" if len(text) < 2 * num_bytes else "long"
        raise DcclEncodeError(
            f"{name}: hex value {text!r} is too {size}: it must be {num_bytes} bytes"
        )
    value = 0
    for i in range(num_bytes):
        value = (value << 8) | _hex_byte(text[2 * i : 2 * i + 2])
    return value


def _hex_byte(pair: str) -> int:
    """A stream read of one hex byte as 1.1 does it: leading blanks skipped, then as many hex
    digits as there are; none gives 0."""
    digits = ""
    for char in pair.lstrip():
        if char not in "0123456789abcdefABCDEF":
            break
        digits += char
    return int(digits, 16) if digits else 0


@dataclass
class Dccl1Header:
    ccl_id: int
    id: int
    time_of_day: int
    src: int
    dest: int
    multimessage: bool = False
    broadcast: bool = False
    unused: int = 0

    def pack(self) -> bytes:
        parts = (
            self.ccl_id,
            self.id,
            self.time_of_day,
            self.src,
            self.dest,
            int(self.multimessage),
            int(self.broadcast),
            self.unused,
        )
        bits = 0
        for (_, width), value in zip(HEADER_LAYOUT, parts, strict=True):
            bits = (bits << width) | (value & ((1 << width) - 1))
        return bits.to_bytes(HEADER_BYTES, "big")

    @classmethod
    def unpack(cls, head: bytes) -> Dccl1Header:
        """Fewer than 6 bytes are read right-aligned, as 1.1 does (its decoder can cut zero
        bytes off the header)."""
        bits = int.from_bytes(head[:HEADER_BYTES], "big")
        values = []
        for _, width in reversed(HEADER_LAYOUT):
            values.append(bits & ((1 << width) - 1))
            bits >>= width
        unused, broadcast, multi, dest, src, tod, dccl_id, ccl_id = values
        return cls(ccl_id, dccl_id, tod, src, dest, bool(multi), bool(broadcast), unused)


def unix_time(time_of_day: int, now: float) -> float:
    """1.1's date for a received time of day: today, unless the time of day is more than 12 h
    away from now's, then yesterday (either way round)."""
    today = math.floor(now / SECONDS_PER_DAY) * SECONDS_PER_DAY
    if abs((now - today) // 1 - time_of_day) > SECONDS_PER_DAY / 2:
        today -= SECONDS_PER_DAY
    return today + time_of_day


@dataclass
class Dccl1Message:
    """A loaded XML message: its header names, its layout with widths, and its size."""

    xml: XmlMessage
    fields: list[Dccl1Field]
    header_names: tuple[str, ...]  # per HEADER_LAYOUT entry (time/src/dest may be renamed)

    @property
    def name(self) -> str:
        return self.xml.name

    @property
    def id(self) -> int:
        return self.xml.id or 0

    @property
    def body_bits(self) -> int:
        return sum(f.total_bits() for f in self.fields)

    @property
    def body_bytes(self) -> int:
        return (self.body_bits + 7) // 8

    @property
    def repeat(self) -> int:
        """Copies packed by <repeat/> (1 without it)."""
        return self.fields[0].array_length if self.xml.repeat and self.fields else 1

    @classmethod
    def build(cls, xml: XmlMessage) -> Dccl1Message:
        header_names = tuple(
            xml.header[tag].name if tag in xml.header else default
            for tag, default in zip(
                ("", "", "time", "src_id", "dest_id", "", "", ""),
                (name for name, _ in HEADER_LAYOUT),
                strict=True,
            )
        )
        size = xml.size or 0
        if size <= HEADER_BYTES:
            raise DcclLoadError(f"<size> must be larger than the header size of {HEADER_BYTES}")
        body_limit = 8 * size - HEADER_BITS
        fields = [Dccl1Field(var, var.array_length) for var in xml.layout]
        message = cls(xml, fields, header_names)
        if xml.repeat:
            if any(var.array_length != 1 for var in xml.layout):
                raise DcclLoadError(
                    "<repeat> is not allowed on messages with arrays (<array_length> not 1)"
                )
            copies = 1
            while message._set_copies(copies) <= body_limit and copies <= body_limit:
                copies += 1
            message._set_copies(copies - 1)
        if message.body_bits > body_limit or (xml.repeat and message.repeat == 0):
            raise DcclLoadError(
                f"the message [{xml.name}] will not fit within <size> {size} bytes: its body "
                f"needs {message.body_bits} bits, {body_limit} are left after the "
                f"{HEADER_BYTES}-byte header"
            )
        return message

    def _set_copies(self, copies: int) -> int:
        for f in self.fields:
            f.array_length = copies
        return self.body_bits


@dataclass
class Dccl1Decoded:
    message: str
    header: Dccl1Header
    values: dict[str, object]
    time: float = 0.0  # the time of day placed on a date as 1.1 does
    field_names: list[str] = field(default_factory=list)


def _elements(value: object, length: int) -> list[Value]:
    if isinstance(value, list | tuple):
        items = list(value)
    elif value is None:
        items = []
    else:
        items = [value]
    return (items + [None] * length)[:length]


def _pre_round(value: Value, precision: int) -> Value:
    """Numbers are rounded to the field's precision before anything else (1.1's pre-encode)."""
    number = as_double(value)
    return value if number is None else unbiased_round(number, precision)


class Dccl1Codec:
    """Encode and decode DCCL1 messages of loaded XML message sets.

    codec = Dccl1Codec(passphrase="secret", modem_id=1)
    codec.load(load_message_set("simple_status.xml"))
    data = codec.encode("SIMPLE_STATUS", {"nav_x": "100", "Speed": 1.5}, dest=0)
    codec.decode(data).values
    """

    def __init__(
        self,
        passphrase: str | bytes | None = None,
        modem_id: int = 0,
        clock: Callable[[], float] = _time.time,
    ) -> None:
        # 1.1 encrypts always: with no passphrase its key is SHA-256 of nothing
        self._cipher = BodyCipher(passphrase or b"")
        self.modem_id = modem_id
        self.clock = clock
        self._by_name: dict[str, Dccl1Message] = {}
        self._by_id: dict[int, Dccl1Message] = {}

    def load(self, message_set) -> list[Dccl1Message]:
        """Load the messages of a `pygoby.dccl.xml.MessageSet` (ConfigError `file:line` when one
        does not fit its <size> or reuses a loaded id)."""
        from pygoby.errors import ConfigError

        loaded = []
        for xml in message_set.messages:
            try:
                message = Dccl1Message.build(xml)
            except DcclLoadError as err:
                raise ConfigError(
                    f"message {xml.name}: {err}", file=message_set.path, line=xml.line
                ) from None
            if message.id in self._by_id and self._by_id[message.id].name != message.name:
                raise ConfigError(
                    f"message {xml.name}: DCCL id {message.id} is already used by "
                    f"{self._by_id[message.id].name}",
                    file=message_set.path,
                    line=xml.line,
                )
            self._by_name[message.name] = message
            self._by_id[message.id] = message
            loaded.append(message)
        return loaded

    def load_all(self, message_sets: Iterable) -> None:
        for message_set in message_sets:
            self.load(message_set)

    @property
    def messages(self) -> list[Dccl1Message]:
        return list(self._by_name.values())

    def message(self, name_or_id: str | int) -> Dccl1Message:
        table: Mapping[Any, Dccl1Message] = (
            self._by_id if isinstance(name_or_id, int) else self._by_name
        )
        try:
            return table[name_or_id]
        except KeyError:
            what = "id" if isinstance(name_or_id, int) else "name"
            raise DcclEncodeError(
                f"no DCCL1 message with {what} {name_or_id!r} is loaded"
            ) from None

    # -- encode --------------------------------------------------------------------------------
    def encode(
        self,
        name_or_id: str | int,
        values: Values,
        *,
        src: Value = None,
        dest: Value = None,
        time: Value = None,
    ) -> bytes:
        """`values` by XML name (strings as pAcommsHandler hands them, or numbers/bools; lists for
        arrays); header parts may be given there under their XML names, or as src/dest/time.
        Defaults as 1.1: src = modem id, dest = 0 (broadcast), time = now."""
        message = self.message(name_or_id)
        head = self._encode_header(message, values, src, dest, time)
        body_value = 0
        for f in message.fields:
            body_value = self._encode_field(f, values.get(f.name), body_value)
        body = body_value.to_bytes(message.body_bytes, "big").rstrip(b"\0")
        return head + self._cipher.apply(head, body)

    def _encode_header(
        self, message: Dccl1Message, values: Values, src: Value, dest: Value, time: Value
    ) -> bytes:
        names = message.header_names
        given: list[Value] = []
        for name in names:
            raw = values.get(name)
            given.append(raw[0] if isinstance(raw, list | tuple) and raw else raw)  # type: ignore[arg-type]
        for index, override in ((2, time), (3, src), (4, dest)):
            if override is not None:
                given[index] = override
        # 1.1's defaults: the CCL id is always 0x20; the others fill only what was not given
        given[0] = DCCL1_FIRST_BYTE
        if given[1] is None:
            given[1] = message.id
        if given[2] is None or as_double(given[2]) is None:
            given[2] = self.clock()
        if given[3] is None:
            given[3] = self.modem_id
        if given[4] is None:
            given[4] = BROADCAST_ID
        rounded = [_pre_round(v, 0) for v in given]
        multi, broadcast = as_bool(rounded[5]), as_bool(rounded[6])
        header = Dccl1Header(
            ccl_id=as_long(rounded[0]) or 0,
            id=as_long(rounded[1]) or 0,
            time_of_day=_time_of_day(float(rounded[2])),  # type: ignore[arg-type]
            src=as_long(rounded[3]) or 0,
            dest=as_long(rounded[4]) or 0,
            multimessage=bool(multi),
            broadcast=bool(broadcast),
            unused=as_long(rounded[7]) or 0,
        )
        return header.pack()

    def _encode_field(self, f: Dccl1Field, raw: object, bits: int) -> int:
        elements = _elements(raw, f.array_length)
        if f.is_number:
            elements = [_pre_round(v, f.precision) for v in elements]
        key = elements[0]
        key_mask, delta_mask = (1 << f.key_bits()) - 1, (1 << f.delta_bits()) - 1
        for element in elements[1:]:
            value = f.encode_element(element, key, f.uses_delta)
            bits = (bits << f.delta_bits()) | (value & delta_mask)
        return (bits << f.key_bits()) | (f.encode_element(key, key, False) & key_mask)

    # -- decode --------------------------------------------------------------------------------
    def decode(self, data: bytes, now: float | None = None) -> Dccl1Decoded:
        """Decode one DCCL1 message (not a multi-message frame: see `frames.unstitch`)."""
        if not data:
            raise DcclDecodeError("empty message")
        if data[0] != DCCL1_FIRST_BYTE:
            raise DcclDecodeError(
                f"not a DCCL1 message: its first byte is 0x{data[0]:02x}, not 0x20"
            )
        dccl_id = Dccl1Header.unpack(data[:HEADER_BYTES]).id
        message = self._by_id.get(dccl_id)
        if message is None:
            raise DcclDecodeError(f"no DCCL1 message with id {dccl_id} is loaded")
        data = data.rstrip(b"\0")
        head, body = data[:HEADER_BYTES], data[HEADER_BYTES:]
        body = self._cipher.apply(head, body)[: message.body_bytes]
        body = body + bytes(message.body_bytes - len(body))
        header = Dccl1Header.unpack(head)
        bits = int.from_bytes(body, "big")
        values: dict[str, object] = {}
        for f in reversed(message.fields):
            key_bits, delta_bits = f.key_bits(), f.delta_bits()
            key = f.decode_element(bits & ((1 << key_bits) - 1), None, False)
            bits >>= key_bits
            others: list[object] = []
            for _ in range(f.array_length - 1):
                others.append(f.decode_element(bits & ((1 << delta_bits) - 1), key, f.uses_delta))
                bits >>= delta_bits
            elements = [key, *reversed(others)]
            values[f.name] = elements if f.array_length > 1 else key
        ordered = {f.name: values[f.name] for f in message.fields}
        moment = self.clock() if now is None else now
        return Dccl1Decoded(
            message.name,
            header,
            ordered,
            unix_time(header.time_of_day, moment),
            [f.name for f in message.fields],
        )


def _time_of_day(unix_seconds: float) -> int:
    """Seconds since midnight UTC of a (whole-second) unix time, as 1.1 computes it: the
    seconds pass through a 32-bit int, so dates past 2038 wrap as they do in 1.1."""
    if not math.isfinite(unix_seconds):
        return 0
    whole = math.floor(unix_seconds)
    if not -(2**31) <= whole < 2**31:
        whole = -(2**31)
    return int(unbiased_round(whole % SECONDS_PER_DAY, 0))
