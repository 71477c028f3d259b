"""pygoby.util.signal.Signal: order, (dis)connection, and which slots' errors propagate."""

from __future__ import annotations

import logging

import pytest

from pygoby.util.signal import Signal


def broken(*args):
    raise RuntimeError("subscriber bug")


def test_emit_calls_every_slot_in_connection_order_with_the_arguments():
    signal, seen = Signal(), []
    assert len(signal) == 0 and not signal
    signal.connect(lambda a, b: seen.append(("first", a, b)))
    signal.connect(lambda a, b: seen.append(("second", a, b)))
    signal.emit(1, 2)
    signal(3, 4)  # calling the signal emits it
    assert seen == [("first", 1, 2), ("second", 1, 2), ("first", 3, 4), ("second", 3, 4)]
    assert len(signal) == 2 and signal


def test_disconnect_removes_one_connection():
    signal, seen = Signal(), []
    signal.connect(seen.append)
    signal.connect(seen.append)
    signal.disconnect(seen.append)  # (an equal bound method)
    signal.emit("x")
    assert seen == ["x"] and len(signal) == 1
    signal.disconnect(seen.append)
    with pytest.raises(ValueError, match="is not connected"):
        signal.disconnect(seen.append)


def test_a_slot_may_disconnect_itself_while_the_signal_is_emitted():
    signal, seen = Signal(), []

    def once(value):
        seen.append(("once", value))
        signal.disconnect(once)

    signal.connect(once)
    signal.connect(lambda value: seen.append(("always", value)))
    signal.emit(1)
    signal.emit(2)
    assert seen == [("once", 1), ("always", 1), ("always", 2)]


def test_by_default_a_slot_error_reaches_the_emitter_and_stops_the_emission():
    signal, seen = Signal(), []
    signal.connect(broken)
    signal.connect(seen.append)
    with pytest.raises(RuntimeError, match="subscriber bug"):
        signal.emit(1)
    assert seen == []


def test_a_containing_signal_logs_a_slot_error_and_runs_the_others(caplog):
    logger = logging.getLogger("test.signal.owner")
    signal, seen = Signal(contain_errors=True, logger=logger), []
    signal.connect(broken)
    signal.connect(seen.append)
    with caplog.at_level(logging.ERROR):
        signal.emit(1)
    assert seen == [1]
    (record,) = caplog.records
    assert record.name == "test.signal.owner" and "broken raised" in record.getMessage()
    assert "subscriber bug" in caplog.text  # with the traceback


def test_containment_can_be_chosen_per_connection(caplog):
    app_log = logging.getLogger("test.signal.app")
    propagating, seen = Signal(), []
    propagating.connect(broken, contain_errors=True, logger=app_log)  # e.g. an app's own slot
    propagating.connect(seen.append)
    with caplog.at_level(logging.ERROR):
        propagating.emit(1)
    assert seen == [1] and [r.name for r in caplog.records] == ["test.signal.app"]

    containing = Signal(contain_errors=True)
    containing.connect(broken, contain_errors=False)
    with pytest.raises(RuntimeError):
        containing.emit(2)


def test_a_typed_signal_passes_positional_and_keyword_arguments():
    signal: Signal[[int, str]] = Signal[[int, str]]()  # subscripted at run time too
    seen = []
    signal.connect(lambda number, text: seen.append((number, text)))
    signal.emit(1, "a")
    signal.emit(2, text="b")
    assert seen == [(1, "a"), (2, "b")]
