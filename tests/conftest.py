"""Shared test fixtures: where ../shared (specs and reference vectors) lives; the hypothesis
profile (tests/hypothesis_profiles.py)."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from tests import hypothesis_profiles

hypothesis_profiles.load()

REPO = Path(__file__).resolve().parents[1]
SHARED = Path(os.environ.get("PYGOBY_SHARED", REPO.parent / "shared"))
VECTORS = SHARED / "vectors"


@pytest.fixture(scope="session")
def vectors_dir() -> Path:
    if not VECTORS.is_dir():
        pytest.fail(f"reference vectors not found at {VECTORS} (set PYGOBY_SHARED)")
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
