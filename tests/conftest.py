"""Shared test fixtures: where ../shared (specs and reference vectors) lives."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from pygoby.protobuf import generate

# the _pb2 modules of our .proto files, for a run of pytest in a fresh clone (pip install and
# `make` make them too; a no-op when they are newer than every .proto)
generate.main([])

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("PYGOBY_SHARED", REPO.parent / "shared"))
VECTORS = SHARED / "vectors"


@pytest.fixture(scope="session")
def vectors_dir() -> Path:
    if not VECTORS.is_dir():
        pytest.fail(f"reference vectors not found at {VECTORS} (set PYGOBY_SHARED)")
    return VECTORS
