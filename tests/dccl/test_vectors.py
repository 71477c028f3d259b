"""Every reference vector in tests/data/vectors/dccl/, in both directions."""

from __future__ import annotations

import pytest

from pygoby.dccl import DcclError
from tests.dccl.vectors import VectorCodecs, message_class, parse_text, read_jsonl

ENCODE_VECTORS = read_jsonl("vectors.jsonl")
DECODE_VECTORS = read_jsonl("decode_vectors.jsonl")
CODECS = VectorCodecs()


def _ids(records: list[dict]) -> list[str]:
    return [f"{i}-{r['message']}" for i, r in enumerate(records)]


def _codec(record: dict, strict: bool = False):
    codec = CODECS.get(record["proto"], record["passphrase"])
    codec.strict = strict
    if record.get("decode_now") is not None:
        CODECS.clock.time = float(record["decode_now"])
    return codec


def test_vectors_present() -> None:
    assert len(ENCODE_VECTORS) == 1874
    assert len(DECODE_VECTORS) == 35


@pytest.mark.parametrize("record", ENCODE_VECTORS, ids=_ids(ENCODE_VECTORS))
def test_encode_vector(record: dict) -> None:
    cls = message_class(record["proto"], record["message"])
    msg = parse_text(cls, record["text"])
    codec = _codec(record, strict=record["strict"])
    if record["error"] is not None:
        with pytest.raises(DcclError):
            codec.encode(msg)
        return
    assert codec.encode(msg).hex() == record["hex"]


@pytest.mark.parametrize(
    "record",
    [r for r in ENCODE_VECTORS if r["hex"] is not None],
    ids=_ids([r for r in ENCODE_VECTORS if r["hex"] is not None]),
)
def test_decode_vector(record: dict) -> None:
    cls = message_class(record["proto"], record["message"])
    codec = _codec(record)
    codec.load(cls)
    decoded = codec.decode(bytes.fromhex(record["hex"]), cls)
    assert decoded == parse_text(cls, record["decoded"])
    if record["reencodes"]:
        assert codec.encode(decoded).hex() == record["hex"]


@pytest.mark.parametrize("record", DECODE_VECTORS, ids=_ids(DECODE_VECTORS))
def test_decode_only_vector(record: dict) -> None:
    cls = message_class(record["proto"], record["message"])
    codec = _codec(record)
    codec.load(cls)
    data = bytes.fromhex(record["hex"])
    if record["error"] is not None:
        with pytest.raises(DcclError):
            codec.decode(data, cls)
        return
    assert codec.decode(data, cls) == parse_text(cls, record["decoded"])
