"""The optional parts of pygoby (pyproject's extras) and the error when one is missing.

The core (DCCL, goby-acomms, MOOS and the apps over them) needs only the packages pyproject.toml
lists as dependencies. Other features need an extra: `sim` (the netsim simulator, its reports
and sweeps), `topside` (iCommander's terminal interface, liaison, `show_gui`), `lua` (DCCL
dynamic_conditions), `cluster` (sweeps on Dask), `bellhop` (the BELLHOP propagation model).
Their imports sit in `with needs_extra(...)`, so a missing package says which extra brings it.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

from pygoby.util.errors import MissingExtraError


def missing_extra_text(error: ImportError, extra: str, feature: str) -> str:
    return f"{feature} needs an optional package ({error}): pip install 'pygoby[{extra}]'"


@contextmanager
def needs_extra(extra: str, feature: str) -> Iterator[None]:
    """Imports in this block belong to `feature`, installed by the pip extra `extra`."""
    try:
        yield
    except ImportError as exc:
        raise MissingExtraError(missing_extra_text(exc, extra, feature)) from exc
