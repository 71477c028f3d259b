"""Helm state from IVPHELM_STATE posts (spec goby-moos-apps.md 5.4, Quirk Q24)."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.helm import helm_state_from_ivphelm
from tests.hypothesis_profiles import examples

NOT_RUNNING, DRIVE, PARK = (
    frontseat_pb.HELM_NOT_RUNNING,
    frontseat_pb.HELM_DRIVE,
    frontseat_pb.HELM_PARK,
)
ALL = (NOT_RUNNING, DRIVE, PARK)


@pytest.mark.parametrize(
    ("source", "value", "expect"),
    [
        ("pHelmIvP", "DRIVE", DRIVE),
        ("pHelmIvP", "PARK", PARK),
        ("pHelmIvP", "drive", DRIVE),
        ("PHELMIVP", "Park", PARK),
        ("  pHelmIvP\t", "  DRIVE \r\n", DRIVE),
        ("pHelmIvP_standby", "DRIVE+", DRIVE),
        ("pHelmIvP_standby", "PARK+", PARK),
        ("phelmivp_STANDBY ", " park+", PARK),
        ("\vpHelmIvP\f", "drive", DRIVE),
    ],
)
@pytest.mark.parametrize("current", ALL)
def test_helm_posts_set_the_state(source, value, expect, current) -> None:
    assert helm_state_from_ivphelm(value, source, current) == expect


@pytest.mark.parametrize(
    ("source", "value"),
    [
        ("pHelmIvP", "DISABLED"),
        ("pHelmIvP", "STANDBY"),
        ("pHelmIvP", "MALCONFIG"),
        ("pHelmIvP", "DRIVE+"),  # the standby helm's word from the main helm
        ("pHelmIvP", ""),
        ("pHelmIvP", "DRIVE PARK"),
        ("pHelmIvP_standby", "DRIVE"),  # the main helm's word from the standby helm
        ("pHelmIvP_standby", "PARK"),
        ("pHelmIvP_standby", "STANDBY"),
    ],
)
@pytest.mark.parametrize("current", ALL)
def test_other_helm_values_leave_the_state_unchanged(source, value, current) -> None:
    assert helm_state_from_ivphelm(value, source, current) == current


@pytest.mark.parametrize(
    "source",
    [
        "uMS",
        "",
        "pHelmIvP2",
        "pHelm",
        "iFrontSeat",
        "pHelmIvP_standby_2",
        "p HelmIvP",
        "pHelmIvP\xa0",  # no-break space is not trimmed (C isspace)
    ],
)
@pytest.mark.parametrize("value", ["DRIVE", "PARK", "DRIVE+", "anything"])
def test_any_other_source_means_not_running(source, value) -> None:
    assert helm_state_from_ivphelm(value, source, DRIVE) == NOT_RUNNING


def test_no_timeout_drive_persists_without_posts() -> None:
    """Q24 reproduced: the state is only ever changed by a post, so silence keeps DRIVE."""
    state = helm_state_from_ivphelm("DRIVE", "pHelmIvP", NOT_RUNNING)
    for _ in range(3):
        state = helm_state_from_ivphelm("DISABLED", "pHelmIvP", state)
    assert state == DRIVE


@settings(max_examples=examples(200), deadline=None)
@given(value=st.text(), source=st.text(), current=st.sampled_from(ALL))
def test_random_posts_never_raise_and_give_a_helm_state(value, source, current) -> None:
    state = helm_state_from_ivphelm(value, source, current)
    assert state in ALL
    if source.strip(" \t\n\v\f\r").lower() not in ("phelmivp", "phelmivp_standby"):
        assert state == NOT_RUNNING
