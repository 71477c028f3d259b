"""Shared test fixtures: where the reference vectors (tests/data/vectors) live; the hypothesis
profile (tests/hypothesis_profiles.py)."""

from __future__ import annotations

from pathlib import Path

import pytest

from pygoby.protobuf import generate
from tests import hypothesis_profiles

# the _pb2 modules of our .proto files, for a run of pytest in a fresh clone (pip install and
# `make` make them too; a no-op when they are newer than every .proto)
generate.main([])
hypothesis_profiles.load()

REPO = Path(__file__).resolve().parents[1]
# byte-exact recordings of the reference implementations (C++ DCCL, MOOS, netsim, Goby 1.1
# libdccl), each folder with a README.md saying how it was made
VECTORS = REPO / "tests" / "data" / "vectors"


@pytest.fixture(scope="session")
def vectors_dir() -> Path:
    return VECTORS


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item, call):
    """Captured output as UTF-8 can carry it: a decoder fuzzed with bytes logs what it refused,
    undecodable bytes included (surrogate escapes), and pytest-xdist's workers send each
    report to the controller as UTF-8."""
    report = yield
    report.sections = [
        (name, text.encode("utf-8", "backslashreplace").decode("utf-8"))
        for name, text in report.sections
    ]
    return report


def pytest_collection_modifyitems(config, items):
    """The end-to-end tests (marked e2e: missions, processes, real-time waits) run first, so that
    with `pytest -n 2` the long ones overlap the thousands of quick tests on the other worker
    instead of being left to run alone at the end (a stable sort: order within each kind stays)."""
    items.sort(key=lambda item: item.get_closest_marker("e2e") is None)
