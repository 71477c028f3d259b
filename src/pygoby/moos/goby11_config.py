"""Goby 1.1 and Goby 2 configuration forms, mapped onto today's (goby3) configuration in one
step when a ProcessConfig block is read.

The block's TextFormat text is tokenized and walked along the configuration's descriptor, so a
rule applies to a message *type* wherever it appears (every app's `common`, every DriverConfig,
every MAC slot). Rewritten fields stay on their lines, so protobuf's own parse errors still name
the right line of the mission file. Each change is described in a note (`line N: ...`) that the
app logs once at VERBOSE.

| Goby 1.1 / 2 form | becomes |
|---|---|
| `verbosity: VERBOSITY_QUIET/WARN/VERBOSE/DEBUG/GUI` | `QUIET/WARN/VERBOSE/DEBUG1/VERBOSE` (GUI: and `show_gui: true`) |
| `[MicroModemConfig.X]`, `[micromodem.protobuf.Config.X]` | `[goby.acomms.micromodem.protobuf.config] { X }` |
| `[UDPDriverConfig.X]`, `[ABCDriverConfig.X]` | `[goby.acomms.udp/abc.protobuf.config] { X }` |
| slot `type: SLOT_DATA/PING/REMUS_LBL/NARROWBAND_LBL` | `DATA` / `DRIVER_SPECIFIC` + Micro-Modem transmission type |
| slot `last_heard_time`, `dccl_cfg.modem_id` | dropped (set internally) |
| `tcp_share_*`, manipulator `TCP_SHARE_IN` | dropped with a warning (TCP sharing is not implemented) |
| `dccl_cfg`/`queue_cfg` `message_file` | `transitional_cfg.message_file` (after parsing; see `finish`) |

`queue_cfg { queue { key { type: QUEUE_CCL ... } } }`, `transitional_cfg` and the top-level
`driver_type` are part of pygoby's configuration and need no rewriting.
"""

from __future__ import annotations

import re
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from pygoby.moos.errors import BlockSyntaxError
from pygoby.protobuf.descriptors import AnyDescriptor, AnyFieldDescriptor

# ---------------------------------------------------------------------------------------------
# Tokens and the field tree


@dataclass
class Token:
    text: str
    line: int


@dataclass
class Field:
    name: Token
    colon: Token | None = None
    value: list[Token] = field(default_factory=list)  # a scalar (or a [list]), or...
    children: list[Field] | None = None  # ...a block
    brackets: tuple[Token, Token] | None = None  # the block's { } or < >
    separator: Token | None = None

    @property
    def key(self) -> str:
        return self.name.text

    def tokens(self) -> list[Token]:
        out = [self.name]
        if self.colon is not None:
            out.append(self.colon)
        if self.children is not None:
            assert self.brackets is not None
            out.append(self.brackets[0])
            for child in self.children:
                out += child.tokens()
            out.append(self.brackets[1])
        else:
            out += self.value
        if self.separator is not None:
            out.append(self.separator)
        return out


_TOKEN = re.compile(
    r"""(?P<space>[ \t\r\f\v]+)|(?P<newline>\n)|(?P<comment>\#[^\n]*)
      |(?P<string>"(?:[^"\\\n]|\\.)*"|'(?:[^'\\\n]|\\.)*')
      |(?P<ext>\[[A-Za-z_][\w.]*(?:/[\w.]+)?\])
      |(?P<word>[\w.+-]+)|(?P<punct>[{}<>:,;\[\]])""",
    re.VERBOSE,
)


def tokenize(text: str) -> list[Token]:
    tokens: list[Token] = []
    line, pos = 1, 0
    while pos < len(text):
        match = _TOKEN.match(text, pos)
        if match is None:
            raise ValueError(f"line {line}: unexpected {text[pos]!r}")
        kind = match.lastgroup
        if kind == "newline":
            line += 1
        elif kind not in ("space", "comment"):
            tokens.append(Token(match.group(), line))
        pos = match.end()
    return tokens


class _Parser:
    def __init__(self, tokens: list[Token]) -> None:
        self.tokens = tokens
        self.pos = 0

    def peek(self) -> str | None:
        return self.tokens[self.pos].text if self.pos < len(self.tokens) else None

    def take(self) -> Token:
        if self.pos >= len(self.tokens):
            raise ValueError("unexpected end of the block")
        token = self.tokens[self.pos]
        self.pos += 1
        return token

    def fields(self, closing: str | None) -> list[Field]:
        out = []
        while self.peek() is not None and self.peek() != closing:
            out.append(self.field())
        return out

    def field(self) -> Field:
        name = self.take()
        if not (re.fullmatch(r"[A-Za-z_]\w*", name.text) or name.text.startswith("[")):
            raise ValueError(f"line {name.line}: {name.text!r} is not a field name")
        result = Field(name)
        if self.peek() == ":":
            result.colon = self.take()
        if self.peek() in ("{", "<"):
            opening = self.take()
            closing = "}" if opening.text == "{" else ">"
            result.children = self.fields(closing)
            if self.peek() is None:
                raise BlockSyntaxError(
                    name.line, f"the '{opening.text}' after {name.text} is never closed"
                )
            result.brackets = (opening, self.take())
        elif result.colon is None:
            raise BlockSyntaxError(name.line, f"expected ':' after {name.text}")
        elif self.peek() == "[":
            result.value.append(self.take())
            while self.peek() not in ("]", None):
                result.value.append(self.take())
            result.value.append(self.take())
        else:
            result.value.append(self.take())
            while (
                (following := self.peek()) is not None
                and following[0] in "\"'"
                and result.value[-1].text[0] in "\"'"
            ):
                result.value.append(self.take())  # adjacent strings concatenate
        if self.peek() in (",", ";"):
            result.separator = self.take()
        return result


def render(fields: list[Field]) -> str:
    """Text whose tokens stand on their original lines (moved or added ones on the line of the
    token before them)."""
    out: list[str] = []
    line = 1
    for f in fields:
        for token in f.tokens():
            if token.line > line:
                out.append("\n" * (token.line - line))
                line = token.line
            elif out:
                out.append(" ")
            out.append(token.text)
    return "".join(out)


# ---------------------------------------------------------------------------------------------
# Rules, by the message type a field appears in

VERBOSITY = {
    "VERBOSITY_QUIET": "QUIET",
    "VERBOSITY_WARN": "WARN",
    "VERBOSITY_VERBOSE": "VERBOSE",
    "VERBOSITY_DEBUG": "DEBUG1",
    "VERBOSITY_GUI": "VERBOSE",
}
# Goby 1.1/2 driver extension scopes -> the goby3 extension holding their fields.
DRIVER_EXTENSIONS = {
    "MicroModemConfig": "goby.acomms.micromodem.protobuf.config",
    "micromodem.protobuf.Config": "goby.acomms.micromodem.protobuf.config",
    "goby.acomms.protobuf.MicroModemConfig": "goby.acomms.micromodem.protobuf.config",
    "UDPDriverConfig": "goby.acomms.udp.protobuf.config",
    "ABCDriverConfig": "goby.acomms.abc.protobuf.config",
}
SLOT_TYPES = {
    "SLOT_DATA": None,
    "SLOT_PING": "MICROMODEM_TWO_WAY_PING",
    "SLOT_REMUS_LBL": "MICROMODEM_REMUS_LBL_RANGING",
    "SLOT_NARROWBAND_LBL": "MICROMODEM_NARROWBAND_LBL_RANGING",
}
MM_TRANSMISSION = "goby.acomms.micromodem.protobuf.transmission"
UNSUPPORTED = {"tcp_share_enable", "tcp_share_port", "tcp_share_to_ip"}

Rule = Callable[[Field, list[str]], list[Field] | None]  # None: keep the field as it is


def _synthetic(text: str, line: int) -> Token:
    return Token(text, line)


def _verbosity(f: Field, notes: list[str]) -> list[Field] | None:
    if f.key not in ("verbosity", "log_verbosity") or len(f.value) != 1:
        return None
    old = f.value[0].text
    new = VERBOSITY.get(old)
    if new is None:
        return None
    gui = old == "VERBOSITY_GUI" and f.key == "verbosity"  # Goby 2 made it show_gui: true
    extra = " and show_gui: true" if gui else ""
    notes.append(f"line {f.name.line}: {f.key}: {old} -> {new}{extra}")
    f.value = [_synthetic(new, f.value[0].line)]
    if not gui:
        return [f]
    line = f.name.line
    show_gui = Field(
        _synthetic("show_gui", line), _synthetic(":", line), [_synthetic("true", line)]
    )
    return [f, show_gui]


def _driver_extension(f: Field, notes: list[str]) -> list[Field] | None:
    if not f.key.startswith("["):
        return None
    scope, _, name = f.key[1:-1].rpartition(".")
    target = DRIVER_EXTENSIONS.get(scope)
    if target is None:
        return None
    line = f.name.line
    notes.append(f"line {line}: [{scope}.{name}] -> [{target}] {{ {name} }}")
    inner = Field(_synthetic(name, line), f.colon, f.value, f.children, f.brackets)
    return [
        Field(
            _synthetic(f"[{target}]", line),
            children=[inner],
            brackets=(_synthetic("{", line), _synthetic("}", line)),
        )
    ]


def _slot(f: Field, notes: list[str]) -> list[Field] | None:
    line = f.name.line
    if f.key == "last_heard_time":
        notes.append(f"line {line}: slot last_heard_time dropped (kept internally by the MAC)")
        return []
    if f.key != "type" or len(f.value) != 1 or f.value[0].text not in SLOT_TYPES:
        return None
    old = f.value[0].text
    driver_type = SLOT_TYPES[old]
    if driver_type is None:
        notes.append(f"line {line}: slot type: {old} -> DATA")
        f.value = [_synthetic("DATA", line)]
        return [f]
    notes.append(f"line {line}: slot type: {old} -> DRIVER_SPECIFIC, Micro-Modem {driver_type}")
    f.value = [_synthetic("DRIVER_SPECIFIC", line)]
    inner = Field(_synthetic("type", line), _synthetic(":", line), [_synthetic(driver_type, line)])
    return [
        f,
        Field(
            _synthetic(f"[{MM_TRANSMISSION}]", line),
            children=[inner],
            brackets=(_synthetic("{", line), _synthetic("}", line)),
        ),
    ]


def _dccl_cfg(f: Field, notes: list[str]) -> list[Field] | None:
    if f.key != "modem_id":
        return None
    notes.append(f"line {f.name.line}: dccl_cfg.modem_id dropped (the top-level modem_id is used)")
    return []


def _app(f: Field, notes: list[str]) -> list[Field] | None:
    if f.key not in UNSUPPORTED:
        return None
    notes.append(
        f"line {f.name.line}: {f.key} dropped: TCP sharing (experimental in Goby 1.1) "
        "is not implemented in pygoby"
    )
    return []


def _message_file(f: Field, notes: list[str]) -> list[Field] | None:
    if f.key != "manipulator" or [t.text for t in f.value] != ["TCP_SHARE_IN"]:
        return None
    notes.append(
        f"line {f.name.line}: manipulator TCP_SHARE_IN dropped (TCP sharing is not "
        "implemented in pygoby)"
    )
    return []


RULES: dict[str, Rule] = {
    "goby.moos.protobuf.GobyMOOSAppConfig": _verbosity,
    "goby.acomms.protobuf.DriverConfig": _driver_extension,
    "goby.acomms.protobuf.ModemTransmission": _slot,
    "goby.acomms.protobuf.DCCLConfig": _dccl_cfg,
    "goby.apps.moos.protobuf.pAcommsHandlerConfig": _app,
    "goby.transitional.protobuf.MessageFile": _message_file,
}


def _field_type(descriptor: AnyDescriptor | None, key: str) -> AnyDescriptor | None:
    if descriptor is None:
        return None
    if key.startswith("["):
        try:
            found: AnyFieldDescriptor | None = descriptor.file.pool.FindExtensionByName(key[1:-1])
        except KeyError:
            return None
    else:
        found = descriptor.fields_by_name.get(key)
    return found.message_type if found is not None else None


def _rewrite(
    fields: list[Field], descriptor: AnyDescriptor | None, notes: list[str]
) -> list[Field]:
    rule = RULES.get(descriptor.full_name) if descriptor is not None else None
    out: list[Field] = []
    for f in fields:
        replaced = rule(f, notes) if rule is not None else None
        for g in [f] if replaced is None else replaced:
            if g.children is not None:
                g.children = _rewrite(g.children, _field_type(descriptor, g.key), notes)
            out.append(g)
    return out


@dataclass
class Translation:
    text: str  # the block in goby3 form, each field on its original line
    notes: list[str]  # what was changed, one line per change


def translate(text: str, descriptor: AnyDescriptor) -> Translation:
    """Rewrite the Goby 1.1/2 forms of a ProcessConfig block for `descriptor` (the app's
    configuration type). Raises BlockSyntaxError for a mistake no parser reads past (protobuf's
    would first report a field before it that only this rewriting makes valid). Other text that
    does not tokenize is returned unchanged (protobuf's parser then reports it with its line)."""
    try:
        parser = _Parser(tokenize(text))
        fields = parser.fields(None)
    except BlockSyntaxError:
        raise
    except ValueError:  # not TextFormat we understand: left for protobuf to report
        return Translation(text, [])
    notes: list[str] = []
    fields = _rewrite(fields, descriptor, notes)
    if not notes:
        return Translation(text, [])
    return Translation(render(fields), notes)


def finish(config: Any, notes: list[str]) -> None:  # (any app's configuration message)
    """The moves that need the parsed message: Goby 1.1 put XML message files in dccl_cfg and
    queue_cfg (and copied each to the other); they all become transitional_cfg.message_file."""
    fields = config.DESCRIPTOR.fields_by_name
    if "transitional_cfg" not in fields:
        return
    moved = 0
    known = {f.path for f in config.transitional_cfg.message_file}
    for parent in ("dccl_cfg", "queue_cfg"):
        if parent not in fields or not config.HasField(parent):
            continue
        block = getattr(config, parent)
        for message_file in block.message_file:
            if message_file.path not in known:
                known.add(message_file.path)
                config.transitional_cfg.message_file.add().CopyFrom(message_file)
                moved += 1
        block.ClearField("message_file")
    if moved:
        notes.append(
            f"{moved} XML message file(s) of dccl_cfg/queue_cfg -> transitional_cfg.message_file"
        )
        # Goby 1.1's form of the files: they travel as Goby 1.1 sent them unless told otherwise
        transitional = config.transitional_cfg
        if not transitional.HasField("wire_format"):
            wire = transitional.DESCRIPTOR.fields_by_name["wire_format"].enum_type
            transitional.wire_format = wire.values_by_name["DCCL1"].number
