"""Goby MOOS application configuration, sans I/O.

* `read_configuration(config_class, mission, app_name, overrides)`: the app's ProcessConfig block
  parsed as protobuf TextFormat, then the MOOS globals
  named by `(goby.field).moos_global` options, then command-line overrides, then the check for
  required fields. Every problem is a `pygoby.errors.ConfigError` naming the file, the line
  and the field where they are known.
* `example_config(config_class, app_name)`: the `--example_config` text.
* `initializer_posts(common, mission)`: what `common.initializer` posts on every connect.
* `prefixed_var_names(moos_var)`: an app's `moos_var { prefix: ... }` block as full names.
* `config_line(block, field, value)`: the file line where a field (with that value) is set, for
  errors found after parsing.
* `goby_field_options(field)`: a field's `(goby.field)` options (description, example,
  moos_global, cfg.action), read from its serialized options so that it works for classes from
  any descriptor pool.
"""

from __future__ import annotations

import contextlib
import functools
import logging
import math
import re
from collections.abc import Callable, Iterator, Sequence
from contextvars import ContextVar
from typing import Any, TypeVar

from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from pygoby.errors import ConfigError
from pygoby.moos import goby11_config
from pygoby.moos.moosfile import GobyBlock, MissionFile, parse_number
from pygoby.protobuf import enum_type, initialization_errors
from pygoby.protobuf.descriptors import AnyDescriptor, AnyFieldDescriptor
from pygoby.protobuf.goby.moos.protobuf.goby_moos_app_pb2 import GobyMOOSAppConfig
from pygoby.protobuf.goby.protobuf.option_extensions_pb2 import GobyFieldOptions
from pygoby.protobuf.textconfig import (
    check_config_values,
    line_of_field,
    merge_config_text,
    printable_text,
)
from pygoby.protobuf.wire import length_delimited

ConfigT = TypeVar("ConfigT", bound=Message)  # an app's configuration message

log = logging.getLogger(__name__)

GOBY_FIELD_EXTENSION = 1009
EXAMPLE_WIDTH = 66
EXAMPLE_MIN_WIDTH = 20
EXAMPLE_FALLBACK_INDENT = 46


@functools.cache
def _options_class() -> type[GobyFieldOptions]:
    return GobyFieldOptions


def goby_field_options(field: AnyFieldDescriptor) -> GobyFieldOptions:
    """The field's `(goby.field)` options (an empty GobyFieldOptions if it has none)."""
    out = _options_class()()
    if not field.has_options:
        return out
    out.MergeFromString(
        length_delimited(field.GetOptions().SerializeToString(), GOBY_FIELD_EXTENSION)
    )
    return out


# ---------------------------------------------------------------------------------------------
# Reading


def locate(err: ConfigError, mission: MissionFile | None, app_name: str) -> ConfigError:
    """`err` (about the field at `err.field` of the app's configuration) with the mission file
    and the line of that field in the app's ProcessConfig block filled in."""
    block = mission.goby_block(app_name) if mission is not None else None
    if mission is None or block is None or err.field is None:
        return err
    path = mission.path if mission.path else "mission file"
    return err.located(file=path, line=line_of_field(block.text, err.field, block.first_line))


def parse_block(config: Message, text: str, first_line: int, source: str) -> None:
    """Merge TextFormat `text` into `config`; errors give the file line and the field."""
    merge_config_text(text, config, file=source, first_line=first_line)


def config_line(block: GobyBlock, field: str, value: str = "") -> int | None:
    """The file line of the first `field:` (the last part of a dotted name) in `block` whose line
    also contains `value`; None when there is none (e.g. set from the command line)."""
    name = re.escape(field.rsplit(".", 1)[-1])
    pattern = re.compile(rf"(?<![\w.]){name}\s*:")
    for index, text in enumerate(block.text.splitlines(), start=1):
        if pattern.search(text) and value in text:
            return block.file_line(index)
    return None


def apply_moos_globals(config: Message, mission: MissionFile) -> None:
    """Fill every non-repeated, non-oneof field that names a MOOS global (recursively through
    non-repeated sub-messages) from the mission file's globals (lines outside ProcessConfig
    blocks). A field already set in the block keeps its value: goby3 lets the global win, its
    documentation says globals apply only to empty fields: fixed as documented, QUIRKS.md
    Q-APPS-2 and Q-APPS-3)."""
    for field in config.DESCRIPTOR.fields:
        if field.is_repeated or field.containing_oneof is not None:
            continue
        if field.type == FieldDescriptor.TYPE_MESSAGE:
            had = config.HasField(field.name)
            sub = getattr(config, field.name)
            apply_moos_globals(sub, mission)
            if not had and not sub.ListFields():
                config.ClearField(field.name)
            continue
        name = goby_field_options(field).moos_global
        if not name:
            continue
        value = mission.get_value(name, outside_blocks=True)
        if value is None:
            continue
        if config.HasField(field.name):
            log.info(
                "MOOS global %s=%s ignored: %s is set in the ProcessConfig block",
                name,
                value,
                field.full_name,
            )
            continue
        try:
            _set_from_global(config, field, name, value)
        except ConfigError as err:
            path = mission.path if mission.path else "mission file"
            raise err.located(file=path, line=mission.global_line(name)) from None


def _set_from_global(config: Message, field: AnyFieldDescriptor, name: str, value: str) -> None:
    """A MOOS global's text as the field's value; text that is no value of its type is an
    error (MOOS would read "abc" as 0: a mistyped ServerPort must not mean port 9000)."""
    kind = field.type
    if value.encode("utf-8", "surrogateescape") != value.encode("utf-8", "replace"):
        # bytes that are not UTF-8 (a Latin-1 file): protobuf strings must be UTF-8
        raise ConfigError(
            f"{name} = {printable_text(value)} is not valid UTF-8 text", field=field.name
        )
    if kind == FieldDescriptor.TYPE_STRING:
        setattr(config, field.name, value)
    elif kind == FieldDescriptor.TYPE_BOOL:
        if value.upper() in ("TRUE", "FALSE"):
            setattr(config, field.name, value.upper() == "TRUE")
        elif (number := parse_number(value)) is not None:
            setattr(config, field.name, number > 0)
    elif kind == FieldDescriptor.TYPE_ENUM:
        enum_value = enum_type(field).values_by_name.get(value)
        if enum_value is None:
            raise ConfigError(
                f'invalid enumeration "{value}" (MOOS global {name})', field=field.name
            )
        setattr(config, field.name, enum_value.number)
    elif (number := parse_number(value)) is None:
        raise ConfigError(f"{name} = {value} is not a number", field=field.full_name)
    elif kind in (FieldDescriptor.TYPE_DOUBLE, FieldDescriptor.TYPE_FLOAT):
        setattr(config, field.name, number)
    elif number != int(number):
        raise ConfigError(f"{name} = {value} is not a whole number", field=field.full_name)
    else:
        try:
            setattr(config, field.name, int(number))
        except ValueError:
            raise ConfigError(f"{name} = {value} is out of range", field=field.full_name) from None


def apply_overrides(config: Message, overrides: Sequence[tuple[str, str]]) -> None:
    """`--field value` pairs for top-level fields: a scalar replaces the configured value; a
    message field's TextFormat text is merged into it; a repeated field gets one more entry."""
    for name, value in overrides:
        field = config.DESCRIPTOR.fields_by_name.get(name)
        if field is None:
            raise ConfigError(f"unknown option --{name}", file="command line")
        if field.type == FieldDescriptor.TYPE_MESSAGE:
            text = f"{name} {{ {value} }}"
        elif field.type == FieldDescriptor.TYPE_STRING:
            text = f"{name}: {_quote(value)}"
        else:
            text = f"{name}: {value}"
        if not field.is_repeated and field.type != FieldDescriptor.TYPE_MESSAGE:
            config.ClearField(name)
        parse_block(config, text, 1, f"command line --{name}")


def _quote(value: str) -> str:
    return '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'


# Where read_configuration reports the Goby 1.1/2 forms it mapped, while `collecting_notes` runs
# (the app logs them once its logging is set up).
_NOTES: ContextVar[list[str] | None] = ContextVar("pygoby_config_notes", default=None)


@contextlib.contextmanager
def collecting_notes() -> Iterator[list[str]]:
    """`with collecting_notes() as notes:` every read_configuration inside adds its notes."""
    notes: list[str] = []
    token = _NOTES.set(notes)
    try:
        yield notes
    finally:
        _NOTES.reset(token)


def read_configuration(
    config_class: type[ConfigT],
    mission: MissionFile | None,
    app_name: str,
    overrides: Sequence[tuple[str, str]] = (),
    complete: Callable[[ConfigT], None] | None = None,
    notes: list[str] | None = None,
    block_optional: bool = False,
) -> ConfigT:
    """`complete(config)`, if given, runs after the overrides and before the check for required
    fields (an app's own rewriting of older configuration forms). `block_optional`: a mission
    without the app's ProcessConfig block gives the defaults (with the mission's globals). Goby 1.1 and Goby 2 forms are
    mapped onto today's configuration first (pygoby.moos.goby11_config); what was mapped is
    appended to `notes` (for the app to log once)."""
    config = config_class()
    source = str(mission.path) if mission is not None and mission.path else "mission file"
    translated: list[str] = []
    block_text, first_line = "", 1
    if mission is not None:
        block = mission.goby_block(app_name)
        if block is None and not block_optional:
            raise ConfigError(f"no ProcessConfig block for {app_name}", file=source)
        if block is not None:
            block_text, first_line = block.text, block.first_line
        try:
            translation = goby11_config.translate(block_text, config_class.DESCRIPTOR)
        except goby11_config.BlockSyntaxError as err:
            raise ConfigError(err.reason, file=source, line=first_line + err.line - 1) from None
        parse_block(config, translation.text, first_line, source)
        translated = [f"{source}:{_shift(note, first_line)}" for note in translation.notes]
        try:
            apply_moos_globals(config, mission)
        except ConfigError as err:
            raise err.located(file=source) from None
    moved: list[str] = []
    goby11_config.finish(config, moved)
    translated += [f"{source}: {note}" for note in moved]
    sink = notes if notes is not None else _NOTES.get()
    if sink is not None:
        sink.extend(translated)
    apply_overrides(config, overrides)
    if complete is not None:
        complete(config)
    missing = initialization_errors(config)
    if missing:
        raise ConfigError(f"missing required configuration fields: {', '.join(missing)}")
    check_config_values(config, block_text, file=source, first_line=first_line)
    return config


def _shift(note: str, first_line: int) -> str:
    """A translation note's block line ("line N: ...") as a file line ("M: ...")."""
    head, sep, rest = note.partition(": ")
    if sep and head.startswith("line ") and head[5:].isdigit():
        return f"{first_line + int(head[5:]) - 1}: {rest}"
    return f" {note}"


# ---------------------------------------------------------------------------------------------
# --example_config


def _format_scalar(field: AnyFieldDescriptor, value: object) -> str:
    if field.type == FieldDescriptor.TYPE_ENUM:
        return enum_type(field).values_by_number[value].name  # type: ignore[index]
    if field.type == FieldDescriptor.TYPE_BOOL:
        return "true" if value else "false"
    if field.type in (FieldDescriptor.TYPE_STRING, FieldDescriptor.TYPE_BYTES):
        raw = value.decode("latin-1") if isinstance(value, bytes) else str(value)
        return _quote(raw)
    if isinstance(value, float):
        text = repr(value)
        return text[:-2] if text.endswith(".0") else text
    return str(value)


def _label(field: AnyFieldDescriptor) -> str:
    if field.is_repeated:
        return " (repeated)"
    return " (required)" if field.is_required else " (optional)"


def _wrap(prefix: str, comment: str) -> list[str]:
    width = EXAMPLE_WIDTH - len(prefix)
    if width < EXAMPLE_MIN_WIDTH:
        lead, width = " " * EXAMPLE_FALLBACK_INDENT, EXAMPLE_WIDTH - EXAMPLE_FALLBACK_INDENT
        head, pieces = [prefix.rstrip()], _wrap_words(comment, width)
        return head + [lead + piece for piece in pieces]
    pieces = _wrap_words(comment, width)
    return [prefix + pieces[0]] + [" " * len(prefix) + piece for piece in pieces[1:]]


def _wrap_words(comment: str, width: int) -> list[str]:
    words = comment.split(" ")
    lines: list[str] = []
    current = ""
    for word in words:
        if current and len(current) + 1 + len(word) > width:
            lines.append(current + " ")
            current = "# " + word
        else:
            current = f"{current} {word}" if current else word
    lines.append(current)
    return lines


def _extensions(descriptor: AnyDescriptor) -> list[AnyFieldDescriptor]:
    """Extensions of `descriptor` loaded into its pool (e.g. driver configurations)."""
    try:
        found = descriptor.file.pool.FindAllExtensions(descriptor)  # type: ignore[arg-type]
    except (AttributeError, KeyError):
        return []
    return sorted(found, key=lambda f: f.number)


def _describe_fields(descriptor: AnyDescriptor, depth: int) -> list[str]:
    out: list[str] = []
    indent = "  " * depth
    for field in [*descriptor.fields, *_extensions(descriptor)]:
        opts = goby_field_options(field)
        if opts.HasField("cfg") and opts.cfg.action != opts.cfg.ALWAYS:
            continue
        comment = "# " + opts.description
        name = f"[{field.full_name}]" if field.is_extension else field.name
        if field.type == FieldDescriptor.TYPE_MESSAGE:
            out.extend(_wrap(f"{indent}{name} {{  ", comment + _label(field)))
            out.extend(_describe_fields(field.message_type, depth + 1))
            out.append(f"{indent}}}")
            continue
        if field.has_default_value:
            value = _format_scalar(field, field.default_value)
        elif opts.HasField("example"):
            value = (
                _quote(opts.example) if field.type == FieldDescriptor.TYPE_STRING else opts.example
            )
        elif field.type == FieldDescriptor.TYPE_STRING:
            value = '""'
        elif field.is_required:  # goby3 prints nothing, which does not parse when copied
            value = _placeholder(field)
        else:
            value = ""
        if field.type == FieldDescriptor.TYPE_ENUM:
            comment += " (" + ", ".join(v.name for v in enum_type(field).values) + ")"
        comment += _label(field)
        if field.has_default_value:
            comment += f" (default={_format_scalar(field, field.default_value)})"
        if opts.moos_global:
            comment += f' (can also set MOOS global "{opts.moos_global}=")'
        out.extend(_wrap(f"{indent}{name}: {value}  ", comment))
    return out


def _placeholder(field: AnyFieldDescriptor) -> str:
    """A value of the field's type that parses (the first enumerator, 0, false, "")."""
    if field.type == FieldDescriptor.TYPE_ENUM:
        return enum_type(field).values[0].name
    if field.type == FieldDescriptor.TYPE_BOOL:
        return "false"
    if field.type == FieldDescriptor.TYPE_BYTES:
        return '""'
    return "0"


def example_config(config_class: type[Message], app_name: str) -> str:
    lines = [f"ProcessConfig = {app_name}", "{", *_describe_fields(config_class.DESCRIPTOR, 1), "}"]
    return "\n".join(lines) + "\n"


def initializer_posts(
    common: GobyMOOSAppConfig, mission: MissionFile | None, log: logging.Logger = log
) -> list[tuple[str, float | str]]:
    """The (MOOS variable, value) posts of `common.initializer`: a constant, or a
    global of the mission file (a double that does not parse is NaN); a missing global is
    warned about on `log` and not posted."""
    posts = []
    for ini in common.initializer:
        value = _initializer_value(ini, common, mission, log)
        if value is not None:
            posts.append((ini.moos_var, value))
    return posts


def _initializer_value(
    ini: GobyMOOSAppConfig.Initializer,
    common: GobyMOOSAppConfig,
    mission: MissionFile | None,
    log: logging.Logger,
) -> float | str | None:
    is_double = ini.type == type(common).Initializer.INI_DOUBLE
    if not ini.HasField("global_cfg_var"):
        if is_double:
            return ini.dval
        return ini.sval.strip() if ini.trim else ini.sval
    raw = mission.get_value(ini.global_cfg_var, outside_blocks=True) if mission else None
    if raw is None:
        log.warning(
            "initializer: global %s not found; %s not posted", ini.global_cfg_var, ini.moos_var
        )
        return None
    if not is_double:
        return raw.strip() if ini.trim else raw
    try:
        return float(raw)
    except ValueError:
        return math.nan


def prefixed_var_names(names: Any, skip: Sequence[str] = ()) -> dict[str, str]:
    """An app's `moos_var` block as {field name: prefix + variable}, for every field but
    `prefix` and those in `skip`."""
    return {
        field.name: names.prefix + getattr(names, field.name)
        for field in names.DESCRIPTOR.fields
        if field.name != "prefix" and field.name not in skip
    }
