"""The .alog reader behind `pygoby log convert`: a block at a time in pyarrow (the `sim` extra).

The line reader (`AlogFile`) spends about 10 µs a line in Python; this one parses blocks of a
few megabytes with pyarrow's compute kernels, RE2 running the line reader's own pattern texts,
and gives the same rows: `AlogTables(path)` yields pyarrow tables of `CONVERT_COLUMNS` equal,
row for row, to `entry_row` applied to each entry of `AlogFile(path)`.

The kernels take the lines nearly every log is made of: `TIME VAR SOURCE VALUE` with a double or
a string value, in UTF-8. Everything else goes through the line reader itself, with the same
`AlogReader` state, so the two cannot disagree on it: a `%%` line (it can change LOGSTART or the
markings), a block holding a `<MOOS_BINARY>` reference or bytes that are not UTF-8 or a line too
long, and every block of a file written with MarkDataType or MarkDataAsBinary.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Iterator
from pathlib import Path
from typing import IO, TYPE_CHECKING, Any

from pygoby.moos.alog.files import MAX_LINE_BYTES, READ_ERRORS, BlogFiles, open_text_or_gz
from pygoby.moos.alog.format import (
    DOUBLE_TEXT,
    ENTRY_TEXT,
    SPACE,
    AlogEntry,
    AlogReader,
    decode_line,
    split_source,
    value_text,
)
from pygoby.util.extras import needs_extra

if TYPE_CHECKING:
    import pyarrow as pa

logger = logging.getLogger(__name__)

# the columns and their pyarrow types (decoded fields follow, as strings)
CONVERT_TYPES = (
    ("time", "double"),
    ("utc_time", "double"),
    ("name", "string"),
    ("source", "string"),
    ("type", "string"),
    ("value", "string"),
    ("value_double", "double"),
)
CONVERT_COLUMNS = tuple(name for name, _ in CONVERT_TYPES)
BLOCK_BYTES = 4 << 20  # parsed at once: memory holds a few times this, whatever the log's size
# RE2 searches: anchored, the patterns are the line reader's full matches
_ENTRY = f"^(?:{ENTRY_TEXT})$"
_DOUBLE = f"^(?:{DOUBLE_TEXT})$"


def entry_row(entry: AlogEntry, log_start: float) -> tuple[Any, ...]:
    """An entry as a row of CONVERT_COLUMNS."""
    double = entry.value if isinstance(entry.value, float) else None
    return (
        entry.time,
        log_start + entry.time,
        entry.name,
        entry.full_source,
        entry.type,
        value_text(entry),
        double,
    )


def convert_schema(columns: list[str]) -> pa.Schema:
    """CONVERT_TYPES, then `columns` (decoded fields) as strings."""
    import pyarrow as pa

    types = [*CONVERT_TYPES, *((name, "string") for name in columns)]
    return pa.schema([(name, pa.type_for_alias(alias)) for name, alias in types])


class AlogTables:
    """The entries of one .alog (`.alog.gz` too) as pyarrow tables, one per block read."""

    def __init__(self, path: str | os.PathLike[str], block_bytes: int = BLOCK_BYTES) -> None:
        self.path = Path(path)
        self.block_bytes = block_bytes
        self.reader = AlogReader()
        self.blogs = BlogFiles(self.path.parent)
        self.rows_by_line_reader = 0  # how many rows did not take the fast path (for tests)

    def __iter__(self) -> Iterator[pa.Table]:
        with needs_extra("sim", "Parquet output"):
            import pyarrow  # noqa: F401
        self.reader = AlogReader()
        self.blogs = BlogFiles(self.path.parent)
        self.rows_by_line_reader = 0
        try:
            with open_text_or_gz(self.path) as stream:
                for block in self._blocks(stream):
                    table = self._table(block)
                    if table.num_rows:
                        yield table
        finally:
            self.blogs.close()

    # -- cutting the file into blocks of whole lines --------------------------------------------

    def _blocks(self, stream: IO[bytes]) -> Iterator[bytes]:
        """Blocks of whole lines, ending where the line reader's reading ends. A line longer
        than MAX_LINE_BYTES is counted as damage and skipped, as there. A read error (a .gz
        cut short) ends the file after the last whole line read before it, the broken line
        lost: pieces are taken as the line reader's buffer takes them (read1: one buffer fill),
        so both stop at the same line."""
        pending = b""  # the start of a line that continues in the next piece
        skipping = False  # inside a line too long, until its newline
        while True:
            pieces = [pending]
            size = len(pending)
            at_end = broken = False
            try:
                while not at_end and (size < self.block_bytes or len(pieces) == 1):
                    piece = stream.read1()  # type: ignore[attr-defined]
                    at_end = not piece
                    pieces.append(piece)
                    size += len(piece)
            except READ_ERRORS as err:
                logger.warning("%s: stopped reading: %s", self.path, err)
                at_end = broken = True
            data = b"".join(pieces)
            if skipping:
                newline = data.find(b"\n")
                if newline < 0:
                    pending = b""
                    if at_end:
                        return
                    continue
                data = data[newline + 1 :]
                skipping = False
            cut = data.rfind(b"\n") + 1
            whole, pending = data[:cut], data[cut:]
            too_long = len(pending) >= MAX_LINE_BYTES
            if at_end and not too_long:
                # a last line without its newline is a line, unless reading broke in it
                yield whole if broken else whole + pending
                return
            if whole:
                yield whole  # read before the line too long is counted (damage is numbered)
            if too_long:
                self.reader.skip_line()
                skipping, pending = True, b""
                if at_end:
                    return

    # -- one block ------------------------------------------------------------------------------

    def _table(self, block: bytes) -> pa.Table:
        """The block's rows: `%%` lines through the line reader one by one, the lines between
        them through the kernels when they can take them."""
        import pyarrow as pa

        tables: list[pa.Table] = []
        start = 0
        while start < len(block):
            if block.startswith(b"%%", start):
                end = block.find(b"\n", start) + 1 or len(block)
                tables.append(self._by_line_reader(block[start:end]))
            else:
                end = block.find(b"\n%%", start) + 1 or len(block)
                tables.append(self._lines_table(block[start:end]))
            start = end
        if not tables:
            return convert_schema([]).empty_table()
        return pa.concat_tables(tables) if len(tables) > 1 else tables[0]

    def _lines_table(self, lines: bytes) -> pa.Table:
        import pyarrow as pa

        if (
            self.reader.data_type_marked
            or self.reader.binary_marked
            or b"<MOOS_BINARY>" in lines
            or len(lines) >= MAX_LINE_BYTES
        ):
            return self._by_line_reader(lines)
        try:
            text = pa.array([lines], pa.binary()).cast(pa.string())
        except pa.ArrowInvalid:  # not UTF-8: the line reader keeps the bytes as surrogates
            return self._by_line_reader(lines)
        return self._by_kernels(text, lines.endswith(b"\n"), _unusual(lines))

    def _by_line_reader(self, lines: bytes) -> pa.Table:
        rows: list[tuple[Any, ...]] = []
        pieces = lines.split(b"\n")
        if lines.endswith(b"\n"):
            pieces.pop()  # the empty text after the last newline
        for raw in pieces:
            if len(raw) >= MAX_LINE_BYTES:
                self.reader.skip_line()
                continue
            entry = self.blogs.feed(self.reader, decode_line(raw))
            if entry is not None:
                rows.append(entry_row(entry, self.reader.log_start or 0.0))
        self.rows_by_line_reader += len(rows)
        return rows_table(rows, [])

    def _by_kernels(self, text: pa.Array, ends_with_newline: bool, unusual: bool) -> pa.Table:
        import pyarrow as pa
        import pyarrow.compute as pc

        lines = pc.split_pattern(text, "\n").flatten()
        if ends_with_newline:
            lines = lines.slice(0, len(lines) - 1)  # the empty text after the last newline
        lines = pc.utf8_rtrim(lines, characters="\r")
        first_line = self.reader.lines
        self.reader.lines += len(lines)
        # which lines are entries: RE2 only says yes or no here (no groups), which is fast
        entries = pc.match_substring_regex(lines, _ENTRY)
        if unusual:
            stamps, names, sources, values = _columns_by_groups(lines.filter(entries))
        else:
            stamps, names, sources, values = _columns_by_split(lines.filter(entries))
        finite = pc.is_finite(stamps)  # a time beyond a double's range is damage
        keep = pc.replace_with_mask(entries, entries, finite)
        self._count_bad(lines, keep, first_line)
        if not pc.all(finite).as_py():
            stamps, names, sources, values = (
                column.filter(finite) for column in (stamps, names, sources, values)
            )
        # pLogger ends every value with one space; a double is padded further
        one_space = pc.ends_with(values, " ")
        values = pc.if_else(one_space, pc.utf8_slice_codeunits(values, 0, -1), values)
        numbers = pc.utf8_rtrim(values, characters=SPACE)
        is_double = pc.match_substring_regex(numbers, _DOUBLE)
        doubles = pc.cast(pc.if_else(is_double, numbers, pa.scalar(None, pa.string())), "double")
        if pc.any(is_double).as_py():  # a double's text is Python's repr, as the line reader's
            shown = [repr(x) for x in doubles.filter(is_double).to_pylist()]
            values = pc.replace_with_mask(values, is_double, pa.array(shown, pa.string()))
        log_start = self.reader.log_start or 0.0
        return pa.Table.from_arrays(
            [
                stamps,
                pc.add(stamps, log_start),
                names,
                _full_sources(sources),
                pc.if_else(is_double, "double", "string"),
                values,
                doubles,
            ],
            schema=convert_schema([]),
        )

    def _count_bad(self, lines: pa.Array, keep: pa.Array, first_line: int) -> None:
        """The line reader's count of damaged lines: those it could not read that are not
        blank (Python's str.strip decides, as there)."""
        import pyarrow.compute as pc

        rejected = pc.invert(keep)
        if not pc.any(rejected).as_py():
            return
        numbers = pc.indices_nonzero(rejected).to_pylist()
        for number, line in zip(numbers, lines.filter(rejected).to_pylist(), strict=True):
            if line.strip():
                self.reader.bad_lines += 1
                if self.reader.first_bad_line is None:
                    self.reader.first_bad_line = first_line + number + 1


def _unusual(lines: bytes) -> bool:
    """Whether some line may start with a blank or hold a \\v, \\f or \\r (other than the
    \\r of a CRLF ending): splitting at blanks could cut those otherwise than the pattern's
    groups do (a byte search over the block, cheaper than asking RE2 line by line)."""
    return (
        lines.startswith((b" ", b"\t"))
        or b"\n " in lines
        or b"\n\t" in lines
        or b"\v" in lines
        or b"\f" in lines
        or lines.count(b"\r") != lines.count(b"\r\n")
    )


def _columns_by_split(lines: pa.Array) -> tuple[pa.Array, pa.Array, pa.Array, pa.Array]:
    """Time, variable, source and value of entry lines that start with the time and hold no
    \\v, \\f or \\r: split at their first three runs of blanks, they give the line reader's
    groups (its separators are runs of spaces and tabs)."""
    import numpy as np
    import pyarrow as pa
    import pyarrow.compute as pc

    words = pc.ascii_split_whitespace(lines, max_splits=3)
    flat = pa.concat_arrays([words.flatten(), pa.array([""], pa.string())])
    starts = words.offsets.to_numpy()[:-1]
    has_value = words.value_lengths().to_numpy() == 4
    # a line without a value has three words: its value is the empty text added at the end
    value_at = np.where(has_value, starts + 3, len(flat) - 1)
    return (
        pc.cast(flat.take(starts), pa.float64()),
        flat.take(starts + 1),
        flat.take(starts + 2),
        flat.take(value_at),
    )


def _columns_by_groups(lines: pa.Array) -> tuple[pa.Array, pa.Array, pa.Array, pa.Array]:
    """The same by the line reader's own groups (slower: RE2 keeps track of each group)."""
    import pyarrow as pa
    import pyarrow.compute as pc

    parts = pc.extract_regex(lines, _ENTRY)
    return (
        pc.cast(parts.field("time"), pa.float64()),
        parts.field("name"),
        parts.field("source"),
        parts.field("value"),
    )


def _full_sources(sources: pa.Array) -> pa.Array:
    """The source column as the line reader rebuilds it from `src[:aux][@community]` (an empty
    aux or community loses its separator). Sources are few: each distinct one is done once."""
    import pyarrow as pa

    encoded = sources.dictionary_encode()
    rebuilt = [_rebuild_source(text) for text in encoded.dictionary.to_pylist()]
    return pa.array(rebuilt, pa.string()).take(encoded.indices)


def _rebuild_source(text: str) -> str:
    src, aux, community = split_source(text)
    return AlogEntry(0.0, "", src, "", aux, community).full_source


def rows_table(rows: list[tuple[Any, ...]], columns: list[str]) -> pa.Table:
    """Rows of CONVERT_COLUMNS (then `columns`) as a table; strings made valid UTF-8 (the line
    reader keeps undecodable bytes as surrogates, Parquet wants UTF-8)."""
    import pyarrow as pa

    schema = convert_schema(columns)
    values: list[Any] = list(zip(*rows, strict=True)) if rows else [[] for _ in schema]
    for index, column in enumerate(schema):
        if column.type == pa.string():
            values[index] = [_utf8(text) for text in values[index]]
    return pa.Table.from_arrays(
        [pa.array(column, type=schema.field(i).type) for i, column in enumerate(values)],
        schema=schema,
    )


def _utf8(text: str | None) -> str | None:
    if text is None:  # a decoded field the entry does not have
        return None
    try:
        text.encode()
        return text
    except UnicodeEncodeError:
        return text.encode("utf-8", "surrogateescape").decode("utf-8", "replace")
