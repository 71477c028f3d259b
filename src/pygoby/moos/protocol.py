"""MOOS V10 wire protocol, sans I/O: messages, packets, framing, handshake and wildcards.

Everything here is pure: functions and classes take bytes and numbers and return bytes, messages
or errors. The asyncio client (`client.py`) and the embedded DB (`db.py`) do the socket work.

Layout (spec moos.md sections 3-7): little-endian throughout;
packet = int32 total_len, int32 n_msgs, uint8 0, messages;
message = int32 msg_len, int32 id, char msg_type, char data_type, str src, str src_aux,
str community, str key, f64 time, f64 dval, f64 dval2, str sval (str = int32 length + bytes).
"""

from __future__ import annotations

import math
import re
import struct
from collections.abc import Iterable, Iterator
from dataclasses import dataclass

from pygoby.moos.errors import MoosProtocolError

PROTOCOL_STRING_TEXT = "ELKS CAN'T DANCE 2/8/10"
PROTOCOL_STRING_SIZE = 32
PROTOCOL_STRING = PROTOCOL_STRING_TEXT.encode("ascii").ljust(PROTOCOL_STRING_SIZE, b"\0")
DEFAULT_PORT = 9000
DEFAULT_COMMUNITY = "#1"
DEFAULT_MAX_PACKET_SIZE = 16 * 1024 * 1024
ASYNC_HANDSHAKE_KEY = "asynchronous"
TIMING_KEY = "_async_timing"
SERVER_REQUEST_ID = -2

# Message types (moos.md 6.1).
NOTIFY = "N"
REGISTER = "R"
UNREGISTER = "U"
WILDCARD_REGISTER = "*"
WILDCARD_UNREGISTER = "/"
SERVER_REQUEST = "Q"
TIMING = "T"
NULL = "."
DATA = "i"
WELCOME = "W"
POISON = "K"
COMMAND = "C"

# Data types (moos.md 6.2).
DOUBLE = "D"
STRING = "S"
BINARY = "B"
NOT_SET = "~"

PACKET_HEADER_SIZE = 9
MESSAGE_FIXED_SIZE = 54
_HEADER = struct.Struct("<iiB")
_INT = struct.Struct("<i")
_ID_TYPES = struct.Struct("<icc")
_DOUBLES = struct.Struct("<ddd")

Value = float | str | bytes


def decode_text(raw: bytes) -> str:
    """MOOS strings are raw bytes; decode losslessly (undecodable bytes survive a round trip)."""
    return raw.decode("utf-8", "surrogateescape")


def encode_text(text: str) -> bytes:
    return text.encode("utf-8", "surrogateescape")


@dataclass(slots=True)
class MOOSMessage:
    """One CMOOSMsg. Defaults are the C++ default constructor's (moos.md 5), so that messages
    built here serialise to the same bytes as C++ clients'."""

    msg_type: str = NULL
    data_type: str = DOUBLE
    key: str = ""
    time: float = -1.0
    dval: float = -1.0
    dval2: float = -1.0
    sval: bytes = b""
    src: str = ""
    src_aux: str = ""
    community: str = ""
    id: int = -1

    @property
    def is_double(self) -> bool:
        return self.data_type == DOUBLE

    @property
    def is_string(self) -> bool:
        return self.data_type == STRING

    @property
    def is_binary(self) -> bool:
        return self.data_type == BINARY

    @property
    def string(self) -> str:
        """sval as text (lossless decoding)."""
        return decode_text(self.sval)

    @property
    def value(self) -> Value:
        """The payload by data type: float for D, str for S, bytes for B (and anything else)."""
        if self.data_type == DOUBLE:
            return self.dval
        if self.data_type == STRING:
            return decode_text(self.sval)
        return self.sval

    def copy(self) -> MOOSMessage:
        return MOOSMessage(
            self.msg_type, self.data_type, self.key, self.time, self.dval, self.dval2,
            self.sval, self.src, self.src_aux, self.community, self.id,
        )  # fmt: skip

    def encoded_size(self) -> int:
        return (
            MESSAGE_FIXED_SIZE
            + len(encode_text(self.src))
            + len(encode_text(self.src_aux))
            + len(encode_text(self.community))
            + len(encode_text(self.key))
            + len(self.sval)
        )


def notify(
    key: str,
    value: Value,
    *,
    time: float,
    src: str = "",
    src_aux: str = "",
    msg_id: int = -1,
    community: str = "",
) -> MOOSMessage:
    """An `N` message for a value: float/int -> double, str -> string, bytes -> binary."""
    if isinstance(value, bool):
        raise TypeError("MOOS has no boolean type; publish a number or a string")
    if isinstance(value, int | float):
        return MOOSMessage(NOTIFY, DOUBLE, key, time, float(value), -1.0, b"", src, src_aux,
                           community, msg_id)  # fmt: skip
    if isinstance(value, str):
        return MOOSMessage(NOTIFY, STRING, key, time, -1.0, -1.0, encode_text(value), src,
                           src_aux, community, msg_id)  # fmt: skip
    if isinstance(value, bytes | bytearray | memoryview):
        return MOOSMessage(NOTIFY, BINARY, key, time, -1.0, -1.0, bytes(value), src, src_aux,
                           community, msg_id)  # fmt: skip
    raise TypeError(f"cannot publish a {type(value).__name__} to MOOS (use float, str or bytes)")


# ---------------------------------------------------------------------------------------------
# Encoding


def encode_message(msg: MOOSMessage) -> bytes:
    src = msg.src.encode("utf-8", "surrogateescape")
    aux = msg.src_aux.encode("utf-8", "surrogateescape")
    com = msg.community.encode("utf-8", "surrogateescape")
    key = msg.key.encode("utf-8", "surrogateescape")
    sval = msg.sval
    a, b, c, k, v = len(src), len(aux), len(com), len(key), len(sval)
    # one pack call with the lengths in the format: the hot path of the DB and the client
    return struct.pack(
        f"<iicci{a}si{b}si{c}si{k}sdddi{v}s",
        MESSAGE_FIXED_SIZE + a + b + c + k + v, msg.id, msg.msg_type.encode("latin-1"),
        msg.data_type.encode("latin-1"), a, src, b, aux, c, com, k, key,
        msg.time, msg.dval, msg.dval2, v, sval,
    )  # fmt: skip


def encode_packet(msgs: Iterable[MOOSMessage], cache: dict[int, bytes] | None = None) -> bytes:
    """One packet holding `msgs` (never empty: an empty packet upsets C++ peers).

    `cache` (keyed by id(message)) lets a caller that sends the same message objects to many
    peers in one go encode each message once; the messages must stay alive meanwhile."""
    if cache is None:
        body = [encode_message(m) for m in msgs]
    else:
        body = []
        for m in msgs:
            raw = cache.get(id(m))
            if raw is None:
                raw = cache[id(m)] = encode_message(m)
            body.append(raw)
    if not body:
        raise ValueError("a MOOS packet must hold at least one message")
    total = PACKET_HEADER_SIZE + sum(len(b) for b in body)
    return _HEADER.pack(total, len(body), 0) + b"".join(body)


# ---------------------------------------------------------------------------------------------
# Decoding


def _get_str(data: bytes | memoryview, pos: int, end: int, what: str) -> tuple[bytes, int]:
    if pos + 4 > end:
        raise MoosProtocolError(f"message truncated in the length of {what}")
    (n,) = _INT.unpack_from(data, pos)
    pos += 4
    if n < 0 or pos + n > end:
        raise MoosProtocolError(f"{what} length {n} is negative or runs past the message end")
    return bytes(data[pos : pos + n]), pos + n


def decode_message(data: bytes | memoryview, offset: int = 0, end: int | None = None) -> tuple[MOOSMessage, int]:
    """Decode the message starting at `offset`; returns it and the offset after it."""
    limit = len(data) if end is None else end
    if offset + 4 > limit:
        raise MoosProtocolError("message truncated before its length field")
    (msg_len,) = _INT.unpack_from(data, offset)
    if msg_len < MESSAGE_FIXED_SIZE or offset + msg_len > limit:
        raise MoosProtocolError(
            f"message length {msg_len} is below {MESSAGE_FIXED_SIZE} or runs past the packet end"
        )
    stop = offset + msg_len
    msg_id, mtype, dtype = _ID_TYPES.unpack_from(data, offset + 4)
    pos = offset + 10
    src, pos = _get_str(data, pos, stop, "src")
    aux, pos = _get_str(data, pos, stop, "src_aux")
    com, pos = _get_str(data, pos, stop, "community")
    key, pos = _get_str(data, pos, stop, "key")
    if pos + 24 > stop:
        raise MoosProtocolError("message truncated in its time/dval/dval2 fields")
    time_, dval, dval2 = _DOUBLES.unpack_from(data, pos)
    sval, pos = _get_str(data, pos + 24, stop, "sval")
    if pos != stop:
        raise MoosProtocolError(f"message has {stop - pos} bytes after sval inside its msg_len")
    msg = MOOSMessage(
        mtype.decode("latin-1"), dtype.decode("latin-1"), decode_text(key), time_, dval, dval2,
        sval, decode_text(src), decode_text(aux), decode_text(com), msg_id,
    )  # fmt: skip
    return msg, stop


def parse_packet_header(header: bytes | memoryview) -> tuple[int, int]:
    """(total_len, n_msgs) from the first 9 bytes, validated."""
    total, n_msgs, _compressed = _HEADER.unpack_from(header, 0)
    if total < PACKET_HEADER_SIZE:
        raise MoosProtocolError(f"packet length {total} is below the {PACKET_HEADER_SIZE}-byte header")
    if n_msgs < 0:
        raise MoosProtocolError(f"packet claims {n_msgs} messages")
    return total, n_msgs


def decode_packet(data: bytes | memoryview) -> list[MOOSMessage]:
    """Decode one complete packet (exactly `total_len` bytes)."""
    if len(data) < PACKET_HEADER_SIZE:
        raise MoosProtocolError(f"packet of {len(data)} bytes is shorter than its header")
    total, n_msgs = parse_packet_header(data)
    if total != len(data):
        raise MoosProtocolError(f"packet length field says {total} bytes but {len(data)} were given")
    msgs = []
    pos = PACKET_HEADER_SIZE
    for _ in range(n_msgs):
        msg, pos = decode_message(data, pos, total)
        msgs.append(msg)
    if pos != total:
        raise MoosProtocolError(f"{total - pos} trailing bytes after the last message of the packet")
    return msgs


class PacketFramer:
    """Cuts a TCP byte stream into packets.

    `feed(data)` buffers bytes; iterating `packets()` yields each complete packet's bytes. A
    length field above `max_packet_size` raises MoosProtocolError as soon as the header is seen, so
    an oversized packet is refused before any of it is buffered beyond its header.
    """

    def __init__(self, max_packet_size: int = DEFAULT_MAX_PACKET_SIZE) -> None:
        self.max_packet_size = max_packet_size
        self._buf = bytearray()
        self._need: int | None = None

    def feed(self, data: bytes) -> None:
        self._buf += data
        if self._need is None:
            self._check_header()

    def _check_header(self) -> None:
        if len(self._buf) >= PACKET_HEADER_SIZE:
            total, _ = parse_packet_header(self._buf)
            if total > self.max_packet_size:
                raise MoosProtocolError(
                    f"packet of {total} bytes exceeds the limit of {self.max_packet_size} bytes"
                )
            self._need = total

    def packets(self) -> Iterator[bytes]:
        while True:
            if self._need is None:
                self._check_header()
                if self._need is None:
                    return
            if len(self._buf) < self._need:
                return
            packet = bytes(self._buf[: self._need])
            del self._buf[: self._need]
            self._need = None
            yield packet

    @property
    def buffered(self) -> int:
        return len(self._buf)


# ---------------------------------------------------------------------------------------------
# Handshake (moos.md 7)


def check_protocol_string(raw: bytes) -> bool:
    """The DB's test: text up to the first NUL equals the protocol string, ignoring case."""
    if len(raw) != PROTOCOL_STRING_SIZE:
        return False
    text = raw.split(b"\0", 1)[0]
    return text.lower() == PROTOCOL_STRING_TEXT.encode("ascii").lower()


def handshake_message(name: str, time: float, asynchronous: bool = True) -> MOOSMessage:
    key = ASYNC_HANDSHAKE_KEY if asynchronous else ""
    return MOOSMessage(DATA, STRING, key, time, sval=encode_text(name))


def welcome_message(community: str, hostname: str, db_time: float, skew: float) -> MOOSMessage:
    return MOOSMessage(
        WELCOME, DOUBLE, "", db_time, skew, -1.0, encode_text(ASYNC_HANDSHAKE_KEY),
        src_aux=f"hostname={hostname}", community=community,
    )  # fmt: skip


def poison_message(reason: str, db_time: float) -> MOOSMessage:
    return MOOSMessage(POISON, STRING, "", db_time, sval=encode_text(reason))


def name_in_use_reason(name: str) -> str:
    return f'A client of this name ("{name}") already exists'


def timing_message(local_time: float) -> MOOSMessage:
    """The V10 client's keep-alive / clock-sync message (moos.md 8.1)."""
    return MOOSMessage(TIMING, DOUBLE, TIMING_KEY, local_time, 0.0, -1.0)


def welcome_hostname(welcome: MOOSMessage) -> str:
    aux = welcome.src_aux
    return aux[len("hostname=") :] if aux.startswith("hostname=") else ""


# ---------------------------------------------------------------------------------------------
# Wildcards (moos.md 11.4)


def format_interval(interval: float) -> str:
    """C++ default stream formatting of a double: 0, 0.5, 1e-05 (6 significant digits)."""
    return f"{interval:g}"


def wildcard_sval(app_pattern: str, var_pattern: str, interval: float) -> bytes:
    text = f"AppPattern={app_pattern},VarPattern={var_pattern},Interval={format_interval(interval)}"
    return encode_text(text)


def _field(text: str, name: str) -> str | None:
    match = re.search(rf"(?:^|,)[ \t]*{re.escape(name)}=([^,]*)", text)
    return match.group(1).strip(" \t") if match else None


def parse_wildcard_sval(sval: bytes) -> tuple[str, str, float]:
    """(app pattern, variable pattern, interval) as the DB reads them; missing parts give
    empty patterns and interval 0."""
    text = decode_text(sval)
    app = _field(text, "AppPattern") or ""
    var = _field(text, "VarPattern") or ""
    raw_interval = _field(text, "Interval")
    try:
        interval = float(raw_interval) if raw_interval else 0.0
    except ValueError:
        interval = 0.0
    if not math.isfinite(interval):
        interval = 0.0
    return app, var, interval


_WILDCARD_CACHE: dict[str, re.Pattern[str]] = {}


def wildcard_match(pattern: str, name: str) -> bool:
    """MOOS glob: `*` any sequence, `?` one character, everything else literal, case-sensitive,
    whole name (unlike fnmatch, `[` and `]` are ordinary characters)."""
    compiled = _WILDCARD_CACHE.get(pattern)
    if compiled is None:
        parts = [".*" if c == "*" else "." if c == "?" else re.escape(c) for c in pattern]
        compiled = re.compile("".join(parts), re.DOTALL)
        if len(_WILDCARD_CACHE) < 4096:
            _WILDCARD_CACHE[pattern] = compiled
    return compiled.fullmatch(name) is not None


@dataclass(slots=True)
class SkewFilter:
    """Client-side clock skew estimate from timing echoes (moos.md 14.2)."""

    skew: float = 0.0

    def update(self, sent_local: float, db_time: float, received_local: float) -> float:
        measured = ((db_time - received_local) + (db_time - sent_local)) / 2.0
        self.skew = measured if self.skew == 0.0 else 0.9 * self.skew + 0.1 * measured
        return self.skew
