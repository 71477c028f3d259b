"""The IvP Helm's state, read from its IVPHELM_STATE posts.

Only the posting process tells whether a helm is running: pHelmIvP posts DRIVE/PARK, a standby
helm (pHelmIvP_standby) posts DRIVE+/PARK+, and a post from any other process means the helm
is not running. No staleness here: a helm that dies after posting DRIVE stays DRIVE (goby3's
documented design, the default: QUIRKS.md Q-APPS-24); InterfaceBase's pygoby option
`helm_state_timeout` adds a timeout for helms that re-post their state.
"""

from __future__ import annotations

from pygoby.frontseat.messages import HELM_DRIVE, HELM_NOT_RUNNING, HELM_PARK, HelmState

# Trimmed as C's isspace() does (boost::trim in the "C" locale), not Unicode whitespace.
_WHITESPACE = " \t\n\v\f\r"

_STATES_BY_SOURCE = {
    "phelmivp": {"drive": HELM_DRIVE, "park": HELM_PARK},
    "phelmivp_standby": {"drive+": HELM_DRIVE, "park+": HELM_PARK},
}


def helm_state_from_ivphelm(
    value: str, source: str, current: HelmState.ValueType
) -> HelmState.ValueType:
    """The helm state after an IVPHELM_STATE post of `value` by process `source`.

    Both are compared trimmed and case-insensitively. A helm process posting anything else
    (e.g. DISABLED, STANDBY) leaves `current` unchanged.
    """
    states = _STATES_BY_SOURCE.get(source.strip(_WHITESPACE).lower())
    if states is None:
        return HELM_NOT_RUNNING
    return states.get(value.strip(_WHITESPACE).lower(), current)
