"""Shared test fixtures: where the reference vectors (tests/data/vectors) live."""

from __future__ import annotations

from pathlib import Path

import pytest

from pygoby.protobuf import generate

# the _pb2 modules of our .proto files, for a run of pytest in a fresh clone (pip install and
# `make` make them too; a no-op when they are newer than every .proto)
generate.main([])

REPO = Path(__file__).resolve().parents[1]
# byte-exact recordings of the reference implementations (C++ DCCL, MOOS, netsim, Goby 1.1
# libdccl), each folder with a README.md saying how it was made
VECTORS = REPO / "tests" / "data" / "vectors"


@pytest.fixture(scope="session")
def vectors_dir() -> Path:
    return VECTORS
