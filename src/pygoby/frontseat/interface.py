"""The frontseat interface base class: the iFrontSeat state machine shared by every driver.

A driver (one vehicle's frontseat protocol) subclasses `InterfaceBase` and implements the
abstract hooks; the application calls `do_work()` once per tick, `set_helm_state()` from the
helm's posts, and forwards commands/data only in the states that allow them (commands only in
COMMAND, data and raw traffic only in LISTEN or COMMAND). Sans-I/O: time comes from the given
Clock.

State machine (goby3's), run by `do_work()` before the driver's `loop()`:

* STANDBY -> LISTEN when the frontseat provides data, else the error check below (whose
  not-providing-data rule cannot fire in STANDBY);
* LISTEN -> COMMAND when the frontseat accepts commands and the helm drives (or the helm is not
  required), else the error check;
* COMMAND -> LISTEN when the frontseat is IDLE or IN_CONTROL, whatever the helm, else the error
  check, with the helm-not-running rule applied without its start-up grace period;
* HELM_ERROR -> STANDBY when the helm drives (the helm error is cleared); FS_ERROR -> STANDBY when
  the condition behind the last frontseat error is gone (the frontseat connects again after
  NOT_CONNECTED, provides data again after NOT_PROVIDING_DATA); an IGNORING_COMMANDS error has no
  automatic exit;
* a driver raising `FrontSeatDriverError` from `loop()` forces the matching error state, from any
  state.

The error check, first rule that fires wins: the helm PARKed -> HELM_ERROR (PARKED); the helm
required and NOT_RUNNING, in COMMAND or once `helm_running_timeout` has passed since start ->
HELM_ERROR (NOT_RUNNING); the frontseat NOT_CONNECTED, outside STANDBY or once
`frontseat_connected_timeout` has passed -> FS_ERROR (NOT_CONNECTED); the frontseat not providing
data outside STANDBY -> FS_ERROR (NOT_PROVIDING_DATA).

goby3 keeps the helm's last reported state with no timeout (reproduced, the default here too:
QUIRKS.md Q-APPS-24). The pygoby option `helm_state_timeout` (> 0) turns a helm that has not
reported for that long into NOT_RUNNING before the check, so a helm that dies in DRIVE leads to
HELM_ERROR (NOT_RUNNING).

When the transition check enters an error state, `loop()` is skipped for that tick. Each error
code is kept until its own exit (the helm driving again clears the helm error, the frontseat's
recovery the frontseat error), as goby3 does: so after a driver's exception moves the interface
from one error state to the other, `status()` can carry both codes.
"""

from __future__ import annotations

import abc
import logging
import math
from typing import Any

from google.protobuf import text_format

from pygoby.frontseat.ctd import compute_missing_ctd as _compute_missing_ctd
from pygoby.frontseat.errors import FrontSeatDriverError, FrontSeatFatalError
from pygoby.frontseat.messages import (
    ERROR_FRONTSEAT_NONE,
    ERROR_FRONTSEAT_NOT_CONNECTED,
    ERROR_FRONTSEAT_NOT_PROVIDING_DATA,
    ERROR_HELM_NONE,
    ERROR_HELM_NOT_RUNNING,
    ERROR_HELM_PARKED,
    ERROR_STATES,
    FRONTSEAT_ACCEPTING_COMMANDS,
    FRONTSEAT_IDLE,
    FRONTSEAT_IN_CONTROL,
    FRONTSEAT_NOT_CONNECTED,
    HELM_DRIVE,
    HELM_NOT_RUNNING,
    HELM_PARK,
    INTERFACE_COMMAND,
    INTERFACE_FS_ERROR,
    INTERFACE_HELM_ERROR,
    INTERFACE_LISTEN,
    INTERFACE_STANDBY,
    CommandResponse,
    FrontSeatError,
    FrontSeatState,
    HelmError,
    HelmState,
    InterfaceData,
    InterfaceState,
    InterfaceStatus,
    Raw,
)
from pygoby.util.clock import Clock, WallClock
from pygoby.util.geodesy import UTMGeodesy
from pygoby.util.signal import Signal

_log = logging.getLogger(__name__)


def _short(status: Any) -> str:
    return text_format.MessageToString(status, as_one_line=True)


class InterfaceBase(abc.ABC):
    """Base of every frontseat driver: state machine, signals and data helpers.

    `cfg` is a goby.middleware.frontseat.protobuf.Config (copied; the driver reads its own
    extension from `self.cfg`). `start_time` (construction time on `clock`) is the origin of the
    helm and frontseat start-up grace periods.
    """

    def __init__(self, cfg: Any, clock: Clock | None = None) -> None:
        self.cfg = type(cfg)()
        self.cfg.CopyFrom(cfg)
        self.clock: Clock = clock if clock is not None else WallClock()
        self.start_time = self.clock.now()
        self.log = logging.getLogger(f"{__name__}.{type(self).__name__}")

        self._state: InterfaceState.ValueType = INTERFACE_STANDBY
        self._helm_state: HelmState.ValueType = HELM_NOT_RUNNING
        self._helm_heard_at = self.start_time  # last set_helm_state(), for helm_state_timeout
        self._last_helm_error: HelmError.ValueType = ERROR_HELM_NONE
        self._last_frontseat_error: FrontSeatError.ValueType = ERROR_FRONTSEAT_NONE

        # A raising subscriber is logged and does not stop the others (nor the interface's tick)
        self.signal_data_from_frontseat: Signal[InterfaceData] = Signal(
            contain_errors=True, logger=_log
        )
        self.signal_command_response: Signal[CommandResponse] = Signal(
            contain_errors=True, logger=_log
        )
        self.signal_raw_from_frontseat: Signal[Raw] = Signal(contain_errors=True, logger=_log)
        self.signal_raw_to_frontseat: Signal[Raw] = Signal(contain_errors=True, logger=_log)
        self.signal_state_change: Signal[InterfaceStatus] = Signal(contain_errors=True, logger=_log)

        self._geodesy: UTMGeodesy | None = None
        origin = self.cfg.origin
        if self.cfg.HasField("origin") and math.isfinite(origin.lat) and math.isfinite(origin.lon):
            self.update_utm_datum(origin.lat, origin.lon)
        else:
            self.log.warning(
                "no valid datum (cfg.origin, from LatOrigin/LongOrigin): compute_missing cannot "
                "convert between global and local fixes until update_utm_datum()"
            )

    # --- driver hooks ---------------------------------------------------------------------

    @abc.abstractmethod
    def send_command_to_frontseat(self, command: Any) -> None:
        """Pass a CommandRequest to the frontseat (called only in INTERFACE_COMMAND)."""

    @abc.abstractmethod
    def send_data_to_frontseat(self, data: Any) -> None:
        """Pass InterfaceData to the frontseat (called in LISTEN and COMMAND)."""

    @abc.abstractmethod
    def send_raw_to_frontseat(self, raw: Any) -> None:
        """Write a Raw message from another process to the frontseat (may be ignored)."""

    @abc.abstractmethod
    def frontseat_state(self) -> FrontSeatState.ValueType:
        """The driver's belief of the frontseat's command state (FrontSeatState)."""

    @abc.abstractmethod
    def frontseat_providing_data(self) -> bool:
        """True while the required data (at least navigation) arrive recently enough."""

    @abc.abstractmethod
    def loop(self) -> None:
        """Non-blocking work every tick after the state check: read, emit signals, age data."""

    async def start(self) -> None:  # noqa: B027 (optional hook, a no-op by default)
        """Open the driver's I/O (default: nothing to open)."""

    async def stop(self) -> None:  # noqa: B027 (optional hook, a no-op by default)
        """Close the driver's I/O (default: nothing to close)."""

    # --- state ----------------------------------------------------------------------------

    @property
    def state(self) -> InterfaceState.ValueType:
        return self._state

    @property
    def helm_state(self) -> HelmState.ValueType:
        return self._helm_state

    def set_helm_state(self, state: HelmState.ValueType) -> None:
        """The helm's state from its latest post; call it for every post, changed or not (each
        one restarts the `helm_state_timeout` clock)."""
        self._helm_state = state
        self._helm_heard_at = self.clock.now()

    def status(self) -> Any:
        status = InterfaceStatus(
            state=self._state, frontseat_state=self.frontseat_state(), helm_state=self._helm_state
        )
        if self._last_helm_error != ERROR_HELM_NONE:
            status.helm_error = self._last_helm_error
        if self._last_frontseat_error != ERROR_FRONTSEAT_NONE:
            status.frontseat_error = self._last_frontseat_error
        return status

    # --- data helpers -----------------------------------------------------------------------------

    def update_utm_datum(self, lat: float, lon: float) -> None:
        """Re-centre the local grid used by compute_missing on (lat, lon) degrees."""
        if not (math.isfinite(lat) and math.isfinite(lon)):
            raise ValueError(f"invalid UTM datum ({lat}, {lon})")
        self._geodesy = UTMGeodesy(lat, lon)

    @property
    def geodesy(self) -> UTMGeodesy | None:
        """The local grid of the current datum (None until one is known)."""
        return self._geodesy

    def compute_missing(self, node_status: Any) -> None:
        """Fill in what a driver's NodeStatus lacks, in place: `name`/`type` from the config,
        `time` = now, and the global fix from the local fix (lat/lon by the UTM inverse,
        depth = -z) or the other way round (x/y by UTM forward, z = -depth). Depth and z are
        carried over only when set. With neither fix: a warning, nothing else changed."""
        if not node_status.HasField("name") and self.cfg.HasField("name"):
            node_status.name = self.cfg.name
        if not node_status.HasField("type"):
            node_status.type = self.cfg.type
        if not node_status.HasField("time"):
            node_status.time = self.clock.now()

        has_global = node_status.HasField("global_fix")
        has_local = node_status.HasField("local_fix")
        if has_global == has_local:
            if not has_global:
                self.log.warning(
                    "compute_missing: NodeStatus has neither global_fix nor local_fix "
                    "(no position to compute from)"
                )
            return
        if self._geodesy is None:
            self.log.warning("compute_missing: no UTM datum, cannot convert the position fix")
            return
        if has_local:
            local = node_status.local_fix
            lat, lon = self._geodesy.to_geo(local.x, local.y)
            fix = node_status.global_fix
            fix.lat, fix.lon = lat, lon
            if local.HasField("z"):
                fix.depth = -local.z
        else:
            fix = node_status.global_fix
            x, y = self._geodesy.to_local(fix.lat, fix.lon)
            local = node_status.local_fix
            local.x, local.y = x, y
            if fix.HasField("depth"):
                local.z = -fix.depth

    def compute_missing_ctd(self, ctd: Any) -> None:
        """Fill in a CTDSample's salinity, depth, sound speed and density where missing
        (UNESCO algorithms; see pygoby.frontseat.ctd)."""
        _compute_missing_ctd(ctd, self.log)

    def do_work(self) -> None:
        """One tick: the transition check, then the driver's loop() unless the check has just
        entered an error state. Raises FrontSeatFatalError in an error state if
        `exit_on_error` is set (after the state change was signalled)."""
        self._expire_helm_state()
        if not self._check_change_state():
            try:
                self.loop()
            except FrontSeatDriverError as exc:
                if not (exc.is_helm_error or exc.is_fs_error):
                    raise
                self.log.warning("driver reported an error: %s", exc)
                self._enter_error(exc.helm_error, exc.frontseat_error)
        if self.cfg.exit_on_error and self._state in ERROR_STATES:
            raise FrontSeatFatalError(self.status())

    def _expire_helm_state(self) -> None:
        timeout = self.cfg.helm_state_timeout
        if (
            timeout > 0
            and self._helm_state != HELM_NOT_RUNNING
            and self.clock.now() - self._helm_heard_at > timeout
        ):
            self.log.warning(
                "no helm state for %g s (helm_state_timeout): the helm counts as not running",
                self.clock.now() - self._helm_heard_at,
            )
            self._helm_state = HELM_NOT_RUNNING

    def _check_change_state(self) -> bool:
        """Applies the transitions above (all but the driver-raised error); True when it has just
        entered an error state (loop() is skipped)."""
        state = self._state
        if state in (INTERFACE_STANDBY, INTERFACE_LISTEN, INTERFACE_COMMAND):
            target = self._normal_transition(state)
            if target is None:
                error = self._error_check()
                if error is not None:
                    self._enter_error(*error)
                    return True
                return False
        elif state == INTERFACE_HELM_ERROR:
            target = self._helm_error_exit()
        else:
            target = self._frontseat_error_exit()
        if target is not None:
            self._change_state(target)
        return False

    def _normal_transition(
        self, state: InterfaceState.ValueType
    ) -> InterfaceState.ValueType | None:
        if state == INTERFACE_STANDBY:
            return INTERFACE_LISTEN if self.frontseat_providing_data() else None
        if state == INTERFACE_LISTEN:  # -> COMMAND: the frontseat accepts commands, the helm drives
            helm_ok = self._helm_state == HELM_DRIVE or not self.cfg.require_helm
            accepting = self.frontseat_state() == FRONTSEAT_ACCEPTING_COMMANDS
            return INTERFACE_COMMAND if accepting and helm_ok else None
        # COMMAND -> LISTEN when the frontseat is idle or in control: the helm is not consulted
        if self.frontseat_state() in (FRONTSEAT_IN_CONTROL, FRONTSEAT_IDLE):
            return INTERFACE_LISTEN
        return None

    def _error_check(
        self,
    ) -> tuple[HelmError.ValueType | None, FrontSeatError.ValueType | None] | None:
        """The error rules in order (used from STANDBY, LISTEN, COMMAND): (helm error, frontseat
        error) of the first rule that fires, or None."""
        now = self.clock.now()
        helm = self._helm_state
        if helm == HELM_PARK:
            return ERROR_HELM_PARKED, None
        if (
            self.cfg.require_helm
            and helm == HELM_NOT_RUNNING
            and (
                self._state == INTERFACE_COMMAND
                or now > self.start_time + self.cfg.helm_running_timeout
            )
        ):
            return ERROR_HELM_NOT_RUNNING, None
        if self.frontseat_state() == FRONTSEAT_NOT_CONNECTED and (
            self._state != INTERFACE_STANDBY
            or now > self.start_time + self.cfg.frontseat_connected_timeout
        ):
            return None, ERROR_FRONTSEAT_NOT_CONNECTED
        if not self.frontseat_providing_data() and self._state != INTERFACE_STANDBY:
            return None, ERROR_FRONTSEAT_NOT_PROVIDING_DATA
        return None

    def _helm_error_exit(self) -> InterfaceState.ValueType | None:
        if self._helm_state == HELM_DRIVE:  # the helm drives again: its error is cleared
            self._last_helm_error = ERROR_HELM_NONE
            return INTERFACE_STANDBY
        return None

    def _frontseat_error_exit(self) -> InterfaceState.ValueType | None:
        error = self._last_frontseat_error
        cleared = (
            error == ERROR_FRONTSEAT_NOT_CONNECTED
            and self.frontseat_state() != FRONTSEAT_NOT_CONNECTED
        ) or (error == ERROR_FRONTSEAT_NOT_PROVIDING_DATA and self.frontseat_providing_data())
        if cleared:  # the condition behind the last frontseat error is gone
            self._last_frontseat_error = ERROR_FRONTSEAT_NONE
            return INTERFACE_STANDBY
        return None

    def _enter_error(
        self,
        helm_error: HelmError.ValueType | None,
        frontseat_error: FrontSeatError.ValueType | None,
    ) -> None:
        """Error entry (from the error rules or a driver's exception). Signals even when the state
        stays the same (a driver reporting the error state it is already in), as goby3 does."""
        if helm_error is not None:
            self._last_helm_error = helm_error
            target = INTERFACE_HELM_ERROR
        else:
            assert frontseat_error is not None
            self._last_frontseat_error = frontseat_error
            target = INTERFACE_FS_ERROR
        self._set_state(target)

    def _change_state(self, target: InterfaceState.ValueType) -> None:
        if target != self._state:
            self._set_state(target)

    def _set_state(self, target: InterfaceState.ValueType) -> None:
        previous, self._state = self._state, target
        status = self.status()
        log = self.log.warning if target in ERROR_STATES else self.log.info
        log(
            "interface state %s -> %s (%s)",
            InterfaceState.Name(previous),
            InterfaceState.Name(target),
            _short(status),
        )
        self.signal_state_change(status)
