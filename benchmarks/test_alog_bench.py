"""MOOS .alog files (`make bench`): pLogger's cost per logged message (one formatted line) and
the reader's and `pygoby log convert`'s throughput (lines per second = rows x ops)."""

from __future__ import annotations

from pathlib import Path

import pytest

from pygoby.moos.alog import AlogFile, AlogFormatter, banner
from pygoby.moos.alog.tools import clip, convert, grep, summarize

ROWS = 20_000
FORMATTER = AlogFormatter(1000.0, log_aux_src=True)


@pytest.fixture(scope="module")
def alog(tmp_path_factory: pytest.TempPathFactory) -> Path:
    path = tmp_path_factory.mktemp("alog") / "bench.alog"
    lines = [banner(str(path), 1000.0)]
    for i in range(ROWS):
        if i % 2:
            lines.append(FORMATTER.line(1000 + i * 0.01, "NAV_X", "uSimMarine", i * 0.5))
        else:
            report = "NAME=alpha,X=12.5,Y=-3.2,SPD=1.5,HDG=90,TYPE=kayak"
            lines.append(FORMATTER.line(1000 + i * 0.01, "NODE_REPORT", "pNodeRep", report, "a"))
    path.write_text("".join(lines))
    return path


@pytest.mark.benchmark(group="alog")
def test_format_one_double_line(benchmark):
    benchmark(FORMATTER.line, 1001.25, "NAV_X", "uSimMarine", -12.5)


@pytest.mark.benchmark(group="alog")
def test_read_20k_lines(benchmark, alog):
    assert benchmark(lambda: sum(1 for _ in AlogFile(alog))) == ROWS


@pytest.mark.benchmark(group="alog")
@pytest.mark.parametrize("suffix", [".parquet", ".csv"])
def test_convert_20k_lines(benchmark, alog, tmp_path, suffix):
    assert benchmark(convert, [alog], tmp_path / f"out{suffix}") == ROWS


@pytest.mark.benchmark(group="alog")
def test_summary_20k_lines(benchmark, alog):
    table = benchmark(lambda: summarize(AlogFile(alog)))
    assert sum(row.count for row in table.values()) == ROWS


@pytest.mark.benchmark(group="alog")
def test_grep_20k_lines(benchmark, alog):
    assert benchmark(lambda: sum(1 for _ in grep(AlogFile(alog), ["NAV_*"]))) == ROWS // 2


@pytest.mark.benchmark(group="alog")
def test_clip_20k_lines(benchmark, alog, tmp_path):
    def clip_all() -> int:
        with open(tmp_path / "clip.alog", "w") as out:
            return clip(AlogFile(alog), 0.0, 1e9, out)

    assert benchmark(clip_all) == ROWS


ACOMMS_DATA = Path(__file__).resolve().parents[1] / "tests" / "data" / "alog"


@pytest.fixture(scope="module")
def acomms_alog(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """ROWS entries of the test mission's acomms variables (tests/data/alog: frames of two DCCL
    messages, $CACST lines, navigation), repeated from its handmade log."""
    entries = list(AlogFile(ACOMMS_DATA / "acomms.alog"))
    path = tmp_path_factory.mktemp("acomms") / "acomms.alog"
    formatter = AlogFormatter(0.0, mark_data_type=True, mark_binary=True)
    lines = [banner(str(path), 1000.0, mark_data_type=True, mark_binary=True)]
    for i in range(ROWS):
        entry = entries[i % len(entries)]
        lines.append(formatter.line(i * 0.01, entry.name, entry.source, entry.value))
    path.write_text("".join(lines))
    return path


@pytest.mark.benchmark(group="alog")
def test_decode_20k_acomms_lines(benchmark, acomms_alog):
    """`log convert --mission`'s decoding alone: every value through the mission's decoder."""
    from pygoby.moosacomms.alog_decode import MissionDecoder

    decode = MissionDecoder(ACOMMS_DATA / "acomms.moos")
    entries = list(AlogFile(acomms_alog))
    assert benchmark(lambda: sum(len(decode(entry)) for entry in entries)) > ROWS


@pytest.mark.benchmark(group="alog")
def test_plot_series_of_20k_acomms_lines(benchmark, acomms_alog):
    """`log plot`'s reading of a log into the series its figures draw."""
    from pygoby.moosacomms.alog_series import AcommsVariables, log_series

    variables = AcommsVariables.of_mission(ACOMMS_DATA / "acomms.moos", "pAcommsHandler")
    series = benchmark(log_series, [acomms_alog], variables)
    assert sum(len(times) for times in series.acked.values()) > 0
