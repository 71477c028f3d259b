"""goby3's own Bluefin driver against pygoby's Huxley simulator, recorded in
tests/data/frontseat/bluefin_goby3_exchange.txt.

The record comes from a run of goby3 3.1.5a's C++ iFrontSeat with its bluefin plug-in
(libgoby_frontseat_bluefin.so.30, built outside the repository) and the C++ MOOSDB, connected to
`bluefin_frontseat_simulator` (nav 2 Hz) stepped on a 0.1 s grid kept to wall time, while
pHelmIvP was played by posting IVPHELM_STATE=DRIVE and DESIRED_HEADING/SPEED/DEPTH three times,
and the legacy MOOS variables asked for trim, buoyancy, a CTD sample, silent mode, an acoustic
message and the end of the payload behaviour (the record's header lists the posts).
Its lines are `<t> < <sentence>` (goby3 to the simulator), `<t> > <sentence>` (the simulator to
goby3), `<t> + connect` and `<t> - disconnect`, t in s after the UNIX time on the `# T0` line.

Replaying goby3's side against the simulator alone, on the same grid, must draw from it exactly
the recorded answers in the recorded order, so a change of the simulator shows without goby3.
"""

from __future__ import annotations

from collections import defaultdict
from pathlib import Path

from pygoby.frontseat.bluefin.simulator import HuxleyOptions, HuxleySimulator

RECORD = Path(__file__).resolve().parents[1] / "data" / "frontseat" / "bluefin_goby3_exchange.txt"
OPTIONS = HuxleyOptions(nav_rate=2.0)
TICK = 0.1  # s


def read_record() -> tuple[float, dict[float, list[str]], float]:
    """(T0, the events of each grid time in order, the last grid time)."""
    t0 = None
    events: dict[float, list[str]] = defaultdict(list)
    for line in RECORD.read_text().splitlines():
        if line.startswith("# T0 "):
            t0 = float(line.split()[2])
            continue
        if not line.strip() or line.startswith("#"):
            continue
        t_text, event = line.split(" ", 1)
        events[float(t_text)].append(event)
    assert t0 is not None, "the record names its T0"
    return t0, events, max(events)


def replay(t0: float, events: dict[float, list[str]], last: float) -> dict[float, list[str]]:
    """Our simulator stepped as the server steps it, fed goby3's recorded lines."""
    simulator = HuxleySimulator(OPTIONS)
    produced: dict[float, list[str]] = defaultdict(list)
    for n in range(round(last / TICK) + 1):
        t = round(n * TICK, 1)
        now = t0 + t
        out = produced[t]
        recorded = events.get(t, [])
        if "- disconnect" in recorded:
            out.append("- disconnect")
            simulator.disconnect()
        if "+ connect" in recorded:
            out.append("+ connect")
            out += [f"> {line}" for line in simulator.connect(now)]
        for event in recorded:
            if event.startswith("< "):
                out.append(event)
                out += [f"> {line}" for line in simulator.handle_line(event[2:], now)]
        out += [f"> {line}" for line in simulator.tick(now)]
    return produced


def test_the_simulator_answers_goby3s_driver_as_recorded():
    t0, events, last = read_record()
    produced = replay(t0, events, last)
    for t in sorted(set(events) | {t for t, out in produced.items() if out}):
        assert produced.get(t, []) == events.get(t, []), f"at {t} s"


def test_goby3s_driver_took_control_and_followed_the_helm():
    _, events, _ = read_record()
    from_goby3 = [event[2:] for t in sorted(events) for event in events[t] if event[0] == "<"]
    to_goby3 = [event[2:] for t in sorted(events) for event in events[t] if event[0] == ">"]
    assert any(line.startswith("$BFMSC,") for line in to_goby3)
    set_points = [line.split(",")[2:5] for line in from_goby3 if line.startswith("$BPRMB,")]
    # heading, depth, depth kind of each leg the helm asked for, in order
    legs = [["90", "10", "0"], ["180", "20", "0"], ["270", "5", "0"]]
    assert [leg for leg in legs if leg in set_points] == legs
    # every extra command of goby3's legacy translator reached the simulator and was done (2)
    for kind in ("TRM", "BOY", "CTD", "SIL", "TMR", "RCE"):
        assert any(line.startswith(f"$BP{kind},") for line in from_goby3), kind
        assert any(
            line.startswith("$BFACK,") and line.split(",")[2:6:3] == [kind, "2"]
            for line in to_goby3
        ), kind
    assert any(line.startswith("$BFTRM,") for line in to_goby3)
    assert any(line.startswith("$BFBOY,") for line in to_goby3)
    assert any(line.startswith("$BFMIS,") and "Stopped" in line for line in to_goby3)
