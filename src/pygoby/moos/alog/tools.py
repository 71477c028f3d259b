"""What `pygoby log` does with .alog files: grep, summary, clip, convert and replay.

Every tool streams its input (memory does not grow with the log's size).
"""

from __future__ import annotations

import asyncio
import csv
import json
import logging
import math
import os
import sys
import tempfile
import time
from collections.abc import Callable, Iterable, Iterator, Sequence
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any

from pygoby.moos.alog.columns import (
    CONVERT_COLUMNS,
    AlogTables,
    convert_schema,
    entry_row,
    rows_table,
)
from pygoby.moos.alog.files import AlogFile
from pygoby.moos.alog.format import BINARY_MARKING, AlogEntry, inline_binary
from pygoby.moos.errors import MoosError, MoosRefusedError
from pygoby.util.extras import needs_extra

logger = logging.getLogger(__name__)

CONVERT_FORMATS = (".parquet", ".csv", ".jsonl")
PARQUET_BATCH = 65_536  # rows per Parquet row group written
CONNECT_TIMEOUT = 5.0  # s for each source's client to reach the DB
DB_SOURCE_PREFIX = "MOOSDB"  # MOOSDB_<community>: the DB's own posts


def db_community(source: str) -> str | None:
    """The community of a MOOSDB's own post (its source is MOOSDB_<community>), else None."""
    head, underscore, community = source.partition("_")
    return community if head == DB_SOURCE_PREFIX and underscore else None


class LogToolError(MoosError):
    """A `pygoby log` request that cannot be done (an unknown output format, ...)."""


# -- grep ----------------------------------------------------------------------------------------


def matches(name: str, patterns: Sequence[str]) -> bool:
    """A pattern matches the whole name, or its start when it ends with `*` (aloggrep's
    documented rule; its code matches anywhere in the name: QUIRKS.md Q-MOOS-17)."""
    for pattern in patterns:
        if pattern.endswith("*"):
            if name.startswith(pattern[:-1]):
                return True
        elif name == pattern:
            return True
    return False


def grep(
    log: AlogFile, variables: Sequence[str], sources: Sequence[str] = ()
) -> Iterator[AlogEntry]:
    """Entries whose variable (and, with `sources`, also whose source, without its :aux and
    @community) matches. Their `line` is what aloggrep prints for them."""
    for entry in log:
        if variables and not matches(entry.name, variables):
            continue
        if sources and not matches(entry.source, sources):
            continue
        yield entry


def write_lines(lines: Iterable[str], out: IO[str]) -> None:
    """Lines (as read, without newline) to `out` as the bytes the file had, as aloggrep prints
    them; a text-only `out` (redirect_stdout) gets them as text."""
    out.flush()
    binary: IO[bytes] | None = getattr(out, "buffer", None)
    for line in lines:
        if binary is not None:
            binary.write(line.encode("utf-8", "surrogateescape") + b"\n")
        else:
            out.write(line + "\n")
    if binary is not None:
        binary.flush()


# -- summary -------------------------------------------------------------------------------------

MAX_LISTED_SOURCES = 64  # a variable's sources listed in the summary (the rest are not)


@dataclass
class VariableSummary:
    """One variable's row of alogscan's table (plus its rate). `chars` counts as alogscan does:
    the variable, the source column up to any `:aux`, and the value column as written."""

    name: str
    count: int = 0
    first: float = math.inf
    last: float = -math.inf
    chars: int = 0
    sources: dict[str, None] = field(default_factory=dict)  # in the order first seen

    @property
    def rate(self) -> float:
        span = self.last - self.first
        return (self.count - 1) / span if self.count > 1 and span > 0 else 0.0


def summary_source(entry: AlogEntry) -> str:
    """How a source is listed: without its :aux, with @community for other communities
    (alogscan loses the community when there is an aux too: QUIRKS.md Q-MOOS-18)."""
    return f"{entry.source}@{entry.community}" if entry.community else entry.source


def _byte_length(text: str) -> int:
    return len(text) if text.isascii() else len(text.encode("utf-8", "surrogateescape"))


def _scan_chars(entry: AlogEntry) -> int:
    """alogscan's Chars for one line: the bytes of the variable, of the source column up to
    its first `:` (so `@community` counts only without an aux) and of the value column."""
    source = _byte_length(entry.source)
    if entry.community and not entry.source_aux:
        source += 1 + _byte_length(entry.community)
    return _byte_length(entry.name) + source + _byte_length(entry.value_column)


def summarize(log: AlogFile) -> dict[str, VariableSummary]:
    """Per variable: count, first and last time, characters, sources (alogscan's table,
    except that entries with an empty value count and sources are compared whole)."""
    table: dict[str, VariableSummary] = {}
    for entry in log:
        row = table.get(entry.name)
        if row is None:
            row = table[entry.name] = VariableSummary(entry.name)
        row.count += 1
        row.first = min(row.first, entry.time)
        row.last = max(row.last, entry.time)
        row.chars += _scan_chars(entry)
        if len(row.sources) < MAX_LISTED_SOURCES:
            row.sources[summary_source(entry)] = None
    return table


def summary_lines(log: AlogFile, table: dict[str, VariableSummary]) -> list[str]:
    width = max([len("Variable Name"), *(len(name) for name in table)])
    lines = [
        f"{'Variable Name':<{width}}  {'Lines':>8}  {'Chars':>10}  {'Start':>10}  {'Stop':>10}"
        f"  {'Rate/s':>8}  Sources",
        f"{'-' * width}  {'-' * 8}  {'-' * 10}  {'-' * 10}  {'-' * 10}  {'-' * 8}  -------",
    ]
    for name in sorted(table):
        row = table[name]
        lines.append(
            f"{name:<{width}}  {row.count:>8}  {row.chars:>10}  {row.first:>10.2f}  "
            f"{row.last:>10.2f}  {row.rate:>8.2f}  {','.join(row.sources)}"
        )
    total = sum(row.count for row in table.values())
    lines.append(
        f"{len(table)} variables, {total} lines, log start {log.log_start:.2f}"
        f", {log.reader.bad_lines} bad lines skipped"
    )
    return lines


# -- clip ----------------------------------------------------------------------------------------

# alogclip keeps these whatever their time: the helm's domain, which alogview needs
ALWAYS_CLIPPED_IN = frozenset({"IVPHELM_DOMAIN"})


def clip(log: AlogFile, t0: float, t1: float, out: IO[str]) -> int:
    """Write the `%%` lines and the entries with t0 <= time <= t1 as they are in the file,
    as alogclip does (same banner, LOGSTART and times); returns how many entries. A binary
    value from the .blog is written inline as `B:<hex>` instead (the clip needs no .blog),
    after a `%% BINARY MARKING ON` line; lines that are not entries are left out, where
    alogclip keeps them when the window includes time 0 (QUIRKS.md Q-MOOS-19)."""
    marked = False
    count = 0
    for text, entry in log.lines():
        if entry is None:
            if text.startswith("%"):
                out.write(text + "\n")
            continue
        if not (t0 <= entry.time <= t1 or entry.name in ALWAYS_CLIPPED_IN):
            continue
        line = text
        from_blog = entry.value_column.startswith("<MOOS_BINARY>")
        if from_blog and entry.binary_ref is None and isinstance(entry.value, bytes):
            if not (marked or log.reader.binary_marked):
                out.write(BINARY_MARKING + "\n")
                marked = True
            # pLogger's inline form: the value, then one space (a .blog tag has none)
            prefix = text[: len(text) - len(entry.value_column)]
            line = prefix + inline_binary(entry.value) + " "
        out.write(line + "\n")
        count += 1
    return count


# -- convert -------------------------------------------------------------------------------------


Decoder = Callable[[AlogEntry], dict[str, str]]  # a value's decoded fields by column name
MAX_DECODED_COLUMNS = 2000  # beyond this, decoded fields are left out (a warning says how many)


def rows(
    paths: Iterable[str | os.PathLike[str]],
    decode: Decoder | None = None,
    columns: Sequence[str] = (),
) -> Iterator[tuple[Any, ...]]:
    """One tuple per entry of each file, in CONVERT_COLUMNS order, then (with `decode`) the
    decoded fields named in `columns` (None where the entry has none)."""
    for path in paths:
        log = AlogFile(path)
        for entry in log:
            row = entry_row(entry, log.log_start)
            if decode is not None and columns:
                fields = decode(entry)
                row += tuple(fields.get(column) for column in columns)
            yield row


def decoded_columns(paths: Iterable[str | os.PathLike[str]], decode: Decoder) -> list[str]:
    """The decoded fields' names in all of `paths`, in the order first seen (a first pass
    over the files, so that CSV and Parquet know their columns before the first row)."""
    columns: dict[str, None] = {}
    left_out: set[str] = set()
    for path in paths:
        for entry in AlogFile(path):
            for name in decode(entry):
                if name in columns or name in left_out:
                    continue
                if len(columns) < MAX_DECODED_COLUMNS:
                    columns[name] = None
                elif len(left_out) < MAX_DECODED_COLUMNS:
                    left_out.add(name)
    if left_out:
        logger.warning(
            "%s%d decoded fields left out (more than %d columns)",
            "at least " if len(left_out) == MAX_DECODED_COLUMNS else "",
            len(left_out),
            MAX_DECODED_COLUMNS,
        )
    return list(columns)


def convert(
    paths: Sequence[str | os.PathLike[str]],
    output: str | os.PathLike[str],
    progress: Callable[[int], None] | None = None,
    jobs: int = 1,
    decoder: Callable[[], Decoder] | None = None,
    columns: Sequence[str] | None = None,
) -> int:
    """Write every entry of `paths` to `output` (.parquet, .csv or .jsonl), file after file;
    returns the rows. With `jobs` > 1 and several files, each file is converted in its own
    process (at most `jobs` at once) to a part beside `output`, and the parts are then joined
    in the files' order: the output is the same as with one job. `decoder()` makes the
    function that adds decoded columns (picklable, for the processes); `columns`: those
    columns when known (else a first pass over the files finds them)."""
    suffix = Path(output).suffix.lower()
    writer = {".parquet": _write_parquet, ".csv": _write_csv, ".jsonl": _write_jsonl}.get(suffix)
    if writer is None:
        raise LogToolError(
            f"{output}: unknown output format {suffix!r} (use {', '.join(CONVERT_FORMATS)})"
        )
    report = progress or (lambda n: None)
    decode = decoder() if decoder is not None else None
    if decode is not None and columns is None:
        columns = decoded_columns(paths, decode)
    columns = list(columns or ())
    if jobs <= 1 or len(paths) <= 1:
        if writer is _write_parquet and not columns:
            return _write_parquet_by_blocks(paths, Path(output), report)
        return writer(rows(paths, decode, columns), Path(output), report, columns)
    return _convert_in_parallel(paths, Path(output), report, jobs, decoder, columns)


def _convert_in_parallel(
    paths: Sequence[str | os.PathLike[str]],
    output: Path,
    progress: Callable[[int], None],
    jobs: int,
    decoder: Callable[[], Decoder] | None,
    columns: list[str],
) -> int:
    with tempfile.TemporaryDirectory(prefix=f".{output.name}.", dir=output.parent) as parts_dir:
        parts = [Path(parts_dir) / f"{index}{output.suffix}" for index in range(len(paths))]
        with ProcessPoolExecutor(max_workers=jobs) as pool:
            futures = [
                pool.submit(convert, [path], part, None, 1, decoder, columns)
                for path, part in zip(paths, parts, strict=True)
            ]
            done = 0
            for future in futures:  # raises the first failure, in the files' order
                done += future.result()
                progress(done)
        return _join_parts(parts, output)


def _join_parts(parts: Sequence[Path], output: Path) -> int:
    """Concatenate converted parts (same format as `output`) into `output`, streaming."""
    count = 0
    if output.suffix.lower() == ".parquet":
        import pyarrow.parquet as pq

        schema = pq.read_schema(parts[0])
        with pq.ParquetWriter(output, schema) as writer:
            for part in parts:
                source = pq.ParquetFile(part)
                for group in range(source.num_row_groups):
                    table = source.read_row_group(group)
                    writer.write_table(table)
                    count += table.num_rows
        return count
    header_lines = 1 if output.suffix.lower() == ".csv" else 0
    with open(output, "wb") as out:
        for index, part in enumerate(parts):
            with open(part, "rb") as source:
                for number, line in enumerate(source):
                    if number < header_lines and index > 0:
                        continue  # one CSV header, the first part's
                    out.write(line)
                    count += number >= header_lines
    return count


def _write_csv(
    source: Iterator[tuple], path: Path, progress: Callable[[int], None], columns: list[str]
) -> int:
    count = 0
    with open(path, "w", newline="") as out:
        writer = csv.writer(out)
        writer.writerow((*CONVERT_COLUMNS, *columns))
        for row in source:
            writer.writerow(row)
            count += 1
            if count % PARQUET_BATCH == 0:
                progress(count)
    return count


def _write_jsonl(
    source: Iterator[tuple], path: Path, progress: Callable[[int], None], columns: list[str]
) -> int:
    base = len(CONVERT_COLUMNS)
    count = 0
    with open(path, "w") as out:
        for row in source:
            record = dict(zip(CONVERT_COLUMNS, row[:base], strict=True))
            # a decoded field only where the entry has it: JSON lines need no fixed columns
            record.update(
                (name, text)
                for name, text in zip(columns, row[base:], strict=True)
                if text is not None
            )
            if record["value_double"] is not None and not math.isfinite(record["value_double"]):
                record["value_double"] = None  # JSON has no inf or nan
            out.write(json.dumps(record, ensure_ascii=False) + "\n")
            count += 1
            if count % PARQUET_BATCH == 0:
                progress(count)
    return count


def _write_parquet(
    source: Iterator[tuple], path: Path, progress: Callable[[int], None], columns: list[str]
) -> int:
    with needs_extra("sim", "Parquet output"):  # pyarrow, as netsim sweeps' results
        import pyarrow.parquet as pq

    count = 0
    with pq.ParquetWriter(path, convert_schema(columns)) as writer:
        while True:
            batch = [row for _, row in zip(range(PARQUET_BATCH), source, strict=False)]
            if not batch:
                break
            writer.write_table(rows_table(batch, columns))
            count += len(batch)
            progress(count)
    return count


def _write_parquet_by_blocks(
    paths: Sequence[str | os.PathLike[str]], path: Path, progress: Callable[[int], None]
) -> int:
    """Without decoded columns: the block reader's tables, written as they come."""
    with needs_extra("sim", "Parquet output"):
        import pyarrow.parquet as pq

    count = 0
    with pq.ParquetWriter(path, convert_schema([])) as writer:
        for source in paths:
            for table in AlogTables(source):
                writer.write_table(table)
                count += table.num_rows
                progress(count)
    return count


# -- replay --------------------------------------------------------------------------------------


async def replay(
    log: AlogFile,
    host: str,
    port: int,
    *,
    warp: float = 1.0,
    start: float = 0.0,
    only: Sequence[str] = (),
    progress: Callable[[float], None] | None = None,
) -> int:
    """Post the entries (from log time `start`, only `only` variables when given) into the
    MOOSDB at host:port with their original spacing divided by `warp`, each under its
    original source name (one client per source, as uPlayBack does); returns how many. A source
    the DB refuses (its name is taken) is skipped with a warning; no DB at all: TimeoutError."""
    from pygoby.moos.client import MOOSClient

    clients: dict[str, MOOSClient] = {}
    refused: set[str] = set()
    loop = asyncio.get_running_loop()
    origin: tuple[float, float] | None = None  # (loop time, log time) of the first post
    count = 0
    try:
        for entry in log:
            if entry.time < start or (only and not matches(entry.name, only)):
                continue
            if entry.source.startswith(DB_SOURCE_PREFIX):
                continue  # the DB's own variables (DB_TIME, ...): the target DB posts its own
            if origin is None:
                origin = (loop.time(), entry.time)
            delay = origin[0] + (entry.time - origin[1]) / warp - loop.time()
            if delay > 0:
                await asyncio.sleep(delay)
            if entry.source in refused:
                continue
            client = clients.get(entry.source)
            if client is None:
                client = clients[entry.source] = MOOSClient(entry.source, host, port)
                try:
                    await client.connect(CONNECT_TIMEOUT)
                except MoosRefusedError as err:
                    # a process of that name is connected already (a live pLogger, ...)
                    logger.warning("not replaying %s's messages: %s", entry.source, err)
                    refused.add(entry.source)
                    await clients.pop(entry.source).close()
                    continue
            client.publish(entry.name, entry.value, src_aux=entry.source_aux)
            count += 1
            if progress is not None and count % 100 == 0:
                progress(entry.time)
    finally:
        for client in clients.values():
            try:
                await client.flush(timeout=2.0)
            finally:
                await client.close()
    return count


def print_progress(stream: IO[str] = sys.stderr) -> Callable[[float], None]:
    last = [0.0]

    def show(log_time: float) -> None:
        now = time.monotonic()
        if now - last[0] >= 0.5:
            last[0] = now
            stream.write(f"\rlog time {log_time:10.2f} s")
            stream.flush()

    return show
