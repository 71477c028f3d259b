"""The sentence exchange of the Bluefin driver with the Huxley simulator, recorded in
tests/data/frontseat/bluefin_exchange.txt (`<t> > <sentence>`: Huxley to the driver,
`<t> < <sentence>`: the driver to Huxley, t in virtual seconds from 2023-11-14 22:13:20 UTC).

* The recording is what the two produce today (bluefin_scenario.run_exchange), so a change of
  either shows here; regenerate with `python -m tests.frontseat.test_bluefin_exchange` after a
  deliberate change.
* Replayed against the driver alone, the Huxley lines of the record draw from the driver exactly
  the payload lines of the record, tick by tick (the same check fits a record of a real Huxley
  or of goby3's driver).
"""

from __future__ import annotations

from pathlib import Path

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.bluefin.simulator import HuxleyOptions

from .bluefin_scenario import (
    T0,
    TICK,
    Helm,
    driver_on_memory,
    format_exchange,
    parse_exchange,
    run_exchange,
)

RECORD = Path(__file__).resolve().parents[1] / "data" / "frontseat" / "bluefin_exchange.txt"
DURATION = 30.0
OPTIONS = HuxleyOptions(nav_rate=2.0)
HEADER = (
    "# Bluefin SPI exchange: pygoby's bluefin driver with bluefin_frontseat_simulator (nav 2 Hz)\n"
)


def record() -> str:
    steps, _, _ = run_exchange(DURATION, OPTIONS)
    return HEADER + format_exchange(steps)


def test_the_record_is_what_driver_and_simulator_exchange_today():
    assert RECORD.read_text() == record()


def test_replaying_the_record_against_the_driver():
    recorded = {step.t: step for step in parse_exchange(RECORD.read_text())}
    driver, link, clock = driver_on_memory()
    helm = Helm(driver)
    states = set()
    for n in range(round(DURATION / TICK) + 1):
        elapsed = round(n * TICK, 1)
        clock.set(T0 + elapsed)
        step = recorded.get(elapsed)
        for line in step.to_driver if step else []:
            link.feed(line + "\r\n")
        helm.act(elapsed)
        driver.do_work()
        written = [text.removesuffix("\r\n") for text in link.take_written()]
        assert written == (step.from_driver if step else []), f"at {elapsed} s"
        states.add(driver.state)
    assert frontseat_pb.INTERFACE_COMMAND in states
    assert any(
        line.startswith("$BPRMB,") and ",90,10,0,1.5,1,0*" in line
        for s in recorded.values()
        for line in s.from_driver
    )


if __name__ == "__main__":
    RECORD.parent.mkdir(parents=True, exist_ok=True)
    RECORD.write_text(record())
    print(f"wrote {RECORD}")
