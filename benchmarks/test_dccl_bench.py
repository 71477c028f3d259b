"""DCCL throughput (run with `make bench`; ops/s is encodes or decodes per second).

NavigationReport: issue target >= 100k encodes/s and >= 80k decodes/s on one core, and at least
3x C++ DCCL 4.2 on the same machine; an encrypted encode+decode round trip; a large v4 message
(benchmarks/protos/survey.proto, ~210 bytes with repeated fields)."""

from __future__ import annotations

from pathlib import Path

import pytest

from pygoby.dccl import Codec


@pytest.fixture(scope="module")
def navreport(vectors_dir):
    codec = Codec()
    cls = codec.load_proto(vectors_dir / "dccl" / "bench" / "navreport.proto", "NavigationReport")
    msg = cls(x=1234.5, y=-678.9, z=-42, veh_class=cls.AUV, battery_ok=True)
    return codec, msg


def test_encode_navreport(benchmark, navreport) -> None:
    codec, msg = navreport
    data = benchmark(codec.encode, msg)
    assert codec.decode(data) == msg


def test_decode_navreport(benchmark, navreport) -> None:
    codec, msg = navreport
    data = codec.encode(msg)
    assert benchmark(codec.decode, data) == msg


def test_encrypted_roundtrip_navreport(benchmark, navreport, vectors_dir) -> None:
    """Encode + decode with AES-256-CTR body encryption (the cipher is set up once per key)."""
    _, msg = navreport
    codec = Codec(passphrase="bench secret")
    codec.load(type(msg))
    assert benchmark(lambda: codec.decode(codec.encode(msg))) == msg


@pytest.fixture(scope="module")
def survey():
    """A large v4 message: 30 embedded samples, 20 counts, 16 flags (about 210 bytes)."""
    codec = Codec()
    proto = Path(__file__).parent / "protos" / "survey.proto"
    cls = codec.load_proto(proto, "bench.Survey")
    msg = cls(vehicle=7, mode=cls.SURVEY, note="leg 3 done")
    for i in range(30):
        msg.samples.add(depth=10.5 + i, temperature=12.25 - 0.1 * i, salinity=35.1, quality=i % 4)
    msg.counts.extend(i * 37 - 300 for i in range(20))
    msg.flags.extend(bool(i % 3) for i in range(16))
    return codec, msg


def test_encode_large_survey(benchmark, survey) -> None:
    codec, msg = survey
    data = benchmark(codec.encode, msg)
    assert len(data) > 200
    assert codec.decode(data).samples[29].depth == 39.5


def test_decode_large_survey(benchmark, survey) -> None:
    codec, msg = survey
    data = codec.encode(msg)
    decoded = benchmark(codec.decode, data)
    assert decoded.counts == msg.counts and len(decoded.samples) == 30
