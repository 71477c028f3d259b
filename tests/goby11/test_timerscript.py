"""uTimerScript (MOOS-IvP semantics) sans I/O, its logic conditions, and the app on the
embedded MOOSDB with seed 003's basic_ccl block."""

from __future__ import annotations

import asyncio
import random

import pytest
from google.protobuf import text_format

from pygoby.acomms import messages as acomms_pb
from pygoby.apps.utimerscript import uTimerScript
from pygoby.errors import ConfigError
from pygoby.moos.client import MOOSClient
from pygoby.moos.db import MOOSDB
from pygoby.moos.logic import LogicCondition
from pygoby.moos.moosfile import MissionFile, Setting
from pygoby.moos.timerscript import TimerScript, parse_value, split_quoted
from tests.goby11.seed_listings import EXAMPLES


def script(*lines: str, seed: int = 1) -> TimerScript:
    return TimerScript(
        [Setting(*(s.strip() for s in line.split("=", 1))) for line in lines], random.Random(seed)
    )


def run(ts: TimerScript, times) -> list[tuple[float, str, object]]:
    return [(t, p.var, p.value) for t in times for p in ts.tick(t)]


def test_seed_event_with_escaped_quotes_posts_the_modem_data_text():
    block = MissionFile.read(EXAMPLES / "MOOS" / "basic_ccl" / "mm1.moos").process_config(
        "uTimerScript", keep_quotes=True
    )
    ts = TimerScript(block)
    posts = run(ts, [100, 109.9, 110, 110.5, 120.4, 120.5])
    # RESET_TIME = end: the script restarts at the tick after the last post (110.5)
    assert [(t, var) for t, var, _ in posts] == [(110, "OUT_TEST_32B"), (120.5, "OUT_TEST_32B")]
    data = acomms_pb.V1ModemDataTransmission()
    text_format.Parse(posts[0][2], data)
    assert posts[0][2] == 'data: "\\002\\002\\003\\004"' and data.data == b"\x02\x02\x03\x04"


def test_values_and_splitting():
    assert parse_value(" 3.5 ") == (3.5, False)
    assert parse_value('"3.5"') == ("3.5", True)
    assert parse_value("hello world") == ("hello world", False)
    assert split_quoted('var=A, val="x,y", time=1') == ["var=A", ' val="x,y"', " time=1"]
    assert split_quoted("var=A, val={1,2}, time=1") == ["var=A", " val={1,2}", " time=1"]


def test_time_ranges_amt_macros_and_quoted_numbers():
    ts = script(
        "EVENT = var=R, val=$(COUNT), time=2:4, amt=3",
        'EVENT = var=Q, val="7", time=1',
        "EVENT = var=N, val=idx$(IDX)t$(DBTIME), time=5",
        "EVENT = var=U, val=$(UTC), time=5",
    )
    posts = run(ts, [10 + i * 0.5 for i in range(13)])
    times = [e.time for e in ts.events if e.var == "R"]  # drawn when the script starts
    assert len(times) == 3 and all(2 <= t <= 4 for t in times)
    assert ("Q", "7") in [(v, x) for _, v, x in posts]  # quoted: a string
    assert sorted(x for _, v, x in posts if v == "R") == [2.0, 3.0, 4.0]
    assert ("N", "idx004t5.00") in [(v, x) for _, v, x in posts]
    assert ("U", 15.0) in [(v, x) for _, v, x in posts]  # the whole value is a macro: a double


def test_reset_time_number_and_reset_max():
    ts = script("EVENT = var=A, val=1, time=1", "RESET_TIME = 3", "RESET_MAX = 2")
    posts = run(ts, range(0, 20))
    assert [t for t, _, _ in posts] == [1, 5, 9]  # resets at 3 s (twice), then stops
    assert ts.reset_count == 2


def test_paused_forward_and_reset_variables():
    ts = script("EVENT = var=A, val=a, time=10", "EVENT = var=B, val=b, time=20", "PAUSED = true")
    assert run(ts, [0, 5, 30]) == []
    ts.on_mail("UTS_PAUSE", "false")
    assert run(ts, [31, 39.9]) == []  # the 30 s paused do not count
    ts.on_mail("UTS_FORWARD", 0.0)  # jump to the next event
    assert [v for _, v, _ in run(ts, [40])] == ["A"]
    ts.on_mail("UTS_FORWARD", 100.0)
    assert [v for _, v, _ in run(ts, [42])] == ["B"]
    ts.on_mail("UTS_RESET", "reset")
    assert run(ts, [43]) == [] and ts.reset_count == 1
    ts.on_mail("UTS_PAUSE", "toggle")
    assert ts.paused


def test_conditions_and_upon_awake():
    ts = script(
        "EVENT = var=GO, val=go, time=2",
        "CONDITION = (DEPLOY = true) and (NAV_DEPTH > 5)",
        "UPON_AWAKE = restart",
    )
    assert ts.subscriptions() == ["DEPLOY", "NAV_DEPTH", "UTS_FORWARD", "UTS_PAUSE", "UTS_RESET"]
    assert run(ts, [0, 10]) == []
    ts.on_mail("DEPLOY", "true")
    ts.on_mail("NAV_DEPTH", 10.0)
    assert run(ts, [11, 12.9]) == [] and [v for _, v, _ in run(ts, [13])] == ["GO"]


@pytest.mark.parametrize(
    ("condition", "values", "expected"),
    [
        ("X = 5", {"X": 5.0}, True),
        ("X = 5", {"X": "5"}, True),
        ("X = 5", {"X": "five"}, False),
        ("X == abc", {"X": "ABC"}, True),
        ("X = abc", {"X": "ABC"}, False),
        ('X = "a b"', {"X": "a b"}, True),
        ("X != 1", {"X": 2.0}, True),
        ("X <= 1", {"X": 1.0}, True),
        ("X < 1", {"X": 1.0}, False),
        ("X >= 2", {"X": 3.0}, True),
        ("X > $(Y)", {"X": 3.0, "Y": 2.0}, True),
        ("X > $(Y)", {"X": 3.0}, False),
        ("X = 1", {}, False),
        ("!(X = 1)", {"X": 2.0}, True),
        ("(X = 1) or (Y = 2)", {"Y": 2.0}, True),
        ("(X = 1) and ((Y = 2) or (Z = 3))", {"X": 1.0, "Z": 3.0}, True),
    ],
)
def test_logic_conditions(condition, values, expected):
    assert LogicCondition(condition).evaluate(values) is expected


@pytest.mark.parametrize(
    ("setting", "reason"),
    [
        ("EVENT = var=A, time=1", "has no val="),
        ("EVENT = val=1, time=1", "has no var="),
        ("EVENT = var=A, val=1, time=5:2", "need 0 <= A <= B"),
        ("EVENT = var=A, val=1, when=2", "unknown field 'when'"),
        ("EVENT = var=A, val=1, amt=0", "amt must be a positive count"),
        ("RESET_TIME = soon", "RESET_TIME: must be"),
        ("RESET_MAX = many", "RESET_MAX: must be"),
        ("PAUSED = maybe", "PAUSED: must be true or false"),
        ("UPON_AWAKE = sleep", "UPON_AWAKE: must be"),
        ("CONDITION = (X = 1", "unbalanced parentheses"),
        ("CONDITION = X", "is not a relation"),
        ("STATUS_VAR = a b", "must be a variable name"),
    ],
)
def test_configuration_errors(setting, reason):
    with pytest.raises(ConfigError, match=reason):
        script(setting)


def test_quit_event_and_unknown_parameters():
    ts = script("EVENT = quit, time=1", "FOO = 3")
    assert ts.warnings == ["unknown uTimerScript parameter 'foo' ignored"]
    assert [(v, x) for _, v, x in run(ts, [0, 1])] == [
        ("EXITED_NORMALLY", "uTimerScript")
    ] and ts.quit


async def test_app_posts_the_seed_script_on_the_embedded_moosdb(tmp_path):
    mission_text = (EXAMPLES / "MOOS" / "basic_ccl" / "mm1.moos").read_text()
    async with MOOSDB(port=0) as db, MOOSClient("tester", port=db.port) as tester:
        path = tmp_path / "mm1.moos"
        path.write_text(
            mission_text.replace("ServerPort = 9101", f"ServerPort = {db.port}").replace(
                "LongOrigin = 0", "LongOrigin = 0\nMOOSTimeWarp = 20"
            )
        )
        tester.subscribe("OUT_TEST_32B")
        tester.subscribe("UTS_STATUS")
        app = uTimerScript.from_mission(path)
        assert app.cfg.common.time_warp_multiplier == 20 and not app.cfg.common.log
        async with app:
            got: dict[str, list] = {}
            while len(got.get("OUT_TEST_32B", [])) < 2 or "UTS_STATUS" not in got:
                msg = await tester.receive(5)
                got.setdefault(msg.key, []).append(msg.value)
        assert got["OUT_TEST_32B"][:2] == ['data: "\\002\\002\\003\\004"'] * 2
        assert got["UTS_STATUS"][0].startswith("name=unnamed, elapsed_time=")


def test_app_configuration_error_names_the_mission_line_and_setting(tmp_path):
    path = tmp_path / "bad.moos"
    path.write_text(
        "ServerPort = 9000\nProcessConfig = uTimerScript\n{\n  EVENT = var=X, val=1\n"
        "  EVENT = var=OUT, vla=3, time=1\n}\n"
    )
    with pytest.raises(ConfigError) as caught:
        uTimerScript.from_mission(path)
    assert str(caught.value) == (
        f"{path}:5: EVENT: 'var=OUT, vla=3, time=1': unknown field 'vla' "
        "(var, val, time, amt, quit)"
    )
    assert (caught.value.line, caught.value.field) == (5, "EVENT")
    path.write_text("ServerPort = 9000\nProcessConfig = uTimerScript\n{\n  AppTick = fast\n}\n")
    with pytest.raises(
        ConfigError, match=rf"^{path}:4: AppTick: must be a positive number, not 'fast'$"
    ):
        uTimerScript.from_mission(path)
    assert asyncio.iscoroutinefunction(uTimerScript.start)


def test_example_config_is_a_block_utimerscript_reads(tmp_path):
    """`uTimerScript --example_config` prints MOOS-IvP's `name = value` lines, which load and
    post as their comments say."""
    block = uTimerScript.example_config("uTimerScript")
    assert block.startswith("ProcessConfig = uTimerScript\n{\n") and "common" not in block
    path = tmp_path / "example.moos"
    path.write_text(f"ServerPort = 1\nCommunity = ex\n{block}")
    ts = TimerScript(MissionFile.read(path).process_config("uTimerScript", keep_quotes=True))
    assert not ts.warnings
    ts.on_mail("DEPLOY", "true")
    posts = run(ts, [0, 10, 30])
    assert [(t, var, value) for t, var, value in posts] == [
        (10, "OUT_TEST", 3.5),
        (30, "OUT_TEXT", 'data: "x"'),
    ]
