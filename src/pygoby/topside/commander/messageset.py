"""The messages an operator can send: the ones pAcommsHandler creates when a MOOS variable is
published (TRIGGER_PUBLISH translator entries), with where each field's value comes from.

The set is read from pAcommsHandler's configuration (its ProcessConfig block): the message
definitions it loads (`load_proto_file`, `load_shared_library`), its `translator_entry` blocks,
its queues (acknowledged or not, destination role) and variable names. Message sets in other
forms (Goby 1.1 XML) plug in by being converted into the same configuration fields first.

Where a field's value comes from: the create rules of the entry, in order (a protobuf-technique
create replaces the whole message, CSV sets any field, FORMAT the fields its directives name).
The operator owns the fields whose value comes from the trigger variable (or from any create
variable when the trigger variable has no create rule, as Goby 1's iCommander posted every
source variable); fields pAcommsHandler fills from other variables (DB_TIME, VEHICLE_NAME,
NAV_X, ...) are shown as automatic and never posted.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass

from google.protobuf.message import Message

from pygoby.acomms import messages as acomms_pb
from pygoby.moos.translator import ModemIdLookup, Technique, Translator, UTMGeodesy
from pygoby.moos.translator.format import parsed_fields
from pygoby.moos.translator.techniques import PROTOBUF_TECHNIQUES
from pygoby.moos.translator_binding import MessageTypes
from pygoby.topside.commander.fields import FieldSpec

TRIGGER_PUBLISH = 1
_CSV = Technique.TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS
_DESTINATION_ROLE = 2  # goby.acomms.protobuf.QueuedMessageEntry.RoleType.DESTINATION_ID


@dataclass(frozen=True)
class CommandType:
    """One sendable message type."""

    name: str
    cls: type[Message]
    fields: tuple[FieldSpec, ...]
    trigger_var: str
    mandatory_content: str
    operator_vars: tuple[str, ...]
    ack: bool
    dest_field: str

    @property
    def short_name(self) -> str:
        return self.name.rsplit(".", 1)[-1]

    def field(self, name: str) -> FieldSpec:
        for spec in self.fields:
            if spec.name == name:
                return spec
        raise KeyError(f"{self.name} has no field {name!r}")


def _effective_sources(entry: Message, cls: type[Message]) -> dict[int, str]:
    """Field number -> the MOOS variable whose create rule sets it last."""
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


def command_type(entry: Message, cls: type[Message], queue_entry: Message | None) -> CommandType:
    trigger = entry.trigger.moos_var
    sources = _effective_sources(entry, cls)
    create_vars = {create.moos_var for create in entry.create}
    operator_vars = {trigger} if trigger in create_vars else create_vars
    fields = []
    for field in cls.DESCRIPTOR.fields:
        var = sources.get(field.number, "")
        mine = var in operator_vars
        fields.append(FieldSpec.from_descriptor(field, var if mine else "", "" if mine else var))
    dest_field = ""
    if queue_entry is not None:
        for role in queue_entry.role:
            if role.type == _DESTINATION_ROLE and role.HasField("field"):
                dest_field = role.field
    return CommandType(
        name=entry.protobuf_name,
        cls=cls,
        fields=tuple(fields),
        trigger_var=trigger,
        mandatory_content=entry.trigger.mandatory_content,
        operator_vars=tuple(sorted(operator_vars)),
        ack=bool(queue_entry is not None and queue_entry.ack),
        dest_field=dest_field,
    )


@dataclass(frozen=True)
class AcommsVariables:
    """pAcommsHandler's variable names the commander listens to or posts."""

    ack_original: str = "ACOMMS_ACK_ORIGINAL"
    expire: str = "ACOMMS_EXPIRE"

    @classmethod
    def from_config(cls, moos_var: Message) -> AcommsVariables:
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
        queue_entries: dict[str, Message],
        *,
        multiplex_var: str = "",
        variables: AcommsVariables = AcommsVariables(),
        modem_ids: ModemIdLookup | None = None,
        lat_origin: float = 0.0,
        lon_origin: float = 0.0,
        resolve: Callable[[str], type[Message]] | None = None,
    ) -> None:
        self.translator = translator
        # every message type of the mission (queues without translator entries too)
        self.resolve = resolve or translator.message_class
        self.queue_entries = queue_entries
        self.multiplex_var = multiplex_var
        self.variables = variables
        self.modem_ids = modem_ids or ModemIdLookup()
        self.geodesy = UTMGeodesy(lat_origin, lon_origin)
        self.types: dict[str, CommandType] = {}
        for name, entry in translator.entries.items():
            if entry.HasField("trigger") and entry.trigger.type == TRIGGER_PUBLISH:
                self.types[name] = command_type(
                    entry, translator.message_class(name), queue_entries.get(name)
                )

    @classmethod
    def from_pacommshandler(
        cls, cfg: Message, find: Callable[[str], str] = str, modem_id_lookup_path: str = ""
    ) -> CommandSet:
        """From a pAcommsHandlerConfig; `find` resolves relative file names (e.g.
        MissionFile.find_file); `modem_id_lookup_path` replaces the config's. Raises ConfigError for files or entries that cannot be used."""
        types = MessageTypes(
            [find(path) for path in cfg.load_proto_file],
            [find(module) for module in cfg.load_shared_library],
            fallback=acomms_pb.goby_message_class,
        )
        lookup_path = modem_id_lookup_path or cfg.modem_id_lookup_path
        modem_ids = ModemIdLookup.from_file(find(lookup_path)) if lookup_path else None
        translator = Translator(
            cfg.translator_entry,
            types,
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
            resolve=types,
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
