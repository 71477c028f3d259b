"""Benchmarks use the tests' fixtures (reference vectors)."""

from tests.conftest import vectors_dir  # noqa: F401 - a fixture, found by pytest by its name
