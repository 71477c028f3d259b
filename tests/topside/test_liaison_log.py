"""liaison over a recorded mission (`pygoby liaison --log`): the log index, the feed's seeks
against reading the log from its start, the player on virtual time, and the errors for files
it cannot replay. No server here (test_liaison_log_web.py serves it)."""

from __future__ import annotations

import gzip
import itertools
import json
import math
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.errors import PygobyError
from pygoby.moos import protocol as p
from pygoby.moos.alog.files import AlogFile
from pygoby.moos.alog.format import AlogFormatter, banner
from pygoby.topside.errors import LogControlError, LogFileError
from pygoby.topside.liaison.log_app import open_replay
from pygoby.topside.liaison.log_feed import SPEEDS, STEP_BUDGET, LogFeed, LogIndex, LogPlayer
from pygoby.util.clock import VirtualClock
from tests.hypothesis_profiles import examples

DATA = Path(__file__).resolve().parents[1] / "data" / "alog"
LOG, MISSION = DATA / "liaison.alog", DATA / "acomms.moos"
START = 1764643673.12


def write_long_log(path: Path, seconds: int = 400) -> Path:
    """A log of `seconds` s: navigation every second, a transmission and a reception (with
    the mission's AC_ names) every 7 s, queue sizes, a variable posted once at the start, a
    pair of lines out of time order every 50 s and a damaged line every 100 s."""
    fmt = AlogFormatter(START)
    lines = [banner(path.name, START), fmt.line(START + 0.1, "MODEM_ID", "pAcommsHandler", 1.0)]
    for second in range(seconds):
        t = START + second
        lines.append(fmt.line(t + 0.2, "NAV_X", "uSimVehicle", 3.0 * second))
        lines.append(fmt.line(t + 0.2, "NAV_Y", "uSimVehicle", -1.5 * second))
        if second % 7 == 0:
            frame = f'src: 1 dest: 2 type: DATA rate: 1 frame: "\\00{second % 8}"'
            lines.append(fmt.line(t + 0.3, "AC_MODEM_TRANSMIT", "pAcommsHandler", frame))
            lines.append(
                fmt.line(t + 0.4, "AC_QSIZE", "pAcommsHandler", f"dccl_id: 20 size: {second % 5}")
            )
        if second % 7 == 3:
            heard = 'src: 2 dest: 1 type: DATA rate: 1 frame: "\\001"'
            lines.append(fmt.line(t + 0.5, "AC_MODEM_RECEIVE", "pAcommsHandler", heard))
        if second % 50 == 10:
            lines.append(fmt.line(t + 0.9, "LATE", "uTimerScript", f"late {second}"))
            lines.append(fmt.line(t + 0.6, "EARLY", "uTimerScript", f"early {second}"))
        if second % 100 == 40:
            lines.append("damaged: not a line of pLogger's\n")
    path.write_text("".join(lines))
    return path


def pages(feed: LogFeed, now: float | None = None) -> tuple:
    """What the Scope, Acomms and Map pages show (as the web layer builds them) at `now`
    (default: the state's clock, the log time the feed is at)."""
    state = feed.state
    now = state.now() if now is None else now
    return state.scope.rows_json(now), state.page("acomms", now), state.page("map", now)


def pages_read_from_start(path: Path, t: float) -> tuple:
    """The pages at log time `t` of a fresh replay state fed the log from its first line up to
    its first entry later than `t` (not through the feed's checkpoints)."""
    feed, _ = open_replay(path, MISSION)  # its state: every entry is applied here, none by it
    for entry in AlogFile(path):
        if entry.time > t:
            break
        feed.state.show(
            p.notify(
                entry.name,
                entry.value,
                time=START + entry.time,
                src=entry.source,
                src_aux=entry.source_aux,
                community=entry.community or feed.community,
            )
        )
    shown = pages(feed, START + t)
    feed.close()
    return shown


# ---------------------------------------------------------------------------------- the index
def test_the_index_counts_entries_and_damaged_lines_and_finds_the_community():
    index = LogIndex.build(LOG, spacing=5.0)
    assert (index.entries, index.bad_lines) == (223, 1)
    assert index.end_time == pytest.approx(60.2) and index.log_start == pytest.approx(START)
    assert index.community == "logtest"  # from MOOSDB_logtest's DB_TIME
    # checkpoints: the start, then about every 5 s of log time, in file order
    assert index.checkpoints[0].offset == 0 and index.checkpoints[0].time == -math.inf
    times = [c.time for c in index.checkpoints[1:]]
    assert times == sorted(times) and all(b - a > 5.0 - 1e-9 for a, b in itertools.pairwise(times))
    assert 10 <= len(index.checkpoints) <= 13


def test_the_index_is_bounded_whatever_the_logs_length(tmp_path):
    path = write_long_log(tmp_path / "long.alog", 2000)
    index = LogIndex.build(path, spacing=1.0, max_checkpoints=16)
    assert len(index.checkpoints) <= 16
    assert index.spacing >= 2000 / 16  # doubled as often as needed
    # a checkpoint's offset starts an entry no earlier than its time says
    for checkpoint in index.checkpoints[1:]:
        offset, entry = next(AlogFile(path).scan(checkpoint.offset))
        assert offset == checkpoint.offset and entry.time >= checkpoint.time - 1.0


def test_scan_from_an_offset_gives_the_rest_of_the_log(tmp_path):
    for path in (LOG, _gzipped(LOG, tmp_path)):
        whole = list(AlogFile(path).scan())
        offset, first = whole[100]
        assert list(AlogFile(path).scan(offset)) == whole[100:], path
        assert first.name in ("NAV_X", "NAV_Y", "NAV_HEADING", "AC_QSIZE", "AC_MODEM_RECEIVE")


def _gzipped(path: Path, tmp_path: Path) -> Path:
    out = tmp_path / (path.name + ".gz")
    out.write_bytes(gzip.compress(path.read_bytes()))
    return out


# ---------------------------------------------------------------------------------- the feed
def test_the_pages_at_a_time_are_the_logs_values_then():
    feed, _ = open_replay(LOG, MISSION, spacing=5.0)
    feed.run_to(25.0)
    scope, acomms, map_page = pages(feed)
    assert json.loads(scope["NAV_X"])["value"] == "58"  # 10 + 2 x 24.2 s, posted at 24.2
    assert json.loads(scope["MODEM_ID"])["value"] == "1"  # posted once, at 0.1 s
    assert "MISSION_PHASE" not in scope  # first posted at 30.3 s
    assert [row["time"] - START for row in acomms["tx"]] == pytest.approx([15.5, 5.5])
    assert [row["snr_in"] for row in acomms["rx"]] == [11, 10]
    own = next(n for n in map_page["nodes"] if n["name"] == "logtest")
    assert (own["x"], own["y"]) == (58.0, -29.0)
    feed.advance(5.0)  # on to 30 s: NAV_X of 29.2 s
    while not feed.step():
        pass
    assert feed.time == 30.0 and json.loads(pages(feed)[0]["NAV_X"])["value"] == "68"
    feed.run_to(50.0)
    scope, acomms, _ = pages(feed)
    assert json.loads(scope["MISSION_PHASE"])["value"] == "return"  # after the damaged line
    assert feed.bad_lines == 1
    feed.close()


@pytest.mark.parametrize(
    "times",
    [
        [120.0, 30.0],  # back, between checkpoints
        [399.0, 0.0, 250.5],  # to the end, to the start, forwards past saved checkpoints
        [60.3, 60.9, 60.6, 10.95],  # inside a pair of lines out of time order
        [200.0, 199.0, 201.0, 140.4],
    ],
)
def test_seeking_anywhere_gives_the_pages_read_from_the_start(tmp_path, times):
    path = write_long_log(tmp_path / "long.alog")
    feed, _ = open_replay(path, MISSION, spacing=3.0, max_snapshots=8)
    for t in times:
        feed.run_to(t)
        assert pages(feed) == pages_read_from_start(path, t), t
    feed.close()


@settings(max_examples=examples(25), deadline=None)
@given(times=st.lists(st.floats(0, 120, allow_nan=False), min_size=1, max_size=5))
def test_random_seeks_give_the_pages_read_from_the_start(times):
    feed, _ = open_replay(LOG, MISSION, spacing=4.0, max_snapshots=4)
    try:
        for t in times:
            feed.run_to(t)
        t = min(times[-1], feed.index.end_time)
        assert pages(feed) == pages_read_from_start(LOG, t)
    finally:
        feed.close()


def test_going_back_reads_from_the_nearest_saved_checkpoint_only(tmp_path):
    path = write_long_log(tmp_path / "long.alog", 1000)
    feed, _ = open_replay(path, MISSION, spacing=10.0, max_snapshots=6)
    feed.run_to(999.0)
    saved = feed.saved_checkpoints
    assert len(saved) <= 7  # the start, and at most max_snapshots others
    feed.run_to(700.0)
    # at most the entries between two saved checkpoints (the log has fewer than 5 a second)
    seconds_apart = max(b - a for a, b in itertools.pairwise(saved)) * 10.0
    assert 0 < feed.applied <= 5 * seconds_apart
    feed.close()


def test_a_seek_is_done_over_steps_of_bounded_work(tmp_path):
    path = write_long_log(tmp_path / "long.alog")
    feed, _ = open_replay(path, MISSION)
    feed.seek(300.0)
    steps, before = 0, feed.applied
    while not feed.step(budget=100):
        assert feed.applied - before == 100  # each step reads its budget of entries, no more
        assert feed.time < 300.0 and not feed.caught_up  # the pages say how far they got
        steps, before = steps + 1, feed.applied
    assert steps >= 5 and feed.time == 300.0 and feed.caught_up
    feed.close()


# ---------------------------------------------------------------------------------- the player
def test_one_update_reads_the_log_for_its_work_time_only(tmp_path):
    path = write_long_log(tmp_path / "long.alog", 2000)
    feed, _ = open_replay(path, MISSION)
    player = LogPlayer(feed, VirtualClock(), work_seconds=0.0)  # one step per update
    player.seek(1999.0)
    player.update()
    assert feed.applied == STEP_BUDGET and not feed.caught_up
    updates = 1
    while not feed.caught_up:
        player.update()
        updates += 1
    assert updates == math.ceil(feed.applied / STEP_BUDGET) >= 4
    feed.close()


def test_the_player_follows_the_clock_at_its_speed_and_stops_at_the_end():
    feed, _ = open_replay(LOG, MISSION)
    clock = VirtualClock(1000.0)
    player = LogPlayer(feed, clock)
    player.seek(10.0)
    player.update()
    assert player.status()["time"] == 10.0 and not player.playing
    clock.advance(5.0)
    player.update()
    assert feed.time == 10.0  # paused: the log time stays
    player.set_speed(10.0)
    player.play()
    clock.advance(2.0)
    player.update()
    assert feed.time == pytest.approx(30.0)
    assert json.loads(feed.state.scope.rows_json(feed.state.now())["NAV_X"])["value"] == "68"
    player.pause()
    clock.advance(100.0)
    player.update()
    assert feed.time == pytest.approx(30.0)
    player.play()
    clock.advance(10.0)
    player.update()
    status = player.status()
    assert status["time"] == pytest.approx(60.2) and not status["playing"]  # the end pauses
    player.play()  # from the end: again from the start
    assert feed.target == 0.0 and player.playing
    with pytest.raises(LogControlError, match="speed 3 is not one of"):
        player.set_speed(3.0)
    with pytest.raises(LogControlError):
        player.seek(math.nan)
    assert 1.0 in SPEEDS and 10.0 in SPEEDS
    feed.close()


# ---------------------------------------------------------------------------------- errors
def test_files_that_cannot_be_replayed_are_refused_clearly(tmp_path):
    binary = tmp_path / "program.alog"
    binary.write_bytes(bytes(range(256)) * 40)
    empty = tmp_path / "empty.alog"
    empty.write_bytes(b"")
    no_newline = tmp_path / "one-line.alog"
    no_newline.write_bytes(b"x" * (3 << 20))  # no newline, no columns
    cases = {
        empty: "empty",
        no_newline: "not a MOOS .alog",
        tmp_path / "missing.alog": "no such file",
        tmp_path: "not a file",
        binary: "not a MOOS .alog",
    }
    for path, reason in cases.items():
        with pytest.raises(LogFileError, match=reason) as caught:
            open_replay(path)
        assert isinstance(caught.value, PygobyError) and str(path) in str(caught.value)
    with pytest.raises(LogFileError, match="no such mission file"):
        open_replay(LOG, tmp_path / "missing.moos")
    bad_gz = tmp_path / "cut.alog.gz"
    bad_gz.write_bytes(b"\x1f\x8b\x08\x00garbage")
    with pytest.raises(LogFileError, match="cannot read"):
        open_replay(bad_gz)


def test_the_command_line_says_what_is_wrong_without_a_traceback(tmp_path, capsys):
    from pygoby.cli import main

    assert main(["liaison", "--log", str(tmp_path / "nothing.alog")]) == 1
    err = capsys.readouterr().err
    assert f"pygoby liaison: {tmp_path / 'nothing.alog'}: no such file" in err
    assert "Traceback" not in err
    with pytest.raises(SystemExit):
        main(["liaison", "--log", str(LOG), "--port", "70000"])
    assert "70000 is no TCP port" in capsys.readouterr().err
