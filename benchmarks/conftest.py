import sys
from pathlib import Path

# Benchmarks reuse the test helpers (vector paths, fixtures).
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from tests.conftest import vectors_dir  # noqa: E402,F401
