"""Access to the reference DCCL vectors in tests/data/vectors/dccl/."""

from __future__ import annotations

import functools
import json

from google.protobuf import text_format
from google.protobuf.message import Message

from pygoby.dccl import Codec
from pygoby.protobuf import ProtoLoader
from tests.conftest import VECTORS

DCCL_VECTORS = VECTORS / "dccl"


def read_jsonl(name: str) -> list[dict]:
    path = DCCL_VECTORS / name
    if not path.is_file():
        return []
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


@functools.cache
def loader() -> ProtoLoader:
    return ProtoLoader([DCCL_VECTORS])


def message_class(proto: str, name: str) -> type[Message]:
    loader().load_file(proto)
    return loader().message_class(name)


class VectorClock:
    """The Clock of the vector codecs: each vector sets the time its decoding ran at, which may
    be earlier than the previous vector's (a VirtualClock only goes forwards)."""

    def __init__(self) -> None:
        self.time = 0.0

    def now(self) -> float:
        return self.time


class VectorCodecs:
    """One Codec per (proto file, passphrase), so IDs reused across files never clash."""

    def __init__(self, trace: bool = False) -> None:
        self.clock = VectorClock()
        self.trace = trace
        self._codecs: dict[tuple[str, str | None], Codec] = {}

    def get(self, proto: str, passphrase: str | None) -> Codec:
        key = (proto, passphrase)
        if key not in self._codecs:
            self._codecs[key] = Codec(passphrase=passphrase, clock=self.clock, trace=self.trace)
        return self._codecs[key]


def parse_text(cls: type[Message], text: str | None) -> Message:
    msg = cls()
    if text:
        text_format.Parse(text, msg)  # does not check required fields
    return msg
