"""C++ DCCL 4.2's answers recorded by tests/dccl/oracle/record.py (files in tests/dccl/data/).

Records name their .proto by `where` ("shared": tests/data/vectors/dccl, "tests":
tests/dccl/protos, "builtin": pygoby's own .proto files) and carry the receiver clock (`now`),
passphrase and, for encodings, strict mode. A decoded message is compared with the C++ one
parsed from protobuf's binary form (`decoded_bin`), which keeps string bytes exactly.
"""

from __future__ import annotations

import functools
import json
from pathlib import Path

from google.protobuf import text_format
from google.protobuf.message import Message

from pygoby.dccl import Codec
from pygoby.dccl.arithmetic import load_model_file
from pygoby.dccl.libraries import builtin_library
from pygoby.protobuf import BUILTIN_PROTO_DIR, ProtoLoader
from pygoby.util.clock import VirtualClock
from tests.conftest import VECTORS

DATA = Path(__file__).parent / "data"
TEST_PROTOS = Path(__file__).parent / "protos"
MODELS = TEST_PROTOS / "arith_models"
PROTO_DIRS = {"shared": VECTORS / "dccl", "tests": TEST_PROTOS, "builtin": BUILTIN_PROTO_DIR}


def read_records(name: str) -> list[dict]:
    path = DATA / name
    return [json.loads(line) for line in path.read_text().splitlines() if line.strip()]


@functools.cache
def loader() -> ProtoLoader:
    return ProtoLoader([VECTORS / "dccl", TEST_PROTOS])


def message_class(where: str, proto: str, name: str) -> type[Message]:
    loader().load_file(PROTO_DIRS[where] / proto if where != "builtin" else proto)
    return loader().message_class(name)


# the C++ libraries the recorder loaded into its codec for each .proto file
LIBRARIES = {
    "arith.proto": ["libdccl_arithmetic.so"],
    "hash.proto": ["libdccl_arithmetic.so"],
    "native.proto": ["libdccl_native_protobuf.so"],
    "cclmix.proto": ["libdccl_ccl_compat.so"],
    "dccl/ccl/protobuf/ccl.proto": ["libdccl_ccl_compat.so"],
}


def models_for(proto: str) -> list[Path]:
    return sorted(MODELS.glob("*.txt")) if proto in ("arith.proto", "hash.proto") else []


def new_codec(record: dict, clock: VirtualClock) -> Codec:
    """A Codec set up as the recorder set up C++ DCCL for this record's .proto file."""
    codec = Codec(passphrase=record.get("passphrase"), clock=clock, loader=loader())
    for library in LIBRARIES.get(record["proto"], []):
        builtin_library(library).apply(codec)
    for path in models_for(record["proto"]):
        codec.set_arithmetic_model(load_model_file(path))
    return codec


class RecordCodecs:
    """One Codec per (.proto, passphrase), as the recorder used one C++ codec per file."""

    def __init__(self) -> None:
        self.clock = VirtualClock(0)
        self._codecs: dict[tuple[str, str, str | None], Codec] = {}

    def drop(self, record: dict) -> None:
        """Forget this record's Codec (the recorder restarted C++ after a hang: fresh state)."""
        self._codecs.pop((record["where"], record["proto"], record.get("passphrase")), None)

    def get(self, record: dict, strict: bool = False) -> Codec:
        key = (record["where"], record["proto"], record.get("passphrase"))
        codec = self._codecs.get(key)
        if codec is None:
            codec = self._codecs[key] = new_codec(record, self.clock)
        codec.strict = strict
        self.clock._now = float(record.get("now") or 0)
        return codec


def parse_text(cls: type[Message], text: str) -> Message:
    msg = cls()
    text_format.Parse(text, msg)
    return msg


def decoded_message(cls: type[Message], record: dict) -> Message:
    """The message C++ DCCL decoded (from its protobuf serialization)."""
    msg = cls()
    msg.MergeFromString(bytes.fromhex(record["decoded_bin"]))
    return msg
