"""Differential decode corpus: random and mutated bytes (bit flips, truncation, extension,
saturated bit runs and count prefixes, valid encodings) for every type of every test .proto,
with C++ DCCL 4.2's answer (a message or an error), recorded by tests/dccl/oracle/record.py.

pygoby must give the same answer for every input, except in the documented cases where C++
4.2 fails to decode what pygoby decodes (a singular arithmetic field without a value; dynamic
min/max conditions that C++ evaluates on the empty message at the start of decoding) and where
C++ returns undefined memory (a dccl.native_protobuf varint longer than protobuf's 10 bytes:
pygoby raises). A string whose bytes are not UTF-8 decodes to exactly the bytes C++ keeps (see
pygoby.dccl.rawtext).
Inputs of one .proto are replayed in order on one Codec (adaptive models carry state).
"""

from __future__ import annotations

import itertools

import pytest

from pygoby.dccl import DcclError
from tests.dccl.recorded import RecordCodecs, decoded_message, message_class, read_records
from tests.dccl.test_recorded_vectors import _documented_decode

CORPUS = read_records("decode_corpus.jsonl")
GROUPS = {
    key: list(group)
    for key, group in itertools.groupby(CORPUS, lambda r: (r["where"], r["proto"], r["passphrase"]))
}


def test_corpus_covers_every_case() -> None:
    assert len(CORPUS) > 5000
    origins = {r["origin"] for r in CORPUS}
    assert origins == {"valid", "flip", "truncate", "saturate", "extend", "count", "random"}
    errors = [r["error"] for r in CORPUS if r["result"] == "error"]
    assert sum("traverse mutable" in e for e in errors) >= 10  # message count > max_repeat
    # strings that are not UTF-8, as C++ decodes them
    assert (
        sum(
            r["message"].startswith("agree.Text") and "\\3" in (r.get("decoded") or "")
            for r in CORPUS
        )
        >= 10
    )


@pytest.mark.parametrize("key", list(GROUPS), ids=[f"{k[1]}-{k[2]}" for k in GROUPS])
def test_decode_agrees_with_cpp(key: tuple) -> None:
    codecs = RecordCodecs()
    disagreements, documented = [], 0
    for record in GROUPS[key]:
        cls = message_class(record["where"], record["proto"], record["message"])
        codec = codecs.get(record)
        codec.load(cls)
        data = bytes.fromhex(record["hex"])
        try:
            decoded = codec.decode(data, cls)
        except DcclError as exc:
            if "protobuf allows 10" in str(exc):
                documented += 1  # C++ reads uninitialized memory (a different value each run)
            elif record["result"] != "error":
                disagreements.append(f"{record['message']} {record['hex']}: pygoby {exc}")
            continue
        if record["result"] == "error":
            if _documented_decode(cls, decoded, record["error"]):
                documented += 1
            else:
                disagreements.append(
                    f"{record['message']} {record['hex']}: C++ {record['error'][:80]}"
                )
        elif decoded != decoded_message(cls, record):
            disagreements.append(
                f"{record['message']} {record['hex']}: {decoded} != {record['decoded']}"
            )
    assert not disagreements, "\n".join(disagreements[:10])
    if not key[1].startswith(("arith", "dyncond", "native")):
        assert documented == 0
