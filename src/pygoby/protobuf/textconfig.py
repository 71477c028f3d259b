"""TextFormat configuration files: read whatever their bytes, every problem a ConfigError that
says file:line and field.

* `read_config_file(path)`: the file's text; bytes that are not UTF-8 are kept as surrogate
  escapes, so a Latin-1 comment is harmless and a Latin-1 string value is reported where it is.
* `merge_config_text(text, message, file=, first_line=)`: TextFormat merge; protobuf's parse
  and encoding errors become ConfigError at the file line of the problem.
* `check_config_values(message, text, file=, first_line=)`: values the schema cannot express:
  every integer field named `...port` must be a TCP/UDP port number (0-65535).
"""

from __future__ import annotations

import os
import re
from collections.abc import Iterator
from pathlib import Path

from google.protobuf import text_format
from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from pygoby.errors import ConfigError
from pygoby.protobuf.descriptors import INTEGER_FIELD_TYPES, AnyFieldDescriptor

PORT_MAX = 65535


def read_config_file(
    path: str | os.PathLike[str], *, error: type[ConfigError] = ConfigError
) -> str:
    try:
        data = Path(path).read_bytes()
    except OSError as exc:
        raise error(f"cannot read: {exc.strerror or exc}", file=path) from None
    return data.decode("utf-8", "surrogateescape")


def merge_config_text(
    text: str,
    message: Message,
    *,
    file: str | os.PathLike[str] | None = None,
    first_line: int = 1,
    parser: text_format._Parser | None = None,
    error: type[ConfigError] = ConfigError,
) -> None:
    """Merge TextFormat `text` (starting at `first_line` of `file`) into `message`; problems
    raise `error` (ConfigError or a subclass, e.g. ScenarioError)."""
    lines = text.split("\n")
    _refuse_non_utf8(lines, file, first_line, error)
    try:
        if parser is None:
            text_format.Merge(text, message)
        else:
            parser.MergeLines(lines, message)
    except text_format.ParseError as err:
        line, column = err.GetLine(), err.GetColumn()
        raise _located(error, str(err), line, column, lines, file, first_line) from None
    except (UnicodeError, ValueError) as err:  # protobuf's own checks on a value it took
        raise error(f"cannot parse configuration: {err}", file=file) from None


def _located(
    error: type[ConfigError],
    message: str,
    line: int | None,
    column: int | None,
    lines: list[str],
    file: str | os.PathLike[str] | None,
    first_line: int,
) -> ConfigError:
    if line is None:
        return error(message, file=file)
    line_text = lines[line - 1] if 0 < line <= len(lines) else ""
    detail = message.split(" : ", 1)[-1]
    quoted = f"'{line_text}': "
    if detail.startswith(quoted):
        detail = detail[len(quoted) :]
    if "surrogates not allowed" in detail:  # bytes of the file that are not UTF-8
        detail = "string is not valid UTF-8 (protobuf strings must be)"
    shown = printable_text(line_text.strip())
    detail = printable_text(detail)
    return error(
        f"{detail}\n    {shown}",
        file=file,
        line=first_line + line - 1,
        field=_field_near(line_text, column or 0),
    )


_SURROGATE = re.compile("[\udc80-\udcff]")  # a byte of the file that is not UTF-8


def _refuse_non_utf8(
    lines: list[str],
    file: str | os.PathLike[str] | None,
    first_line: int,
    error: type[ConfigError],
) -> None:
    """A non-UTF-8 byte outside comments is a located error here: in a string protobuf could
    not store it, and in an enum value (quoted or not) its parser fails with a SystemError.
    In a `#` comment it is harmless."""
    for number, line in enumerate(lines, start=1):
        if _SURROGATE.search(line) is None:
            continue
        quote = ""
        escaped = False
        for column, char in enumerate(line):
            if quote:
                if escaped:
                    escaped = False
                elif char == "\\":
                    escaped = True
                elif char == quote:
                    quote = ""
            elif char in "\"'":
                quote = char
            elif char == "#":
                break
            if _SURROGATE.match(char):
                reason = (
                    "string is not valid UTF-8 (protobuf strings must be)"
                    if quote
                    else f"byte 0x{ord(char) - 0xDC00:02X} is not valid UTF-8 (configuration "
                    "text must be UTF-8 outside comments)"
                )
                raise error(
                    f"{reason}\n    {printable_text(line.strip())}",
                    file=file,
                    line=first_line + number - 1,
                    field=_field_near(line, column + 1),
                )


def printable_text(text: str) -> str:
    """Text with the file's non-UTF-8 bytes shown as \\xNN escapes."""
    raw = text.encode("utf-8", "surrogateescape")
    return raw.decode("utf-8", "backslashreplace")


def _field_near(line_text: str, column: int) -> str | None:
    """The field name at or before the (1-based) column of an error on `line_text`."""
    names = list(re.finditer(r"([A-Za-z_][\w.]*|\[[\w.]+\])\s*[:{]", line_text))
    before = [match for match in names if match.start() < max(column, 1)]
    chosen = before[-1] if before else (names[0] if names else None)
    return chosen.group(1) if chosen else None


def check_config_values(
    message: Message,
    text: str = "",
    *,
    file: str | os.PathLike[str] | None = None,
    first_line: int = 1,
    error: type[ConfigError] = ConfigError,
) -> None:
    """Port numbers in range; the error names the field's path and, found in `text`, its line."""
    for path, field, value in _integer_values(message, ""):
        if field.name.lower().endswith("port") and not 0 <= value <= PORT_MAX:
            raise error(
                f"{value} is not a port number (0-{PORT_MAX})",
                file=file,
                line=line_of_field(text, path, first_line),
                field=path,
            )


def line_of_field(text: str, path: str, first_line: int = 1) -> int | None:
    """The file line where the field at `path` ("mac_cfg.slot[2].rate", "translator_entry[1]",
    "driver_cfg.[ext.name].tcp_port") is set in TextFormat `text`: each part is looked for after
    the previous one, its n-th occurrence for an index [n]. None if it cannot be found."""
    code = "\n".join(line.split("#", 1)[0] for line in text.split("\n"))
    position = 0
    for part in re.findall(r"\[[^\]]*\]\.?|[^.\[\]]+(?:\[\d+\])?", path):
        part = part.rstrip(".")
        if part.startswith("[") and not part[1:-1].isdigit():
            name, index = part, 0  # an extension: [full.name]
        else:
            name, _, index_text = part.partition("[")
            index = int(index_text.rstrip("]") or 0)
        pattern = re.compile(rf"(?<![\w.]){re.escape(name)}\s*[:{{]")
        for _ in range(index + 1):
            match = pattern.search(code, position)
            if match is None:
                return None
            position = match.end()
    return first_line + code.count("\n", 0, position) if path else None


def _integer_values(message: Message, prefix: str) -> Iterator[tuple[str, AnyFieldDescriptor, int]]:
    for field, value in message.ListFields():
        name = f"[{field.full_name}]" if field.is_extension else field.name
        path = f"{prefix}{name}"
        values = value if field.is_repeated else [value]
        for index, item in enumerate(values):
            item_path = f"{path}[{index}]" if field.is_repeated else path
            if field.type == FieldDescriptor.TYPE_MESSAGE:
                yield from _integer_values(item, item_path + ".")
            elif field.type in INTEGER_FIELD_TYPES:
                yield item_path, field, item
