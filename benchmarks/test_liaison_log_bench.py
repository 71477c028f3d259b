"""liaison over a recorded log (`make bench`): indexing a log (lines per second = 20k x ops; a
1 GB log of ~100-byte lines is ~10M lines), replaying it through the Scope, Acomms and Map
models, and one seek back (restore the nearest saved checkpoint, read on to the time)."""

from __future__ import annotations

from pathlib import Path

import pytest

from pygoby.moos.alog import AlogFormatter, banner
from pygoby.topside.liaison.log_app import open_replay
from pygoby.topside.liaison.log_feed import LogIndex

ROWS = 20_000
START = 1000.0
MISSION = Path(__file__).resolve().parents[1] / "tests" / "data" / "alog" / "acomms.moos"


@pytest.fixture(scope="module")
def alog(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """20k lines over 2000 s: navigation, node reports, and a modem reception every 50 lines."""
    fmt = AlogFormatter(START)
    path = tmp_path_factory.mktemp("liaison") / "bench.alog"
    lines = [banner(str(path), START)]
    heard = 'src: 2 dest: 1 type: DATA rate: 1 frame: "\\001\\253"'
    for i in range(ROWS):
        t = START + i * 0.1
        if i % 50 == 0:
            lines.append(fmt.line(t, "AC_MODEM_RECEIVE", "pAcommsHandler", heard))
        elif i % 2:
            lines.append(fmt.line(t, "NAV_X", "uSimMarine", i * 0.5))
        else:
            lines.append(fmt.line(t, "NODE_REPORT", "pNodeRep", f"NAME=alpha,X={i},Y=-3.2"))
    path.write_text("".join(lines))
    return path


@pytest.mark.benchmark(group="liaison-log")
def test_index_20k_lines(benchmark, alog):
    assert benchmark(LogIndex.build, alog).entries == ROWS


@pytest.mark.benchmark(group="liaison-log")
def test_replay_20k_lines_through_the_pages(benchmark, alog):
    def replay() -> int:
        feed, _ = open_replay(alog, MISSION)
        feed.run_to(feed.index.end_time)
        feed.close()
        return feed.applied

    assert benchmark.pedantic(replay, rounds=3) == ROWS


@pytest.mark.benchmark(group="liaison-log")
def test_seek_back_into_a_replayed_log(benchmark, alog):
    feed, _ = open_replay(alog, MISSION)
    feed.run_to(feed.index.end_time)

    def back_and_forth() -> None:
        feed.run_to(1234.5)
        feed.run_to(1999.0)

    benchmark(back_and_forth)
    feed.close()
