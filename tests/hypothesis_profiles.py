"""How hard the property tests search: a light profile for the edit loop and `make test`, the
full depth under `HYPOTHESIS_PROFILE=ci` (`make soak`).

A test that needs more examples than others asks for `examples(n)`: n under the ci profile, the
same share of it under the light one.
"""

from __future__ import annotations

import os

from hypothesis import settings

FULL_DEPTH = 100  # examples per property test under the ci profile (hypothesis' own default)
LIGHT_DEPTH = 20

# no deadline: a shared CI machine stalls now and then, and a test is about results, not speed
settings.register_profile("ci", max_examples=FULL_DEPTH, deadline=None)
settings.register_profile("light", max_examples=LIGHT_DEPTH, deadline=None)


def load() -> None:
    """The profile HYPOTHESIS_PROFILE names (default: light)."""
    settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "light"))


def examples(full: int) -> int:
    """The examples a test that asks for `full` at the full depth runs under the loaded profile."""
    return max(1, full * settings.default.max_examples // FULL_DEPTH)
