"""`pygoby log grep|summary|clip` against MOOS-IvP's aloggrep / alogscan / alogclip, recorded on
pygoby pLogger logs and the hand-made acomms log (tests/data/alog/moosivp/README.md).

Where pygoby means to match, the bytes must be the same; where it differs on purpose
(QUIRKS.md Q-MOOS-17 to Q-MOOS-20), the expected output is derived from the recording by the
stated rule, and the recording is checked to show the difference."""

from __future__ import annotations

import contextlib
import io
import re
from pathlib import Path

import pytest

from pygoby.cli import main as pygoby_main
from pygoby.moos.alog import AlogFile
from pygoby.moos.alog.tools import summarize

DATA = Path(__file__).resolve().parent.parent / "data" / "alog"
RECORDED = DATA / "moosivp" / "out"
LOGS = {
    "acomms": DATA / "moosivp" / "acomms.alog",
    "plogger_blog": DATA / "moosivp" / "plogger_blog.alog",
    "plogger_inline": DATA / "moosivp" / "plogger_inline.alog",
}
PLOGGER_LOGS = ["plogger_blog", "plogger_inline"]
BLOG_TAG = re.compile(rb"<MOOS_BINARY>File=([^,]*),Offset=(\d+),Bytes=(\d+)</MOOS_BINARY>$")


def recorded(log: str, what: str) -> bytes:
    return (RECORDED / f"{log}.{what}").read_bytes()


def lines_of(data: bytes) -> list[bytes]:
    return data.splitlines(keepends=True)


def variable(line: bytes) -> str:
    return line.split()[1].decode()


def pygoby_grep(capsysbinary: pytest.CaptureFixture[bytes], log: str, *args: str) -> bytes:
    assert pygoby_main(["log", "grep", str(LOGS[log]), *args]) == 0
    out, err = capsysbinary.readouterr()
    assert err == b""  # no damaged line in any of these logs
    return out


# -- grep ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("log", LOGS)
def test_grep_prints_aloggreps_lines_byte_for_byte(
    log: str, capsysbinary: pytest.CaptureFixture[bytes]
) -> None:
    ours = pygoby_grep(capsysbinary, log, "NAV_X", "MSG", "AC_QSIZE")
    assert ours == recorded(log, "grep_vars_q.txt")
    assert ours  # each log has some of these
    # aloggrep without -q: the banner, the same lines, then its report
    full = recorded(log, "grep_vars.txt")
    assert ours in full and full.startswith(b"%%%%")


@pytest.mark.parametrize("log", PLOGGER_LOGS)
def test_grep_of_binary_empty_and_external_values(
    log: str, capsysbinary: pytest.CaptureFixture[bytes]
) -> None:
    # aloggrep drops *_LEN variables even when named, unless -gl; pygoby shows what is named
    ours = pygoby_grep(capsysbinary, log, "MSG_LEN", "EMPTY", "RAW")
    assert ours == recorded(log, "grep_len_gl_q.txt")
    without_gl = lines_of(recorded(log, "grep_len_q.txt"))
    assert without_gl == [line for line in lines_of(ours) if variable(line) != "MSG_LEN"]
    assert b"B:" in ours if log == "plogger_inline" else b"<MOOS_BINARY>" in ours
    # a message from another community: its line keeps pShare@bravo
    bridged = pygoby_grep(capsysbinary, log, "NODE_REPORT")
    assert bridged == recorded(log, "grep_bridged_q.txt") and b"pShare@bravo" in bridged


@pytest.mark.parametrize("log", LOGS)
def test_grep_star_is_a_prefix_where_aloggrep_matches_anywhere(
    log: str, capsysbinary: pytest.CaptureFixture[bytes]
) -> None:
    ours = pygoby_grep(capsysbinary, log, "NAV*", "AC_*")
    theirs = lines_of(recorded(log, "grep_star_q.txt"))
    assert lines_of(ours) == [line for line in theirs if variable(line).startswith(("NAV", "AC_"))]
    if log != "acomms":  # aloggrep's NAV* also took DESIRED_NAV_X
        assert {variable(line) for line in theirs} - {
            variable(line) for line in lines_of(ours)
        } == {"DESIRED_NAV_X"}


@pytest.mark.parametrize("log", LOGS)
def test_grep_by_source(log: str, capsysbinary: pytest.CaptureFixture[bytes]) -> None:
    # aloggrep takes a source among its keys; pygoby says --source (any variable: *)
    ours = pygoby_grep(capsysbinary, log, "*", "--source", "vehicle", "--source", "pAcommsHandler")
    assert ours  # both sources occur
    # aloggrep leaves out the line before LOGSTART (a negative time)
    assert lines_of(recorded(log, "grep_source_gl_q.txt")) == after_logstart(lines_of(ours))


@pytest.mark.parametrize("log", PLOGGER_LOGS)
def test_grep_shows_what_was_logged_before_logstart(
    log: str, capsysbinary: pytest.CaptureFixture[bytes]
) -> None:
    ours = lines_of(pygoby_grep(capsysbinary, log, "PRESTART", "SCI_TEXT"))
    assert [variable(line) for line in ours] == ["PRESTART", "SCI_TEXT"]
    assert ours[0].startswith(b"-0.5")  # pLogger got it from the DB as it registered
    assert lines_of(recorded(log, "grep_prestart_q.txt")) == ours[1:]


def after_logstart(lines: list[bytes]) -> list[bytes]:
    """The lines MOOS-IvP's aloggrep and alogscan read as entries: not those with a negative
    time, which they take for lines that are not entries (QUIRKS.md Q-MOOS-20)."""
    return [line for line in lines if not line.startswith(b"-")]


# -- summary -------------------------------------------------------------------------------------

_ROW = re.compile(r"(\S+)\s+(\d+)\s+([\d,]+)\s+(-?\d+\.\d\d)\s+(-?\d+\.\d\d)\s+(\S+)")


def alogscan_table(log: str) -> dict[str, tuple[int, int, str, str, list[str]]]:
    """alogscan's rows: variable -> (lines, chars, start, stop, sources)."""
    text = recorded(log, "scan_vars.txt").decode()
    body = text.split("------------- ")[1].split(
        "\n--------------------------------------------------"
    )[0]
    rows = {}
    for line in body.splitlines()[1:]:
        match = _ROW.fullmatch(line)
        assert match, line
        name, count, chars, start, stop, sources = match.groups()
        rows[name] = (int(count), int(chars.replace(",", "")), start, stop, sources.split(","))
    return rows


@pytest.mark.parametrize("log", LOGS)
def test_summary_matches_alogscans_table(log: str, tmp_path: Path) -> None:
    # the lines alogscan reads as entries: a time not negative and a value column not empty
    # (pygoby counts both: QUIRKS.md Q-MOOS-18, Q-MOOS-20)
    scanned = tmp_path / "scanned.alog"
    with scanned.open("w", encoding="utf-8", errors="surrogateescape") as out:
        for text, entry in AlogFile(LOGS[log]).lines():
            if entry is None or (entry.time >= 0 and entry.value_column):
                out.write(text + "\n")
    ours = {
        name: (row.count, row.chars, f"{row.first:.2f}", f"{row.last:.2f}", list(row.sources))
        for name, row in summarize(AlogFile(scanned)).items()
    }
    assert ours == alogscan_table(log)
    left_out = set(summarize(AlogFile(LOGS[log]))) - set(ours)
    assert (
        left_out
        == {
            "acomms": set(),
            "plogger_blog": {"PRESTART", "EMPTY"},
            "plogger_inline": {"PRESTART"},  # its empty value is written "S:"
        }[log]
    )


@pytest.mark.parametrize("log", PLOGGER_LOGS)
def test_moosivp_tools_read_every_line_of_our_plogger_logs(log: str) -> None:
    entries = list(AlogFile(LOGS[log]))
    scanned = {e.name for e in entries if e.time >= 0 and e.value_column}
    assert set(alogscan_table(log)) == scanned
    assert f"Total variables: {len(scanned)}" in recorded(log, "scan.txt").decode()
    # aloggrep's report counts each entry line as kept or left out
    report = recorded(log, "grep_vars.txt").decode()
    (kept,) = re.findall(r"Total lines retained: (\d+)", report)
    (left,) = re.findall(r"Total lines excluded: (\d+)", report)
    not_banner = [
        line for line in LOGS[log].read_bytes().splitlines() if not line.startswith(b"%%")
    ]
    assert int(kept) + int(left) == len(entries) == len(not_banner)


def test_summary_command_shows_a_bridged_source_with_its_community(
    capsys: pytest.CaptureFixture[str],
) -> None:
    assert pygoby_main(["log", "summary", str(LOGS["plogger_blog"])]) == 0
    out = capsys.readouterr().out.splitlines()
    row = next(line for line in out if line.startswith("NODE_REPORT "))
    assert row.split()[1:3] == ["2", "110"] and row.endswith("  pShare@bravo")


# -- clip ----------------------------------------------------------------------------------------


def inline_from_blog(log_path: Path, lines: list[bytes]) -> list[bytes]:
    """alogclip's lines with each .blog reference written inline as B:<hex> (read from the
    .blog at the tag's offset), after one `%% BINARY MARKING ON` line: pygoby's clip rule."""
    result: list[bytes] = []
    marked = False
    for line in lines:
        tag = BLOG_TAG.search(line.rstrip(b"\n"))
        if tag is None:
            result.append(line)
            continue
        blog = (log_path.parent / tag[1].decode()).read_bytes()
        offset, size = int(tag[2]), int(tag[3])
        if not marked:
            result.append(b"%% BINARY MARKING ON\n")
            marked = True
        hex_text = blog[offset : offset + size].hex().upper().encode()
        result.append(line[: tag.start()] + b"B:" + hex_text + b" \n")
    return result


@pytest.mark.parametrize("log", LOGS)
@pytest.mark.parametrize(
    ("window", "t0", "t1"), [("clip_mid", "1.5", "6.5"), ("clip_start", "0", "1.2")]
)
def test_clip_writes_alogclips_lines(
    log: str,
    window: str,
    t0: str,
    t1: str,
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
) -> None:
    out = tmp_path / "clip.alog"
    assert pygoby_main(["log", "clip", str(LOGS[log]), t0, t1, "-o", str(out)]) == 0
    capsys.readouterr()
    theirs = lines_of(recorded(log, f"{window}.alog"))
    if float(t0) <= 0:
        # alogclip reads the end of the file as one more line at time 0: an empty line
        assert theirs[-1] == b"\n"
        theirs = theirs[:-1]
    expected = inline_from_blog(LOGS[log], theirs)
    assert lines_of(out.read_bytes()) == expected
    if log == "plogger_blog" and window == "clip_mid":  # both binary values were inlined
        assert expected != theirs and sum(b"B:" in line for line in expected) == 2
        entries = [e for e in AlogFile(out) if e.name == "RAW"]
        assert [e.value for e in entries] == [b"\x00\x01\xfe\xff\n", b"binary\x00 data"]


def test_clip_without_the_blog_keeps_the_references(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    alone = tmp_path / "plogger_blog.alog"  # no .blog beside it
    alone.write_bytes(LOGS["plogger_blog"].read_bytes())
    out = tmp_path / "clip.alog"
    assert pygoby_main(["log", "clip", str(alone), "1.5", "6.5", "-o", str(out)]) == 0
    assert "2 binary values not found in the .blog" in capsys.readouterr().err
    assert out.read_bytes() == recorded("plogger_blog", "clip_mid.alog")


def test_grep_into_a_text_only_stdout() -> None:
    out = io.StringIO()  # no .buffer, as under redirect_stdout
    with contextlib.redirect_stdout(out):
        assert pygoby_main(["log", "grep", str(LOGS["plogger_blog"]), "NAV_X", "MSG"]) == 0
    assert out.getvalue().encode() == recorded("plogger_blog", "grep_vars_q.txt")
