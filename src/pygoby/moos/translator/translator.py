"""The translator: TranslatorEntry rules applied to MOOS values and protobuf messages.

Pure logic, no MOOS I/O. `Translator` converts (MOOS variable table -> message, message ->
MOOS posts); `TranslatorRunner` adds the trigger logic (publish and time triggers, the
variable table, run-time UTM datum) for an application to feed with mail and ticks.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Callable, Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass

from google.protobuf.message import Message

from pygoby.moos.translator import format as format_technique
from pygoby.moos.translator import keyvalue
from pygoby.moos.translator.algorithms import AlgorithmRegistry
from pygoby.moos.translator.conversions import double_to_string17, looks_like_double
from pygoby.moos.translator.errors import TranslatorConfigError, TranslatorError
from pygoby.moos.translator.techniques import (
    BINARY_TECHNIQUES,
    PROTOBUF_TECHNIQUES,
    MoosValue,
    Technique,
    as_text,
    dynamic_parse,
    parse_protobuf,
    serialize_for_moos,
    serialize_protobuf,
)
from pygoby.protobuf.goby.moos.protobuf.translator_pb2 import TranslatorEntry
from pygoby.util.clock import Clock, WallClock
from pygoby.util.modem_id import ModemIdLookup

log = logging.getLogger("pygoby.moos.translator")

TRIGGER_PUBLISH = 1
TRIGGER_TIME = 2
LAT_ORIGIN_VAR = "LAT_ORIGIN"
LONG_ORIGIN_VAR = "LONG_ORIGIN"
# Seconds between two warnings about the same create rule's partly matching input.
MISMATCH_WARNING_INTERVAL = 60.0

# Outputs that may be posted as MOOS doubles when they look like numbers. goby3 converts
# every non-binary output, even an all-digit hex string; hex and @PB outputs are kept as
# strings here (QUIRKS.md Q-APPS-5).
_NUMBER_CANDIDATES = frozenset(
    {
        Technique.TECHNIQUE_PROTOBUF_TEXT_FORMAT,
        Technique.TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS,
        Technique.TECHNIQUE_FORMAT,
    }
)


@dataclass(frozen=True)
class EntryNote:
    """Something in a translator entry that behaves as in goby3 but looks like a mistake.
    `field`: its path in the entry, e.g. "publish[0].format"."""

    field: str
    message: str


@dataclass(frozen=True)
class CreateMismatch:
    """A TECHNIQUE_FORMAT create whose input matched only part of its format."""

    protobuf_name: str
    var: str
    format: str
    value: MoosValue
    where: format_technique.FormatMismatch

    def __str__(self) -> str:
        return (
            f"{self.protobuf_name} from {self.var}: input {as_text(self.value)[:80]!r} does not "
            f"match format {self.format!r}: {self.where}"
        )


@dataclass(frozen=True)
class Post:
    """One MOOS post: `value` is a float (MOOS double), str (string) or bytes (binary string).

    String and binary posts carry `source_aux = "<type name>:<TECHNIQUE_NAME>"`."""

    var: str
    value: str | float | bytes
    source_aux: str = ""


def make_post(var: str, value: str | bytes, technique: Technique, type_name: str) -> Post:
    # binary or not is decided for each post from its own value (goby3 keeps the binary flag of
    # an earlier NATIVE_ENCODED publish for the entry's later ones: QUIRKS.md Q-APPS-6)
    technique = Technique(technique)
    aux = f"{type_name}:{technique.name}"
    if isinstance(value, bytes):
        return Post(var, value, aux)
    if technique in _NUMBER_CANDIDATES and looks_like_double(value):
        return Post(var, float(value))
    return Post(var, value, aux)


def moos_value_to_source(value: MoosValue | None, technique: Technique) -> MoosValue:
    """What a create rule reads from a variable: strings as they are, doubles with 17
    significant digits, a never-received variable as the empty string."""
    if value is None:
        return ""
    if isinstance(value, float | int) and not isinstance(value, bool):
        return double_to_string17(float(value))
    if isinstance(value, bytes) and technique not in BINARY_TECHNIQUES:
        return as_text(value)
    return value


def post_for_moos(var: str, msg: Message, technique: Technique) -> Post:
    """An app-internal message (serialize_for_moos) as a MOOS post, with SourceAux."""
    return make_post(var, serialize_for_moos(msg, technique), technique, msg.DESCRIPTOR.full_name)


MessageResolver = Callable[[str], type[Message]]
# a create or a publish rule: both have technique, format and repeated_delimiter
_ReadableRule = TranslatorEntry.CreateParser | TranslatorEntry.PublishSerializer
# {variable: [(entry name, rule, algorithms to apply)]}
_RuleIndex = dict[str, list[tuple[str, _ReadableRule, Sequence[object]]]]


class Translator:
    """Applies TranslatorEntry rules.

    `entries`: goby.moos.protobuf.TranslatorEntry messages. `resolve`: full type name ->
    message class (e.g. `ProtoLoader.message_class`). Every problem with the entries is a
    TranslatorConfigError at construction; problems with data are TranslatorError at use.
    """

    def __init__(
        self,
        entries: Iterable[TranslatorEntry],
        resolve: MessageResolver,
        *,
        lat_origin: float = 0.0,
        lon_origin: float = 0.0,
        modem_ids: ModemIdLookup | None = None,
    ) -> None:
        self.registry = AlgorithmRegistry(lat_origin, lon_origin, modem_ids)
        self._resolve = resolve
        self._entries: dict[str, TranslatorEntry] = {}
        self._classes: dict[str, type[Message]] = {}
        self._named_values: dict[str, dict[str, str]] = {}
        self._read_rules: _RuleIndex | None = None  # read_back's, built on first use
        for entry in entries:
            self.add_entry(entry)

    # --- configuration -------------------------------------------------------------------

    def add_entry(self, entry: TranslatorEntry) -> list[EntryNote]:
        """Add one entry; returns what in it behaves as in goby3 but looks like a mistake (to
        log once at start-up); raises TranslatorConfigError where goby3 would crash or
        corrupt data."""
        name = entry.protobuf_name
        if name in self._entries:
            raise TranslatorConfigError(f"Duplicate translator entry for {name}")
        try:
            cls = self._resolve(name)
        except Exception as exc:
            raise TranslatorConfigError(
                f"translator_entry protobuf_name {name!r} is not a loaded message type: {exc}"
            ) from None
        notes = self._check_entry(entry, cls)
        self._read_rules = None
        self._entries[name] = entry
        self._classes[name] = cls
        return notes

    def _check_algorithms(self, name: str, algorithms, where: str) -> list[EntryNote]:
        return [
            EntryNote(
                f"{where}.algorithm[{index}].name",
                f"{name}: {self.registry.unknown_reason(algorithm.name)}: the value passes through "
                "unchanged, as in goby3",
            )
            for index, algorithm in enumerate(algorithms)
            if self.registry.find(algorithm.name) is None
        ]

    def _check_entry(self, entry: TranslatorEntry, cls: type[Message]) -> list[EntryNote]:
        name = entry.protobuf_name
        descriptor = cls.DESCRIPTOR
        notes: list[EntryNote] = []
        if entry.HasField("trigger"):
            trigger = entry.trigger
            if trigger.type == TRIGGER_PUBLISH and not trigger.moos_var:
                raise TranslatorConfigError(f"{name}: TRIGGER_PUBLISH needs trigger.moos_var")
            if trigger.type == TRIGGER_TIME and trigger.period == 0:
                raise TranslatorConfigError(f"{name}: TRIGGER_TIME needs a period > 0")
        for index, create in enumerate(entry.create):
            technique = Technique(create.technique)
            notes += self._check_algorithms(name, create.algorithm, f"create[{index}]")
            for algorithm in create.algorithm:
                known = self.registry.find(algorithm.name)
                if known is not None and known.needs_references:
                    raise TranslatorConfigError(
                        f"{name}: algorithm {algorithm.name!r} needs reference fields and cannot "
                        "be used in a create rule"
                    )
            if technique == Technique.TECHNIQUE_FORMAT:
                if not create.HasField("format"):
                    raise TranslatorConfigError(
                        f"{name}: create from {create.moos_var} needs a format"
                    )
                format_technique.check_parse_format(descriptor, create.format)
        for index, publish in enumerate(entry.publish):
            technique = Technique(publish.technique)
            notes += self._check_algorithms(name, publish.algorithm, f"publish[{index}]")
            for publish_algorithm in publish.algorithm:
                for number in publish_algorithm.reference_field:
                    field = descriptor.fields_by_number.get(number)
                    if field is None or field.is_repeated:
                        raise TranslatorConfigError(
                            f"{name}: algorithm {publish_algorithm.name!r} reference field {number} is "
                            "missing or repeated (must be optional or required)"
                        )
            if technique == Technique.TECHNIQUE_FORMAT:
                if not publish.HasField("format"):
                    raise TranslatorConfigError(
                        f"{name}: publish to {publish.moos_var} needs a format"
                    )
                virtual = {algorithm.output_virtual_field for algorithm in publish.algorithm}
                for field_name in ("format", "moos_var"):
                    notes += [
                        EntryNote(f"publish[{index}].{field_name}", f"{name}: {note}")
                        for note in format_technique.check_serialize_format(
                            descriptor, getattr(publish, field_name), virtual
                        )
                    ]
        return notes

    def read_named_values(self, protobuf_name: str, keys: Mapping[str, str]) -> None:
        """Goby 1.1's rule for the message's create variables in `keys` ({variable: name}):
        a string value holding `<name>=value` gives that value, any other
        value is read whole (`NAV_X: "nav_x=3.5"` and `NAV_X: 3.5` both give 3.5). For the
        messages of Goby 1.1 XML files, whose iCommander posted `name=value` strings."""
        self._entry(protobuf_name)
        self._named_values[protobuf_name] = dict(keys)

    def set_datum(self, lat_origin: float, lon_origin: float) -> None:
        """Re-initialise the UTM datum used by the UTM algorithms."""
        self.registry.set_datum(lat_origin, lon_origin)

    @property
    def entries(self) -> Mapping[str, TranslatorEntry]:
        return self._entries

    def message_class(self, protobuf_name: str) -> type[Message]:
        return self._classes[protobuf_name]

    def subscriptions(self) -> list[str]:
        """Every trigger and create variable (sorted, without duplicates)."""
        names = set()
        for entry in self._entries.values():
            if entry.HasField("trigger") and entry.trigger.type == TRIGGER_PUBLISH:
                names.add(entry.trigger.moos_var)
            names.update(create.moos_var for create in entry.create)
        return sorted(names)

    def triggered_by(self, var: str, value: MoosValue) -> list[str]:
        """Entries whose TRIGGER_PUBLISH fires on this mail (in configuration order)."""
        # A double's string value is empty, so it never satisfies a mandatory_content.
        text = as_text(value) if isinstance(value, str | bytes) else ""
        return [
            name
            for name, entry in self._entries.items()
            if entry.HasField("trigger")
            and entry.trigger.type == TRIGGER_PUBLISH
            and entry.trigger.moos_var == var
            and entry.trigger.mandatory_content in text
        ]

    def time_triggered(self) -> dict[str, int]:
        """{protobuf_name: period in seconds} of the TRIGGER_TIME entries."""
        return {
            name: entry.trigger.period
            for name, entry in self._entries.items()
            if entry.HasField("trigger") and entry.trigger.type == TRIGGER_TIME
        }

    # --- MOOS -> protobuf --------------------------------------------------------------------

    def create(
        self,
        protobuf_name: str,
        variables: Mapping[str, MoosValue],
        mismatches: list[CreateMismatch] | None = None,
    ) -> Message:
        """Build a message from the newest variable values with the entry's create rules.

        A TECHNIQUE_FORMAT input that matches only part of its format still fills the fields
        (as goby3 does) and is reported in `mismatches`; with the entry's `strict_format` it
        is a TranslatorError instead. Raises TranslatorError if any rule fails: no partially
        built message comes out."""
        entry = self._entry(protobuf_name)
        msg = self._classes[protobuf_name]()
        named = self._named_values.get(protobuf_name, {})
        for create in entry.create:
            technique = Technique(create.technique)
            source = moos_value_to_source(variables.get(create.moos_var), technique)
            key = named.get(create.moos_var)
            if key is not None and isinstance(source, str):
                value = keyvalue.val_from_string(source, key)
                source = source if value is None else value
            try:
                mismatch = self._apply_rule(
                    msg, create, create.algorithm, source, entry.use_short_enum
                )
            except TranslatorError as exc:
                raise type(exc)(f"{protobuf_name} from {create.moos_var}: {exc}") from None
            if mismatch is None:
                continue
            found = CreateMismatch(protobuf_name, create.moos_var, create.format, source, mismatch)
            if entry.strict_format:
                raise TranslatorError(f"{found} (strict_format: nothing created)")
            if mismatches is not None:
                mismatches.append(found)
        return msg

    def _apply_rule(
        self,
        msg: Message,
        rule: _ReadableRule,
        algorithms: Sequence[object],
        source: MoosValue,
        short: bool,
    ) -> format_technique.FormatMismatch | None:
        """Parse `source` into `msg` by `rule`'s technique (a create rule, or a publish rule
        read back), running `algorithms` on the parsed fields."""
        technique = Technique(rule.technique)
        if technique in PROTOBUF_TECHNIQUES:
            parse_protobuf(source, msg, technique)
        elif technique == Technique.TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS:
            keyvalue.parse(as_text(source), msg, algorithms, short, self.registry, rule.moos_var)
        else:
            return format_technique.parse(
                as_text(source),
                msg,
                rule.format,
                rule.repeated_delimiter,
                algorithms,
                short,
                self.registry,
            )
        return None

    # --- protobuf -> MOOS --------------------------------------------------------------------

    def publish(self, msg: Message) -> list[Post]:
        """The entry's publish rules applied to `msg`, sorted by variable name (stable), not in
        declaration order, as goby3 posts them (QUIRKS.md Q-APPS-22)."""
        name = msg.DESCRIPTOR.full_name
        entry = self._entries.get(name)
        if entry is None:
            raise TranslatorError(f"No TranslatorEntry for Protobuf type: {name}")
        posts = []
        for publish in entry.publish:
            technique = Technique(publish.technique)
            var = publish.moos_var
            value: str | bytes
            short = entry.use_short_enum
            if technique == Technique.TECHNIQUE_FORMAT:
                args = (publish.repeated_delimiter, publish.algorithm, short, self.registry)
                var = format_technique.serialize(msg, publish.moos_var, *args)
                value = format_technique.serialize(msg, publish.format, *args)
            elif technique == Technique.TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS:
                value = keyvalue.serialize(msg, publish.algorithm, short, self.registry)
            else:
                value = serialize_protobuf(msg, technique)
            posts.append(make_post(var, value, technique, name))
        return sorted(posts, key=lambda post: post.var)

    def inverse_publish(self, msg: Message) -> list[Post]:
        """multiplex_create_moos_var: post `msg` to its entry's create variables with the create
        techniques (no algorithms), plus an empty trigger post if the trigger variable is not
        one of them; sorted by variable name."""
        name = msg.DESCRIPTOR.full_name
        entry = self._entries.get(name)
        if entry is None:
            raise TranslatorError(f"No TranslatorEntry for Protobuf type: {name}")
        posts = []
        short = entry.use_short_enum
        for create in entry.create:
            technique = Technique(create.technique)
            value: str | bytes
            if technique == Technique.TECHNIQUE_FORMAT:
                value = format_technique.serialize(
                    msg, create.format, create.repeated_delimiter, (), short
                )
            elif technique == Technique.TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS:
                value = keyvalue.serialize(msg, (), short)
            else:
                value = serialize_protobuf(msg, technique)
            posts.append(make_post(create.moos_var, value, technique, name))
        trigger = entry.trigger
        if (
            entry.HasField("trigger")
            and trigger.type == TRIGGER_PUBLISH
            and trigger.moos_var not in {create.moos_var for create in entry.create}
        ):
            posts.append(Post(trigger.moos_var, "", ""))
        return sorted(posts, key=lambda post: post.var)

    # --- MOOS posts read back (log tools) ----------------------------------------------------

    def read_back(self, var: str, value: MoosValue) -> list[Message]:
        """The messages `var`'s value gives back, one per rule naming `var`: each create rule
        reading it (its algorithms applied, as at creation) and each publish rule posting to it
        (the value as published: publish algorithms only run message -> text). Rules whose
        value cannot be parsed back are not read: a publish variable name that is itself a
        format, a publish format with a field the message does not have (an algorithm's
        virtual field). A format that matches only part of the value counts as not read.
        Raises TranslatorError when no rule reads the value."""
        rules = self._readers().get(var, [])
        messages: list[Message] = []
        errors: list[str] = []
        for name, rule, algorithms in rules:
            entry = self._entries[name]
            msg = self._classes[name]()
            technique = Technique(rule.technique)
            source = moos_value_to_source(value, technique)
            try:
                mismatch = self._apply_rule(msg, rule, algorithms, source, entry.use_short_enum)
                if mismatch is not None:
                    raise TranslatorError(f"does not match format {rule.format!r}: {mismatch}")
            except (TranslatorError, ValueError, KeyError) as exc:
                errors.append(f"{name}: {exc}")
                continue
            messages.append(msg)
        if rules and not messages:
            raise TranslatorError(f"{var}: no rule reads the value ({'; '.join(errors)})")
        return messages

    def read_back_variables(self) -> set[str]:
        """The variables `read_back` can read."""
        return set(self._readers())

    def _readers(self) -> _RuleIndex:
        """{variable: [(entry name, rule, algorithms to apply)]}, built once."""
        if self._read_rules is not None:
            return self._read_rules
        readers: _RuleIndex = {}
        for name, entry in self._entries.items():
            descriptor = self._classes[name].DESCRIPTOR
            for create in entry.create:
                readers.setdefault(create.moos_var, []).append((name, create, create.algorithm))
            for publish in entry.publish:
                if Technique(publish.technique) == Technique.TECHNIQUE_FORMAT:
                    if "%" in publish.moos_var:
                        continue
                    try:
                        format_technique.check_parse_format(descriptor, publish.format)
                    except TranslatorError:
                        continue
                readers.setdefault(publish.moos_var, []).append((name, publish, ()))
        self._read_rules = readers
        return readers

    def _entry(self, protobuf_name: str) -> TranslatorEntry:
        try:
            return self._entries[protobuf_name]
        except KeyError:
            raise TranslatorError(
                f"No TranslatorEntry for Protobuf type: {protobuf_name}"
            ) from None


class MoosValues(Mapping):
    """Read-only view of an application's newest-message table ({var: message with .value},
    e.g. GobyMOOSApp.dynamic_vars) as {var: value}, for TranslatorRunner(variables=...)."""

    def __init__(self, messages: Mapping) -> None:
        self._messages = messages

    def __getitem__(self, key: str) -> MoosValue:
        return self._messages[key].value

    def __iter__(self) -> Iterator[str]:
        return iter(self._messages)

    def __len__(self) -> int:
        return len(self._messages)


class TranslatorRunner:
    """Trigger logic around a Translator, fed by an application (sans-I/O).

    `on_mail` for every mail of `subscriptions()` (with `stale=True` for mail older than the
    application start: it updates the table but triggers nothing); `tick(now)` from the
    application loop (time triggers, datum changes). Both return the created messages; a rule
    that fails is logged as a warning and that message is skipped.
    """

    def __init__(
        self,
        translator: Translator,
        start_time: float,
        multiplex_vars: Iterable[str] = (),
        variables: Mapping[str, MoosValue] | None = None,
        clock: Clock | None = None,
    ) -> None:
        self.translator = translator
        self.clock = clock or WallClock()
        # (entry, create variable) -> when its partial-match warning was last logged
        self._mismatch_warned: dict[tuple[str, str], float] = {}
        # The newest value per variable: our own table, or the application's (e.g. a view of
        # GobyMOOSApp.dynamic_vars, which also holds mail from before the start).
        self._owns_variables = variables is None
        self.variables: Mapping[str, MoosValue] = {} if variables is None else variables
        self.multiplex_vars = list(multiplex_vars)
        self._periods = translator.time_triggered()
        self._deadlines = {name: start_time + period for name, period in self._periods.items()}
        self._origin: dict[str, float] = {}
        self._origin_changed = False

    def subscriptions(self) -> list[str]:
        names = set(self.translator.subscriptions())
        names.update((LAT_ORIGIN_VAR, LONG_ORIGIN_VAR), self.multiplex_vars)
        return sorted(names)

    def on_mail(self, var: str, value: MoosValue, *, stale: bool = False) -> list[Message]:
        if self._owns_variables:
            self.variables[var] = value  # type: ignore[index]
        if (
            var in (LAT_ORIGIN_VAR, LONG_ORIGIN_VAR)
            and isinstance(value, float)
            and not math.isnan(value)
        ):
            self._origin[var] = value
            self._origin_changed = True
        if stale:
            return []
        created = (self.create(name) for name in self.translator.triggered_by(var, value))
        return [msg for msg in created if msg is not None]

    def on_multiplex(self, value: MoosValue, technique: Technique) -> list[Post]:
        """Mail on a multiplex variable -> the inverse-publish posts (empty if unusable)."""
        msg = dynamic_parse(value, self._resolve_entry_type, technique)
        if msg is None:
            log.warning("multiplexed value is not a prefixed message of a known type: %.80r", value)
            return []
        return self.translator.inverse_publish(msg)

    def _resolve_entry_type(self, name: str) -> type[Message]:
        return self.translator.message_class(name)

    def tick(self, now: float) -> list[Message]:
        if self._origin_changed and len(self._origin) == 2:
            self.translator.set_datum(self._origin[LAT_ORIGIN_VAR], self._origin[LONG_ORIGIN_VAR])
            self._origin_changed = False
        created = []
        for name, deadline in self._deadlines.items():
            period = self._periods[name]
            if now < deadline:
                if deadline - now > period + 1:  # clock jumped backwards
                    self._deadlines[name] = now + period
                continue
            # Late by more than 1 s (clock jump): restart the schedule from now.
            self._deadlines[name] = now + period if now - deadline > 1 else deadline + period
            msg = self.create(name)
            if msg is not None:
                created.append(msg)
        return created

    def create(self, name: str) -> Message | None:
        """`name` made now from the newest values; None, with a warning, when a rule fails."""
        mismatches: list[CreateMismatch] = []
        try:
            msg = self.translator.create(name, self.variables, mismatches)
        except TranslatorError as exc:
            log.warning("not creating %s: %s", name, exc)
            return None
        now = self.clock.now()
        for mismatch in mismatches:
            key = (mismatch.protobuf_name, mismatch.var)
            last = self._mismatch_warned.get(key)
            if last is None or not 0 <= now - last < MISMATCH_WARNING_INTERVAL:
                self._mismatch_warned[key] = now
                log.warning(
                    "%s; created from the part that matched, as goby3 does (this warning at "
                    "most once a minute; strict_format: true creates nothing instead)",
                    mismatch,
                )
        return msg
