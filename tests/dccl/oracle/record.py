"""Record C++ DCCL's answers as test data (tests/dccl/data/*.jsonl).

    python tests/dccl/oracle/record.py HARNESS --lib-dir DIR [--suite NAME ...]

HARNESS is a small program linked against a C++ DCCL 4.2 build (built outside this repository;
nothing here builds it) that speaks the line protocol below on stdin/stdout; DIR holds that
build's codec libraries (libdccl_arithmetic.so, libdccl_ccl_compat.so,
libdccl_native_protobuf.so). The tests only read the recorded files: CI never runs C++.

Protocol (one request per line, one answer per line; free text travels hex-encoded):

    reset | include DIR | library PATH | proto PATH | load NAME -> "ok [HASH]" | "error HEX"
    model HEX (an ArithmeticModel in TextFormat) | passphrase HEX | strict 0|1
    now SECONDS | now -                      (the harness's CLOCK_REALTIME)
    encode NAME HEXTEXT -> "hex HEX" | "error HEX"
    decode NAME HEXBYTES -> "text HEXTEXT HEXSERIALIZED" | "error HEX"

Suites: corpus (differential decode corpus of random and mutated bytes for every test .proto),
arith, native, ccl, dyn, hash (encode/decode vectors per codec), adaptive (arithmetic sessions),
hashes (the definition hash C++ computes for every test type), cross (C++ decoding pygoby's
bytes where pygoby writes other bytes on purpose; run after arith).
"""

from __future__ import annotations

import argparse
import json
import math
import random
import select
import subprocess
import sys
from pathlib import Path

from google.protobuf import text_format
from google.protobuf.descriptor import Descriptor, FieldDescriptor
from google.protobuf.message import Message

REPO = Path(__file__).resolve().parents[3]
sys.path[:0] = [str(REPO / "src"), str(REPO)]

from pygoby.dccl.options import field_extension, field_options, message_options  # noqa: E402
from pygoby.protobuf import ProtoLoader  # noqa: E402
from pygoby.protobuf.dccl.arithmetic.protobuf.arithmetic_extensions_pb2 import ArithmeticOptions  # noqa: E402
from pygoby.protobuf.dccl.ccl.protobuf.ccl_extensions_pb2 import LegacyCCLFieldOptions  # noqa: E402
from tests.dccl.recorded import (  # noqa: E402
    LIBRARIES,
    MODELS,
    PROTO_DIRS,
    TEST_PROTOS,
    models_for,
)

SHARED = PROTO_DIRS["shared"]
OUT = REPO / "tests" / "dccl" / "data"
NOW = 1_700_000_000
ANSWERS = ("ok", "error", "hex", "text", "size", "pong")

# a record's "proto" is found in PROTO_DIRS[record["where"]]: "shared" (tests/data/vectors/dccl),
# "tests" (tests/dccl/protos), "builtin" (pygoby's own .proto files)
CORPUS_PROTOS = [
    ("shared", "example.proto"),
    ("shared", "edge.proto"),
    ("shared", "inhead.proto"),
    ("shared", "versions.proto"),
    ("shared", "features.proto"),
    ("shared", "bench/navreport.proto"),
    ("tests", "agree.proto"),
    ("tests", "arith.proto"),
    ("tests", "native.proto"),
    ("tests", "dyncond.proto"),
    ("tests", "hash.proto"),
    ("tests", "cclmix.proto"),
    ("builtin", "dccl/ccl/protobuf/ccl.proto"),
]


def hexs(text: str | bytes) -> str:
    return (text.encode() if isinstance(text, str) else text).hex()


class HarnessDied(Exception):
    pass


class Oracle:
    """The C++ harness as a process; restarted (and set up again) after a crash or a hang."""

    def __init__(self, harness: str, lib_dir: Path) -> None:
        self.harness = harness
        self.lib_dir = lib_dir
        self.setup: list[str] = []
        self.proc: subprocess.Popen | None = None
        self._start()

    def _start(self) -> None:
        self.proc = subprocess.Popen(
            [self.harness],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            stderr=subprocess.DEVNULL,
            text=True,
            bufsize=1,
        )
        for line in self.setup:
            self._raw(line, 20)

    def _kill(self) -> None:
        assert self.proc is not None
        self.proc.kill()
        self.proc.wait()

    def _raw(self, line: str, timeout: float) -> list[str]:
        assert self.proc is not None and self.proc.stdin and self.proc.stdout
        try:
            self.proc.stdin.write(line + "\n")
            self.proc.stdin.flush()
        except BrokenPipeError:
            raise HarnessDied("crash") from None
        while True:
            ready, _, _ = select.select([self.proc.stdout], [], [], timeout)
            if not ready:
                raise HarnessDied("hang")
            answer = self.proc.stdout.readline()
            if not answer:
                raise HarnessDied("crash")
            parts = answer.split()
            if parts and parts[0] in ANSWERS:
                return parts

    def ask(self, line: str, timeout: float = 2.0) -> list[str]:
        """The answer's words; ["crash"] or ["hang"] when the harness died on this request."""
        try:
            return self._raw(line, timeout)
        except HarnessDied as died:
            self._kill()
            self._start()
            return [str(died)]

    def configure(self, line: str) -> list[str]:
        """A request that changes the harness state: replayed after a restart."""
        answer = self.ask(line, 20)
        self.setup.append(line)
        return answer

    def reset(self) -> None:
        self.setup = []
        self.ask("reset")

    def open_codec(
        self, where: str, proto: str, passphrase: str | None = None, models: list[Path] = ()
    ) -> list[str]:
        """A fresh codec with this proto's libraries, models and messages loaded; the names of
        the loaded messages."""
        self.reset()
        for lib in LIBRARIES.get(proto, []):
            self.configure(f"library {self.lib_dir / lib}")
        for path in models:
            self.configure(f"model {hexs(path.read_text())}")
        self.configure(f"include {PROTO_DIRS[where]}")
        if where != "builtin":
            answer = self.configure(f"proto {PROTO_DIRS[where] / proto}")
            if answer[0] != "ok":
                raise RuntimeError(f"{proto}: {bytes.fromhex(answer[1]).decode()}")
        self.configure(f"now {NOW}")
        if passphrase is not None:  # (any passphrase, even "", turns C++ encryption on)
            self.configure(f"passphrase {hexs(passphrase)}")
        loaded = []
        for name in message_names(where, proto):
            if self.configure(f"load {name}")[0] == "ok":
                loaded.append(name)
        return loaded

    def encode(self, name: str, text: str) -> tuple[str | None, str | None, str]:
        """(hex, error, status) where status is ok/error/crash/hang."""
        answer = self.ask(f"encode {name} {hexs(text)}")
        if answer[0] == "hex":
            return (answer[1] if len(answer) > 1 else ""), None, "ok"
        if answer[0] == "error":
            return None, bytes.fromhex(answer[1]).decode(errors="replace"), "error"
        return None, answer[0], answer[0]

    def decode(self, name: str, data: bytes) -> dict:
        answer = self.ask(f"decode {name} {data.hex()}")
        if answer[0] == "text":
            text = (
                bytes.fromhex(answer[1]).decode(errors="backslashreplace")
                if len(answer) > 1
                else ""
            )
            serialized = answer[2] if len(answer) > 2 else ""
            return {"result": "ok", "decoded": text.strip(), "decoded_bin": serialized}
        if answer[0] == "error":
            return {"result": "error", "error": bytes.fromhex(answer[1]).decode(errors="replace")}
        return {"result": answer[0]}


# ------------------------------------------------------------------ message definitions
_LOADER = ProtoLoader([SHARED, TEST_PROTOS])


def file_descriptor(where: str, proto: str):
    path = PROTO_DIRS[where] / proto
    return _LOADER.load_file(path if where != "builtin" else proto)


def message_names(where: str, proto: str) -> list[str]:
    """Root message types (those with DCCL message options) in declaration order."""
    fd = file_descriptor(where, proto)
    names = []
    for desc in fd.message_types_by_name.values():
        opts = message_options(desc)
        if opts.HasField("codec_version"):
            names.append(desc.full_name)
    return names


def descriptor(name: str) -> Descriptor:
    return _LOADER.find_descriptor(name)


def message_class(name: str) -> type[Message]:
    return _LOADER.message_class(name)


# ------------------------------------------------------------------ random values
INT_LIMITS = {
    FieldDescriptor.CPPTYPE_INT32: (-(2**31), 2**31 - 1),
    FieldDescriptor.CPPTYPE_INT64: (-(2**63), 2**63 - 1),
    FieldDescriptor.CPPTYPE_UINT32: (0, 2**32 - 1),
    FieldDescriptor.CPPTYPE_UINT64: (0, 2**64 - 1),
}
ASCII = "abcdefghijklmnopqrstuvwxyz ABCXYZ0123456789-_.:"
UNICODE = "éü°Ωж中€"


class Values:
    """Random field values near what the field's options allow (bounds, midpoints, out of range)."""

    def __init__(
        self,
        rng: random.Random,
        wild: float = 0.15,
        models: dict | None = None,
        avoid_top: bool = False,
    ) -> None:
        self.rng = rng
        self.wild = wild  # probability of a value outside the field's limits
        self.models = models or {}
        # no arithmetic value nearest to a model's top bound (C++ DCCL loops forever on them)
        self.avoid_top = avoid_top

    def numeric(self, f: FieldDescriptor, opts) -> float | int:
        rng = self.rng
        codec = opts.codec
        integer = f.cpp_type in INT_LIMITS
        if codec == "dccl.arithmetic":
            return self.arithmetic(f, integer)
        if codec in ("dccl.native_protobuf",) or (codec == "" and not opts.HasField("min")):
            return self.native(f)
        if codec in ("dccl.time", "_time"):
            seconds = (
                NOW + rng.randint(-3 * 86400, 3 * 86400) + rng.choice([0, 0.25, 0.5, 0.123456])
            )
            return int(seconds * 1_000_000) if integer else seconds
        lo, hi = opts.min, opts.max
        res = opts.resolution if opts.HasField("resolution") else math.pow(10.0, -opts.precision)
        pick = rng.random()
        if pick < 0.15:
            v = rng.choice([lo, hi])
        elif pick < 0.3:
            steps = rng.randint(0, max(0, int(min((hi - lo) / res, 1e12))))
            v = lo + (steps + 0.5) * res  # a rounding midpoint
        elif pick < 0.3 + self.wild:
            span = max(hi - lo, 1.0)
            v = rng.choice([lo - res, hi + res, lo - span * rng.random(), hi + span * rng.random()])
        else:
            v = rng.uniform(lo, hi)
        if integer:
            lim = INT_LIMITS[f.cpp_type]
            return max(lim[0], min(lim[1], math.floor(v + 0.5)))
        return v

    def native(self, f: FieldDescriptor):
        rng = self.rng
        if f.cpp_type in INT_LIMITS:
            lo, hi = INT_LIMITS[f.cpp_type]
            return rng.choice(
                [
                    0,
                    1,
                    -1 if lo < 0 else 2,
                    lo,
                    hi,
                    rng.randint(lo, hi),
                    rng.randint(-300, 300) if lo < 0 else rng.randint(0, 300),
                ]
            )
        return rng.choice(
            [
                0.0,
                -0.0,
                1.5,
                -2.25,
                1e300,
                -1e-300,
                rng.uniform(-1e6, 1e6),
                float("inf"),
                rng.uniform(-1, 1),
            ]
        )

    def arithmetic(self, f: FieldDescriptor, integer: bool):
        model = self.models[field_options_ext(f, "arithmetic").model]
        bounds = list(model.value_bound)
        rng = self.rng
        pick = rng.random()
        if pick < 0.4:
            v = rng.choice(bounds[:-1])
        elif pick < 0.55:
            i = rng.randrange(len(bounds) - 1)
            v = (bounds[i] + bounds[i + 1]) / 2
        elif pick < 0.55 + self.wild:
            v = rng.choice([bounds[0] - 1, bounds[-1] + 1, bounds[-1], bounds[0] - 0.5])
        else:
            v = rng.uniform(bounds[0], bounds[-2] + (bounds[-1] - bounds[-2]) * 0.4)
        if f.cpp_type == FieldDescriptor.CPPTYPE_ENUM:
            numbers = [e.number for e in f.enum_type.values]
            return rng.choice(numbers)
        if f.cpp_type == FieldDescriptor.CPPTYPE_BOOL:
            return rng.random() < 0.6
        if integer:
            lo = (
                0
                if f.cpp_type in (FieldDescriptor.CPPTYPE_UINT32, FieldDescriptor.CPPTYPE_UINT64)
                else -(2**31)
            )
            v = max(lo, math.floor(v + 0.5))
        if self.avoid_top and (bounds[-2] + bounds[-1]) / 2 <= v <= bounds[-1]:
            return bounds[-2]
        return v

    def text(self, opts, unicode_ok: bool = True) -> str:
        rng = self.rng
        limit = opts.max_length if opts.HasField("max_length") else 8
        n = rng.choice([0, 1, limit, limit + rng.randint(1, 3), rng.randint(0, max(limit, 1))])
        if rng.random() < self.wild * 0.5:
            n = 0
        alphabet = ASCII + (UNICODE if unicode_ok and rng.random() < 0.3 else "")
        return "".join(rng.choice(alphabet) for _ in range(n))

    def raw(self, opts) -> bytes:
        rng = self.rng
        limit = opts.max_length if opts.HasField("max_length") else 8
        n = rng.choice([0, 1, limit, limit + 1, rng.randint(0, max(limit, 1))])
        return bytes(rng.randrange(256) for _ in range(n))

    def value(self, f: FieldDescriptor, depth: int):
        opts = field_options(f)
        rng = self.rng
        if f.cpp_type == FieldDescriptor.CPPTYPE_MESSAGE:
            return self.message(f.message_type, depth + 1)
        if f.cpp_type == FieldDescriptor.CPPTYPE_BOOL:
            return rng.random() < 0.5
        if f.cpp_type == FieldDescriptor.CPPTYPE_ENUM:
            if opts.codec == "dccl.arithmetic":
                return self.arithmetic(f, True)
            return rng.choice([v.number for v in f.enum_type.values])
        if f.type == FieldDescriptor.TYPE_STRING:
            return self.text(opts)
        if f.type == FieldDescriptor.TYPE_BYTES:
            return self.raw(opts)
        return self.numeric(f, opts)

    def message(self, desc: Descriptor, depth: int = 0) -> Message:
        rng = self.rng
        msg = message_class(desc.full_name)()
        chosen = {}
        for oneof in desc.oneofs:
            chosen[oneof.name] = rng.choice([None, *oneof.fields])
        for f in desc.fields:
            opts = field_options(f)
            if f.containing_oneof is not None:
                if chosen.get(f.containing_oneof.name) is not f:
                    continue
            elif not f.is_required and not f.is_repeated and rng.random() < 0.3:
                continue
            if f.is_required and rng.random() < self.wild * 0.05:
                continue  # a missing required field: encoding must fail
            if depth > 3 and f.cpp_type == FieldDescriptor.CPPTYPE_MESSAGE:
                continue
            try:
                if f.is_repeated:
                    limit = opts.max_repeat if opts.HasField("max_repeat") else 3
                    n = rng.choice([0, 1, limit, rng.randint(0, limit), limit + 1, opts.min_repeat])
                    for _ in range(n):
                        v = self.value(f, depth)
                        if f.cpp_type == FieldDescriptor.CPPTYPE_MESSAGE:
                            getattr(msg, f.name).add().CopyFrom(v)
                        else:
                            getattr(msg, f.name).append(v)
                else:
                    v = self.value(f, depth)
                    if f.cpp_type == FieldDescriptor.CPPTYPE_MESSAGE:
                        getattr(msg, f.name).CopyFrom(v)
                    else:
                        setattr(msg, f.name, v)
            except (ValueError, TypeError, OverflowError):
                continue  # a value the protobuf type cannot hold
        return msg


def field_options_ext(f: FieldDescriptor, name: str):
    """An extension of (dccl.field) read from the field's options (arithmetic, ccl)."""
    if name == "arithmetic":
        return field_extension(field_options(f), ArithmeticOptions, 1001)
    return field_extension(field_options(f), LegacyCCLFieldOptions, 1000)


def to_text(msg: Message) -> str:
    return text_format.MessageToString(msg, as_one_line=True)


def load_models() -> dict:
    from pygoby.protobuf import builtin_class

    cls = builtin_class(
        "dccl/arithmetic/protobuf/arithmetic.proto", "dccl.arith.protobuf.ArithmeticModel"
    )
    models = {}
    for path in sorted(MODELS.glob("*.txt")):
        model = text_format.Parse(path.read_text(), cls())
        models[model.name] = model
    return models


# ------------------------------------------------------------------ mutations
def mutations(rng: random.Random, data: bytes, id_prefix: bytes) -> list[tuple[str, bytes]]:
    out = []
    if data:
        b = bytearray(data)
        for _ in range(rng.randint(1, 3)):
            i = rng.randrange(len(b) * 8)
            b[i // 8] ^= 1 << (i % 8)
        out.append(("flip", bytes(b)))
        out.append(("truncate", data[: rng.randrange(len(data))]))
        # a window of bits set to one (count prefixes and lengths beyond their maximum)
        b = bytearray(data)
        start = rng.randrange(len(id_prefix) * 8, max(len(b) * 8, len(id_prefix) * 8 + 1))
        for i in range(start, min(start + rng.randint(2, 8), len(b) * 8)):
            b[i // 8] |= 1 << (i % 8)
        out.append(("saturate", bytes(b)))
    out.append(("extend", data + bytes(rng.randrange(256) for _ in range(rng.randint(1, 6)))))
    if len(data) > len(id_prefix):
        # the first fields after the id at their largest (count prefixes: more elements than
        # max_repeat; lengths beyond max_length)
        b = bytearray(data)
        start = len(id_prefix) * 8
        for i in range(start, min(start + rng.randint(2, 6), len(b) * 8)):
            b[i // 8] |= 1 << (i % 8)
        out.append(("count", bytes(b)))
    return out


def id_bytes(data: bytes, ccl_frame: bool) -> bytes:
    """The identifier at the start of an encoding: a CCL frame's mode byte, or the DCCL ID (1 or
    2 bytes by bit 0 of its first byte), after the byte 0x20 that marks a DCCL message in a codec
    using the CCL identifier codec."""
    if ccl_frame:
        return data[:1]
    start = 1 if data[:1] == b"\x20" else 0
    width = 2 if data[start : start + 1] and data[start] & 1 else 1
    return data[: start + width]


def random_bytes(rng: random.Random, max_bytes: int, id_prefix: bytes) -> bytes:
    n = rng.randint(0, max_bytes + 4)
    data = bytes(rng.randrange(256) for _ in range(n))
    if rng.random() < 0.75:
        data = id_prefix + data[len(id_prefix) :]
    return data


# ------------------------------------------------------------------ suites
def write(name: str, records: list[dict]) -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    path = OUT / name
    with path.open("w") as out:
        for record in records:
            out.write(json.dumps(record, sort_keys=False) + "\n")
    print(f"{path.relative_to(REPO)}: {len(records)} records", file=sys.stderr)


def corpus(oracle: Oracle, rng: random.Random, per_type: int) -> list[dict]:
    records = []
    models = load_models()
    values = Values(rng, wild=0.2, models=models)
    for where, proto in CORPUS_PROTOS:
        for passphrase in (None, "corpus key"):
            loaded = oracle.open_codec(where, proto, passphrase, models_for(proto))
            for name in loaded:
                desc = descriptor(name)
                opts = message_options(desc)
                id_prefix = b""
                if not opts.omit_id:
                    enc, _, _ = oracle.encode(name, to_text(values.message(desc)))
                    id_prefix = (
                        id_bytes(bytes.fromhex(enc), proto.endswith("ccl.proto")) if enc else b""
                    )
                inputs: list[tuple[str, bytes]] = []
                count = per_type if passphrase is None else per_type // 4
                for _ in range(count):
                    msg = values.message(desc)
                    enc, _, status = oracle.encode(name, to_text(msg))
                    if status != "ok":
                        continue
                    data = bytes.fromhex(enc)
                    inputs.append(("valid", data))
                    inputs.extend(mutations(rng, data, id_prefix))
                for _ in range(count):
                    inputs.append(("random", random_bytes(rng, opts.max_bytes, id_prefix)))
                seen = set()
                for origin, data in inputs:
                    if data in seen:
                        continue
                    seen.add(data)
                    answer = oracle.decode(name, data)
                    records.append(
                        {
                            "where": where,
                            "proto": proto,
                            "message": name,
                            "passphrase": passphrase,
                            "now": NOW,
                            "origin": origin,
                            "hex": data.hex(),
                            **answer,
                        }
                    )
    return records


def encode_vectors(
    oracle: Oracle,
    rng: random.Random,
    suite: str,
    where: str,
    proto: str,
    count: int,
    passphrases=(None, "vector key"),
    strict_share: float = 0.3,
    nows=(NOW,),
    wild: float = 0.15,
) -> list[dict]:
    models = load_models()
    values = Values(rng, wild=wild, models=models)
    records = []
    for passphrase in passphrases:
        loaded = oracle.open_codec(where, proto, passphrase, models_for(proto))
        for name in loaded:
            desc = descriptor(name)
            n = count if passphrase is None else max(count // 5, 4)
            for _ in range(n):
                now = rng.choice(nows)
                oracle.ask(f"now {now}")
                strict = rng.random() < strict_share
                oracle.ask(f"strict {int(strict)}")
                text = to_text(values.message(desc))
                enc, error, status = oracle.encode(name, text)
                record = {
                    "suite": suite,
                    "where": where,
                    "proto": proto,
                    "message": name,
                    "text": text,
                    "strict": strict,
                    "passphrase": passphrase,
                    "now": now,
                    "status": status,
                    "hex": enc,
                    "error": error,
                }
                if status == "ok":
                    record.update(oracle.decode(name, bytes.fromhex(enc)))
                records.append(record)
            oracle.ask("strict 0")
    return records


def definition_hashes(oracle: Oracle) -> list[dict]:
    """The 64-bit definition hash C++ DCCL's load() returns, for every type of every test
    .proto (what dccl.hash fields send, masked)."""
    records = []
    for where, proto in CORPUS_PROTOS:
        oracle.reset()
        for lib in LIBRARIES.get(proto, []):
            oracle.configure(f"library {oracle.lib_dir / lib}")
        for path in models_for(proto):
            oracle.configure(f"model {hexs(path.read_text())}")
        oracle.configure(f"include {PROTO_DIRS[where]}")
        if where != "builtin":
            oracle.configure(f"proto {PROTO_DIRS[where] / proto}")
        for name in message_names(where, proto):
            answer = oracle.ask(f"load {name}")
            if answer[0] == "ok":
                records.append({"where": where, "proto": proto, "message": name, "hash": answer[1]})
    return records


def adaptive_sessions(oracle: Oracle, rng: random.Random, sessions: int) -> list[dict]:
    """Adaptive models change with every symbol: each record is a sequence of operations on one
    fresh codec (encodes update the encoder's model, decodes the decoder's)."""
    models = load_models()
    values = Values(rng, wild=0.1, models=models, avoid_top=True)
    records = []
    for _ in range(sessions):
        oracle.open_codec("tests", "arith.proto", None, models_for("arith.proto"))
        steps = []
        encoded = []
        for _ in range(rng.randint(3, 12)):
            name = rng.choice(["arith.Adaptive", "arith.Adaptive", "arith.Ints"])
            if encoded and rng.random() < 0.45:
                name, data = (
                    encoded.pop(0)
                    if rng.random() < 0.8
                    else (
                        name,
                        bytes.fromhex(
                            "".join(f"{rng.randrange(256):02x}" for _ in range(rng.randint(1, 6)))
                        ),
                    )
                )
                steps.append(
                    {
                        "op": "decode",
                        "message": name,
                        "hex": data.hex(),
                        **oracle.decode(name, data),
                    }
                )
                continue
            text = to_text(values.message(descriptor(name)))
            enc, error, status = oracle.encode(name, text)
            if status in ("hang", "crash"):
                break  # the harness restarted with fresh models: the session ends here
            steps.append(
                {
                    "op": "encode",
                    "message": name,
                    "text": text,
                    "status": status,
                    "hex": enc,
                    "error": error,
                }
            )
            if status == "ok":
                encoded.append((name, bytes.fromhex(enc)))
        records.append(
            {"suite": "adaptive", "where": "tests", "proto": "arith.proto", "steps": steps}
        )
    return records


def cross(oracle: Oracle) -> list[dict]:
    """Where pygoby writes other bytes than C++ on purpose (the arithmetic cases where C++
    cannot read back its own encoding, see pygoby.dccl.arithmetic): C++'s decoder on pygoby's
    bytes, each on fresh codecs (adaptive models start afresh)."""
    from pygoby.dccl import Codec, DcclError
    from pygoby.dccl.arithmetic import load_model_file
    from pygoby.util.clock import VirtualClock

    records = []
    file_descriptor("tests", "arith.proto")
    for record in (json.loads(line) for line in (OUT / "arith_vectors.jsonl").open()):
        if record["status"] == "error":
            continue
        codec = Codec(passphrase=record["passphrase"], clock=VirtualClock(NOW), loader=_LOADER)
        for path in models_for("arith.proto"):
            codec.set_arithmetic_model(load_model_file(path))
        cls = message_class(record["message"])
        msg = text_format.Parse(record["text"], cls())
        try:
            ours = codec.encode(msg)
        except DcclError:
            continue
        if record["status"] == "ok" and ours.hex() == record["hex"]:
            continue
        oracle.open_codec("tests", "arith.proto", record["passphrase"], models_for("arith.proto"))
        records.append(
            {
                "where": "tests",
                "proto": "arith.proto",
                "message": record["message"],
                "passphrase": record["passphrase"],
                "text": record["text"],
                "cpp_status": record["status"],
                "cpp_hex": record["hex"],
                "pygoby_hex": ours.hex(),
                **oracle.decode(record["message"], ours),
            }
        )
    return records


def ccl_times() -> list[int]:
    # receiver clocks: mid-year, just before and after new year, and in a leap year
    return [NOW, 1_704_067_190, 1_704_067_210, 1_709_164_800, 1_735_689_599, 1_000_000_000]


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("harness")
    parser.add_argument("--lib-dir", type=Path, required=True)
    parser.add_argument(
        "--suite",
        action="append",
        choices=["corpus", "arith", "adaptive", "native", "ccl", "dyn", "hash", "hashes", "cross"],
    )
    parser.add_argument("--seed", type=int, default=14)
    args = parser.parse_args()
    suites = args.suite or ["corpus", "arith", "adaptive", "native", "ccl", "dyn", "hash", "hashes"]
    oracle = Oracle(args.harness, args.lib_dir.resolve())
    for suite in suites:
        rng = random.Random(f"{args.seed}-{suite}")
        if suite == "corpus":
            write("decode_corpus.jsonl", corpus(oracle, rng, per_type=12))
        elif suite == "arith":
            write(
                "arith_vectors.jsonl",
                encode_vectors(oracle, rng, suite, "tests", "arith.proto", 60),
            )
        elif suite == "adaptive":
            write("arith_adaptive.jsonl", adaptive_sessions(oracle, rng, 60))
        elif suite == "native":
            write(
                "native_vectors.jsonl",
                encode_vectors(oracle, rng, suite, "tests", "native.proto", 80),
            )
        elif suite == "ccl":
            records = encode_vectors(
                oracle,
                rng,
                suite,
                "builtin",
                "dccl/ccl/protobuf/ccl.proto",
                80,
                nows=ccl_times(),
                wild=0.25,
            )
            records += encode_vectors(oracle, rng, suite, "tests", "cclmix.proto", 40)
            write("ccl_vectors.jsonl", records)
        elif suite == "dyn":
            write(
                "dyn_vectors.jsonl",
                encode_vectors(oracle, rng, suite, "tests", "dyncond.proto", 80),
            )
        elif suite == "hash":
            write(
                "hash_vectors.jsonl", encode_vectors(oracle, rng, suite, "tests", "hash.proto", 25)
            )
        elif suite == "hashes":
            write("definition_hashes.jsonl", definition_hashes(oracle))
        elif suite == "cross":
            write("arith_cross.jsonl", cross(oracle))
    return 0


if __name__ == "__main__":
    sys.exit(main())
