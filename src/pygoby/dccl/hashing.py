"""`dccl.hash`: a uint32 field that carries a hash of the message definition (C++ DCCL 4.2).

C++ DCCL computes the hash when a type is loaded, from text: for the root message its DCCL
message options (without max_bytes), then, in the header and the body pass, every field it
traverses: the field's descriptor (number, label, type; not its name, type name, default or
options) and its DCCL field options, each printed as protobuf's C++ `DebugString()` and
hashed with the C++ standard library's `std::hash<std::string>`, folded with boost's
`hash_combine`; embedded messages, enums (their `DebugString()`) and v4 oneofs (theirs) add
their own hashes. The field sends `hash & max`; a decoder with another definition fails.

pygoby reproduces this exactly for the common platform: `std::hash` of GNU libstdc++ on 64-bit
(MurmurHash64A-style `_Hash_bytes`, seed 0xc70f6907) and protobuf 3.x/4.x's `DebugString`
format. A C++ peer built with another standard library (libc++ on macOS: a different
`std::hash`) or on a 32-bit platform computes other values; so does C++ against itself.
"""

from __future__ import annotations

from google.protobuf import descriptor_pb2
from google.protobuf.descriptor import FieldDescriptor, OneofDescriptor
from google.protobuf.message import Message

from pygoby.dccl.codecs.enum import EnumCodec
from pygoby.dccl.codecs.hash import HashCodec
from pygoby.dccl.options import field_options, message_options
from pygoby.dccl.plan import MessageItem, RepeatedItem
from pygoby.protobuf import enum_type, message_type
from pygoby.protobuf.cpp_text import c_escape, message_text, scalar_text
from pygoby.protobuf.descriptors import AnyDescriptor, AnyEnumDescriptor, AnyFieldDescriptor

_U64 = (1 << 64) - 1
_MUL = 0xC6A4A7935BD1E995
_SEED = 0xC70F6907


# ------------------------------------------------------------------ libstdc++ std::hash
def _shift_mix(v: int) -> int:
    return v ^ (v >> 47)


def cpp_string_hash(data: bytes) -> int:
    """`std::hash<std::string>` of GNU libstdc++ on a 64-bit platform."""
    n = len(data)
    h = (_SEED ^ (n * _MUL)) & _U64
    aligned = n & ~7
    for i in range(0, aligned, 8):
        word = int.from_bytes(data[i : i + 8], "little")
        h ^= (_shift_mix((word * _MUL) & _U64) * _MUL) & _U64
        h = (h * _MUL) & _U64
    if n & 7:
        h ^= int.from_bytes(data[aligned:], "little")
        h = (h * _MUL) & _U64
    h = (_shift_mix(h) * _MUL) & _U64
    return _shift_mix(h)


def hash_combine(seed: int, value: int) -> int:
    """boost::hash_combine on 64-bit size_t (std::hash of an integer is the integer)."""
    return (seed ^ ((value + 0x9E3779B9 + (seed << 6) + (seed >> 2)) & _U64)) & _U64


def _combine_text(seed: int, text: str) -> int:
    return hash_combine(seed, cpp_string_hash(text.encode()))


# ------------------------------------------------------------------ protobuf C++ text
def _sorted_fields(msg: Message):
    return sorted(msg.ListFields(), key=lambda fv: fv[0].number)


def text_format(msg: Message, indent: int = 0) -> str:
    """C++ `TextFormat::Printer` (what `DebugString()` prints), from `indent` spaces."""
    return message_text(msg, single_line=False, indent=indent)


def _option_entries(depth: int, options: Message, dccl_options: Message | None) -> list[str]:
    """protobuf's RetrieveOptions: `name = value` of each set option, by field number; the
    (dccl.field) extension comes from `dccl_options`."""
    entries: list[tuple[int, str]] = []
    for f, value in _sorted_fields(options):
        if f.is_extension:
            continue
        entries.append((f.number, f"{f.name} = {scalar_text(f, value)}"))
    if dccl_options is not None and dccl_options.ListFields():
        body = text_format(dccl_options, 2 * (depth + 1))
        entries.append((1012, f"(.dccl.field) = {{\n{body}{' ' * (2 * depth)}}}"))
    return [text for _, text in sorted(entries, key=lambda e: e[0])]


_TYPE_NAMES = {
    FieldDescriptor.TYPE_DOUBLE: "double",
    FieldDescriptor.TYPE_FLOAT: "float",
    FieldDescriptor.TYPE_INT64: "int64",
    FieldDescriptor.TYPE_UINT64: "uint64",
    FieldDescriptor.TYPE_INT32: "int32",
    FieldDescriptor.TYPE_FIXED64: "fixed64",
    FieldDescriptor.TYPE_FIXED32: "fixed32",
    FieldDescriptor.TYPE_BOOL: "bool",
    FieldDescriptor.TYPE_STRING: "string",
    FieldDescriptor.TYPE_GROUP: "group",
    FieldDescriptor.TYPE_BYTES: "bytes",
    FieldDescriptor.TYPE_UINT32: "uint32",
    FieldDescriptor.TYPE_SFIXED32: "sfixed32",
    FieldDescriptor.TYPE_SFIXED64: "sfixed64",
    FieldDescriptor.TYPE_SINT32: "sint32",
    FieldDescriptor.TYPE_SINT64: "sint64",
}
_PROTO_TYPES = {number: "TYPE_" + name.upper() for number, name in _TYPE_NAMES.items()} | {
    FieldDescriptor.TYPE_MESSAGE: "TYPE_MESSAGE",
    FieldDescriptor.TYPE_ENUM: "TYPE_ENUM",
}


def _field_proto(f: AnyFieldDescriptor) -> descriptor_pb2.FieldDescriptorProto:
    proto = descriptor_pb2.DescriptorProto()
    f.containing_type.CopyToProto(proto)  # type: ignore[union-attr]  # (a field of a message)
    return next(p for p in proto.field if p.number == f.number)


def _label(f: AnyFieldDescriptor) -> str:
    if f.is_repeated:
        return "LABEL_REPEATED"
    return "LABEL_REQUIRED" if f.is_required else "LABEL_OPTIONAL"


def _explicit_json_name(f: AnyFieldDescriptor) -> bool:
    camel, upper = "", False
    for char in f.name:
        if char == "_":
            upper = True
        else:
            camel += char.upper() if upper else char
            upper = False
    return f.json_name != camel


def field_descriptor_text(f: AnyFieldDescriptor) -> str:
    """DebugString() of the FieldDescriptorProto without name, options, type name and
    default (what C++ DCCL hashes for a field)."""
    lines = [f"number: {f.number}\n", f"label: {_label(f)}\n", f"type: {_PROTO_TYPES[f.type]}\n"]
    if f.containing_oneof is not None:
        lines.append(f"oneof_index: {f.containing_oneof.index}\n")
    if _explicit_json_name(f):
        lines.append(f'json_name: "{c_escape(f.json_name.encode())}"\n')
    if getattr(f, "has_presence", False) and _field_proto(f).proto3_optional:
        lines.append("proto3_optional: true\n")
    return "".join(lines)


def _field_debug_string(f: AnyFieldDescriptor, depth: int) -> str:
    """FieldDescriptor::DebugString at `depth` (as inside a oneof)."""
    prefix = " " * (2 * depth)
    if f.type in (FieldDescriptor.TYPE_MESSAGE, FieldDescriptor.TYPE_GROUP):
        type_name = "." + message_type(f).full_name
    elif f.type == FieldDescriptor.TYPE_ENUM:
        type_name = "." + enum_type(f).full_name
    else:
        type_name = _TYPE_NAMES[f.type]
    label = "" if f.containing_oneof is not None else _label(f)[6:].lower() + " "
    text = f"{prefix}{label}{type_name} {f.name} = {f.number}"
    options = _option_entries(depth, f.GetOptions(), field_options(f))
    if options:
        text += " [" + ", ".join(options) + "]"
    return text + ";\n"


def oneof_debug_string(oneof: OneofDescriptor) -> str:
    fields = "".join(_field_debug_string(f, 1) for f in oneof.fields)
    return f"oneof {oneof.name} {{\n{fields}}}\n"


def enum_debug_string(enum: AnyEnumDescriptor) -> str:
    proto = descriptor_pb2.EnumDescriptorProto()
    enum.CopyToProto(proto)
    lines = [f"enum {enum.name} {{\n"]
    for f, value in _sorted_fields(proto.options):
        if not f.is_extension:
            lines.append(f"  option {f.name} = {scalar_text(f, value)};\n")
    for value in enum.values:
        value_proto = next(
            v for v in proto.value if v.number == value.number and v.name == value.name
        )
        options = _option_entries(1, value_proto.options, None)
        suffix = f" [{', '.join(options)}]" if options else ""
        lines.append(f"  {value.name} = {value.number}{suffix};\n")
    if proto.reserved_range:
        parts = []
        for r in proto.reserved_range:
            if r.start == r.end:
                parts.append(str(r.start))
            elif r.end == 2**31 - 1:
                parts.append(f"{r.start} to max")
            else:
                parts.append(f"{r.start} to {r.end}")
        lines.append("  reserved " + ", ".join(parts) + ";\n")
    if proto.reserved_name:
        names = ", ".join(f'"{c_escape(n.encode())}"' for n in proto.reserved_name)
        lines.append(f"  reserved {names};\n")
    lines.append("}\n")
    return "".join(lines)


# ------------------------------------------------------------------ the definition's hash
def _codec_hash(item) -> int:
    """FieldCodecBase::hash() of a field's codec: a sub-message's own hash, an enum's
    DebugString for the default enum codecs, 0 otherwise."""
    if isinstance(item, MessageItem) or (isinstance(item, RepeatedItem) and item.child is not None):
        return node_hash(item.child)
    codec = getattr(item, "codec", None)
    if isinstance(codec, EnumCodec):
        return cpp_string_hash(enum_debug_string(item.field.enum_type).encode())
    return 0


def node_hash(node) -> int:
    value = 0
    for oneof in node.oneofs:
        desc = node.descriptor.oneofs_by_name[oneof.name]
        value = _combine_text(value, oneof_debug_string(desc))
    for item in node.items:
        f = item.field
        value = _combine_text(value, field_descriptor_text(f))
        value = _combine_text(value, text_format(field_options(f)))
        value = hash_combine(value, _codec_hash(item))
    return value


def definition_hash(descriptor: AnyDescriptor, head, body) -> int:
    """The 64-bit hash C++ DCCL's `Codec::load` returns for a root type (from its plans)."""
    opts = message_options(descriptor)
    opts.ClearField("max_bytes")
    text = text_format(opts)
    value = 0
    for node in (head, body):
        value = _combine_text(value, text)
        value = hash_combine(value, node_hash(node))
    return value


def hash_codecs(node):
    """Every HashCodec in a plan."""
    for item in node.items:
        codec = getattr(item, "codec", None)
        if isinstance(codec, HashCodec):
            yield codec
        if isinstance(item, MessageItem) or (isinstance(item, RepeatedItem) and item.child):
            yield from hash_codecs(item.child)
