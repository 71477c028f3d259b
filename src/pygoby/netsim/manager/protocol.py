"""The NETSIM line protocol, sans-I/O: ``<preamble>|<protobuf full name>|<base64>\\n``.

Writing: `encode_line` gives one complete line (standard base64 with padding, no line breaks, a
single ``\\n``). Reading: a `LineDecoder` is fed raw bytes as they arrive and returns, for every
complete line, either a `ReceivedMessage` or a `LineError` (an exception *value*, never raised),
so one bad line is reported and skipped while the stream carries on at the next newline.

Tolerance (upstream netsim's and libb64's rules, where they have one):

* every ``\\n``-terminated line is handled on its own; blank lines are skipped; a line longer than
  `max_line_length` is discarded (without buffering it) and reported once as `LineTooLongError`;
* a line is split at its first two ``|``; fewer than two is `MissingSeparatorError`; the
  preamble is not checked (it is reported in the message so callers can log a non-``NETSIM`` one);
* the name must match an accepted name exactly (no trimming), else `UnknownNameError`;
* the payload is base64-decoded with libb64 semantics (`b64decode_libb64`), which never fails;
* the protobuf payload is parsed permissively: missing required fields read as defaults, and a
  corrupt payload yields the part parsed before the error, with `ReceivedMessage.parse_error`
  saying what was wrong (upstream processes such messages, and so does the manager).
"""

from __future__ import annotations

import base64
import re
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache

from google.protobuf.message import DecodeError, Message

from pygoby.netsim.errors import (
    LineError,
    LineTooLongError,
    MissingSeparatorError,
    UnknownNameError,
)
from pygoby.protobuf import builtin_class
from pygoby.protobuf.netsim.messages import netsim_pb2

NETSIM_PROTO = "netsim/messages/netsim.proto"
PREAMBLE = b"NETSIM"

REQUEST_NAME = "netsim.protobuf.NetSimManagerRequest"
RESPONSE_NAME = "netsim.protobuf.NetSimManagerResponse"
# Before netsim commit 585eb33 (2020-10-15) the .proto had no package; payloads are identical.
LEGACY_REQUEST_NAME = "NetSimManagerRequest"
LEGACY_RESPONSE_NAME = "NetSimManagerResponse"

DEFAULT_MAX_LINE_LENGTH = 1 << 20


@cache
def message_class(short_name: str) -> type[Message]:
    """`NavUpdate`, `ReceiveStats`, `NetSimManagerRequest`, `NetSimManagerResponse`, ..."""
    return builtin_class(NETSIM_PROTO, f"netsim.protobuf.{short_name}")


NavUpdate = netsim_pb2.NavUpdate
ReceiveStats = netsim_pb2.ReceiveStats
NetSimManagerRequest = netsim_pb2.NetSimManagerRequest
NetSimManagerResponse = netsim_pb2.NetSimManagerResponse
EnvironmentNavUpdate = netsim_pb2.EnvironmentNavUpdate


def request_class() -> type[NetSimManagerRequest]:
    return NetSimManagerRequest


def response_class() -> type[NetSimManagerResponse]:
    return NetSimManagerResponse


def request_names() -> dict[str, type[Message]]:
    """Names a manager accepts, current and legacy, mapped to the request class."""
    cls = request_class()
    return {REQUEST_NAME: cls, LEGACY_REQUEST_NAME: cls}


def response_names() -> dict[str, type[Message]]:
    """Names a client accepts, current and legacy, mapped to the response class."""
    cls = response_class()
    return {RESPONSE_NAME: cls, LEGACY_RESPONSE_NAME: cls}


# ---------------------------------------------------------------------------------------------
# base64


_NOT_BASE64 = re.compile(rb"[^A-Za-z0-9+/]")


def b64decode_libb64(text: bytes) -> bytes:
    """Decode like libb64: skip every non-alphabet character (``=`` included), whole bytes only."""
    sextets = _NOT_BASE64.sub(b"", text)
    if len(sextets) % 4 == 1:
        sextets = sextets[:-1]  # a lone trailing sextet cannot make a byte
    sextets += b"=" * (-len(sextets) % 4)
    return base64.b64decode(sextets, validate=True)  # always valid after the clean-up above


def b64encode(data: bytes) -> bytes:
    return base64.b64encode(data)


# ---------------------------------------------------------------------------------------------
# writing


def encode_line(message: Message, name: str | None = None) -> bytes:
    """One NETSIM line for `message` (name defaults to its full protobuf name).

    Raises `google.protobuf.message.EncodeError` if a required field is not set.
    """
    type_name = name if name is not None else message.DESCRIPTOR.full_name
    payload = message.SerializeToString()
    return b"|".join((PREAMBLE, type_name.encode(), b64encode(payload))) + b"\n"


# ---------------------------------------------------------------------------------------------
# reading


@dataclass(frozen=True)
class NetsimLine:
    preamble: bytes
    name: bytes
    payload: bytes  # base64-decoded


@dataclass
class ReceivedMessage:
    name: str
    message: Message
    preamble: bytes
    parse_error: str | None = None  # set when the payload was corrupt (message is partial)

    @property
    def legacy(self) -> bool:
        """True for the pre-2020 un-packaged names."""
        return "." not in self.name


def split_line(line: bytes) -> NetsimLine:
    """Split one line (without its ``\\n``) into preamble, name and decoded payload."""
    parts = line.split(b"|", 2)
    if len(parts) < 3:
        raise MissingSeparatorError("line has fewer than two '|' separators", line)
    preamble, name, text = parts
    return NetsimLine(preamble, name, b64decode_libb64(text))


def parse_payload(cls: type[Message], payload: bytes) -> tuple[Message, str | None]:
    """Parse permissively: returns the (possibly partial) message and the parse error, if any."""
    message = cls()
    try:
        message.ParseFromString(payload)
    except DecodeError as exc:
        return message, f"corrupt protobuf payload ({len(payload)} bytes): {exc}"
    return message, None


class LineDecoder:
    """Feed bytes in, get one `ReceivedMessage` or `LineError` per complete line out."""

    def __init__(
        self,
        accepted: Mapping[str, type[Message]],
        max_line_length: int = DEFAULT_MAX_LINE_LENGTH,
    ) -> None:
        if max_line_length < 1:
            raise ValueError("max_line_length must be positive")
        self._accepted = {name.encode(): (name, cls) for name, cls in accepted.items()}
        self.max_line_length = max_line_length
        self._buffer = bytearray()
        self._discarding = False  # inside an over-long line, waiting for its newline

    @property
    def buffered(self) -> int:
        """Bytes held for an incomplete line (never more than max_line_length)."""
        return len(self._buffer)

    def feed(self, data: bytes) -> list[ReceivedMessage | LineError]:
        events: list[ReceivedMessage | LineError] = []
        start = 0
        while start < len(data):
            newline = data.find(b"\n", start)
            end = len(data) if newline < 0 else newline
            if self._discarding:
                if newline >= 0:
                    self._discarding = False
            elif len(self._buffer) + (end - start) > self.max_line_length:
                events.append(
                    LineTooLongError(
                        f"line longer than {self.max_line_length} bytes discarded",
                        bytes(self._buffer[:80]) or data[start : start + 80],
                    )
                )
                self._buffer.clear()
                self._discarding = newline < 0
            elif newline < 0:
                self._buffer += data[start:end]
            else:
                if self._buffer:
                    self._buffer += data[start:end]
                    line = bytes(self._buffer)
                    self._buffer.clear()
                else:
                    line = data[start:end]
                event = self.decode_line(line)
                if event is not None:
                    events.append(event)
            if newline < 0:
                break
            start = newline + 1
        return events

    def decode_line(self, line: bytes) -> ReceivedMessage | LineError | None:
        """Decode one line without its ``\\n``; None for a blank line."""
        if not line.strip(b"\r"):
            return None
        try:
            parts = split_line(line)
        except LineError as exc:
            return exc
        known = self._accepted.get(parts.name)
        if known is None:
            return UnknownNameError(parts.name, line)
        name, cls = known
        message, error = parse_payload(cls, parts.payload)
        return ReceivedMessage(name, message, parts.preamble, error)
