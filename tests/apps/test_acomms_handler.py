"""AcommsHandler without MOOS: modem_id propagation, driver selection and plugins, and the
driver failure approaches (spec goby-moos-apps.md 4.2-4.3), on a virtual clock."""

from __future__ import annotations

from pathlib import Path

import pytest
from google.protobuf import text_format

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.handler import AcommsHandler, HandlerError
from pygoby.apps.pacommshandler import pAcommsHandler
from pygoby.util.clock import VirtualClock

from .plugin_driver import ScriptedDriver

PLUGIN = Path(__file__).with_name("plugin_driver.py")


@pytest.fixture
def plugins(monkeypatch):
    monkeypatch.setenv("PACOMMSHANDLER_PLUGINS", "tests.apps.plugin_driver")
    ScriptedDriver.instances.clear()
    ScriptedDriver.fail_startups = 0
    yield
    ScriptedDriver.instances.clear()


def config(text: str):
    cfg = pAcommsHandler.load_config_class()()
    text_format.Merge(text, cfg)
    return cfg


SCRIPTED = 'driver_name: "SCRIPTED"'
SLOT = "mac_cfg { type: MAC_FIXED_DECENTRALIZED slot { src: 3 slot_seconds: 10 } }"


def test_plugins_by_file_path_and_separators(monkeypatch):
    monkeypatch.setenv("PACOMMSHANDLER_PLUGINS", f"pygoby.acomms.messages,{PLUGIN}")
    handler = AcommsHandler(config(f"modem_id: 4 driver_cfg {{ {SCRIPTED} }}"), VirtualClock())
    assert type(handler.primary.driver).__name__ == "ScriptedDriver"
    monkeypatch.setenv("PACOMMSHANDLER_PLUGINS", "no.such.module")
    with pytest.raises(HandlerError, match="unknown modem driver 'no.such.module'"):
        AcommsHandler(config(f"modem_id: 4 driver_cfg {{ {SCRIPTED} }}"), VirtualClock())


def test_modem_id_is_propagated_and_goby2_driver_type_is_used(plugins):
    cfg = config(f"""modem_id: 3 driver_cfg {{ {SCRIPTED} }}
                     listen_driver_cfg {{ {SCRIPTED} modem_id: 9 }}
                     queue_cfg {{ modem_id: 1 }} mac_cfg {{ modem_id: 1 }}""")
    handler = AcommsHandler(cfg, VirtualClock(100.0))
    assert handler.queue_cfg.modem_id == 3 and handler.mac_cfg.modem_id == 3
    assert [s.cfg.modem_id for s in handler.slots] == [3, 9]  # own ids are kept
    assert handler.primary is handler.slots[0]
    old_style = AcommsHandler(config("modem_id: 2 driver_type: DRIVER_UDP"), VirtualClock())
    assert type(old_style.primary.driver).__name__ == "UDPDriver"
    none = AcommsHandler(config("modem_id: 2"), VirtualClock())
    assert none.primary is None and none.slots == []


@pytest.mark.parametrize(
    ("text", "error"),
    [
        ("modem_id: 0", "broadcast"),
        ("modem_id: 1 driver_cfg { driver_type: DRIVER_IRIDIUM }", "not implemented"),
        ('modem_id: 1 driver_cfg { driver_name: "NOPE" }', "no driver plugin named 'NOPE'"),
    ],
)
def test_bad_configurations_are_clear_errors(plugins, text, error):
    with pytest.raises(HandlerError, match=error):
        AcommsHandler(config(text), VirtualClock())


def run(handler: AcommsHandler, clock: VirtualClock, seconds: float) -> None:
    for _ in range(int(seconds * 4)):
        clock.advance(0.25)
        handler.do_work()


def started(text: str, clock: VirtualClock) -> AcommsHandler:
    handler = AcommsHandler(config(text), clock)
    handler.start()
    handler.do_work()
    return handler


def test_continually_restart_driver_after_backoff(plugins):
    clock = VirtualClock(1000.0)
    ScriptedDriver.fail_startups = 1
    handler = started(f"modem_id: 3 driver_cfg {{ {SCRIPTED} }} {SLOT}", clock)
    (driver,) = ScriptedDriver.instances
    assert not handler.primary.running and driver.started == 0
    run(handler, clock, 59.5)
    assert driver.started == 0  # driver_backoff_sec defaults to 60
    run(handler, clock, 0.5)
    assert driver.started == 1 and handler.primary.running
    run(handler, clock, 20)
    assert driver.initiated  # the MAC runs the primary's slots
    driver.fail_next_work = True
    handler.do_work()  # fails in do_work: shut down, retried after the back-off
    assert driver.stopped == 1 and not handler.primary.running
    slots_before = len(driver.initiated)
    run(handler, clock, 59.5)  # the MAC does not run while the primary waits to restart
    assert len(driver.initiated) == slots_before
    run(handler, clock, 0.5)
    assert driver.started == 2
    handler.reset_primary()  # ACOMMS_DRIVER_RESET: MANUAL_RESET, then the same approach
    assert driver.stopped == 2 and handler.primary.restart_at == clock.now() + 60


@pytest.mark.parametrize("disable", [False, True])
def test_listen_driver_moves_to_primary(plugins, disable):
    technique = (
        "DISABLE_AND_MOVE_LISTEN_DRIVER_TO_PRIMARY" if disable else "MOVE_LISTEN_DRIVER_TO_PRIMARY"
    )
    clock = VirtualClock(1000.0)
    handler = started(
        f"""modem_id: 3 driver_cfg {{ {SCRIPTED} }} listen_driver_cfg {{ {SCRIPTED} modem_id: 7 }}
            driver_failure_approach {{ technique: {technique} }} {SLOT}""",
        clock,
    )
    first, second = handler.slots
    first.driver.fail_next_work = True
    handler.do_work()
    assert handler.primary is second
    assert (first.cfg.modem_id, second.cfg.modem_id) == (7, 3)  # the two swap modem ids
    assert not second.running and second.restart_at == clock.now() + 5  # new_driver_backoff_sec
    if disable:
        assert handler.slots == [second]
    else:
        assert first.restart_at == clock.now() + 60
    run(handler, clock, 20)  # modem 3's slots go to the new primary once it runs
    assert second.running and second.driver.initiated and not first.driver.initiated


def test_only_driver_failing_with_move_approach_is_fatal(plugins):
    clock = VirtualClock(1000.0)
    handler = started(
        f"modem_id: 3 driver_cfg {{ {SCRIPTED} }} "
        "driver_failure_approach { technique: MOVE_LISTEN_DRIVER_TO_PRIMARY }",
        clock,
    )
    handler.primary.driver.fail_next_work = True
    with pytest.raises(HandlerError, match="no listen driver"):
        handler.do_work()


def test_driver_cfg_update_goes_to_running_drivers_with_that_id(plugins):
    clock = VirtualClock(1000.0)
    handler = started(
        f"modem_id: 3 driver_cfg {{ {SCRIPTED} }} listen_driver_cfg {{ {SCRIPTED} modem_id: 7 }}",
        clock,
    )
    handler.update_driver_cfg(acomms_pb.DriverConfig(modem_id=7))
    assert [len(s.driver.cfg_updates) for s in handler.slots] == [0, 1]


def test_a_transmission_the_driver_rejects_costs_only_that_slot(plugins, caplog):
    clock = VirtualClock(1000.0)
    handler = started(f"modem_id: 3 driver_cfg {{ {SCRIPTED} }} {SLOT}", clock)
    driver = handler.primary.driver

    def reject(transmission):
        raise ValueError("rate 9 is not a Micro-Modem rate")

    driver.signal_data_request.connect(reject)
    run(handler, clock, 31)  # three slots: each one fails alone, the MAC keeps its schedule
    assert len(driver.initiated) == 3 and handler.primary.running
    assert caplog.text.count("cannot start the transmission") == 3


def test_a_driver_that_cannot_start_says_why_and_when_it_is_tried_again(plugins, caplog):
    """One warning per attempt (every driver_backoff_sec: once a minute by default), the state
    in show_gui's words and on ACOMMS_DRIVER_STATUS (liaison's Acomms page shows it)."""
    clock = VirtualClock(1000.0)
    ScriptedDriver.fail_startups = 2
    handler = AcommsHandler(config(f"modem_id: 3 driver_cfg {{ {SCRIPTED} }} {SLOT}"), clock)
    states: list[str] = []
    handler.signal_driver_status.connect(lambda slot, text: states.append(text))
    handler.start()
    with caplog.at_level("WARNING", logger="pygoby"):
        handler.do_work()
        (failed,) = [r.getMessage() for r in caplog.records]
        assert "driver SCRIPTED::3 failed (STARTUP_FAILED: " in failed
        assert failed.endswith("; trying again in 60 s")
        run(handler, clock, 30)
        assert handler.primary.describe(clock.now()).endswith("; next attempt in 30 s")
        assert handler.primary.describe(clock.now()).startswith("failed (1x): STARTUP_FAILED: ")
        run(handler, clock, 30)  # the second attempt fails too: a second warning, a minute on
        assert len(caplog.records) == 2
        run(handler, clock, 60)
        assert handler.primary.running and handler.primary.describe(clock.now()) == "running"
        handler_warnings = [r.getMessage() for r in caplog.records if r.name.endswith("handler")]
        assert handler_warnings[-1] == "driver SCRIPTED::3 running again (after 2 failures)"
    assert [s.split(":")[0] for s in states] == ["failed (1x)", "failed (2x)", "running"]
