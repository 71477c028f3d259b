"""The MOOS .alog text format, sans I/O: what pLogger writes and what MOOS-IvP's alog tools read.

A file starts with a banner of `%%` lines::

    %%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%
    %% LOG FILE:       ./MOOSLog_2_12_2026_____02_47_53/MOOSLog_2_12_2026_____02_47_53.alog
    %% FILE OPENED ON  Wed Dec  2 02:47:53 2026
    %% LOGSTART           1764643673.12
    %%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%%

then one line per message, as pLogger pads it: the time since LOGSTART (fixed, 3 decimals,
left-justified in 15 columns), the variable (20 columns), the source (15 columns; `src:aux`
with LogAuxSrc, `...@community` with MarkExternalCommunityMessages), the value and one space
(a binary value's `<MOOS_BINARY>` .blog reference ends the line without one).
Doubles are fixed with DoublePrecision decimals (5 by default) left-justified in 12 columns;
strings are written as they are. A reader cannot tell the string "3.5" from the double 3.5
unless the file was written with MarkDataType (`D:`/`S:` before each value), so like MOOS-IvP's
tools it takes any value that is a number as a double.
"""

from __future__ import annotations

import math
import re
import time as _time
from dataclasses import dataclass, field

from pygoby.moos.protocol import decode_text

BANNER_RULE = "%" * 59
DEFAULT_DOUBLE_PRECISION = 5
# pLogger writes this line when MarkDataType is on: values then start with D: or S:
DATATYPE_MARKING = "%% DATATYPE MARKING ON"
# ours: with MarkDataAsBinary, binary values are written inline as B:<hex> (see QUIRKS.md)
BINARY_MARKING = "%% BINARY MARKING ON"
BINARY_TAG = re.compile(
    r"<MOOS_BINARY>File=(?P<file>[^,]*),Offset=(?P<offset>\d+),Bytes=(?P<size>\d+)</MOOS_BINARY>"
)
# The patterns are ASCII-only and written with explicit classes (no \d or \S, whose meaning
# differs between Python's and RE2's regular expressions) because the block parser
# (pygoby.moos.alog.columns) runs the same pattern texts in pyarrow and must agree line for line.
# whitespace as C's isspace (the MOOS tools' trimming): a value ending in U+00A0 is not a number
SPACE = " \t\n\r\f\v"
# a number, exponent allowed: a time, LOGSTART, a value marked D:
NUMBER_TEXT = r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)(?:[eE][+-]?[0-9]+)?"
_NUMBER = re.compile(rf"{NUMBER_TEXT}|[+-]?(?:inf|nan)")
# an unmarked value read as a double: what pLogger writes for one (fixed digits, or C++'s inf
# and nan), which is also what MOOS-IvP's isNumber takes for a number (no exponent: "1e5" is a
# string to both)
DOUBLE_TEXT = r"[+-]?(?:[0-9]+\.?[0-9]*|\.[0-9]+)|[+-]?(?:inf|nan)"
_DOUBLE_AS_WRITTEN = re.compile(DOUBLE_TEXT)
# TIME VARIABLE SOURCE [VALUE]: one match checks the columns and that the time is a number; a
# negative time (a value pLogger got from the DB as it registered) is an entry, where MOOS-IvP's
# aloggrep and alogscan skip it (QUIRKS.md Q-MOOS-20)
_WORD = r"[^ \t\n\r\f\v]+"
ENTRY_TEXT = (
    rf"[ \t]*(?P<time>{NUMBER_TEXT})[ \t]+(?P<name>{_WORD})[ \t]+(?P<source>{_WORD})"
    r"(?:[ \t]+(?P<value>.*))?"
)
_ENTRY = re.compile(ENTRY_TEXT)

Value = float | str | bytes


@dataclass(slots=True)
class AlogEntry:
    """One logged message. `time` is seconds since LOGSTART; `value` is a float (double), str
    (string) or bytes (binary; `binary_ref` holds the .blog reference while it is unresolved).
    `line` is the line as the file has it (without its newline) and `value_column` its value
    column as written (padding and trailing space included): the tools that copy lines, as
    MOOS-IvP's do, copy these."""

    time: float
    name: str
    source: str
    value: Value
    source_aux: str = ""
    community: str = ""
    binary_ref: tuple[str, int, int] | None = None
    line: str = ""
    value_column: str = ""

    @property
    def type(self) -> str:
        if isinstance(self.value, float):
            return "double"
        if isinstance(self.value, bytes) or self.binary_ref is not None:
            return "binary"
        return "string"

    @property
    def full_source(self) -> str:
        """The source column as written: `src[:aux][@community]`."""
        text = f"{self.source}:{self.source_aux}" if self.source_aux else self.source
        return f"{text}@{self.community}" if self.community else text


def value_text(entry: AlogEntry) -> str:
    """The value as a string column: doubles as Python prints them, binary as hex."""
    value = entry.value
    if isinstance(value, bytes):
        return value.hex()
    if isinstance(value, float):
        return repr(value)
    return value


def banner(
    file_name: str,
    log_start: float,
    *,
    opened_on: float | None = None,
    mark_data_type: bool = False,
    mark_binary: bool = False,
) -> str:
    """The `%%` header pLogger writes at the top of each of its files."""
    opened = _time.ctime(_time.time() if opened_on is None else opened_on)
    lines = [
        BANNER_RULE,
        f"%% LOG FILE:       {file_name}",
        f"%% FILE OPENED ON  {opened}",
        f"%% LOGSTART        {log_start:>20.12g}",
    ]
    if mark_data_type:
        lines.append(DATATYPE_MARKING)
    if mark_binary:
        lines.append(BINARY_MARKING)
    lines.append(BANNER_RULE)
    return "\n".join(lines) + "\n"


@dataclass
class AlogFormatter:
    """Formats messages as pLogger does. `own_community` is the logger's community: with
    `mark_external`, sources of messages from other communities get `@community`."""

    log_start: float
    double_precision: int = DEFAULT_DOUBLE_PRECISION
    log_aux_src: bool = False
    mark_external: bool = False
    own_community: str = ""
    mark_data_type: bool = False
    mark_binary: bool = False

    def prefix(
        self, msg_time: float, name: str, src: str, src_aux: str = "", community: str = ""
    ) -> str:
        """The time, variable and source columns (with their separating spaces)."""
        source = src
        if self.log_aux_src and src_aux:
            source += ":" + src_aux
        if self.mark_external and community and community != self.own_community:
            source += "@" + community
        return f"{msg_time - self.log_start:<15.3f} {name:<20} {source:<15} "

    def value_text(self, value: Value) -> str:
        """The value column (without the trailing space). Binary values: only with
        mark_binary (inline hex); otherwise the caller writes them to the .blog."""
        if isinstance(value, float | int):
            text = f"{float(value):<12.{self.double_precision}f}"
            return "D:" + text if self.mark_data_type else text
        if isinstance(value, bytes):
            if not self.mark_binary:
                raise ValueError("binary values go to the .blog unless mark_binary is set")
            return inline_binary(value)
        return "S:" + value if self.mark_data_type else value

    def line(
        self,
        msg_time: float,
        name: str,
        src: str,
        value: Value,
        src_aux: str = "",
        community: str = "",
    ) -> str:
        """One whole line for a double or string value (or binary with mark_binary)."""
        return f"{self.prefix(msg_time, name, src, src_aux, community)}{self.value_text(value)} \n"


def inline_binary(value: bytes) -> str:
    """A binary value as the MarkDataAsBinary files write it in the value column."""
    return "B:" + value.hex().upper()


def binary_tag(blog_name: str, offset: int, size: int) -> str:
    """What pLogger writes in the .alog for a binary value stored at `offset` in the .blog."""
    return f"<MOOS_BINARY>File={blog_name},Offset={offset},Bytes={size}</MOOS_BINARY>"


@dataclass
class AlogReader:
    """Parses .alog lines one at a time. Never raises on content: lines that are not a banner
    line or a `TIME VAR SOURCE VALUE` entry are counted in `bad_lines` and skipped."""

    log_start: float | None = None
    log_file: str = ""
    opened_on: str = ""
    data_type_marked: bool = False
    binary_marked: bool = False
    lines: int = 0
    bad_lines: int = 0
    first_bad_line: int | None = None
    _header: list[str] = field(default_factory=list)

    def feed(self, line: str) -> AlogEntry | None:
        """The entry on `line` (without or with its newline), or None for header or bad lines."""
        self.lines += 1
        line = line.rstrip("\r\n")
        if line.startswith("%%"):
            self._header_line(line)
            return None
        match = _ENTRY.fullmatch(line)
        if match is None:
            self._bad(line)
            return None
        stamp, name, source, raw = match.groups()
        msg_time = float(stamp)
        if not math.isfinite(msg_time):  # digits beyond a double's range
            self._bad(line)
            return None
        value = self._value(raw or "")
        if value is None:
            self._bad(line)
            return None
        src, aux, community = split_source(source)
        return AlogEntry(msg_time, name, src, value[0], aux, community, value[1], line, raw or "")

    def _value(self, raw: str) -> tuple[Value, tuple[str, int, int] | None] | None:
        # pLogger ends every value with one space; doubles are padded further
        if raw.endswith(" "):
            raw = raw[:-1]
        if self.data_type_marked and raw[:2] in ("D:", "S:"):
            kind, raw = raw[0], raw[2:]
            if kind == "S":
                return raw, None
            number = raw.rstrip(SPACE)
            return (float(number), None) if _NUMBER.fullmatch(number) else None
        if self.binary_marked and raw.startswith("B:"):
            try:
                return bytes.fromhex(raw[2:].strip()), None
            except ValueError:
                return None
        if raw.startswith("<MOOS_BINARY>"):
            tag = BINARY_TAG.fullmatch(raw.strip())
            if tag:
                return b"", (tag["file"], int(tag["offset"]), int(tag["size"]))
        number = raw.rstrip(SPACE)
        if _DOUBLE_AS_WRITTEN.fullmatch(number):
            return float(number), None
        return raw, None

    def _header_line(self, line: str) -> None:
        body = line[2:].strip()
        if body.startswith("LOGSTART"):
            stamp = body[len("LOGSTART") :].strip()
            if _NUMBER.fullmatch(stamp) and math.isfinite(float(stamp)):
                self.log_start = float(stamp)
        elif body.startswith("LOG FILE:"):
            self.log_file = body[len("LOG FILE:") :].strip()
        elif body.startswith("FILE OPENED ON"):
            self.opened_on = body[len("FILE OPENED ON") :].strip()
        elif line == DATATYPE_MARKING:
            self.data_type_marked = True
        elif line == BINARY_MARKING:
            self.binary_marked = True

    def skip_line(self) -> None:
        """Count a line the caller could not hand over (too long) as a damaged one."""
        self.lines += 1
        self._bad("?")

    def _bad(self, line: str) -> None:
        if line.strip():  # blank lines are not damage
            self.bad_lines += 1
            if self.first_bad_line is None:
                self.first_bad_line = self.lines


def split_source(source: str) -> tuple[str, str, str]:
    """`src[:aux][@community]` -> (src, aux, community)."""
    if "@" not in source and ":" not in source:
        return source, "", ""
    community = ""
    if "@" in source:
        source, community = source.rsplit("@", 1)
    src, _, aux = source.partition(":")
    return src, aux, community


def decode_line(raw: bytes) -> str:
    """A line of a file as text: MOOS strings are bytes, kept losslessly."""
    return decode_text(raw)


SYNC_COLUMN_WIDTH = 18


def slog_header(file_name: str, log_start: float, variables: list[str]) -> str:
    """The .slog banner and its list of columns (pLogger's SyncLog file)."""
    lines = [banner(file_name, log_start).rstrip("\n"), "%%   (1) TIME "]
    lines += [f"%%   ({n}) {var}" for n, var in enumerate(variables, start=2)]
    lines.append("%" * 56)
    return "\n".join(lines) + "\n"


def slog_labels(variables: list[str], since_start: float) -> str:
    """The two comment lines pLogger repeats every 30 rows: the names, then the time."""
    width = SYNC_COLUMN_WIDTH
    names = "".join(f"{var:<{width}} " for var in ["%% TIME", *variables])
    stamp = f"[{since_start:7.2f}]"
    times = f"{'%% TIME':<{width}} " + "".join(f"{stamp:<{width}} " for _ in variables)
    return names + "\n" + times + "\n"


def slog_row(since_start: float, values: list[float | None]) -> str:
    """One .slog row: the time, then each variable's newest double since the last row or NaN."""
    width = SYNC_COLUMN_WIDTH
    cells = [f"{since_start:<{width}.7g} "]
    cells += [f"{'NaN' if v is None else format(v, 'g'):<{width}} " for v in values]
    return "".join(cells) + "\n"
