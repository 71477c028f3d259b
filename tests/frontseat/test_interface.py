"""InterfaceBase state machine (spec goby-moos-apps.md 5.3): every transition T1-T9 and every
error rule E1-E4, on a scripted driver and a virtual clock."""

from __future__ import annotations

import logging
from dataclasses import dataclass, field

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.interface import (
    FrontSeatDriverError,
    FrontSeatFatalError,
    InterfaceBase,
)
from pygoby.util.clock import VirtualClock
from pygoby.util.signal import Signal
from tests.hypothesis_profiles import examples

from .scripted_driver import ScriptedFrontSeat

START = 1000.0
ERRORS = (frontseat_pb.INTERFACE_HELM_ERROR, frontseat_pb.INTERFACE_FS_ERROR)

STANDBY, LISTEN, COMMAND = (
    frontseat_pb.INTERFACE_STANDBY,
    frontseat_pb.INTERFACE_LISTEN,
    frontseat_pb.INTERFACE_COMMAND,
)
HELM_ERROR, FS_ERROR = frontseat_pb.INTERFACE_HELM_ERROR, frontseat_pb.INTERFACE_FS_ERROR
NOT_CONNECTED, IDLE = frontseat_pb.FRONTSEAT_NOT_CONNECTED, frontseat_pb.FRONTSEAT_IDLE
ACCEPTING, IN_CONTROL = frontseat_pb.FRONTSEAT_ACCEPTING_COMMANDS, frontseat_pb.FRONTSEAT_IN_CONTROL
NOT_RUNNING, DRIVE, PARK = (
    frontseat_pb.HELM_NOT_RUNNING,
    frontseat_pb.HELM_DRIVE,
    frontseat_pb.HELM_PARK,
)
PARKED, HELM_NOT_RUNNING_ERR = frontseat_pb.ERROR_HELM_PARKED, frontseat_pb.ERROR_HELM_NOT_RUNNING
FS_NOT_CONNECTED_ERR = frontseat_pb.ERROR_FRONTSEAT_NOT_CONNECTED
NOT_PROVIDING_ERR = frontseat_pb.ERROR_FRONTSEAT_NOT_PROVIDING_DATA
IGNORING_ERR = frontseat_pb.ERROR_FRONTSEAT_IGNORING_COMMANDS


def make(start: float = START, **cfg_fields) -> ScriptedFrontSeat:
    driver = ScriptedFrontSeat(frontseat_pb.Config(**cfg_fields), VirtualClock(start))
    driver.changes = []
    driver.signal_state_change.connect(driver.changes.append)
    return driver


def tick(driver: ScriptedFrontSeat, *, helm=None, fs=None, providing=None, at=None) -> None:
    if helm is not None:
        driver.set_helm_state(helm)
    if fs is not None:
        driver.fs_state = fs
    if providing is not None:
        driver.providing = providing
    if at is not None:
        driver.clock.set(START + at)
    driver.do_work()


def errors(driver: InterfaceBase) -> tuple[int | None, int | None]:
    status = driver.status()
    return (
        status.helm_error if status.HasField("helm_error") else None,
        status.frontseat_error if status.HasField("frontseat_error") else None,
    )


# How each starting point of the table is reached through legitimate transitions, at START.
def bring_to(driver: ScriptedFrontSeat, where: str) -> None:
    if where != "STANDBY":
        if where == "HELM_PARKED":
            tick(driver, helm=PARK)
        else:
            tick(driver, helm=DRIVE, fs=IDLE, providing=True)
            if where in ("COMMAND", "HELM_NOT_RUNNING", "FS_IGNORING"):
                tick(driver, fs=ACCEPTING)
            if where == "HELM_NOT_RUNNING":
                tick(driver, helm=NOT_RUNNING)
            elif where == "FS_NOT_CONNECTED":
                tick(driver, fs=NOT_CONNECTED)
            elif where == "FS_NOT_PROVIDING":
                tick(driver, providing=False)
            elif where == "FS_IGNORING":
                driver.raise_in_loop = FrontSeatDriverError(frontseat_error=IGNORING_ERR)
                tick(driver)
    expected = {
        "STANDBY": (STANDBY, None, None),
        "LISTEN": (LISTEN, None, None),
        "COMMAND": (COMMAND, None, None),
        "HELM_PARKED": (HELM_ERROR, PARKED, None),
        "HELM_NOT_RUNNING": (HELM_ERROR, HELM_NOT_RUNNING_ERR, None),
        "FS_NOT_CONNECTED": (FS_ERROR, None, FS_NOT_CONNECTED_ERR),
        "FS_NOT_PROVIDING": (FS_ERROR, None, NOT_PROVIDING_ERR),
        "FS_IGNORING": (FS_ERROR, None, IGNORING_ERR),
    }[where]
    assert (driver.state, *errors(driver)) == expected
    driver.changes.clear()
    driver.loop_calls = 0


@dataclass(frozen=True)
class Row:
    rule: str
    start: str
    helm: int
    fs: int
    providing: bool
    expect: int
    helm_error: int | None = None
    fs_error: int | None = None
    at: float = 0.0  # seconds after start-up at the tick
    cfg: dict = field(default_factory=dict)


NO_HELM = {"require_helm": False}

ROWS = [
    # T1: STANDBY -> LISTEN on data, before any error rule
    Row("T1", "STANDBY", NOT_RUNNING, IDLE, True, LISTEN),
    Row("T1 before E1", "STANDBY", PARK, IDLE, True, LISTEN),
    Row("T1 before E3", "STANDBY", DRIVE, NOT_CONNECTED, True, LISTEN, at=100),
    # T2: STANDBY -> error, E1-E3 with the start-up grace periods
    Row("T2 E1", "STANDBY", PARK, IDLE, False, HELM_ERROR, PARKED),
    Row("T2 E1 no helm", "STANDBY", PARK, IDLE, False, HELM_ERROR, PARKED, cfg=NO_HELM),
    Row("T2 E2 in grace", "STANDBY", NOT_RUNNING, IDLE, False, STANDBY, at=10),
    Row("T2 E2", "STANDBY", NOT_RUNNING, IDLE, False, HELM_ERROR, HELM_NOT_RUNNING_ERR, at=10.5),
    Row("T2 E2 no helm", "STANDBY", NOT_RUNNING, IDLE, False, STANDBY, at=1e6, cfg=NO_HELM),
    Row(
        "T2 E2 own timeout",
        "STANDBY",
        NOT_RUNNING,
        IDLE,
        False,
        STANDBY,
        at=20,
        cfg={"helm_running_timeout": 30},
    ),
    Row("T2 E3 in grace", "STANDBY", DRIVE, NOT_CONNECTED, False, STANDBY, at=10),
    Row(
        "T2 E3",
        "STANDBY",
        DRIVE,
        NOT_CONNECTED,
        False,
        FS_ERROR,
        None,
        FS_NOT_CONNECTED_ERR,
        at=10.5,
    ),
    Row(
        "T2 E3 no helm",
        "STANDBY",
        NOT_RUNNING,
        NOT_CONNECTED,
        False,
        FS_ERROR,
        None,
        FS_NOT_CONNECTED_ERR,
        at=11,
        cfg=NO_HELM,
    ),
    Row(
        "T2 E2 before E3",
        "STANDBY",
        NOT_RUNNING,
        NOT_CONNECTED,
        False,
        HELM_ERROR,
        HELM_NOT_RUNNING_ERR,
        at=11,
    ),
    Row(
        "T2 E3 sooner than E2",
        "STANDBY",
        NOT_RUNNING,
        NOT_CONNECTED,
        False,
        FS_ERROR,
        None,
        FS_NOT_CONNECTED_ERR,
        at=6,
        cfg={"helm_running_timeout": 30, "frontseat_connected_timeout": 5},
    ),
    Row("T2 E1 before E3", "STANDBY", PARK, NOT_CONNECTED, False, HELM_ERROR, PARKED, at=11),
    Row("T2 no E4 in STANDBY", "STANDBY", DRIVE, IDLE, False, STANDBY, at=1e6),
    # T3: LISTEN -> COMMAND
    Row("T3", "LISTEN", DRIVE, ACCEPTING, True, COMMAND),
    Row("T3 waits for helm", "LISTEN", NOT_RUNNING, ACCEPTING, True, LISTEN, at=5),
    Row("T3 no helm", "LISTEN", NOT_RUNNING, ACCEPTING, True, COMMAND, at=100, cfg=NO_HELM),
    Row("T3 no helm, parked", "LISTEN", PARK, ACCEPTING, True, COMMAND, cfg=NO_HELM),
    Row("T3 needs accepting", "LISTEN", DRIVE, IN_CONTROL, True, LISTEN),
    Row("T3 needs accepting (idle)", "LISTEN", DRIVE, IDLE, True, LISTEN, cfg=NO_HELM),
    # T4: LISTEN -> error, E1-E4
    Row("T4 E1", "LISTEN", PARK, IDLE, True, HELM_ERROR, PARKED),
    Row("T4 E1 no helm", "LISTEN", PARK, IDLE, True, HELM_ERROR, PARKED, cfg=NO_HELM),
    Row("T4 E1 accepting", "LISTEN", PARK, ACCEPTING, True, HELM_ERROR, PARKED),
    Row("T4 E2 in grace", "LISTEN", NOT_RUNNING, IDLE, True, LISTEN, at=10),
    Row("T4 E2", "LISTEN", NOT_RUNNING, IDLE, True, HELM_ERROR, HELM_NOT_RUNNING_ERR, at=10.5),
    Row("T4 E2 no helm", "LISTEN", NOT_RUNNING, IDLE, True, LISTEN, at=1e6, cfg=NO_HELM),
    Row(
        "T4 E3 no grace", "LISTEN", DRIVE, NOT_CONNECTED, True, FS_ERROR, None, FS_NOT_CONNECTED_ERR
    ),
    Row("T4 E4", "LISTEN", DRIVE, IDLE, False, FS_ERROR, None, NOT_PROVIDING_ERR),
    Row(
        "T4 E4 no helm",
        "LISTEN",
        NOT_RUNNING,
        IDLE,
        False,
        FS_ERROR,
        None,
        NOT_PROVIDING_ERR,
        cfg=NO_HELM,
    ),
    Row("T4 E1 before E3/E4", "LISTEN", PARK, NOT_CONNECTED, False, HELM_ERROR, PARKED),
    Row(
        "T4 E3 before E4",
        "LISTEN",
        DRIVE,
        NOT_CONNECTED,
        False,
        FS_ERROR,
        None,
        FS_NOT_CONNECTED_ERR,
    ),
    Row(
        "T4 E2 before E4",
        "LISTEN",
        NOT_RUNNING,
        IDLE,
        False,
        HELM_ERROR,
        HELM_NOT_RUNNING_ERR,
        at=11,
    ),
    # T5: COMMAND -> LISTEN, the helm not consulted
    Row("T5 idle", "COMMAND", DRIVE, IDLE, True, LISTEN),
    Row("T5 in control", "COMMAND", DRIVE, IN_CONTROL, True, LISTEN),
    Row("T5 helm parked", "COMMAND", PARK, IDLE, True, LISTEN),
    Row("T5 helm not running", "COMMAND", NOT_RUNNING, IN_CONTROL, True, LISTEN, at=100),
    Row("T5 before E4", "COMMAND", DRIVE, IN_CONTROL, False, LISTEN),
    Row("T5 stays", "COMMAND", DRIVE, ACCEPTING, True, COMMAND, at=1e6),
    # T6: COMMAND -> error, E1-E4 (E2 without grace period)
    Row("T6 E1", "COMMAND", PARK, ACCEPTING, True, HELM_ERROR, PARKED),
    Row("T6 E1 no helm", "COMMAND", PARK, ACCEPTING, True, HELM_ERROR, PARKED, cfg=NO_HELM),
    Row(
        "T6 E2 no grace",
        "COMMAND",
        NOT_RUNNING,
        ACCEPTING,
        True,
        HELM_ERROR,
        HELM_NOT_RUNNING_ERR,
        at=0,
    ),
    Row("T6 E2 no helm", "COMMAND", NOT_RUNNING, ACCEPTING, True, COMMAND, at=1e6, cfg=NO_HELM),
    Row("T6 E3", "COMMAND", DRIVE, NOT_CONNECTED, True, FS_ERROR, None, FS_NOT_CONNECTED_ERR),
    Row("T6 E4", "COMMAND", DRIVE, ACCEPTING, False, FS_ERROR, None, NOT_PROVIDING_ERR),
    Row(
        "T6 E2 before E3",
        "COMMAND",
        NOT_RUNNING,
        NOT_CONNECTED,
        False,
        HELM_ERROR,
        HELM_NOT_RUNNING_ERR,
    ),
    # T7: HELM_ERROR -> STANDBY only when the helm drives
    Row("T7", "HELM_PARKED", DRIVE, IDLE, False, STANDBY),
    Row("T7 from not running", "HELM_NOT_RUNNING", DRIVE, ACCEPTING, True, STANDBY),
    Row("T7 still parked", "HELM_PARKED", PARK, ACCEPTING, True, HELM_ERROR, PARKED, at=1e6),
    Row("T7 not running", "HELM_PARKED", NOT_RUNNING, ACCEPTING, True, HELM_ERROR, PARKED),
    Row(
        "T7 no helm: not running",
        "HELM_PARKED",
        NOT_RUNNING,
        ACCEPTING,
        True,
        HELM_ERROR,
        PARKED,
        cfg=NO_HELM,
    ),
    Row("T7 no helm: drive", "HELM_PARKED", DRIVE, NOT_CONNECTED, False, STANDBY, cfg=NO_HELM),
    Row(
        "T7 still not running",
        "HELM_NOT_RUNNING",
        NOT_RUNNING,
        ACCEPTING,
        True,
        HELM_ERROR,
        HELM_NOT_RUNNING_ERR,
    ),
    # T8: FS_ERROR -> STANDBY when the cause of the last frontseat error is gone
    Row("T8 connected", "FS_NOT_CONNECTED", PARK, IDLE, False, STANDBY),
    Row(
        "T8 still not connected",
        "FS_NOT_CONNECTED",
        DRIVE,
        NOT_CONNECTED,
        True,
        FS_ERROR,
        None,
        FS_NOT_CONNECTED_ERR,
    ),
    Row("T8 data again", "FS_NOT_PROVIDING", PARK, NOT_CONNECTED, True, STANDBY),
    Row(
        "T8 still no data",
        "FS_NOT_PROVIDING",
        DRIVE,
        ACCEPTING,
        False,
        FS_ERROR,
        None,
        NOT_PROVIDING_ERR,
    ),
    Row(
        "T8 ignoring: no exit",
        "FS_IGNORING",
        DRIVE,
        ACCEPTING,
        True,
        FS_ERROR,
        None,
        IGNORING_ERR,
        at=1e6,
    ),
    Row(
        "T8 ignoring: no exit (idle)",
        "FS_IGNORING",
        DRIVE,
        IDLE,
        True,
        FS_ERROR,
        None,
        IGNORING_ERR,
    ),
]


@pytest.mark.parametrize("row", ROWS, ids=[r.rule for r in ROWS])
def test_transition_table(row: Row) -> None:
    driver = make(**row.cfg)
    bring_to(driver, row.start)
    before = driver.state

    tick(driver, helm=row.helm, fs=row.fs, providing=row.providing, at=row.at)

    assert driver.state == row.expect, frontseat_pb.InterfaceState.Name(driver.state)
    assert errors(driver) == (row.helm_error, row.fs_error)
    entered_error_by_check = row.expect in ERRORS and before not in ERRORS
    # loop() is skipped exactly on the tick the transition check enters an error state
    assert driver.loop_calls == (0 if entered_error_by_check else 1)
    if row.expect == before:
        assert driver.changes == []
    else:
        assert [s.state for s in driver.changes] == [row.expect]
        assert driver.changes[0] == driver.status()


def test_every_transition_and_error_rule_is_in_the_table() -> None:
    rules = {r.rule.split()[0] for r in ROWS} | {
        part for r in ROWS for part in r.rule.split() if part.startswith("E")
    }
    assert {f"T{i}" for i in range(1, 9)} | {"E1", "E2", "E3", "E4"} <= rules


def test_initial_state() -> None:
    driver = make()
    assert driver.state == STANDBY
    assert driver.helm_state == NOT_RUNNING
    assert driver.start_time == START
    status = driver.status()
    assert (status.state, status.frontseat_state, status.helm_state) == (
        STANDBY,
        NOT_CONNECTED,
        NOT_RUNNING,
    )
    assert errors(driver) == (None, None)


def test_grace_periods_are_measured_from_construction() -> None:
    clock = VirtualClock(0.0)
    clock.advance(500)
    driver = ScriptedFrontSeat(frontseat_pb.Config(), clock)
    driver.fs_state = IDLE
    clock.set(510)
    driver.do_work()
    assert driver.state == STANDBY
    clock.set(510.001)
    driver.do_work()
    assert driver.state == HELM_ERROR


def test_helm_timeout_is_from_start_not_from_when_the_helm_stopped() -> None:
    driver = make()
    tick(driver, helm=DRIVE, fs=IDLE, providing=True)
    assert driver.state == LISTEN
    tick(driver, at=60)
    assert driver.state == LISTEN
    # the helm stops long after start-up: no new grace period
    tick(driver, helm=NOT_RUNNING, at=60.1)
    assert driver.state == HELM_ERROR
    assert errors(driver) == (HELM_NOT_RUNNING_ERR, None)


def test_last_error_kept_while_in_error_state_and_cleared_on_exit() -> None:
    driver = make()
    bring_to(driver, "FS_NOT_PROVIDING")
    for t in (1, 2, 3):
        tick(driver, at=t)
        assert driver.state == FS_ERROR
        assert errors(driver) == (None, NOT_PROVIDING_ERR)
    tick(driver, providing=True, at=4)
    assert driver.state == STANDBY
    assert not driver.status().HasField("frontseat_error")

    tick(driver, helm=PARK, providing=False, at=5)
    for t in (6, 7):
        tick(driver, at=t)
        assert errors(driver) == (PARKED, None)
    tick(driver, helm=DRIVE, at=8)
    assert driver.state == STANDBY
    assert not driver.status().HasField("helm_error")


def test_status_reports_driver_and_helm_state() -> None:
    driver = make()
    tick(driver, helm=DRIVE, fs=ACCEPTING, providing=True)
    tick(driver)
    status = driver.status()
    assert status.state == COMMAND
    assert status.frontseat_state == ACCEPTING
    assert status.helm_state == DRIVE
    assert not status.HasField("helm_error") and not status.HasField("frontseat_error")
    driver.fs_state = IN_CONTROL  # the frontseat state is read live from the driver
    assert driver.status().frontseat_state == IN_CONTROL


def test_a_full_session_signals_each_change_once() -> None:
    driver = make()
    tick(driver, fs=IDLE)  # STANDBY
    tick(driver, providing=True)  # T1
    tick(driver, fs=ACCEPTING)  # waiting for the helm
    tick(driver, helm=DRIVE)  # T3
    tick(driver, fs=IDLE)  # T5
    tick(driver, providing=False, at=1)  # E4
    tick(driver, at=20)  # stays
    tick(driver, providing=True, at=21)  # T8
    assert [frontseat_pb.InterfaceState.Name(s.state) for s in driver.changes] == [
        "INTERFACE_LISTEN",
        "INTERFACE_COMMAND",
        "INTERFACE_LISTEN",
        "INTERFACE_FS_ERROR",
        "INTERFACE_STANDBY",
    ]
    assert driver.changes[3].frontseat_error == NOT_PROVIDING_ERR
    assert not driver.changes[4].HasField("frontseat_error")


# --- T9: errors raised by the driver's loop() ---------------------------------------------


@pytest.mark.parametrize(
    "where", ["STANDBY", "LISTEN", "COMMAND", "HELM_PARKED", "FS_NOT_PROVIDING"]
)
@pytest.mark.parametrize(
    ("exc_args", "expect"),
    [
        ({"helm_error": PARKED}, (HELM_ERROR, PARKED, None)),
        ({"frontseat_error": IGNORING_ERR}, (FS_ERROR, None, IGNORING_ERR)),
        ({"frontseat_error": FS_NOT_CONNECTED_ERR}, (FS_ERROR, None, FS_NOT_CONNECTED_ERR)),
    ],
)
def test_t9_driver_exception_forces_error_state(where, exc_args, expect) -> None:
    driver = make()
    bring_to(driver, where)
    driver.raise_in_loop = FrontSeatDriverError(**exc_args, message="frontseat says no")
    driver.do_work()
    state, helm_error, fs_error = expect
    assert driver.state == state
    status = driver.status()
    if helm_error is not None:
        assert status.helm_error == helm_error
    if fs_error is not None:
        assert status.frontseat_error == fs_error
    assert driver.loop_calls == 1
    # signalled even when the state stays the same (a new report in that error state)
    assert [s.state for s in driver.changes] == [state]


def test_t9_keeps_the_other_error_code_until_its_own_exit() -> None:
    """goby3 clears each error only on its own exit (T7 / T8)."""
    driver = make()
    bring_to(driver, "FS_NOT_PROVIDING")
    driver.raise_in_loop = FrontSeatDriverError(helm_error=PARKED)
    tick(driver)
    assert driver.state == HELM_ERROR
    assert errors(driver) == (PARKED, NOT_PROVIDING_ERR)
    tick(driver, helm=DRIVE)  # T7
    assert driver.state == STANDBY
    assert errors(driver) == (None, NOT_PROVIDING_ERR)


def test_t9_after_a_transition_on_the_same_tick() -> None:
    driver = make()
    driver.fs_state, driver.providing = IDLE, True
    driver.raise_in_loop = FrontSeatDriverError(frontseat_error=IGNORING_ERR)
    driver.do_work()
    assert [s.state for s in driver.changes] == [LISTEN, FS_ERROR]


def test_exception_without_error_propagates() -> None:
    driver = make()
    bring_to(driver, "LISTEN")
    driver.raise_in_loop = FrontSeatDriverError(message="bad")
    with pytest.raises(FrontSeatDriverError, match="bad"):
        driver.do_work()
    assert driver.state == LISTEN
    driver.raise_in_loop = KeyError("bug")
    with pytest.raises(KeyError):
        driver.do_work()
    assert driver.state == LISTEN


def test_exception_carries_one_error() -> None:
    with pytest.raises(ValueError):
        FrontSeatDriverError(helm_error=PARKED, frontseat_error=IGNORING_ERR)
    exc = FrontSeatDriverError(frontseat_error=IGNORING_ERR, message="no ack")
    assert exc.is_fs_error and not exc.is_helm_error
    assert str(exc) == "ERROR_FRONTSEAT_IGNORING_COMMANDS: no ack"
    assert FrontSeatDriverError(helm_error=PARKED).is_helm_error


# --- exit_on_error ----------------------------------------------------------------------


def test_exit_on_error_raises_after_the_state_change() -> None:
    driver = make(exit_on_error=True)
    tick(driver, helm=DRIVE, fs=IDLE, providing=True)
    with pytest.raises(FrontSeatFatalError) as info:
        tick(driver, providing=False)
    assert isinstance(info.value, RuntimeError)
    assert driver.state == FS_ERROR
    assert [s.state for s in driver.changes] == [LISTEN, FS_ERROR]
    assert info.value.status.frontseat_error == NOT_PROVIDING_ERR
    assert "INTERFACE_FS_ERROR" in str(info.value)


def test_exit_on_error_on_driver_exception() -> None:
    driver = make(exit_on_error=True)
    driver.raise_in_loop = FrontSeatDriverError(helm_error=PARKED)
    with pytest.raises(FrontSeatFatalError):
        driver.do_work()
    assert driver.state == HELM_ERROR


def test_without_exit_on_error_error_states_do_not_raise() -> None:
    driver = make()
    tick(driver, helm=PARK)
    tick(driver)
    assert driver.state == HELM_ERROR


# --- Signal -----------------------------------------------------------------------------


def test_signal_calls_every_callback_in_order_even_if_one_raises(caplog) -> None:
    sig = Signal(contain_errors=True)  # (as the interface's signals are)
    seen: list = []

    def broken(value):
        raise RuntimeError("subscriber bug")

    sig.connect(lambda v: seen.append(("a", v)))
    sig.connect(broken)
    sig.connect(lambda v: seen.append(("b", v)))
    with caplog.at_level(logging.ERROR):
        sig(7)
        sig.emit(8)
    assert seen == [("a", 7), ("b", 7), ("a", 8), ("b", 8)]
    assert "subscriber bug" in caplog.text
    assert len(sig) == 3


def test_raising_state_change_subscriber_does_not_break_the_tick() -> None:
    driver = make()
    driver.signal_state_change.connect(lambda status: 1 / 0)
    tick(driver, fs=IDLE, providing=True)
    assert driver.state == LISTEN
    assert driver.loop_calls == 1


def test_driver_hooks_are_abstract() -> None:
    class Incomplete(InterfaceBase):
        def loop(self) -> None:
            pass

    with pytest.raises(TypeError):
        Incomplete(frontseat_pb.Config())


def test_cfg_is_a_copy() -> None:
    cfg = frontseat_pb.Config(name="auv1")
    driver = ScriptedFrontSeat(cfg, VirtualClock(0))
    cfg.name = "changed"
    assert driver.cfg.name == "auv1"


# --- random sequences -------------------------------------------------------------------

_steps = st.lists(
    st.tuples(
        st.sampled_from([NOT_RUNNING, DRIVE, PARK]),
        st.sampled_from([NOT_CONNECTED, IDLE, ACCEPTING, IN_CONTROL]),
        st.booleans(),
        st.sampled_from([0.0, 0.5, 3.0, 11.0]),
        st.sampled_from(
            [
                None,
                None,
                None,
                None,
                ("helm", PARKED),
                ("fs", IGNORING_ERR),
                ("fs", NOT_PROVIDING_ERR),
            ]
        ),
    ),
    max_size=40,
)


@settings(max_examples=examples(200), deadline=None)
@given(require_helm=st.booleans(), steps=_steps)
def test_random_sequences_respect_command_and_error_exits(require_helm, steps) -> None:
    driver = make(require_helm=require_helm)
    for helm, fs, providing, dt, raised in steps:
        driver.set_helm_state(helm)
        driver.fs_state, driver.providing = fs, providing
        driver.clock.advance(dt)
        driver.raise_in_loop = None  # a report not raised (loop skipped) does not carry over
        if raised is not None:
            kind, code = raised
            key = "helm_error" if kind == "helm" else "frontseat_error"
            driver.raise_in_loop = FrontSeatDriverError(**{key: code})
        before = driver.state
        last_fs_error = errors(driver)[1]
        loops = driver.loop_calls
        driver.do_work()
        after = driver.state
        if driver.loop_calls == loops:  # skipped: only when the check has just entered an error
            assert before not in ERRORS and after in ERRORS
        if after == COMMAND and before != COMMAND:
            assert before == LISTEN
            assert fs == ACCEPTING
            assert helm == DRIVE or not require_helm
        if before in ERRORS and after not in ERRORS:
            assert after == STANDBY
            if before == HELM_ERROR:
                assert helm == DRIVE  # T7
            else:  # T8
                assert (last_fs_error == FS_NOT_CONNECTED_ERR and fs != NOT_CONNECTED) or (
                    last_fs_error == NOT_PROVIDING_ERR and providing
                )
        if before in ERRORS and after in ERRORS and after != before:
            assert raised is not None  # only a driver report moves between error states
        assert driver.changes == [] or driver.changes[-1].state == after
        driver.changes.clear()


def test_helm_state_timeout_off_by_default_keeps_a_silent_drive_helm() -> None:
    driver = make()  # Q24 reproduced: no staleness without the pygoby option
    bring_to(driver, "COMMAND")
    tick(driver, at=3600)
    assert (driver.state, driver.helm_state) == (COMMAND, DRIVE)


def test_helm_state_timeout_turns_a_silent_helm_into_helm_error() -> None:
    driver = make(helm_state_timeout=5)
    bring_to(driver, "COMMAND")
    driver.clock.set(START + 4)
    tick(driver, helm=DRIVE)  # a post (same state) restarts the timeout
    tick(driver, at=9)
    assert (driver.state, driver.helm_state) == (COMMAND, DRIVE)
    tick(driver, at=9.01)
    assert (driver.state, driver.helm_state) == (HELM_ERROR, NOT_RUNNING)
    assert errors(driver) == (HELM_NOT_RUNNING_ERR, None)
    driver.clock.set(START + 10)
    tick(driver, helm=DRIVE)  # the helm is back: T7
    assert driver.state == STANDBY


def test_helm_state_timeout_without_require_helm_only_forgets_the_state() -> None:
    driver = make(helm_state_timeout=5, require_helm=False)
    bring_to(driver, "COMMAND")
    tick(driver, at=6)
    assert (driver.state, driver.helm_state) == (COMMAND, NOT_RUNNING)
