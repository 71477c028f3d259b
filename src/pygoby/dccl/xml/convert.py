"""Goby 1.1 XML messages -> DCCL protobuf descriptors, queue entries and translator entries,
following Goby 2's transitional layer.

* One protobuf message per XML message, named as in the XML (no package), codec version 2
  (Goby 2's DCCL): field 1 = header time (`_time` codec, in the head), 2 = source id, 3 =
  destination id (0-31, in the head), 4... = the layout variables in XML order. Enums become
  nested `<Name>Enum` types with values `<NAME>_<value>`; `array_length > 1` becomes repeated.
* One `QueuedMessageEntry` per message: the <queuing> options (Goby 1.1 defaults), the
  SOURCE_ID / DESTINATION_ID / TIMESTAMP roles on the header fields, the file's manipulators.
* One `TranslatorEntry` per message: trigger, create rules (one per source MOOS variable:
  FORMAT for one field, key=value pairs when several fields share it), publish rules (FORMAT
  with the v1 `%k%` placeholders renumbered to field numbers, algorithms as virtual fields).
"""

from __future__ import annotations

from collections.abc import Iterable

from google.protobuf import descriptor_pb2

from pygoby.dccl.xml.model import V1_PLACEHOLDER, Publish, Var, XmlMessage
from pygoby.protobuf import builtin_class
from pygoby.protobuf.goby.acomms.protobuf.manipulator_pb2 import Manipulator
from pygoby.protobuf.goby.acomms.protobuf.queue_pb2 import QueuedMessageEntry
from pygoby.protobuf.goby.moos.protobuf.translator_pb2 import TranslatorEntry

DCCL_OPTIONS_PROTO = "dccl/option_extensions.proto"
CODEC_VERSION = 2
_CARRIER_PROTO = "pygoby/dccl/option_carrier.proto"

_FD = descriptor_pb2.FieldDescriptorProto
PROTO_TYPES = {
    "int": _FD.TYPE_INT32,
    "float": _FD.TYPE_DOUBLE,
    "bool": _FD.TYPE_BOOL,
    "string": _FD.TYPE_STRING,
    "static": _FD.TYPE_STRING,
    "hex": _FD.TYPE_BYTES,
    "time": _FD.TYPE_DOUBLE,
    "src_id": _FD.TYPE_INT32,
    "dest_id": _FD.TYPE_INT32,
}
PROTO_TYPE_NAMES = {
    _FD.TYPE_INT32: "int32",
    _FD.TYPE_DOUBLE: "double",
    _FD.TYPE_BOOL: "bool",
    _FD.TYPE_STRING: "string",
    _FD.TYPE_BYTES: "bytes",
}


def enum_type_name(var: Var) -> str:
    name = var.name + "Enum"
    return name[0].upper() + name[1:]


def enum_value_name(var: Var, value: str) -> str:
    return f"{var.name.upper()}_{value}"


def _fixed(value: float, precision: int) -> float:
    """A bound as Goby 2 wrote it into the .proto (fixed notation with `precision` decimals)."""
    return float(f"{value:.{precision if precision >= 0 else 6}f}")


def field_options(var: Var) -> dict[str, object]:
    """The (dccl.field) options of a variable, in the order Goby 2 wrote them."""
    if var.kind == "time":
        return {"codec": "_time", "in_head": True}
    opts: dict[str, object] = {}
    if var.max is not None and var.min is not None:
        precision = var.precision if var.kind == "float" else 0
        opts["max"] = _fixed(var.max, precision)
        opts["min"] = _fixed(var.min, precision)
    if var.kind == "float":
        opts["precision"] = var.precision
    if var.max_length is not None:
        opts["max_length"] = var.max_length
    if var.num_bytes is not None:
        opts["max_length"] = var.num_bytes
    if var.kind == "static":
        opts["static_value"] = var.static_value
        opts["codec"] = "_static"
    if var.array_length != 1:
        opts["max_repeat"] = var.array_length
    if var.kind in ("src_id", "dest_id"):
        opts["in_head"] = True
    return opts


def _option_bytes(carrier_name: str, attribute: str, values: dict[str, object]) -> bytes:
    """Serialized `(dccl.field)`/`(dccl.msg)` extension bytes, ready to merge into the
    descriptor's options (the extension lives in another descriptor pool than descriptor_pb2)."""
    carrier = builtin_class(_CARRIER_PROTO, carrier_name)()
    target = getattr(carrier, attribute)
    for key, value in values.items():
        setattr(target, key, value)
    return carrier.SerializeToString()


def file_descriptor(
    messages: Iterable[XmlMessage], file_name: str
) -> descriptor_pb2.FileDescriptorProto:
    """The in-memory .proto file of a message set."""
    fdp = descriptor_pb2.FileDescriptorProto(name=file_name, syntax="proto2")
    fdp.dependency.append(DCCL_OPTIONS_PROTO)
    for msg in messages:
        dp = fdp.message_type.add(name=msg.name)
        dp.options.MergeFromString(
            _option_bytes(
                "pygoby.dccl.MessageOptionsCarrier",
                "msg",
                {"id": msg.id, "max_bytes": msg.size, "codec_version": CODEC_VERSION},
            )
        )
        for var in msg.all_vars():
            field = dp.field.add(name=var.name, number=var.number)
            field.label = _FD.LABEL_REPEATED if var.array_length != 1 else _FD.LABEL_OPTIONAL
            if var.kind == "enum":
                field.type = _FD.TYPE_ENUM
                field.type_name = enum_type_name(var)
                enum = dp.enum_type.add(name=enum_type_name(var))
                for index, value in enumerate(var.enum_values):
                    enum.value.add(name=enum_value_name(var, value), number=index)
            else:
                field.type = PROTO_TYPES[var.kind]
            if var.kind == "static":
                field.default_value = var.static_value or ""
            field.options.MergeFromString(
                _option_bytes("pygoby.dccl.FieldOptionsCarrier", "field", field_options(var))
            )
    return fdp


def _option_text(key: str, value: object) -> str:
    if isinstance(value, bool):
        text = "true" if value else "false"
    elif isinstance(value, str):
        text = '"' + value.replace("\\", "\\\\").replace('"', '\\"') + '"'
    elif isinstance(value, float):
        text = repr(value)
    else:
        text = str(value)
    return f"(dccl.field).{key} = {text}"


def proto_text(messages: Iterable[XmlMessage], source: str = "") -> str:
    """The same message set as a .proto file, for users moving their XML to DCCL .proto."""
    lines = ['syntax = "proto2";', f'import "{DCCL_OPTIONS_PROTO}";', ""]
    if source:
        lines.insert(0, f"// Converted from the Goby 1.1 DCCL XML message set {source} by pygoby.")
    for msg in messages:
        lines.append(f"message {msg.name}")
        lines.append("{")
        lines.append(f"    option (dccl.msg).id = {msg.id};")
        lines.append(f"    option (dccl.msg).max_bytes = {msg.size};")
        lines.append(f"    option (dccl.msg).codec_version = {CODEC_VERSION};")
        for var in msg.all_vars():
            if var.kind == "enum":
                lines.append(f"    enum {enum_type_name(var)}")
                lines.append("    {")
                lines += [
                    f"        {enum_value_name(var, v)} = {i};"
                    for i, v in enumerate(var.enum_values)
                ]
                lines.append("    }")
            label = "repeated" if var.array_length != 1 else "optional"
            kind = (
                enum_type_name(var)
                if var.kind == "enum"
                else PROTO_TYPE_NAMES[PROTO_TYPES[var.kind]]
            )
            options = [_option_text(k, v) for k, v in field_options(var).items()]
            if var.kind == "static":
                options.insert(0, f'default = "{var.static_value}"')
            suffix = f" [{', '.join(options)}]" if options else ""
            lines.append(f"    {label} {kind} {var.name} = {var.number}{suffix};")
        lines.append("}")
        lines.append("")
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# Queue and translator entries


def queue_entry(
    msg: XmlMessage, manipulators: Iterable[Manipulator.ValueType] = ()
) -> QueuedMessageEntry:
    entry = QueuedMessageEntry()
    q = msg.queuing
    entry.protobuf_name = msg.name
    entry.ack, entry.blackout_time, entry.max_queue = q.ack, q.blackout_time, q.max_queue
    entry.newest_first, entry.value_base, entry.ttl = q.newest_first, q.value_base, q.ttl
    entry.manipulator.extend(manipulators)
    Role = type(entry).Role
    for role_type, tag in (
        (Role.SOURCE_ID, "src_id"),
        (Role.DESTINATION_ID, "dest_id"),
        (Role.TIMESTAMP, "time"),
    ):
        entry.role.add(type=role_type, field=msg.header[tag].name)
    return entry


def translator_entry(msg: XmlMessage) -> TranslatorEntry:
    entry = TranslatorEntry()
    T = type(entry)
    entry.protobuf_name = msg.name
    entry.use_short_enum = True
    if msg.trigger == "time":
        entry.trigger.type = T.Trigger.TRIGGER_TIME
        entry.trigger.period = msg.trigger_time or 0
    elif msg.trigger == "publish":
        entry.trigger.type = T.Trigger.TRIGGER_PUBLISH
        entry.trigger.moos_var = msg.trigger_var
        if msg.mandatory_content:
            entry.trigger.mandatory_content = msg.mandatory_content
    creates: dict[str, TranslatorEntry.CreateParser] = {}
    for var in msg.all_vars():
        _add_create(entry, creates, var)
    highest = max(v.number for v in msg.all_vars())
    next_virtual = (highest + 100) // 100 * 100
    for publish in msg.publishes:
        next_virtual = _add_publish(entry, msg, publish, next_virtual)
    return entry


def _add_create(
    entry: TranslatorEntry, creates: dict[str, TranslatorEntry.CreateParser], var: Var
) -> None:
    T = TranslatorEntry
    if not var.source_var:
        return
    create = creates.get(var.source_var)
    if create is not None:  # several fields share the variable: key=value parsing
        create.technique = T.TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS
        create.ClearField("format")
    else:
        create = entry.create.add(
            technique=T.TECHNIQUE_FORMAT, moos_var=var.source_var, format=f"%{var.number}%"
        )
        creates[var.source_var] = create
    for algorithm in var.algorithms:
        create.algorithm.add(name=algorithm, primary_field=var.number)


def default_format(msg: XmlMessage, publish: Publish) -> str:
    """Goby 1.1's format when <format> is left out: `%1%` for one value, else
    `name=%1%,name2=%2%` (arrays in braces; a variable listed twice named by its algorithms)."""
    values = publish.values
    parts: list[str] = []
    count = 0
    names = [v.name for v in values]
    for value in values:
        var = msg.var(value.name)
        assert var is not None
        label = ""
        if len(values) > 1:
            if names.count(value.name) > 1 and value.algorithms:
                label = "".join(value.algorithms) + f"({value.name})="
            else:
                label = f"{value.name}="
        length = var.array_length
        placeholders = []
        for _ in range(length):
            count += 1
            placeholders.append(f"%{count}%")
        body = ",".join(placeholders)
        if len(values) > 1 and length > 1:
            body = "{" + body + "}"
        parts.append(label + body)
    return ",".join(parts)


def _add_publish(
    entry: TranslatorEntry, msg: XmlMessage, publish: Publish, next_virtual: int
) -> int:
    T = TranslatorEntry
    serializer = entry.publish.add(technique=T.TECHNIQUE_FORMAT)
    replacement: dict[int, str] = {}
    v1_index = 0
    for value in publish.values:
        var = msg.var(value.name)
        assert var is not None
        for k in range(var.array_length):
            v1_index += 1
            field = var.number
            if value.algorithms:
                for algorithm in value.algorithms:
                    name, *references = algorithm.split(":")
                    serializer.algorithm.add(
                        name=name,
                        primary_field=var.number,
                        output_virtual_field=next_virtual,
                        reference_field=[_reference_number(msg, r) for r in references],
                    )
                field = next_virtual
                next_virtual += 1
            replacement[v1_index] = f"{field}.{k}" if var.array_length > 1 else str(field)
    fmt = publish.format if publish.format is not None else default_format(msg, publish)

    def renumber(text: str) -> str:
        return V1_PLACEHOLDER.sub(lambda m: "%" + replacement[int(m.group(1))], text)

    serializer.moos_var = renumber(publish.moos_var)
    serializer.format = renumber(fmt)
    return next_virtual


def _reference_number(msg: XmlMessage, name: str) -> int:
    var = msg.var(name)
    assert var is not None  # checked by the parser
    return var.number
