"""MOOS V10 wire protocol, sans I/O: messages, packets, framing, handshake and wildcards.

Everything here is pure: functions and classes take bytes and numbers and return bytes, messages
or errors. The asyncio client (`client.py`) and the embedded DB (`db.py`) do the socket work.

Layout: little-endian throughout;
packet = int32 total_len, int32 n_msgs, uint8 0, messages;
message = int32 msg_len, int32 id, char msg_type, char data_type, str src, str src_aux,
str community, str key, f64 time, f64 dval, f64 dval2, str sval (str = int32 length + bytes).
"""

from __future__ import annotations

import math
import re
import struct
from collections.abc import Iterable
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

# Message types.
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

# Data types.
DOUBLE = "D"
STRING = "S"
BINARY = "B"
NOT_SET = "~"

PACKET_HEADER_SIZE = 9
_HEADER = struct.Struct("<iiB")
_INT = struct.Struct("<i")

# The V10 message layout (little-endian), read here and by the MOOSDB's fast path (dbcore):
#   int32 msg_len (the whole message), int32 id, char msg_type, char data_type,
#   four strings, each an int32 length + bytes: src, src_aux, community, key,
#   the tail: double time, double dval, double dval2, int32 sval length; then sval's bytes.
MESSAGE_START = struct.Struct("<iiBB")  # msg_len, id, msg_type, data_type
ID_AT = 4  # offsets from the start of the message
MSG_TYPE_AT = 8
DATA_TYPE_AT = 9
SRC_AT = MESSAGE_START.size  # the length of src, the first of the four strings
STRING_LENGTH_SIZE = _INT.size
MESSAGE_TAIL = struct.Struct("<dddi")  # time, dval, dval2, sval length: right after the key
SVAL_LENGTH_IN_TAIL = 24  # offset of the sval length from the start of the tail
MESSAGE_FIXED_SIZE = SRC_AT + 4 * STRING_LENGTH_SIZE + MESSAGE_TAIL.size  # 54: empty strings
_START = struct.Struct(MESSAGE_START.format + "i")  # ... and the length of src
_CHARS = tuple(map(chr, range(256)))
_SRC_BYTES_AT = SRC_AT + STRING_LENGTH_SIZE
_TAIL_SIZE = MESSAGE_TAIL.size
_AFTER_COMMUNITY = STRING_LENGTH_SIZE + _TAIL_SIZE  # the bytes a string leaves after it
_AFTER_AUX = STRING_LENGTH_SIZE + _AFTER_COMMUNITY
_AFTER_SRC = STRING_LENGTH_SIZE + _AFTER_AUX

Value = float | str | bytes


def decode_text(raw: bytes) -> str:
    """MOOS strings are raw bytes; decode losslessly (undecodable bytes survive a round trip)."""
    return raw.decode("utf-8", "surrogateescape")


def encode_text(text: str) -> bytes:
    return text.encode("utf-8", "surrogateescape")


def text_or_binary(data: bytes) -> str | bytes:
    """`data` as a MOOS string when it is printable ASCII (NMEA), else as a binary string."""
    try:
        text = data.decode("ascii")
    except UnicodeDecodeError:
        return data
    return text if text.isprintable() else data


@dataclass(slots=True)
class MOOSMessage:
    """One CMOOSMsg. Defaults are the C++ default constructor's, so that messages
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
            self.msg_type,
            self.data_type,
            self.key,
            self.time,
            self.dval,
            self.dval2,
            self.sval,
            self.src,
            self.src_aux,
            self.community,
            self.id,
        )

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
        return MOOSMessage(
            NOTIFY, DOUBLE, key, time, float(value), -1.0, b"", src, src_aux, community, msg_id
        )
    if isinstance(value, str):
        return MOOSMessage(
            NOTIFY,
            STRING,
            key,
            time,
            -1.0,
            -1.0,
            encode_text(value),
            src,
            src_aux,
            community,
            msg_id,
        )
    if isinstance(value, bytes | bytearray | memoryview):
        return MOOSMessage(
            NOTIFY, BINARY, key, time, -1.0, -1.0, bytes(value), src, src_aux, community, msg_id
        )
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
        MESSAGE_FIXED_SIZE + a + b + c + k + v,
        msg.id,
        msg.msg_type.encode("latin-1"),
        msg.data_type.encode("latin-1"),
        a,
        src,
        b,
        aux,
        c,
        com,
        k,
        key,
        msg.time,
        msg.dval,
        msg.dval2,
        v,
        sval,
    )


def encode_packet(msgs: Iterable[MOOSMessage]) -> bytes:
    """One packet holding `msgs` (never empty: an empty packet upsets C++ peers)."""
    return packet_of([encode_message(m) for m in msgs])


def packet_of(encoded: list[bytes]) -> bytes:
    """One packet of already encoded messages."""
    if not encoded:
        raise ValueError("a MOOS packet must hold at least one message")
    total = PACKET_HEADER_SIZE + sum(map(len, encoded))
    return _HEADER.pack(total, len(encoded), 0) + b"".join(encoded)


# ---------------------------------------------------------------------------------------------
# Decoding


def read_str(data: bytes | memoryview, pos: int, end: int, what: str) -> tuple[bytes, int]:
    """The MOOS string (int32 length + bytes) at `pos`, which must end by `end`; and the offset
    after it."""
    if pos + 4 > end:
        raise MoosProtocolError(f"message truncated in the length of {what}")
    (n,) = _INT.unpack_from(data, pos)
    pos += 4
    if n < 0 or pos + n > end:
        raise MoosProtocolError(f"{what} length {n} is negative or runs past the message end")
    return bytes(data[pos : pos + n]), pos + n


def decode_message(
    data: bytes | memoryview, offset: int = 0, end: int | None = None
) -> tuple[MOOSMessage, int]:
    """Decode the message starting at `offset`; returns it and the offset after it."""
    if not isinstance(data, bytes):
        data = bytes(data)
    msgs, stop = _decode_messages(data, offset, len(data) if end is None else end, 1)
    return msgs[0], stop


def _decode_messages(
    data: bytes, pos: int, limit: int, count: int
) -> tuple[list[MOOSMessage], int]:
    """`count` messages from data[pos:limit]; and the offset after the last."""
    msgs: list[MOOSMessage] = []
    append = msgs.append
    read_start = _START.unpack_from
    read_int = _INT.unpack_from
    read_tail = MESSAGE_TAIL.unpack_from
    chars = _CHARS
    for _ in range(count):
        if limit - pos < MESSAGE_FIXED_SIZE:
            raise MoosProtocolError(
                f"message truncated: {limit - pos} bytes left, a message has "
                f"at least {MESSAGE_FIXED_SIZE}"
            )
        msg_len, msg_id, msg_type, data_type, n = read_start(data, pos)
        stop = pos + msg_len
        if msg_len < MESSAGE_FIXED_SIZE or stop > limit:
            raise MoosProtocolError(
                f"message length {msg_len} is below {MESSAGE_FIXED_SIZE} or runs past the packet end"
            )
        # each string must leave room for the lengths of those after it and the tail
        pos += _SRC_BYTES_AT
        if n < 0 or pos + n + _AFTER_SRC > stop:
            raise _bad_length("src", n)
        src = data[pos : pos + n].decode("utf-8", "surrogateescape") if n else ""
        pos += n
        (n,) = read_int(data, pos)
        pos += STRING_LENGTH_SIZE
        if n < 0 or pos + n + _AFTER_AUX > stop:
            raise _bad_length("src_aux", n)
        aux = data[pos : pos + n].decode("utf-8", "surrogateescape") if n else ""
        pos += n
        (n,) = read_int(data, pos)
        pos += STRING_LENGTH_SIZE
        if n < 0 or pos + n + _AFTER_COMMUNITY > stop:
            raise _bad_length("community", n)
        community = data[pos : pos + n].decode("utf-8", "surrogateescape") if n else ""
        pos += n
        (n,) = read_int(data, pos)
        pos += STRING_LENGTH_SIZE
        if n < 0 or pos + n + _TAIL_SIZE > stop:
            raise _bad_length("key", n)
        key = data[pos : pos + n].decode("utf-8", "surrogateescape")
        time_, dval, dval2, sval_len = read_tail(data, pos + n)
        pos += n + _TAIL_SIZE
        if sval_len < 0 or pos + sval_len != stop:
            raise MoosProtocolError(
                f"sval length {sval_len} does not end the message at its msg_len"
            )
        append(
            MOOSMessage(
                chars[msg_type],
                chars[data_type],
                key,
                time_,
                dval,
                dval2,
                data[pos:stop],
                src,
                aux,
                community,
                msg_id,
            )
        )
        pos = stop
    return msgs, pos


def _bad_length(what: str, n: int) -> MoosProtocolError:
    return MoosProtocolError(f"{what} length {n} is negative or runs past the message end")


def parse_packet_header(data: bytes | memoryview, offset: int = 0) -> tuple[int, int]:
    """(total_len, n_msgs) from the 9 bytes at `offset`, validated."""
    total, n_msgs, _compressed = _HEADER.unpack_from(data, offset)
    if total < PACKET_HEADER_SIZE:
        raise MoosProtocolError(
            f"packet length {total} is below the {PACKET_HEADER_SIZE}-byte header"
        )
    if n_msgs < 0:
        raise MoosProtocolError(f"packet claims {n_msgs} messages")
    return total, n_msgs


def decode_packet(
    data: bytes | memoryview, start: int = 0, end: int | None = None
) -> list[MOOSMessage]:
    """Decode one complete packet: data[start:end] (by default all of `data`) must be exactly
    its `total_len` bytes."""
    if not isinstance(data, bytes):
        data = bytes(data)
    end = len(data) if end is None else end
    if end - start < PACKET_HEADER_SIZE:
        raise MoosProtocolError(f"packet of {end - start} bytes is shorter than its header")
    total, n_msgs = parse_packet_header(data, start)
    if total != end - start:
        raise MoosProtocolError(
            f"packet length field says {total} bytes but {end - start} were given"
        )
    msgs, pos = _decode_messages(data, start + PACKET_HEADER_SIZE, end, n_msgs)
    if pos != end:
        raise MoosProtocolError(f"{end - pos} trailing bytes after the last message of the packet")
    return msgs


class PacketFramer:
    """Cuts a TCP byte stream into packets, copying each byte at most once.

    `feed(data)` returns `(buffer, spans)`: the packets that `data` completed are
    buffer[start:end] for each (start, end) in spans; what follows them is kept for the next
    feed. A length field above `max_packet_size` raises MoosProtocolError as soon as the header is
    seen, so an oversized packet is refused before any of it is buffered beyond its header.
    `buffered` is the number of bytes held; `began_packet` tells whether the last feed left an
    incomplete packet that it started (rather than one already begun).
    """

    def __init__(self, max_packet_size: int = DEFAULT_MAX_PACKET_SIZE) -> None:
        self.max_packet_size = max_packet_size
        self._chunks: list[bytes] = []  # an incomplete packet, as received
        self.buffered = 0
        self._need = PACKET_HEADER_SIZE  # bytes the incomplete packet needs, once known
        self.began_packet = False

    def feed(self, data: bytes) -> tuple[bytes, list[tuple[int, int]]]:
        if self._chunks:
            self._chunks.append(data)
            self.buffered += len(data)
            self.began_packet = False
            if self.buffered < self._need:
                return b"", []
            data = b"".join(self._chunks)
        pos, end = 0, len(data)
        need = PACKET_HEADER_SIZE
        spans = []
        while end - pos >= PACKET_HEADER_SIZE:
            total, _ = parse_packet_header(data, pos)
            if total > self.max_packet_size:
                raise MoosProtocolError(
                    f"packet of {total} bytes exceeds the limit of {self.max_packet_size} bytes"
                )
            if end - pos < total:
                need = total
                break
            spans.append((pos, pos + total))
            pos += total
        self.began_packet = pos < end and (bool(spans) or not self._chunks)
        self._chunks = [data[pos:]] if pos < end else []
        self.buffered = end - pos
        self._need = need
        return data, spans


# ---------------------------------------------------------------------------------------------
# Handshake


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
        WELCOME,
        DOUBLE,
        "",
        db_time,
        skew,
        -1.0,
        encode_text(ASYNC_HANDSHAKE_KEY),
        src_aux=f"hostname={hostname}",
        community=community,
    )


def poison_message(reason: str, db_time: float) -> MOOSMessage:
    return MOOSMessage(POISON, STRING, "", db_time, sval=encode_text(reason))


def name_in_use_reason(name: str) -> str:
    return f'A client of this name ("{name}") already exists'


def timing_message(local_time: float) -> MOOSMessage:
    """The V10 client's keep-alive / clock-sync message."""
    return MOOSMessage(TIMING, DOUBLE, TIMING_KEY, local_time, 0.0, -1.0)


def welcome_hostname(welcome: MOOSMessage) -> str:
    aux = welcome.src_aux
    return aux[len("hostname=") :] if aux.startswith("hostname=") else ""


# ---------------------------------------------------------------------------------------------
# Wildcards


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


class Glob:
    """A MOOS glob, compiled once: `*` any sequence, `?` one character, everything else
    literal, case-sensitive, whole name (unlike fnmatch, `[` and `]` are ordinary characters).

    Matching never backtracks and costs time linear in the name: the text between stars is
    placed at its leftmost possible position, one piece after the other (which finds a match
    whenever there is one); a piece holding `?` is searched for by bit-parallel matching
    (shift-and: one step per character of the name, whatever the piece's length)."""

    __slots__ = ("_min_len", "_pieces", "_searches", "pattern")

    def __init__(self, pattern: str) -> None:
        self.pattern = pattern
        self._pieces = pattern.split("*")  # one piece: no star; else head, middles..., tail
        self._min_len = len(pattern) - len(self._pieces) + 1
        self._searches = [_PieceSearch(piece) for piece in self._pieces[1:-1]]

    def match(self, name: str) -> bool:
        pieces = self._pieces
        if len(pieces) == 1:
            return len(name) == self._min_len and _piece_at(pieces[0], name, 0)
        if len(name) < self._min_len or not _piece_at(pieces[0], name, 0):
            return False
        tail_start = len(name) - len(pieces[-1])
        pos = len(pieces[0])
        for search in self._searches:
            pos = search.find(name, pos, tail_start)
            if pos < 0:
                return False
        return _piece_at(pieces[-1], name, tail_start)

    def __repr__(self) -> str:
        return f"Glob({self.pattern!r})"


def _piece_at(piece: str, name: str, at: int) -> bool:
    """Does the star-free `piece` (`?` = any character) match `name` at offset `at`?"""
    if "?" not in piece:
        return name.startswith(piece, at)
    if at + len(piece) > len(name):
        return False
    return all(c == "?" or c == name[at + i] for i, c in enumerate(piece))


class _PieceSearch:
    """The leftmost place of one star-free piece in a name."""

    __slots__ = ("_last", "_masks", "_wild", "piece")

    def __init__(self, piece: str) -> None:
        self.piece = piece
        # shift-and tables: bit i of a character's mask is set when piece[i] accepts it
        self._wild = sum(1 << i for i, c in enumerate(piece) if c == "?")
        self._masks: dict[str, int] = {}
        for i, c in enumerate(piece):
            if c != "?":
                self._masks[c] = self._masks.get(c, self._wild) | 1 << i
        self._last = 1 << (len(piece) - 1) if piece else 0

    def find(self, name: str, start: int, stop: int) -> int:
        """The end (exclusive) of the leftmost match at or after `start` that ends at or
        before `stop`; -1 if none."""
        piece = self.piece
        if not self._masks:  # no literal character: only the length counts
            end = start + len(piece)
            return end if end <= stop else -1
        if not self._wild:
            at = name.find(piece, start, stop)
            return at + len(piece) if at >= 0 else -1
        masks, wild, last = self._masks, self._wild, self._last
        state = 0
        for end in range(start, stop):
            state = ((state << 1) | 1) & masks.get(name[end], wild)
            if state & last:
                return end + 1
        return -1


def wildcard_match(pattern: str, name: str) -> bool:
    """`Glob(pattern).match(name)`, for one-off tests."""
    return Glob(pattern).match(name)


@dataclass(slots=True)
class SkewFilter:
    """Client-side clock skew estimate from timing echoes."""

    skew: float = 0.0

    def update(self, sent_local: float, db_time: float, received_local: float) -> float:
        measured = ((db_time - received_local) + (db_time - sent_local)) / 2.0
        self.skew = measured if self.skew == 0.0 else 0.9 * self.skew + 0.1 * measured
        return self.skew
