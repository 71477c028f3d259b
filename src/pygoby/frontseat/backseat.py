"""iFrontSeat's rules between the backseat and a frontseat driver, sans I/O. The app reads the
backseat's variables from MOOS and hands them over as plain values; `Backseat` applies them to the
driver (`InterfaceBase`) and returns what is to be posted:

* `may_command(var)`: a command request goes to the driver only in INTERFACE_COMMAND;
  `may_send(var)`: data and raw traffic only in INTERFACE_LISTEN or INTERFACE_COMMAND (a debug
  line names `var` and the state when not);
* `helm_state(value, source)`: an IVPHELM_STATE post (every post counts for
  helm_state_timeout);
* `set_origin(lat=..., lon=...)`: the local grid's datum, applied once both are known;
* `desired(var, value, time)`: a DESIRED_* double; the CommandRequest to post after
  DESIRED_SPEED (legacy `subscribe_desired`);
* `ctd(var, value, time)`: a CTD_* double; the InterfaceData to post after CTD_TEMPERATURE,
  its missing fields computed (legacy `subscribe_ctd`);
* `bluefin_command(var, text, number)`: a Bluefin command variable; the CommandRequest to post
  (legacy `pub_sub_bf_commands`);
* `legacy_posts(data)`: the NAV_* (MOOS variable, value) posts for the driver's data (legacy
  `publish_nav`), and TRIM_REPORT / BUOYANCY_REPORT (legacy `pub_sub_bf_commands`); its
  position also places the next CTD sample.
"""

from __future__ import annotations

import logging
import math
from typing import Any

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.helm import helm_state_from_ivphelm
from pygoby.frontseat.interface import InterfaceBase
from pygoby.frontseat.legacy import (
    BluefinCommands,
    CtdSamples,
    DesiredCourseCommands,
    Post,
    RequestIds,
    bluefin_report_posts,
    nav_posts,
)

CONTROL_STATES = frozenset({frontseat_pb.INTERFACE_LISTEN, frontseat_pb.INTERFACE_COMMAND})
HELM_STATE_VAR = "IVPHELM_STATE"

_log = logging.getLogger(__name__)


class Backseat:
    def __init__(
        self,
        interface: InterfaceBase,
        legacy_cfg: Any,
        origin: tuple[float, float] = (math.nan, math.nan),
        log: logging.Logger = _log,
    ) -> None:
        """`legacy_cfg`: iFrontSeatConfig.legacy_cfg; `origin`: the datum known at start
        (NaN where unknown)."""
        self.interface = interface
        self.origin = origin
        self.log = log
        self.publish_nav = legacy_cfg.publish_nav
        ids = RequestIds()  # one count for every command iFrontSeat makes (as goby3)
        self.desired_course = DesiredCourseCommands(ids) if legacy_cfg.subscribe_desired else None
        self.ctd_samples = CtdSamples() if legacy_cfg.subscribe_ctd else None
        self.bluefin_commands = BluefinCommands(ids) if legacy_cfg.pub_sub_bf_commands else None

    # -- backseat -> frontseat -------------------------------------------------------------

    def may_command(self, var: str) -> bool:
        state = self.interface.state
        if state == frontseat_pb.INTERFACE_COMMAND:
            return True
        self.log.debug(
            "%s not sent: the interface is in %s, not INTERFACE_COMMAND",
            var,
            frontseat_pb.InterfaceState.Name(state),
        )
        return False

    def may_send(self, var: str) -> bool:
        if self.interface.state in CONTROL_STATES:
            return True
        self.log.debug(
            "%s not sent: the interface is in %s",
            var,
            frontseat_pb.InterfaceState.Name(self.interface.state),
        )
        return False

    def helm_state(self, value: str, source: str) -> None:
        current = self.interface.helm_state
        state = helm_state_from_ivphelm(value, source, current)
        if state != current:
            self.log.info(
                "helm state %s -> %s (%s=%r from %s)",
                frontseat_pb.HelmState.Name(current),
                frontseat_pb.HelmState.Name(state),
                HELM_STATE_VAR,
                value,
                source,
            )
        self.interface.set_helm_state(state)  # every post counts for helm_state_timeout

    def set_origin(self, *, lat: float | None = None, lon: float | None = None) -> None:
        old_lat, old_lon = self.origin
        self.origin = (old_lat if lat is None else lat, old_lon if lon is None else lon)
        if all(math.isfinite(v) for v in self.origin):
            self.interface.update_utm_datum(*self.origin)
            self.log.info("local grid datum now %.8f, %.8f", *self.origin)

    def desired(self, var: str, value: float, time: float) -> Any | None:
        assert self.desired_course is not None
        return self.desired_course.update(var, value, time)

    def ctd(self, var: str, value: float, time: float) -> Any | None:
        assert self.ctd_samples is not None
        sample = self.ctd_samples.update(var, value, time)
        if sample is None:
            return None
        self.interface.compute_missing_ctd(sample)
        return frontseat_pb.InterfaceData(ctd_sample=sample)

    def bluefin_command(self, var: str, text: str, number: float | None) -> Any | None:
        assert self.bluefin_commands is not None
        return self.bluefin_commands.update(var, text, number)

    # -- frontseat -> backseat -------------------------------------------------------------

    def legacy_posts(self, data: Any) -> list[Post]:
        posts: list[Post] = []
        if data.HasField("node_status"):
            status = data.node_status
            if self.ctd_samples is not None:
                self.ctd_samples.update_position(status)
            if self.publish_nav:
                posts += nav_posts(status)
        if self.bluefin_commands is not None:
            posts += bluefin_report_posts(data)
        return posts
