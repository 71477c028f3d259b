"""The command composer shared by iCommander (terminal) and liaison (browser); no UI code.

    commander = Commander(commands, community="topside", now=app.moos_time, publish=post)
    draft = commander.open("pygoby.examples.Command")
    commander.set_value(draft, "heading", "90")        # FieldValueError: above the maximum 360
    outgoing = commander.preview(draft)                 # the posts, nothing published
    record = commander.send(draft)                      # published; autosaved; awaiting ack
    for notice in commander.handle_mail(var, value):    # ACOMMS_ACK_ORIGINAL / ACOMMS_EXPIRE
        print(notice.banner())

What "send" publishes:

* key=value style (Goby 1.1 iCommander): for a Goby 1.1 XML message, one
  `name1=value1,name2=value2,...` string per source variable (the fields it feeds, in message
  order, static ones included, unset ones left out), except that a variable holding a double
  (NAV_X, ...) that feeds one numeric field gets the number: the MOOSDB refuses a string there,
  and Goby 1.1's pAcommsHandler reads a double as the value itself; for a translator entry, the message
  serialized with each operator variable's create technique (a CSV create gives the same
  `name=value,...` string). Variables in sorted order but the trigger variable last (so
  pAcommsHandler has every other value when the trigger fires); an empty post to the trigger
  variable (its mandatory content, if any) when no field reads it.
* multiplex style (goby3 liaison): one `@PB[<type>] <text>` post to pAcommsHandler's
  `multiplex_create_moos_var`.
"""

from __future__ import annotations

import itertools
import math
import time
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from google.protobuf import text_format
from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from pygoby.moos.translator import (
    MoosValue,
    Post,
    Technique,
    TranslatorError,
    dynamic_parse,
    make_post,
    serialize_for_moos,
)
from pygoby.protobuf import enum_type, initialization_errors
from pygoby.protobuf.descriptors import AnyFieldDescriptor
from pygoby.topside.commander import savefile, specials
from pygoby.topside.commander.fields import FieldSpec, FieldValueError
from pygoby.topside.commander.messageset import CommandSet, CommandType
from pygoby.topside.errors import CommanderError
from pygoby.util.signal import Signal

KEY_VALUE = "key_value"
MULTIPLEX = "multiplex"
_PREFIXED_TEXT = Technique.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT
_FD = FieldDescriptor


@dataclass
class Draft:
    """An open message: the operator's texts by field name."""

    type: CommandType
    values: dict[str, str] = field(default_factory=dict)

    @property
    def name(self) -> str:
        return self.type.name

    def value(self, field_name: str) -> str:
        spec = self.type.field(field_name)
        if spec.kind == "static":
            return spec.static_value or ""
        return self.values.get(field_name, "")


@dataclass
class Outgoing:
    """What sending a draft publishes, and what will not go (warnings)."""

    posts: list[Post]
    warnings: list[str]
    message: Message

    def lines(self) -> list[str]:
        return [
            f"{post.var}: {post.value!r}"
            if not isinstance(post.value, str)
            else f"{post.var}: {post.value}"
            for post in self.posts
        ]


PENDING = ("awaiting ack", "sent")


@dataclass
class SentRecord:
    """One sent message and what became of it."""

    record_id: int
    type: CommandType
    time: float
    message: Message
    posts: list[Post]
    status: str  # awaiting ack | sent | acknowledged | expired
    status_time: float | None = None

    @property
    def text(self) -> str:
        return text_format.MessageToString(self.message, as_one_line=True)


@dataclass(frozen=True)
class Notice:
    """An ACOMMS_ACK_ORIGINAL / ACOMMS_EXPIRE seen: `record` is ours, when it matches."""

    kind: str  # acknowledged | expired
    type_name: str
    dest: str
    time: float
    text: str
    record: SentRecord | None

    def banner(self) -> str:
        stamp = time.strftime("%Y-%b-%d %H:%M:%S", time.gmtime(self.time))
        return (
            f"Message {self.kind} from queue: {self.type_name.rsplit('.', 1)[-1]}\n"
            f" for destination: {self.dest}\n at time: {stamp}\n {self.text}"
        )


class Commander:
    def __init__(
        self,
        commands: CommandSet,
        *,
        community: str = "",
        now: Callable[[], float] = time.time,
        publish: Callable[[Post], None] | None = None,
        style: str = KEY_VALUE,
        force_xy_only: bool = False,
        autosave_path: str | Path | None = "iCommander_autosave.txt",
        values: Mapping[str, MoosValue] | None = None,
    ) -> None:
        """`values`: the newest value of the MOOS variables (e.g. MoosValues(app.dynamic_vars),
        with `source_variables` subscribed), to post a number where a variable holds doubles."""
        if style not in (KEY_VALUE, MULTIPLEX):
            raise CommanderError(f"unknown send style {style!r} (key_value or multiplex)")
        if style == MULTIPLEX and not commands.multiplex_var:
            raise CommanderError(
                "multiplex style needs a multiplex_create_moos_var in pAcommsHandler's config"
            )
        self.commands = commands
        self.community = community
        self.now = now
        self._publish = publish
        self.style = style
        self.force_xy_only = force_xy_only
        self.autosave_path = Path(autosave_path) if autosave_path else None
        self.drafts: dict[str, Draft] = {}
        self.active: Draft | None = None
        self.records: list[SentRecord] = []
        self.notices: list[Notice] = []
        self._ids = itertools.count(1)
        self.values: Mapping[str, MoosValue] = values if values is not None else {}
        self.signal_import: Signal[list[str]] = (
            Signal()
        )  # (names) after import_xml: new source variables

    @property
    def source_variables(self) -> set[str]:
        """The variables a send of a Goby 1.1 message may post to (whose types matter)."""
        return {
            var
            for kind in self.commands.types.values()
            if kind.goby11
            for var in kind.operator_vars
        }

    def import_xml(self, path: str) -> list[str]:
        """Add the messages of a Goby 1.1 XML file; ConfigError for a file that cannot be used."""
        names = self.commands.import_xml(path)
        self.signal_import.emit(names)
        return names

    # ------------------------------------------------------------------ drafts
    def open(self, name: str) -> Draft:
        """The open draft of a message type (a new one the first time); it becomes active."""
        kind = self.commands.find(name)
        draft = self.drafts.get(kind.name)
        if draft is None:
            draft = self.drafts[kind.name] = Draft(kind)
            if self.force_xy_only:
                for lat, lon in self._lat_lon_pairs(kind):
                    draft.values[kind.fields[lat].name] = specials.xy_placeholder("y")
                    draft.values[kind.fields[lon].name] = specials.xy_placeholder("x")
        self.active = draft
        return draft

    def check(self, draft: Draft, field_name: str, text: str, *, partial: bool = False) -> None:
        """FieldValueError unless `text` can go (or, `partial`, is being typed) into the field."""
        draft.type.field(field_name).check(text, partial=partial)

    def set_value(self, draft: Draft, field_name: str, text: str) -> None:
        spec = draft.type.field(field_name)
        if self.force_xy_only and text and not specials.is_placeholder(text):
            axis = self._xy_axis(draft.type, field_name)
            if axis:
                text = specials.xy_placeholder(axis, text)
        spec.check(text)
        if text:
            draft.values[field_name] = text
        else:
            draft.values.pop(field_name, None)

    def clear(self, draft: Draft) -> None:
        draft.values.clear()

    # ------------------------------------------------------------------ specials
    def specials(self, kind: CommandType, field_name: str) -> list[str]:
        """The specials that make sense in a field: `time` in a double field or an integer
        one named for a time, `xy` in a latitude/longitude pair, `modem_id` in an integer
        field, `community` in a string field (none in a field the operator does not edit)."""
        spec = kind.field(field_name)
        if not spec.editable:
            return []
        out = []
        if spec.kind == "float" or (spec.kind == "int" and "time" in field_name.lower()):
            out.append("time")
        if self._xy_axis(kind, field_name):
            out.append("xy")
        if spec.kind == "int":
            out.append("modem_id")
        if spec.kind == "string":
            out.append("community")
        return out

    def insert_time(self, draft: Draft, field_name: str) -> None:
        self.set_value(draft, field_name, specials.TIME)

    def insert_community(self, draft: Draft, field_name: str) -> None:
        self.set_value(draft, field_name, self.community)

    def modem_ids(self) -> list[tuple[int, str, str]]:
        """(id, name, type) of the modem id lookup file, for the "modem id" picker."""
        return [(e.modem_id, e.name, e.type) for e in self.commands.modem_ids.entries()]

    def insert_modem_id(self, draft: Draft, field_name: str, modem_id: int) -> None:
        self.set_value(draft, field_name, str(modem_id))

    def insert_xy(self, draft: Draft, field_name: str) -> None:
        """Put x/y placeholders into the latitude/longitude pair the field belongs to; the
        metres already typed after a placeholder are kept."""
        for lat, lon in self._lat_lon_pairs(draft.type):
            names = (draft.type.fields[lat].name, draft.type.fields[lon].name)
            if field_name in names:
                for axis, name in zip("yx", names, strict=True):
                    current = draft.values.get(name, "")
                    metres = (
                        current.split(":", 1)[1]
                        if specials.is_placeholder(current) and ":" in current
                        else ""
                    )
                    self.set_value(draft, name, specials.xy_placeholder(axis, metres))
                return
        raise FieldValueError(f"{field_name}: not one of a latitude/longitude pair of fields")

    def _lat_lon_pairs(self, kind: CommandType) -> list[tuple[int, int]]:
        pairs = specials.lat_lon_pairs([f.name for f in kind.fields])
        return [(a, b) for a, b in pairs if kind.fields[a].editable and kind.fields[b].editable]

    def _xy_axis(self, kind: CommandType, field_name: str) -> str:
        for lat, lon in self._lat_lon_pairs(kind):
            if kind.fields[lat].name == field_name:
                return "y"
            if kind.fields[lon].name == field_name:
                return "x"
        return ""

    # ------------------------------------------------------------------ sending
    def preview(self, draft: Draft) -> Outgoing:
        """What `send` would publish, without publishing anything (an old iCommander's preview
        published the message: QUIRKS.md Q-APPS-18)."""
        return self._compose(draft)

    def send(self, draft: Draft) -> SentRecord:
        if self._publish is None:
            raise CommanderError("this commander has no MOOS connection to publish with")
        outgoing = self._compose(draft)
        for post in outgoing.posts:
            self._publish(post)
        record = SentRecord(
            next(self._ids),
            draft.type,
            self.now(),
            outgoing.message,
            outgoing.posts,
            "awaiting ack" if draft.type.ack else "sent",
        )
        self.records.append(record)
        if self.autosave_path is not None:
            self.save(self.autosave_path)
        return record

    def _compose(self, draft: Draft) -> Outgoing:
        kind = draft.type
        warnings: list[str] = []
        editable = [spec for spec in kind.fields if spec.editable]
        texts = [draft.values.get(spec.name, "") for spec in editable]
        try:
            texts = specials.substitute(texts, self.now(), self.commands.geodesy.to_geo)
        except specials.SpecialError as err:
            raise FieldValueError(str(err)) from None
        msg = kind.cls()
        values: dict[str, str] = {}  # what goes, by field
        for spec in kind.fields:
            if spec.kind == "static" and spec.static_value is not None:
                _set_field(msg, spec, spec.static_value)
                values[spec.name] = spec.static_value
        for spec, text in zip(editable, texts, strict=True):
            if text == "":
                if spec.required:
                    warnings.append(f"{spec.name}: not set")
                continue
            try:
                spec.check(text)
                _set_field(msg, spec, text)
            except (FieldValueError, ValueError) as err:
                warnings.append(f"{err} (not sent)")
            else:
                values[spec.name] = text
        # what the rules above cannot see: an element of a repeated sub-message left without a
        # required field
        warnings += [f"{path}: not set" for path in initialization_errors(msg) if "[" in path]
        try:
            posts = self._posts(kind, msg, values, warnings)
        except TranslatorError as err:
            raise CommanderError(f"{kind.name} cannot be serialized: {err}") from None
        trigger = posts[-1] if posts and posts[-1].var == kind.trigger_var else None
        if (
            self.style == KEY_VALUE
            and trigger is not None
            and kind.mandatory_content
            and kind.mandatory_content not in str(trigger.value)
        ):
            warnings.append(
                f"{kind.trigger_var} lacks its mandatory content "
                f"{kind.mandatory_content!r}: pAcommsHandler will not make the message"
            )
        return Outgoing(posts, warnings, msg)

    def _posts(
        self, kind: CommandType, msg: Message, values: dict[str, str], warnings: list[str]
    ) -> list[Post]:
        if self.style == MULTIPLEX:
            return [
                make_post(
                    self.commands.multiplex_var, serialize_for_moos(msg), _PREFIXED_TEXT, kind.name
                )
            ]
        if kind.goby11:
            posts = self._goby11_posts(kind, values, warnings)
        else:
            posts = [
                p
                for p in self.commands.translator.inverse_publish(msg)
                if p.var in kind.operator_vars or p.var == kind.trigger_var
            ]
        trigger = [p for p in posts if p.var == kind.trigger_var]
        if kind.trigger_var and (not trigger or trigger[0].value == ""):
            trigger = [Post(kind.trigger_var, kind.mandatory_content, "")]
        return [p for p in posts if p.var != kind.trigger_var] + trigger

    def _goby11_posts(
        self, kind: CommandType, values: dict[str, str], warnings: list[str]
    ) -> list[Post]:
        """Goby 1.1 iCommander: `name=value,...` (message order) on each source variable,
        sorted; repeated values in braces (`name={1,2}`), as Goby 1.1's key=value reading takes
        them; a number where the variable holds doubles (see the module's docstring)."""
        by_var: dict[str, list[tuple[FieldSpec, str]]] = {}
        for spec in kind.fields:
            text = values.get(spec.name)
            if spec.source and text is not None:
                by_var.setdefault(spec.source, []).append((spec, text))
        posts = []
        for var, items in sorted(by_var.items()):
            if isinstance(self.values.get(var), float):
                spec, text = items[0]
                if var in kind.single_field_vars and spec.kind in _NUMERIC and not spec.repeated:
                    posts.append(Post(var, _number(text), ""))
                else:
                    warnings.append(f"{var} holds numbers: the MOOSDB would refuse text, not sent")
                continue
            pairs = [
                f"{spec.name}={'{' + text.strip('{}') + '}' if spec.repeated else text}"
                for spec, text in items
            ]
            posts.append(Post(var, ",".join(pairs), ""))
        return posts

    # ------------------------------------------------------------------ acks and expiries
    @property
    def watched_variables(self) -> tuple[str, str]:
        variables = self.commands.variables
        return variables.ack_original, variables.expire

    def handle_mail(self, var: str, value: MoosValue, when: float | None = None) -> list[Notice]:
        """Feed ACOMMS_ACK_ORIGINAL / ACOMMS_EXPIRE mail (not older than the app's start)."""
        ack_var, expire_var = self.watched_variables
        if var not in (ack_var, expire_var):
            return []
        original = dynamic_parse(value, self.commands.message_class, _PREFIXED_TEXT)
        if original is None:
            return []
        kind = "acknowledged" if var == ack_var else "expired"
        stamp = self.now() if when is None else when
        record = self._match(original)
        if record is not None:
            record.status, record.status_time = kind, stamp
        name = original.DESCRIPTOR.full_name
        command = self.commands.types.get(name)
        dest = ""
        if command is not None and command.dest_field:
            dest = str(getattr(original, command.dest_field))
        notice = Notice(
            kind, name, dest, stamp, text_format.MessageToString(original, as_one_line=True), record
        )
        self.notices.append(notice)
        return [notice]

    def _match(self, original: Message) -> SentRecord | None:
        name = original.DESCRIPTOR.full_name
        for record in self.records:
            if record.status in PENDING and record.type.name == name and _same(record, original):
                return record
        return None

    # ------------------------------------------------------------------ save and load
    def save(self, path: str | Path) -> None:
        messages = []
        for draft in self.drafts.values():
            values = [
                (spec.source, spec.name, draft.values.get(spec.name, ""))
                for spec in draft.type.fields
                if spec.editable
            ]
            messages.append((draft.type.short_name, values))
        Path(path).write_text(savefile.dump(messages))

    def load(self, path: str | Path) -> list[str]:
        """Open the messages of a save file; returns warnings (unknown messages, values the
        fields refuse). Raises SaveFileError / OSError for an unusable file."""
        names: dict[str, Sequence[str]] = {}
        for kind in self.commands.types.values():
            names[kind.short_name] = names[kind.name] = [f.name for f in kind.fields]
        warnings = []
        # a hand-edited file in another encoding still loads (its odd bytes become U+FFFD)
        text = Path(path).read_text(encoding="utf-8", errors="replace")
        for message_name, values in savefile.parse(text, names):
            try:
                draft = self.open(message_name)
            except KeyError:
                warnings.append(f"{message_name}: not a message of this mission")
                continue
            for field_name, text in values.items():
                try:
                    self.set_value(draft, field_name, text)
                except (FieldValueError, KeyError) as err:
                    warnings.append(f"{message_name}: {err}".replace("KeyError", ""))
        return warnings


_NUMERIC = ("int", "float", "bool")


def _number(text: str) -> float:
    """A checked int/float/bool text as the double Goby 1.1's pAcommsHandler reads."""
    lowered = text.lower()
    return 1.0 if lowered == "true" else 0.0 if lowered == "false" else float(text)


def _convert(spec: FieldSpec, field: AnyFieldDescriptor, text: str) -> object:
    kind = field.type
    if kind == _FD.TYPE_ENUM:
        for value, shown in zip(enum_type(field).values, spec.enum_values, strict=True):
            if shown.upper() == text.upper():
                return value.number  # type: ignore[attr-defined]  # (an EnumValueDescriptor)
        raise FieldValueError(f"{spec.name}: {text!r} is not one of its values")
    if kind == _FD.TYPE_BOOL:
        return text.lower() in ("true", "1")
    if kind == _FD.TYPE_STRING:
        return text
    if kind == _FD.TYPE_BYTES:
        return bytes.fromhex(text)
    if kind in (_FD.TYPE_DOUBLE, _FD.TYPE_FLOAT):
        number = float(text)
        return round(number, spec.precision) if spec.precision is not None else number
    return int(float(text)) if "." in text or "e" in text.lower() else int(text)


def _parent(msg: Message, path: str) -> tuple[Message, str]:
    """The (sub-)message holding the field at `path` (`pose.x`: msg.pose) and its name; reading
    a sub-message this way does not set it."""
    *steps, name = path.split(".")
    for step in steps:
        msg = getattr(msg, step)
    return msg, name


def _has(msg: Message, path: str) -> bool:
    *steps, name = path.split(".")
    for step in steps:
        if not msg.HasField(step):
            return False
        msg = getattr(msg, step)
    return msg.HasField(name)


def _set_field(msg: Message, spec: FieldSpec, text: str) -> None:
    *steps, name = spec.name.split(".")
    items = [t.strip() for t in text.strip("{}").split(",")] if spec.repeated else [text]
    for step in steps:
        if msg.DESCRIPTOR.fields_by_name[step].is_repeated:  # one value per element
            elements = getattr(msg, step)
            for index, item in enumerate(items):
                element = elements[index] if index < len(elements) else elements.add()
                setattr(
                    element, name, _convert(spec, element.DESCRIPTOR.fields_by_name[name], item)
                )
            return
        msg = getattr(msg, step)
    field = msg.DESCRIPTOR.fields_by_name[name]
    if spec.repeated:
        getattr(msg, name).extend(_convert(spec, field, item) for item in items)
    else:
        setattr(msg, name, _convert(spec, field, text))


def _close(a: object, b: object, precision: int | None) -> bool:
    if isinstance(a, float) or isinstance(b, float):
        tolerance = 0.5 * 10.0 ** -(precision if precision is not None else 9) + 1e-9
        return math.isclose(float(a), float(b), rel_tol=1e-9, abs_tol=tolerance)  # type: ignore[arg-type]
    if isinstance(a, str) and isinstance(b, str):
        return a.lower() == b.lower()  # the key=value parser lower-cases strings (Q-APPS-20)
    return a == b


def _same(record: SentRecord, original: Message) -> bool:
    """Does the acknowledged/expired original carry what we sent (DCCL rounding allowed)?"""
    sent = record.message
    for spec in record.type.fields:
        if not spec.editable or spec.repeated or not _has(sent, spec.name):
            continue
        if not _has(original, spec.name):
            return False
        mine, theirs = _parent(sent, spec.name), _parent(original, spec.name)
        if not _close(getattr(*mine), getattr(*theirs), spec.precision):
            return False
    return True
