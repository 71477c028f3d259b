"""The messages an operator can send, with where each field's value comes from, read from the
message set pAcommsHandler loads (`pygoby.moosacomms.acomms_config.AcommsMessageSet`: its
`load_proto_file`/`load_shared_library` definitions, `translator_entry` blocks, queues, and the
Goby 1.1 XML `message_file`s).

Two kinds of sendable message:

* Goby 1.1 XML messages: every message of the files, as Goby 1.1's iCommander listed them. The
  fields are the named source/destination header pieces and the layout (the time header is
  filled by pAcommsHandler); each reads its `<src_var>` (the trigger variable when the XML gives
  none), so every one of them is the operator's, static fields included (they are posted, not
  edited). Sending posts one `name=value,...` string per source variable.
* Translator entries with a publish trigger (goby3 style): where a field's value comes from is
  the entry's create rules, in order (a protobuf-technique create replaces the whole message,
  CSV sets any field, FORMAT the fields its directives name). The operator owns the fields whose
  value comes from the trigger variable (or from any create variable when the trigger variable
  has no create rule, as Goby 1's iCommander posted every source variable); fields
  pAcommsHandler fills from other variables (DB_TIME, VEHICLE_NAME, NAV_X, ...) are shown as
  automatic and never posted. Sub-message fields are composed field by field (`pose.x`).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from dataclasses import dataclass

from google.protobuf.message import Message

from pygoby.dccl.xml import XmlMessage
from pygoby.moos.translator import ModemIdLookup, Technique, Translator, UTMGeodesy
from pygoby.moos.translator.format import parsed_fields
from pygoby.moos.translator.techniques import PROTOBUF_TECHNIQUES
from pygoby.moosacomms.acomms_config import AcommsMessageSet
from pygoby.protobuf.descriptors import AnyDescriptor, AnyFieldDescriptor
from pygoby.protobuf.goby.acomms.protobuf.queue_pb2 import QueuedMessageEntry
from pygoby.protobuf.goby.apps.moos.protobuf.pAcommsHandler_config_pb2 import pAcommsHandlerConfig
from pygoby.protobuf.goby.moos.protobuf.translator_pb2 import TranslatorEntry
from pygoby.topside.commander.fields import FieldSpec

TRIGGER_PUBLISH = 1
_CSV = Technique.TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS
_DESTINATION_ROLE = 2  # goby.acomms.protobuf.QueuedMessageEntry.RoleType.DESTINATION_ID
# How deep sub-messages are unfolded into fields (recursive types stop there too).
MAX_NESTING = 4


@dataclass(frozen=True)
class CommandType:
    """One sendable message type. `goby11`: a Goby 1.1 XML message (posted as its iCommander
    did: `name=value,...` per source variable); `single_field_vars`: its source variables that
    feed one field only (pAcommsHandler reads a double there as the value)."""

    name: str
    cls: type[Message]
    fields: tuple[FieldSpec, ...]
    trigger_var: str
    mandatory_content: str
    operator_vars: tuple[str, ...]
    ack: bool
    dest_field: str
    goby11: bool = False
    single_field_vars: frozenset[str] = frozenset()
    # offered as a command: a goby3 entry's publish trigger, a Goby 1.1 message's
    # <trigger>publish</trigger> (a time-triggered one is telemetry)
    command: bool = True

    @property
    def short_name(self) -> str:
        return self.name.rsplit(".", 1)[-1]

    def field(self, name: str) -> FieldSpec:
        for spec in self.fields:
            if spec.name == name:
                return spec
        raise KeyError(f"{self.name} has no field {name!r}")


def _effective_sources(entry: TranslatorEntry, cls: type[Message]) -> dict[int, str]:
    """Top-level field number -> the MOOS variable whose create rule sets it last."""
    descriptor = cls.DESCRIPTOR
    trigger = entry.trigger.moos_var
    sources: dict[int, str] = {}
    for create in entry.create:
        technique = Technique(create.technique)
        var = create.moos_var
        if technique in PROTOBUF_TECHNIQUES:
            sources = {f.number: var for f in descriptor.fields}
        elif technique == _CSV:
            # Which keys a CSV value holds is only known at run time: a CSV create claims every
            # field when it reads the trigger variable (the operator's), none otherwise.
            if var == trigger:
                sources = {f.number: var for f in descriptor.fields}
        else:
            for number in parsed_fields(descriptor, create.format):
                sources[number] = var
    return sources


def _leaves(
    descriptor: AnyDescriptor,
    prefix: str,
    required: bool,
    chain: tuple[str, ...],
    elements_of: AnyFieldDescriptor | None = None,
) -> Iterator[tuple[str, AnyFieldDescriptor, bool, AnyFieldDescriptor | None]]:
    """(path, field, required all the way down, the repeated sub-message whose elements hold
    it) of every field: singular sub-messages unfolded (`pose.x`), and repeated ones of plain
    fields (`track.x`: one value per element); deeper, recursive and other repeated
    sub-messages stay one field."""
    for field in descriptor.fields:
        path = prefix + field.name
        needed = required and field.is_required and elements_of is None
        sub = field.message_type
        if sub is None or len(chain) >= MAX_NESTING or sub.full_name in chain:
            yield path, field, needed, elements_of
        elif not field.is_repeated:
            yield from _leaves(sub, path + ".", needed, (*chain, sub.full_name), elements_of)
        elif elements_of is None and all(
            f.message_type is None and not f.is_repeated for f in sub.fields
        ):
            yield from _leaves(sub, path + ".", False, (*chain, sub.full_name), field)
        else:
            yield path, field, needed, elements_of


def command_type(
    entry: TranslatorEntry, cls: type[Message], queue_entry: QueuedMessageEntry | None
) -> CommandType:
    """A translator entry with a publish trigger (goby3 style)."""
    trigger = entry.trigger.moos_var
    sources = _effective_sources(entry, cls)
    create_vars = {create.moos_var for create in entry.create}
    operator_vars = {trigger} if trigger in create_vars else create_vars
    short = entry.use_short_enum
    fields = []
    top = cls.DESCRIPTOR.fields_by_name
    for path, field, required, elements_of in _leaves(
        cls.DESCRIPTOR, "", True, (cls.DESCRIPTOR.full_name,)
    ):
        var = sources.get(top[path.split(".", 1)[0]].number, "")
        mine = var in operator_vars
        fields.append(
            FieldSpec.from_descriptor(
                field,
                var if mine else "",
                "" if mine else var,
                path=path,
                required=required,
                short_enum=short,
                elements_of=elements_of,
            )
        )
    return CommandType(
        name=entry.protobuf_name,
        cls=cls,
        fields=tuple(fields),
        trigger_var=trigger,
        mandatory_content=entry.trigger.mandatory_content,
        operator_vars=tuple(sorted(operator_vars)),
        ack=bool(queue_entry is not None and queue_entry.ack),
        dest_field=_dest_field(queue_entry),
    )


def goby11_command_type(
    msg: XmlMessage, cls: type[Message], queue_entry: QueuedMessageEntry | None
) -> CommandType:
    """A Goby 1.1 XML message, with the fields Goby 1.1's iCommander showed: the named
    source and destination header pieces, then the layout."""
    shown = [msg.header[tag] for tag in ("src_id", "dest_id") if msg.header[tag].named]
    by_number = cls.DESCRIPTOR.fields_by_number
    fields = tuple(
        FieldSpec.from_descriptor(by_number[var.number], var.source_var, short_enum=True)
        for var in [*shown, *msg.layout]
    )
    return CommandType(
        name=msg.name,
        cls=cls,
        fields=fields,
        trigger_var=msg.trigger_var,
        mandatory_content=msg.mandatory_content,
        operator_vars=tuple(sorted({spec.source for spec in fields if spec.source})),
        ack=bool(queue_entry is not None and queue_entry.ack),
        dest_field=_dest_field(queue_entry),
        goby11=True,
        single_field_vars=frozenset(msg.single_field_sources()),
        command=msg.trigger != "time",
    )


def _dest_field(queue_entry: QueuedMessageEntry | None) -> str:
    dest_field = ""
    if queue_entry is not None:
        for role in queue_entry.role:
            if role.type == _DESTINATION_ROLE and role.HasField("field"):
                dest_field = role.field
    return dest_field


@dataclass(frozen=True)
class AcommsVariables:
    """pAcommsHandler's variable names the commander listens to or posts."""

    ack_original: str = "ACOMMS_ACK_ORIGINAL"
    expire: str = "ACOMMS_EXPIRE"

    @classmethod
    def from_config(cls, moos_var: pAcommsHandlerConfig.MOOSVariables) -> AcommsVariables:
        return cls(
            moos_var.prefix + moos_var.queue_ack_original_msg,
            moos_var.prefix + moos_var.queue_expire,
        )


class CommandSet:
    """The sendable messages of one pAcommsHandler configuration, and what converting their
    values needs (datum, modem id lookup)."""

    def __init__(
        self,
        translator: Translator,
        queue_entries: dict[str, QueuedMessageEntry],
        *,
        multiplex_var: str = "",
        variables: AcommsVariables = AcommsVariables(),
        modem_ids: ModemIdLookup | None = None,
        lat_origin: float = 0.0,
        lon_origin: float = 0.0,
        resolve: Callable[[str], type[Message]] | None = None,
        messages: AcommsMessageSet | None = None,
    ) -> None:
        self.translator = translator
        # every message type of the mission (queues without translator entries too)
        self.resolve = resolve or translator.message_class
        self.queue_entries = queue_entries
        self.multiplex_var = multiplex_var
        self.variables = variables
        self.modem_ids = modem_ids or ModemIdLookup()
        self.geodesy = UTMGeodesy(lat_origin, lon_origin)
        self.messages = messages
        self.types: dict[str, CommandType] = {}
        goby11 = messages.transitional.messages if messages is not None else {}
        for name, entry in translator.entries.items():
            if name in goby11:
                self._add_goby11(goby11[name])
            elif entry.HasField("trigger") and entry.trigger.type == TRIGGER_PUBLISH:
                self.types[name] = command_type(
                    entry, translator.message_class(name), queue_entries.get(name)
                )

    @classmethod
    def from_pacommshandler(
        cls,
        cfg: pAcommsHandlerConfig,
        find: Callable[[str], str] = str,
        modem_id_lookup_path: str = "",
    ) -> CommandSet:
        """From a pAcommsHandlerConfig (read from a mission, not yet loaded: its XML files'
        entries are added to it); `find` resolves relative file names (e.g.
        MissionFile.find_file). Raises ConfigError for files or entries that cannot be used."""
        return cls.from_messages(AcommsMessageSet.load(cfg, find), modem_id_lookup_path)

    @classmethod
    def from_messages(
        cls, messages: AcommsMessageSet, modem_id_lookup_path: str = ""
    ) -> CommandSet:
        """From a loaded message set (e.g. the one a running pAcommsHandler uses);
        `modem_id_lookup_path` replaces the configuration's."""
        cfg, find = messages.cfg, messages.find
        lookup_path = modem_id_lookup_path or cfg.modem_id_lookup_path
        # without a lookup file the modem-id algorithms still load (the commander runs none)
        modem_ids = ModemIdLookup.from_file(find(lookup_path)) if lookup_path else ModemIdLookup()
        translator = Translator(
            cfg.translator_entry,
            messages.types,
            lat_origin=cfg.common.lat_origin,
            lon_origin=cfg.common.lon_origin,
            modem_ids=modem_ids,
        )
        return cls(
            translator,
            {entry.protobuf_name: entry for entry in cfg.queue_cfg.message_entry},
            multiplex_var=cfg.multiplex_create_moos_var[0] if cfg.multiplex_create_moos_var else "",
            variables=AcommsVariables.from_config(cfg.moos_var),
            modem_ids=modem_ids,
            lat_origin=cfg.common.lat_origin,
            lon_origin=cfg.common.lon_origin,
            resolve=messages.types,
            messages=messages,
        )

    def import_xml(self, path: str) -> list[str]:
        """Add the messages of a Goby 1.1 XML file (iCommander's "Import Message File");
        returns their names. ConfigError (file:line) for a file that cannot be used."""
        if self.messages is None:
            raise TypeError("this command set has no message set to import into")
        names = self.messages.import_xml(path)
        cfg = self.messages.cfg
        for entry in cfg.translator_entry:
            if entry.protobuf_name in names:
                self.translator.add_entry(entry)
        for queue_entry in cfg.queue_cfg.message_entry:
            if queue_entry.protobuf_name in names:
                self.queue_entries[queue_entry.protobuf_name] = queue_entry
        goby11 = self.messages.transitional.messages
        for name in names:
            self._add_goby11(goby11[name])
        return names

    def _add_goby11(self, msg: XmlMessage) -> None:
        name = msg.name
        self.types[name] = goby11_command_type(
            msg, self.translator.message_class(name), self.queue_entries.get(name)
        )

    def __len__(self) -> int:
        return len(self.types)

    def find(self, name: str) -> CommandType:
        """A type by full name or by its short name (Goby 1 save files use short names)."""
        if name in self.types:
            return self.types[name]
        matches = [t for t in self.types.values() if t.short_name == name]
        if len(matches) == 1:
            return matches[0]
        raise KeyError(f"no sendable message {name!r}")

    def message_class(self, name: str) -> type[Message]:
        return self.translator.message_class(name)
