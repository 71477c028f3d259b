"""DCCL throughput on the NavigationReport message (issue target: >= 100k encodes/s and
>= 80k decodes/s on one core). Run with `make bench`; ops/s is encodes or decodes per second."""

from __future__ import annotations

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
    _, msg = navreport
    codec = Codec(passphrase="bench secret")
    codec.load(type(msg))
    assert benchmark(lambda: codec.decode(codec.encode(msg))) == msg
