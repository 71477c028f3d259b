"""The Huxley simulator alone (sans I/O): its answers to each payload sentence, the payload
control state machine, and no line making it raise."""

from __future__ import annotations

from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.frontseat.bluefin import sentences
from pygoby.frontseat.bluefin.simulator import HuxleyOptions, HuxleySimulator
from tests.hypothesis_profiles import examples

from .bluefin_scenario import T0


def say(sim: HuxleySimulator, token: str, *values: object, now: float = T0) -> list[str]:
    return sim.handle_line(sentences.build(token, values).message(), now)


def acks(lines: list[str]) -> list[tuple[str, str, str]]:
    """(sentence, status, description) of each $BFACK."""
    parsed = [sentences.parse(line) for line in lines]
    return [(s[2], s[5], s[7]) for s in parsed if s.sentence_id == "ACK"]


def test_acks_only_once_asked_and_by_status():
    sim = HuxleySimulator(HuxleyOptions(control_delay=1.0))
    sim.connect(T0)
    assert say(sim, "$BPSTS", "221320.000", 1, "Deploy") == []  # ACKs not asked for yet
    assert acks(say(sim, "$BPLOG", "ACK", "ON")) == [("LOG", "2", "")]
    assert acks(say(sim, "$BPXYZ", "221320.000")) == [("XYZ", "0", "unknown sentence")]
    assert acks(say(sim, "$BPLOG", "NVG")) == [
        ("LOG", "0", "expected a sentence name and ON or OFF")
    ]
    rmb = ("221320.000", 90, 10, 0, 1.5, 1, 0)
    assert acks(say(sim, "$BPRMB", *rmb)) == [("RMB", "1", "payload is not in control")]
    for name in ("MIS", "MSC", "CTL"):
        say(sim, "$BPLOG", name, "ON")
    assert sim.tick(T0 + 0.5) == []
    started = [sentences.parse(line).sentence_id for line in sim.tick(T0 + 1.0)]
    assert started == ["MIS", "MSC", "CTL"]
    assert acks(say(sim, "$BPRMB", *rmb)) == [("RMB", "2", "")]
    assert (sim.model.desired.heading, sim.model.desired.speed, sim.model.desired.z) == (
        90,
        1.5,
        -10,
    )
    say(sim, "$BPRMB", "221320.000", 0, 0, 2, 0, 0, 1)  # the stop request
    assert (sim.model.desired.heading, sim.model.desired.speed) == (90, 0)
    ended = [sentences.parse(line).fields[1:] for line in say(sim, "$BPRCE", "221321.000", 0)[1:]]
    assert [f[1:] for f in ended] == [("0",), ("payload_mission", "Stopped")]


def test_trim_is_pending_then_done_with_a_report():
    sim = HuxleySimulator()
    sim.connect(T0)
    for name in ("ACK", "TRM"):
        say(sim, "$BPLOG", name, "ON")
    assert acks(say(sim, "$BPTRM", "221320.000")) == [("TRM", "3", "")]
    report = sim.tick(T0 + 0.1)
    assert acks(report) == [("TRM", "2", "")]
    assert sentences.parse(report[1]).fields[2:] == ("2", "0", "trim done", "0.5", "0")


@settings(max_examples=examples(200))
@given(st.text(max_size=100), st.floats(min_value=0, max_value=4e9))
def test_no_line_makes_it_raise(line, now):
    sim = HuxleySimulator()
    sim.connect(now)
    sim.handle_line("$BPLOG,ACK,ON", now)
    sim.handle_line(line, now)
    sim.handle_line("$BP" + line, now)
    sim.tick(now + 1)
