"""The block reader (`pygoby log convert` to Parquet) gives the line reader's rows exactly: the
same entries, values, types, times and damaged-line counts, whatever the file holds."""

from __future__ import annotations

import gzip
import math
import tempfile
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.moos.alog import AlogFile, AlogFormatter, banner, columns, files
from pygoby.moos.alog.columns import AlogTables, rows_table
from pygoby.moos.alog.tools import rows
from tests.hypothesis_profiles import examples

FORMATTER = AlogFormatter(100.0, log_aux_src=True, mark_external=True, own_community="a")


def comparable(table_rows: list[dict[str, Any]]) -> list[tuple[Any, ...]]:
    """Rows with NaN made equal to NaN."""
    return [
        tuple("NaN" if isinstance(v, float) and math.isnan(v) else v for v in row.values())
        for row in table_rows
    ]


def assert_same_rows(path: Path, block_bytes: int) -> AlogTables:
    by_lines = AlogFile(path)
    expected = rows_table(list(rows([path])), []).to_pylist()
    for _ in by_lines:  # the line reader's counts
        pass
    tables = AlogTables(path, block_bytes)
    got = [row for table in tables for row in table.to_pylist()]
    assert comparable(got) == comparable(expected)
    assert (tables.reader.lines, tables.reader.bad_lines, tables.reader.first_bad_line) == (
        by_lines.reader.lines,
        by_lines.reader.bad_lines,
        by_lines.reader.first_bad_line,
    )
    assert tables.reader.log_start == by_lines.reader.log_start
    return tables


def test_a_plain_log_takes_the_kernels(tmp_path: Path) -> None:
    path = tmp_path / "plain.alog"
    lines = [banner(str(path), 100.0)]
    for i in range(2000):
        lines.append(FORMATTER.line(100 + i * 0.05, "NAV_X", "uSimMarine", i * 0.25))
        lines.append(FORMATTER.line(100 + i * 0.05, "MSG", "pHelm", f"a = {i}, b c", "bhv"))
    lines.append("12.5   NAV_Y   src@b   -1e400 \n")  # an exponent: a string, as pLogger reads it
    lines.append("not a line at all\n")
    path.write_text("".join(lines))
    tables = assert_same_rows(path, 16 << 10)
    # only the banner went through the line reader: every entry through the kernels
    assert tables.rows_by_line_reader == 0
    assert tables.reader.bad_lines == 1


@pytest.mark.parametrize("block_bytes", [64, 1 << 20])
def test_the_test_data_log(block_bytes: int) -> None:
    assert_same_rows(Path(__file__).parents[1] / "data" / "alog" / "acomms.alog", block_bytes)


# lines of every kind the two readers must agree on
LINE = st.one_of(
    st.builds(
        lambda t, name, src, value: FORMATTER.line(t, name, src, value),
        st.floats(100, 1e6, allow_nan=False),
        st.sampled_from(["NAV_X", "A", "DB_TIME", "Ω_VAR"]),
        st.sampled_from(["src", "src:aux", "s@b", "s:@", "p:x:y@c@d", "é"]),
        st.floats(allow_nan=True) | st.text(max_size=30),
    ),
    st.sampled_from(
        [
            "%% LOGSTART 555.5\n",
            "%% LOGSTART nope\n",
            "%% DATATYPE MARKING ON\n",
            "%% BINARY MARKING ON\n",
            "1.0 A src D:2.5 \n",
            "1.0 A src S:2.5 \n",
            "1.0 B src B:00ff \n",
            "1.0 C src <MOOS_BINARY>File=x.blog,Offset=0,Bytes=2</MOOS_BINARY> \n",
            "\n",
            "   \t \n",
            "\r\n",
            "2.0 X src 3.5\r\r\n",
            "2.0 X src a b\r\n",
            " 1.0 A src v \n",
            "\t2 B s x\n",
            "3 C s \x0bv\n",
            "3 C s \x0cv\n",
            "3 C s \rv\n",
            "2.0 X src a b  \n",
            "2.0 X src  3.5\u00a0\n",
            "2.0 X src\u00a0y 1\n",
            "\u0663 X src 1\n",
            "1e400 X src 1\n",
            "+.5 X src -inf \n",
            "-3 X src +nan \n",
            "7 X\x0bY src 1\n",
            "7 X src\n",
            "7 X src \n",
        ]
    ),
    st.text(max_size=40).map(lambda text: text.replace("\n", "") + "\n"),
)
CONTENT = st.lists(LINE | st.binary(max_size=30), max_size=40)


def write(path: Path, parts: list[str | bytes]) -> None:
    data = b"".join(
        p if isinstance(p, bytes) else p.encode("utf-8", "surrogatepass") for p in parts
    )
    path.write_bytes(data)


@settings(max_examples=examples(300), deadline=None)
@given(CONTENT, st.integers(1, 400), st.booleans())
def test_same_rows_as_the_line_reader(parts: list[str | bytes], block: int, header: bool) -> None:
    with tempfile.TemporaryDirectory() as folder:
        path = Path(folder) / "f.alog"
        write(path, [banner("f", 100.0)] * header + parts)
        assert_same_rows(path, block)


@settings(max_examples=examples(100), deadline=None)
@given(CONTENT, st.integers(0, 2000), st.integers(1, 400))
def test_same_rows_from_a_gz_cut_short(parts: list[str | bytes], cut: int, block: int) -> None:
    with tempfile.TemporaryDirectory() as folder:
        plain = Path(folder) / "f.alog"
        write(plain, [banner("f", 100.0), *parts])
        packed = Path(folder) / "f.alog.gz"
        packed.write_bytes(gzip.compress(plain.read_bytes())[:cut])
        assert_same_rows(packed, block)


@settings(max_examples=examples(100), deadline=None)
@given(st.lists(st.integers(0, 40), max_size=12), st.integers(1, 50), st.booleans())
def test_lines_too_long_are_skipped_alike(
    lengths: list[int], block: int, newline_at_end: bool
) -> None:
    with (
        tempfile.TemporaryDirectory() as folder,
        pytest.MonkeyPatch.context() as patch,
    ):
        patch.setattr(files, "MAX_LINE_BYTES", 16)
        patch.setattr(columns, "MAX_LINE_BYTES", 16)
        path = Path(folder) / "f.alog"
        text = "\n".join(f"1 A s {'v' * n}"[: 6 + n] for n in lengths)
        path.write_text(text + "\n" * newline_at_end)
        assert_same_rows(path, block)
