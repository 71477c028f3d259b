"""The .alog format (pLogger's layout), its reader on damaged files, and `pygoby log`'s tools."""

from __future__ import annotations

import asyncio
import csv
import functools
import gzip
import json
import math
from pathlib import Path

import pyarrow.parquet as pq
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.cli import main as pygoby_main
from pygoby.errors import ConfigError
from pygoby.moos.alog import AlogFile, AlogFormatter, AlogReader, AlogSink, banner
from pygoby.moos.alog.logger_config import parse_log_request, read_logger_config
from pygoby.moos.alog.tools import LogToolError, convert, summarize
from pygoby.moos.moosfile import Setting
from tests.hypothesis_profiles import examples

LOG_START = 1764643673.125

# pLogger's layout: time (fixed, 3 decimals) in 15 columns, variable in 20, source in 15, each
# followed by a space; doubles fixed with 5 decimals left-justified in 12 columns; every value
# followed by one space. The banner's LOGSTART is 12 significant digits right-aligned in 20.
EXPECTED = (
    "%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%\n"
    "%% LOG FILE:       ./MOOSLog/MOOSLog.alog\n"
    "%% FILE OPENED ON  {opened}\n"
    "%% LOGSTART               1764643673.12\n"
    "%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%\n"
    "0.375           NAV_X                uSimMarine      -12.25000    \n"
    "1.000           DEPLOY               pMarineViewer   true \n"
    "12.500          VIEW_POINT           pHelmIvP:waypt  x=1,y=2,label=a b \n"
    "123.457         A_VERY_LONG_VARIABLE_NAME_X pNodeReporter@alpha 1234567.12346 \n"
)


def sample_log(opened: str) -> str:
    fmt = AlogFormatter(LOG_START, log_aux_src=True, mark_external=True, own_community="shore")
    return (
        banner("./MOOSLog/MOOSLog.alog", LOG_START, opened_on=0.0)
        + fmt.line(LOG_START + 0.375, "NAV_X", "uSimMarine", -12.25)
        + fmt.line(LOG_START + 1, "DEPLOY", "pMarineViewer", "true", community="shore")
        + fmt.line(LOG_START + 12.5, "VIEW_POINT", "pHelmIvP", "x=1,y=2,label=a b", "waypt")
        + fmt.line(
            LOG_START + 123.4567,
            "A_VERY_LONG_VARIABLE_NAME_X",
            "pNodeReporter",
            1234567.123456,
            community="alpha",
        )
    )


def test_lines_are_padded_as_plogger_pads_them() -> None:
    import time

    assert sample_log(time.ctime(0)) == EXPECTED.format(opened=time.ctime(0))


def test_reader_gets_back_what_was_written() -> None:
    reader = AlogReader()
    entries = [e for line in sample_log("").splitlines() if (e := reader.feed(line))]
    assert reader.log_start == 1764643673.12  # %.12g of an exact tie rounds to even
    assert reader.bad_lines == 0
    assert [(e.time, e.name, e.source, e.source_aux, e.community, e.value) for e in entries] == [
        (0.375, "NAV_X", "uSimMarine", "", "", -12.25),
        (1.0, "DEPLOY", "pMarineViewer", "", "", "true"),
        (12.5, "VIEW_POINT", "pHelmIvP", "waypt", "", "x=1,y=2,label=a b"),
        (123.457, "A_VERY_LONG_VARIABLE_NAME_X", "pNodeReporter", "", "alpha", 1234567.12346),
    ]
    assert entries[2].full_source == "pHelmIvP:waypt"


def test_data_type_marking_keeps_numeric_strings_strings() -> None:
    fmt = AlogFormatter(0.0, mark_data_type=True, double_precision=2)
    reader = AlogReader()
    for line in banner("f", 0.0, mark_data_type=True).splitlines():
        reader.feed(line)
    assert (
        fmt.line(1.0, "A", "s", 3.5)
        == "1.000           A                    s               D:3.50         \n"
    )
    assert reader.feed(fmt.line(1.0, "A", "s", "3.5")).value == "3.5"
    assert reader.feed(fmt.line(1.0, "A", "s", 3.5)).value == 3.5
    # without marking, a value that is a number is read as a double (as MOOS-IvP's tools do)
    assert AlogReader().feed(AlogFormatter(0.0).line(1.0, "A", "s", "3.5")).value == 3.5
    # ... as pLogger writes doubles (fixed digits, inf, nan) and MOOS-IvP's isNumber takes
    # numbers: with an exponent it is a string (pLogger never writes a double so)
    plain = AlogFormatter(0.0)
    for text in ("1e5", "2E-3", "0x10", "1.2.3"):
        assert AlogReader().feed(plain.line(1.0, "A", "s", text)).value == text
    for text, double in (("12.", 12.0), (".5", 0.5), ("-7", -7.0), ("-inf", -math.inf)):
        assert AlogReader().feed(plain.line(1.0, "A", "s", text)).value == double
    assert math.isnan(AlogReader().feed(plain.line(1.0, "A", "s", "-nan")).value)
    assert AlogReader().feed(plain.line(1.0, "A", "s", math.inf)).value == math.inf


def test_binary_inline_hex_and_through_the_blog(tmp_path: Path) -> None:
    fmt = AlogFormatter(0.0, mark_binary=True)
    assert fmt.line(2.0, "B", "s", b"\x00\xff") == (
        "2.000           B                    s               B:00FF \n"
    )
    sink = AlogSink(tmp_path, "L", lambda name: banner(name, 100.0))
    plain = AlogFormatter(100.0)
    sink.put_line(plain.line(101.0, "TEXT", "src", "a"))
    sink.put_binary(plain.prefix(102.0, "RAW", "src"), b"\x01\n\x02 \xfe")
    sink.put_line(plain.line(103.0, "X", "src", 7.0))
    sink.close()
    text = (tmp_path / "L.alog").read_text()
    # as pLogger: the .blog holds the line's prefix, then the bytes and a newline; the .alog line
    # ends right after the tag (no space), the offset being where the bytes start in the .blog
    prefix = plain.prefix(102.0, "RAW", "src")
    assert (
        prefix + f"<MOOS_BINARY>File=L.blog,Offset={len(prefix)},Bytes=5</MOOS_BINARY>\n"
    ) in text
    assert (tmp_path / "L.blog").read_bytes() == prefix.encode() + b"\x01\n\x02 \xfe\n"
    assert [e.value for e in AlogFile(tmp_path / "L.alog")] == ["a", b"\x01\n\x02 \xfe", 7.0]
    (tmp_path / "L.blog").unlink()
    log = AlogFile(tmp_path / "L.alog")
    assert [e.type for e in log] == ["string", "binary", "double"]
    assert log.unresolved_binary == 1


def test_sink_rotates_and_compresses(tmp_path: Path) -> None:
    sink = AlogSink(tmp_path, "R", lambda name: banner(name, 0.0), max_bytes=2000, compress=True)
    fmt = AlogFormatter(0.0)
    for i in range(100):
        sink.put_line(fmt.line(float(i), "COUNT", "me", float(i)))
    sink.close()
    assert [f.name for f in sink.files[:3]] == ["R.alog.gz", "R_1.alog.gz", "R_2.alog.gz"]
    assert all(len(gzip.decompress(f.read_bytes())) <= 2000 for f in sink.files)
    values = [e.value for f in sink.files for e in AlogFile(f)]
    assert values == [float(i) for i in range(100)]
    assert {AlogFile(f).log_start for f in sink.files} == {0.0}


async def test_sink_flushes_without_being_closed(tmp_path: Path) -> None:
    # a logger killed with -9 loses at most the lines of its last flush period
    sink = AlogSink(tmp_path, "F", lambda name: banner(name, 0.0))
    sink.put_line(AlogFormatter(0.0).line(1.0, "ALIVE", "me", 1.0))
    try:
        for _ in range(100):
            if [e.name for e in AlogFile(tmp_path / "F.alog")] == ["ALIVE"]:
                break
            await asyncio.sleep(0.05)
        assert [e.name for e in AlogFile(tmp_path / "F.alog")] == ["ALIVE"]
    finally:
        sink.close()


def test_sink_drops_and_counts_when_its_buffer_is_full(tmp_path: Path) -> None:
    sink = AlogSink(tmp_path, "D", lambda name: banner(name, 0.0), max_pending=3)
    with sink._cond:  # hold the writer thread off, as a stalled disk would
        accepted = [sink.put_line(f"{i}.000 V s {i} \n") for i in range(5)]
    sink.close()
    assert accepted == [True, True, True, False, False] and sink.dropped == 2
    assert len(list(AlogFile(tmp_path / "D.alog"))) == 3


def test_damaged_file_is_read_to_the_end(tmp_path: Path) -> None:
    path = tmp_path / "bad.alog"
    path.write_bytes(
        banner("bad", 10.0).encode()
        + b"1.000 A s 1 \n"
        + b"garbage\n"
        + b"x.0 A s 2 \n"
        + b"\xff\xfe\x00 \n"
        + b"2.000 B s caf\xc3\xa9 \xff \n"
        + b"3.000 C"  # cut mid-line
    )
    log = AlogFile(path)
    entries = list(log)
    assert [e.name for e in entries] == ["A", "B"]
    assert entries[1].value.encode("utf-8", "surrogateescape") == b"caf\xc3\xa9 \xff"
    assert log.reader.bad_lines == 4 and log.reader.first_bad_line == 7


def test_an_over_long_line_is_skipped_in_bounded_memory(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    import pygoby.moos.alog.files as files

    monkeypatch.setattr(files, "MAX_LINE_BYTES", 64)
    path = tmp_path / "long.alog"
    path.write_bytes(b"1.000 A s " + b"x" * 1000 + b"\n2.000 B s ok \n")
    log = AlogFile(path)
    assert [(e.name, e.value) for e in log] == [("B", "ok")]
    assert (log.reader.bad_lines, log.reader.first_bad_line) == (1, 1)
    assert [e.name for e in log] == ["B"] and log.reader.bad_lines == 1  # a second pass


@settings(max_examples=examples(300), deadline=None)
@given(st.lists(st.binary(max_size=80) | st.text(max_size=80), max_size=20))
def test_reader_never_raises(lines: list[bytes | str]) -> None:
    reader = AlogReader()
    for line in lines:
        text = line.decode("utf-8", "surrogateescape") if isinstance(line, bytes) else line
        entry = reader.feed(text)
        if entry is not None:
            assert math.isfinite(entry.time) and entry.name and entry.source


@settings(max_examples=examples(100), deadline=None)
@given(st.binary(max_size=400), st.integers(0, 400), st.integers(10, 400))
def test_damaged_files_plain_or_gz_never_raise(data: bytes, cut: int, flip: int) -> None:
    import tempfile

    with tempfile.TemporaryDirectory() as folder:
        plain = Path(folder) / "f.alog"
        plain.write_bytes(banner("f", 1.0).encode() + data)
        packed = Path(folder) / "f.alog.gz"
        packed.write_bytes(gzip.compress(plain.read_bytes())[:cut])  # cut mid-stream
        garbled = Path(folder) / "g.alog.gz"
        compressed = bytearray(gzip.compress(plain.read_bytes()))
        compressed[flip % len(compressed)] ^= 0x5A
        garbled.write_bytes(compressed)
        for path in (plain, packed, garbled):
            log = AlogFile(path)
            entries = list(log)
            assert log.reader.bad_lines + len(entries) <= log.reader.lines


@settings(max_examples=examples(200), deadline=None)
@given(
    st.floats(0, 1e6, allow_nan=False),
    st.from_regex(r"[A-Z_][A-Z0-9_]{0,30}", fullmatch=True),
    st.text(st.characters(blacklist_categories=("Cc", "Cs", "Zs", "Zl", "Zp")), max_size=40),
)
def test_round_trip_of_strings(t: float, name: str, value: str) -> None:
    entry = AlogReader().feed(AlogFormatter(0.0).line(t, name, "src", value))
    assert (
        entry is not None and entry.name == name and entry.time == pytest.approx(t, abs=5e-4 + 1e-9)
    )  # half a millisecond, rounded either way
    if isinstance(entry.value, float):
        assert float(value) == pytest.approx(entry.value, rel=1e-12, abs=1e-5)
    else:
        assert entry.value == value


def test_logger_config() -> None:
    def err(reason: str, s: Setting) -> ConfigError:
        return ConfigError(reason, file="m.moos", line=s.line, field=s.name)

    cfg = read_logger_config(
        [
            Setting("FILE", "Day1", 2),
            Setting("path", "./logs/", 3),
            Setting("SyncLog", "true @ 0.05", 4),
            Setting("Log", "NAV_X @ 0.5 NOSYNC", 5),
            Setting("Log", "NAV_Y", 6),
            Setting("WildCardOmitPattern", "*_STATUS, DB_*", 7),
            Setting("Colour", "blue", 8),
            Setting("MaxAlogSize", "2M", 9),
            Setting("WildcardExclusionLog", "true", 10),
        ],
        err,
    )
    assert (cfg.file, cfg.path, cfg.sync_log, cfg.sync_period) == ("Day1", "./logs", True, 0.1)
    assert [(r.var, r.period, r.sync) for r in cfg.logs] == [
        ("NAV_X", 0.5, False),
        ("NAV_Y", 2.0, True),
    ]
    assert cfg.wildcard_omit == ["MISSION_FILE", "*_STATUS", "DB_*"]
    assert cfg.max_alog_bytes == 2 << 20
    assert cfg.warnings == [
        "line 8: unknown option 'Colour' ignored",
        "line 10: WildcardExclusionLog: the .xlog of excluded variables is not written; ignored",
    ]
    assert parse_log_request("X@0").period == 0.0
    with pytest.raises(ConfigError) as caught:
        read_logger_config([Setting("DoublePrecision", "many", 4)], err)
    assert (
        str(caught.value)
        == "m.moos:4: DoublePrecision: must be a whole number of decimals (0-20), not 'many'"
    )
    assert read_logger_config([], err, global_log_path="/data/").path == "/data"


# -- pygoby log ----------------------------------------------------------------------------------


@pytest.fixture
def alog(tmp_path: Path) -> Path:
    path = tmp_path / "m.alog"
    fmt = AlogFormatter(LOG_START, log_aux_src=True)
    lines = [banner(str(path), LOG_START)]
    for i in range(10):
        lines.append(fmt.line(LOG_START + i, "NAV_X", "uSim", i * 1.5))
        lines.append(fmt.line(LOG_START + i + 0.5, "NAV_HEADING", "uSim", 90.0))
        lines.append(fmt.line(LOG_START + i + 0.5, "MSG", "pHelm", f"hello {i}", "bhv"))
    path.write_text("".join(lines) + "junk line\n")
    return path


def test_grep_and_summary(alog: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert pygoby_main(["log", "grep", str(alog), "NAV_*", "--source", "uSim"]) == 0
    out, err = capsys.readouterr()
    assert len(out.splitlines()) == 20 and "MSG" not in out
    assert "1 damaged lines skipped (the first at line 36)" in err
    assert pygoby_main(["log", "grep", str(alog), "MSG"]) == 0
    first = capsys.readouterr().out.splitlines(keepends=True)[0]
    # the line as the file has it (aloggrep prints lines so), its trailing space included
    written = AlogFormatter(LOG_START, log_aux_src=True).line(
        LOG_START + 0.5, "MSG", "pHelm", "hello 0", "bhv"
    )
    assert first == written and first.endswith("hello 0 \n")
    assert pygoby_main(["log", "summary", str(alog)]) == 0
    out = capsys.readouterr().out.splitlines()
    nav_x = next(line for line in out if line.startswith("NAV_X "))
    # chars as alogscan counts them: NAV_X (5) + uSim (4) + the padded value column (13)
    assert nav_x.split() == ["NAV_X", "10", "220", "0.00", "9.00", "1.00", "uSim"]
    assert out[-1].startswith("3 variables, 30 lines")


def test_clip(alog: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "clip.alog"
    assert pygoby_main(["log", "clip", str(alog), "2", "4", "-o", str(out)]) == 0
    entries = list(AlogFile(out))
    assert [e.time for e in entries if e.name == "NAV_X"] == [2.0, 3.0, 4.0]
    assert all(2 <= e.time <= 4 for e in entries) and len(entries) == 7
    assert {e.full_source for e in entries} == {"uSim", "pHelm:bhv"}
    assert AlogFile(out).log_start == pytest.approx(LOG_START, abs=0.01)


def test_summary_counts_chars_and_lists_sources_as_alogscan(tmp_path: Path) -> None:
    path = tmp_path / "s.alog"
    fmt = AlogFormatter(LOG_START, log_aux_src=True, mark_external=True, own_community="a")
    path.write_text(
        banner(str(path), LOG_START)
        + fmt.line(LOG_START + 1, "V", "pNavX", "ab")
        + fmt.line(LOG_START + 2, "V", "pNav", "ab", community="b")
        + fmt.line(LOG_START + 3, "V", "pNav", "ab", "aux", community="b")
        + fmt.line(LOG_START + 4, "V", "pNav", "ab")
    )
    (row,) = summarize(AlogFile(path)).values()
    # chars: variable + source column up to its first ':' + value column ("ab "): alogscan
    # drops "@b" where an aux comes first
    assert row.chars == (1 + 5 + 3) + (1 + 6 + 3) + (1 + 4 + 3) + (1 + 4 + 3)
    # every source, compared whole (alogscan leaves pNav out: "pNavX" contains it), in the
    # order first seen, with its community
    assert list(row.sources) == ["pNavX", "pNav@b", "pNav"]


def test_clip_keeps_the_helm_domain_whatever_its_time(tmp_path: Path) -> None:
    path = tmp_path / "helm.alog"
    fmt = AlogFormatter(LOG_START)
    posts = [(0.5, "IVPHELM_DOMAIN"), (1.0, "BHV"), (2.5, "BHV"), (4.0, "BHV")]
    lines = [fmt.line(LOG_START + t, name, "pHelmIvP", "x") for t, name in posts]
    header = banner(str(path), LOG_START)
    path.write_text(header + "".join(lines) + "continued text \n")
    out = tmp_path / "clip.alog"
    assert pygoby_main(["log", "clip", str(path), "2", "3", "-o", str(out)]) == 0
    # alogclip's rule: IVPHELM_DOMAIN (alogview needs it) is kept outside the window too; the
    # banner is copied as it is; the line that is no entry is dropped
    assert out.read_text() == header + lines[0] + lines[2]


@pytest.mark.parametrize("suffix", [".csv", ".jsonl", ".parquet"])
def test_convert(
    alog: Path, tmp_path: Path, suffix: str, capsys: pytest.CaptureFixture[str]
) -> None:
    out = tmp_path / f"m{suffix}"
    assert pygoby_main(["log", "convert", str(alog), str(alog), "-o", str(out)]) == 0
    assert capsys.readouterr().out == f"{out}: 60 rows\n"
    if suffix == ".csv":
        with open(out) as f:
            records = list(csv.DictReader(f))
    elif suffix == ".jsonl":
        records = [json.loads(line) for line in out.read_text().splitlines()]
    else:
        records = pq.read_table(out).to_pylist()
    assert list(records[0]) == [
        "time",
        "utc_time",
        "name",
        "source",
        "type",
        "value",
        "value_double",
    ]
    second = records[1]
    assert second["name"] == "NAV_HEADING" and float(second["value_double"]) == 90.0
    assert float(second["utc_time"]) == pytest.approx(1764643673.12 + 0.5)
    msg = records[2]
    assert (msg["source"], msg["type"], msg["value"]) == ("pHelm:bhv", "string", "hello 0")
    assert msg["value_double"] in (None, "")


def _records(path: Path) -> list[dict]:
    if path.suffix == ".csv":
        with open(path) as f:
            return list(csv.DictReader(f))
    if path.suffix == ".jsonl":
        return [json.loads(line) for line in path.read_text().splitlines()]
    return pq.read_table(path).to_pylist()


@pytest.mark.parametrize("suffix", [".csv", ".jsonl", ".parquet"])
def test_convert_in_parallel_gives_the_same_output(
    alog: Path, tmp_path: Path, suffix: str, capsys: pytest.CaptureFixture[str]
) -> None:
    part = tmp_path / "part.alog"
    assert pygoby_main(["log", "clip", str(alog), "2", "4", "-o", str(part)]) == 0
    inputs = [str(alog), str(part), str(alog)]  # 30 + 7 + 30 rows, in this order
    serial, parallel = tmp_path / f"serial{suffix}", tmp_path / f"parallel{suffix}"
    assert pygoby_main(["log", "convert", *inputs, "-o", str(serial)]) == 0
    capsys.readouterr()
    assert pygoby_main(["log", "convert", *inputs, "-o", str(parallel), "-j", "2"]) == 0
    assert capsys.readouterr().out == f"{parallel}: 67 rows\n"
    records = _records(parallel)
    assert records == _records(serial) and len(records) == 67
    assert all(2 <= float(r["time"]) <= 4 for r in records[30:37])  # the clip, second
    assert not [p for p in tmp_path.iterdir() if p.name.startswith(".")]  # parts removed


def test_convert_refuses_unknown_formats(alog: Path, tmp_path: Path) -> None:
    with pytest.raises(LogToolError, match=r"unknown output format '\.xlsx'"):
        convert([alog], tmp_path / "x.xlsx")


def test_slog_layout() -> None:
    from pygoby.moos.alog.format import slog_header, slog_labels, slog_row

    # 18-column left-justified cells, each followed by a space; NaN for no fresh double
    assert slog_row(1.25, [3.5, None]) == f"{'1.25':<18} {'3.5':<18} {'NaN':<18} \n"
    assert slog_labels(["NAV_X"], 12.0) == (
        f"{'%% TIME':<18} {'NAV_X':<18} \n{'%% TIME':<18} {'[  12.00]':<18} \n"
    )
    header = slog_header("f.slog", 0.0, ["NAV_X", "NAV_Y"]).splitlines()
    assert header[-4:] == ["%%   (1) TIME ", "%%   (2) NAV_X", "%%   (3) NAV_Y", "%" * 56]


def test_cli_errors_are_one_line(
    alog: Path, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert pygoby_main(["log", "summary", str(tmp_path / "none.alog")]) == 1
    assert capsys.readouterr().err == f"pygoby log: no such file: {tmp_path / 'none.alog'}\n"
    assert pygoby_main(["log", "convert", str(alog), "-o", str(tmp_path / "x.xlsx")]) == 1
    assert "unknown output format '.xlsx'" in capsys.readouterr().err
    assert pygoby_main(["log", "clip", str(alog), "0", "1", "-o", str(tmp_path / "no/x.alog")]) == 1
    assert capsys.readouterr().err.startswith("pygoby log: [Errno 2] No such file or directory")


ACOMMS_DATA = Path(__file__).resolve().parents[1] / "data" / "alog"


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_convert_decodes_the_missions_acomms_variables(
    tmp_path: Path, jobs: str, capsys: pytest.CaptureFixture[str]
) -> None:
    """A log of a mission whose pAcommsHandler names its variables AC_* (values made by
    pygoby's encoder and serializers: make_acomms_alog.py): protobuf text and `@PB[type]`
    values, the DCCL messages in the frames, and the translator variables of pAcommsHandler
    and pTranslator become `<Type>.<field path>` columns; what does not decode stays raw."""
    alog, mission = ACOMMS_DATA / "acomms.alog", ACOMMS_DATA / "acomms.moos"
    out = tmp_path / "acomms.parquet"
    args = ["log", "convert", str(alog), str(alog), "-o", str(out), "-j", jobs]
    assert pygoby_main([*args, "--mission", str(mission)]) == 0
    captured = capsys.readouterr()
    assert captured.out == f"{out}: 60 rows\n"
    # in both copies: the garbage text, a frame that is not DCCL and two cut messages in
    # frames; an unknown @PB type; a FORMAT publication that does not match its format
    assert captured.err == (
        "values left undecoded (kept raw): AC_MODEM_RECEIVE 8, AC_QUEUE_RECEIVE 2, "
        "PT_STATUS_FMT 2\n"
    )
    records = pq.read_table(out).to_pylist()
    assert len(records) == 60 and records[30:] == records[:30]
    by_name: dict[str, list[dict]] = {}
    for record in records[:30]:
        by_name.setdefault(record["name"], []).append(record)
    decoded = [name for name in records[0] if "." in name]

    def fields(record: dict) -> dict[str, str]:
        return {k: v for k, v in record.items() if k in decoded and v is not None}

    assert fields(by_name["NAV_X"][0]) == {}  # not an acomms or translator variable
    handmade, garbage, packed, packed_again = by_name["AC_MODEM_RECEIVE"]
    assert fields(packed_again) == fields(packed)
    assert fields(handmade) == {
        "ModemTransmission.src": "2",
        "ModemTransmission.dest": "1",
        "ModemTransmission.type": "DATA",
        "ModemTransmission.frame[0]": "01ab",  # bytes as hex; not a DCCL message
        "ModemTransmission.frame[1]": "",
        "ModemTransmission.[goby.acomms.micromodem.protobuf.transmission]"
        ".receive_stat[0].mode": "RECEIVE_GOOD",
        "ModemTransmission.[goby.acomms.micromodem.protobuf.transmission]"
        ".receive_stat[0].mse_equalizer": "-12",
    }
    assert fields(garbage) == {} and garbage["value"] == "this is not protobuf text"
    # two Status messages packed in the first frame (the second is `Status[1]`); the second
    # frame's cut message is left out
    assert {k: v for k, v in fields(packed).items() if k.startswith("Status")} == {
        "Status.src": "2",
        "Status.depth": "5.0",
        "Status.tags[0]": "1",
        "Status.tags[1]": "4",
        "Status[1].src": "3",
        "Status[1].depth": "12.5",
    }
    sent = fields(by_name["AC_MODEM_TRANSMIT"][0])
    assert (sent["Status.src"], sent["Status.depth"], sent["ModemTransmission.src"]) == (
        "3",
        "12.5",
        "1",
    )
    qsize = by_name["AC_QSIZE"][0]
    assert (qsize["QueueSize.dccl_id"], qsize["QueueSize.size"]) == ("20", "3")
    status, unknown = by_name["AC_QUEUE_RECEIVE"]
    assert (status["Status.src"], status["Status.depth"]) == ("2", "5.0")
    assert (status["Status.tags[0]"], status["Status.tags[1]"]) == ("1", "4")
    # an unknown type, and the default name the mission renamed: raw value, no fields
    assert fields(unknown) == {} and unknown["value"].startswith("@PB[logtest.Unknown]")
    assert fields(by_name["ACOMMS_QSIZE"][0]) == {}
    # translator variables, each by its rule's technique
    published = {"Status.src": "4", "Status.depth": "7.5", "Status.tags[0]": "2"}
    for name in (
        "STATUS_OUT",  # pAcommsHandler's create: key=value pairs
        "STATUS_IN",  # pAcommsHandler's publish: prefixed text format
        "PT_STATUS_TEXT",
        "PT_STATUS_HEX",
        "PT_STATUS_BIN",  # a binary value (B: in the log)
        "PT_STATUS_KV",
    ):
        assert fields(by_name[name][0]) == published, name
    assert fields(by_name["PT_DEPTH"][0]) == {"Status.depth": "3.25"}  # create: format
    matching, not_matching = by_name["PT_STATUS_FMT"]
    assert fields(matching) == {"Status.src": "4", "Status.depth": "7.5"}
    assert fields(not_matching) == {} and not_matching["value"] == "no match here"


def test_convert_without_mission_has_no_decoded_columns(tmp_path: Path) -> None:
    out = tmp_path / "plain.csv"
    assert pygoby_main(["log", "convert", str(ACOMMS_DATA / "acomms.alog"), "-o", str(out)]) == 0
    with open(out) as f:
        assert next(csv.reader(f)) == [
            "time",
            "utc_time",
            "name",
            "source",
            "type",
            "value",
            "value_double",
        ]


def test_convert_with_a_bad_mission_says_where(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mission = tmp_path / "bad.moos"
    mission.write_text("ProcessConfig = pAcommsHandler\n{\n  modem_id: one\n}\n")
    alog = str(ACOMMS_DATA / "acomms.alog")
    out = str(tmp_path / "x.csv")
    assert pygoby_main(["log", "convert", alog, "-o", out, "--mission", str(mission)]) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"pygoby log: {mission}:3: modem_id: ") and "Traceback" not in err


def _transmission_text(frames: list[bytes]) -> str:
    """A DATA ModemTransmission in protobuf text format with these frames (octal escapes)."""
    escaped = ["".join(f"\\{byte:03o}" for byte in frame) for frame in frames]
    return " ".join(["type: DATA", *(f'frame: "{text}"' for text in escaped)])


@settings(max_examples=examples(200), deadline=None)
@given(
    name=st.sampled_from(
        [
            "AC_MODEM_RECEIVE",
            "AC_MODEM_TRANSMIT",
            "AC_QSIZE",
            "AC_QUEUE_RECEIVE",
            "AC_RAW_INCOMING",
            "STATUS_OUT",
            "PT_STATUS_HEX",
            "PT_STATUS_BIN",
            "PT_STATUS_FMT",
            "PT_DEPTH",
        ]
    ),
    value=st.one_of(
        st.text(max_size=80),
        st.binary(max_size=40),
        st.builds(lambda body: f"@PB[logtest.Status] {body}", st.text(max_size=40)),
        # ModemTransmissions with random frames: the DCCL unpacking of arbitrary bytes
        st.builds(_transmission_text, st.lists(st.binary(max_size=24), max_size=3)),
        st.floats(allow_nan=True),
    ),
)
def test_mission_decoder_never_raises(name: str, value: str | bytes) -> None:
    from pygoby.moos.alog.format import AlogEntry

    decoded = _acomms_decoder()(AlogEntry(1.0, name, "pAcommsHandler", value))
    assert all(isinstance(text, str) for text in decoded.values())


@functools.cache
def _acomms_decoder():
    from pygoby.moosacomms.alog_decode import MissionDecoder

    return MissionDecoder(ACOMMS_DATA / "acomms.moos")
