"""Dynamic conditions: `(dccl.field).dynamic_conditions` Lua expressions, evaluated
with a real Lua 5.3 (the `lupa` package) as C++ DCCL does.

A condition sees three globals: `this` (the message holding the field; for a message-typed
field's own `required_if`, the sub-message itself, as in C++), `root` (the root message) and
`this_index` (1 + the index of the last repeated element coded). Messages appear to Lua as C++
DCCL hands them over (lua-protobuf tables, `use_default_metatable`): set fields only, enum values
by name, a oneof's name giving its set member, 64-bit integers as Lua integers, and a field with
an explicit `[default = ...]` reading its default when unset. While decoding they hold what is
decoded so far. A script without the word `return` is run as `return <script>`.

| condition | effect |
|---|---|
| `omit_if` | true: the field (or repeated element) takes no bits (v3/v4 message codecs; elements in all) |
| `required_if` | true: the required encoding (v3/v4) |
| `only_if` | required if true, omitted if false |
| `min`, `max` | the numeric bounds for this value, within the static ones (the width follows them) |

One Lua state per Codec (its globals persist between scripts, as in C++). `this_index` is
tracked across the repeated fields of message types that have conditions (C++ also counts those
of other types coded in between).

C++ DCCL 4.2 also evaluates `min`/`max` when it computes the message's minimum size at the start
of decoding, on the still empty message, and fails the decode if that raises (e.g.
`this.lo + 10` with `lo` unset); pygoby evaluates them only at the field.
"""

from __future__ import annotations

import dataclasses
import functools
import math
from dataclasses import dataclass
from typing import Any

from google.protobuf import descriptor_pb2
from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from pygoby.dccl.errors import DcclError, DcclLoadError
from pygoby.protobuf import enum_type
from pygoby.protobuf.dccl.option_extensions_pb2 import DCCLFieldOptions
from pygoby.protobuf.descriptors import AnyDescriptor, AnyFieldDescriptor
from pygoby.util.errors import MissingExtraError
from pygoby.util.extras import needs_extra

_INT64 = (FieldDescriptor.CPPTYPE_INT64, FieldDescriptor.CPPTYPE_UINT64)


def _lupa():
    try:
        with needs_extra("lua", "dynamic_conditions (Lua 5.3 expressions)"):
            from lupa import lua53
    except MissingExtraError as exc:
        raise DcclLoadError(str(exc)) from None
    return lua53


def with_return(script: str) -> str:
    return script if "return" in script else "return " + script


@dataclass
class FieldConditions:
    """The dynamic conditions of one field, as the plan uses them."""

    field: AnyFieldDescriptor
    required_if: str | None = None  # required_if, or only_if
    omit_if: str | None = None  # omit_if, or "not (only_if)"
    omit_negates: bool = False  # omit_if is an only_if: omit when it is false
    min: str | None = None
    max: str | None = None
    scripts: dict[str, Any] = dataclasses.field(default_factory=dict)  # compiled, by role

    @classmethod
    def of(cls, f: AnyFieldDescriptor, options: DCCLFieldOptions) -> FieldConditions | None:
        if not options.HasField("dynamic_conditions"):
            return None
        dc = options.dynamic_conditions
        conditions = cls(f)
        if dc.HasField("required_if"):
            conditions.required_if = dc.required_if
        elif dc.HasField("only_if"):
            conditions.required_if = dc.only_if
        if dc.HasField("omit_if"):
            conditions.omit_if = dc.omit_if
        elif dc.HasField("only_if"):
            conditions.omit_if, conditions.omit_negates = dc.only_if, True
        if dc.HasField("min"):
            conditions.min = dc.min
        if dc.HasField("max"):
            conditions.max = dc.max
        if not (conditions.required_if or conditions.omit_if or conditions.min or conditions.max):
            return None
        return conditions

    @property
    def bounds(self) -> bool:
        return self.min is not None or self.max is not None

    def for_singular(self, message_codec: int, root_version: int) -> FieldConditions | None:
        """The conditions that act on a singular field handled by the v`message_codec`
        message codec of a v`root_version` root (or on a repeated field's elements: the
        repeated rules live in the plan)."""
        kept = dataclasses.replace(self)
        if message_codec < 3:
            kept.omit_if = None
        if root_version < 3:
            kept.required_if = None
        if not (kept.omit_if or kept.required_if or kept.bounds):
            return None
        return kept

    def without_required(self) -> FieldConditions | None:
        """For a field that is required anyway (label, oneof member): required_if is moot."""
        kept = dataclasses.replace(self, required_if=None)
        return kept if kept.omit_if or kept.bounds else None


class DynamicConditions:
    """The Lua state of one Codec and the evaluation of conditions in it."""

    def __init__(self) -> None:
        self.lua = _lupa().LuaRuntime(unpack_returned_tuples=False)
        self.index = 0  # C++'s repeated index: this_index is index + 1
        self._globals = self.lua.globals()
        self._to_number = self.lua.eval("function(r) return (r ~= nil and tonumber(r)) or 0 end")
        self._set_meta = self.lua.eval("setmetatable")
        self._meta: dict[str, Any] = {}

    def compile(self, conditions: FieldConditions) -> None:
        for role in ("required_if", "omit_if", "min", "max"):
            script = getattr(conditions, role)
            if script is None or role in conditions.scripts:
                continue
            source = (
                "return function()\n local r = (function()\n"
                f"{with_return(script)}\n end)()\n return r\n end"
            )
            try:
                conditions.scripts[role] = self.lua.execute(source)
            except Exception as exc:  # lupa.LuaSyntaxError
                raise DcclLoadError(
                    f"{conditions.field.full_name}: dynamic_conditions {role} {script!r} is"
                    f" not valid Lua: {exc}"
                ) from None

    # ------------------------------------------------------------------ evaluation
    def _run(
        self,
        conditions: FieldConditions,
        role: str,
        this: Message,
        root: Message,
        index: int | None,
    ) -> Any:
        if index is not None:
            self.index = index
        g = self._globals
        g.root = self._table(root)
        g.this = self._table(this)
        g.this_index = self.index + 1
        try:
            return conditions.scripts[role]()
        except Exception as exc:  # lupa.LuaError
            raise DcclError(
                f"{conditions.field.full_name}: dynamic_conditions {role}"
                f" {getattr(conditions, role)!r} failed: {exc}"
            ) from None

    def required(self, conditions: FieldConditions, this: Message, root: Message) -> bool:
        result = self._run(conditions, "required_if", this, root, None)
        return result is not None and result is not False

    def omit(
        self, conditions: FieldConditions, this: Message, root: Message, index: int | None = None
    ) -> bool:
        result = self._run(conditions, "omit_if", this, root, index)
        truth = result is not None and result is not False
        return not truth if conditions.omit_negates else truth

    def number(self, conditions: FieldConditions, role: str, this: Message, root: Message) -> float:
        if getattr(conditions, role) is None:
            return -math.inf if role == "min" else math.inf
        return float(self._to_number(self._run(conditions, role, this, root, None)))

    # ------------------------------------------------------------------ messages as Lua
    def _table(self, msg: Message):
        table = self.lua.table()
        for f, value in msg.ListFields():
            if f.is_repeated:
                table[f.name] = self.lua.table(*(self._value(f, v) for v in value))
            else:
                table[f.name] = self._value(f, value)
                if f.containing_oneof is not None and not _synthetic(f):
                    table[f.containing_oneof.name] = f.name
        return self._set_meta(table, self._defaults(msg.DESCRIPTOR))

    def _value(self, f: AnyFieldDescriptor, value: Any) -> Any:
        cpp = f.cpp_type
        if cpp == FieldDescriptor.CPPTYPE_MESSAGE:
            return self._table(value)
        if cpp == FieldDescriptor.CPPTYPE_ENUM:
            known = enum_type(f).values_by_number.get(value)
            return known.name if known is not None else value
        if cpp in _INT64 and value >= 1 << 63:
            return value - (1 << 64)  # a Lua integer is signed 64-bit
        return value

    def _defaults(self, desc: AnyDescriptor):
        meta = self._meta.get(desc.full_name)
        if meta is None:
            meta = self.lua.table()
            for f in desc.fields:
                text = _explicit_default(f)
                if text is None or f.containing_oneof is not None:
                    continue
                meta[f.name] = _default_value(f, text)
            meta["__index"] = meta
            self._meta[desc.full_name] = meta
        return meta


def _synthetic(f: AnyFieldDescriptor) -> bool:
    oneof = f.containing_oneof
    return oneof is not None and len(oneof.fields) == 1 and oneof.name == "_" + f.name


@functools.cache
def _file_proto(serialized: bytes) -> dict[str, descriptor_pb2.FieldDescriptorProto]:
    proto = descriptor_pb2.FileDescriptorProto.FromString(serialized)
    fields: dict[str, descriptor_pb2.FieldDescriptorProto] = {}

    def walk(prefix: str, messages) -> None:
        for m in messages:
            name = f"{prefix}{m.name}"
            for fp in m.field:
                fields[f"{name}.{fp.name}"] = fp
            walk(name + ".", m.nested_type)

    walk(f"{proto.package}." if proto.package else "", proto.message_type)
    return fields


def _explicit_default(f: AnyFieldDescriptor) -> str | None:
    """The text of a field's `[default = ...]`, None without one (only singular scalars)."""
    if f.is_repeated or f.cpp_type == FieldDescriptor.CPPTYPE_MESSAGE:
        return None
    proto = _file_proto(f.file.serialized_pb).get(f.full_name)  # type: ignore[union-attr]
    if proto is None or not proto.HasField("default_value"):
        return None
    return proto.default_value


def _default_value(f: AnyFieldDescriptor, text: str) -> Any:
    cpp = f.cpp_type
    if cpp == FieldDescriptor.CPPTYPE_ENUM:
        return text  # the value's name
    if cpp == FieldDescriptor.CPPTYPE_BOOL:
        return text == "true"
    if cpp in (FieldDescriptor.CPPTYPE_DOUBLE, FieldDescriptor.CPPTYPE_FLOAT):
        return float(text)
    if cpp == FieldDescriptor.CPPTYPE_STRING:
        return text
    return int(text)


def with_bounds(codec: Any, lo: float, hi: float) -> Any:
    """`codec` with the dynamic bounds [lo, hi] kept within its static ones (the default
    numeric codec, possibly behind a presence bit; other codecs have fixed bounds in C++)."""
    from pygoby.dccl.codecs.numeric import NumericCodec
    from pygoby.dccl.codecs.presence import PresenceCodec

    if isinstance(codec, PresenceCodec):
        return PresenceCodec(codec.info, with_bounds(codec.inner, lo, hi))
    if type(codec) is not NumericCodec:
        return codec
    static_lo, static_hi = codec.static_bounds
    hi = max(static_lo, min(hi, static_hi))
    lo = min(static_hi, max(lo, static_lo))
    return codec.rebound(lo, hi)


class ConditionedField:
    """A field's codec chosen at run time by its conditions (the generated code calls this)."""

    def __init__(
        self,
        lua: DynamicConditions,
        conditions: FieldConditions,
        codec: Any,
        required_codec: Any = None,
    ) -> None:
        self.lua = lua
        self.conditions = conditions
        self.codec = codec
        self.required_codec = required_codec
        self.omits = conditions.omit_if is not None

    def omit(self, this: Message, root: Message, index: int | None = None) -> bool:
        return self.omits and self.lua.omit(self.conditions, this, root, index)

    def required(self, this: Message, root: Message) -> bool:
        return self.required_codec is not None and self.lua.required(self.conditions, this, root)

    def codec_for(self, this: Message, root: Message) -> Any:
        codec = self.required_codec if self.required(this, root) else self.codec
        if self.conditions.bounds:
            lo = self.lua.number(self.conditions, "min", this, root)
            hi = self.lua.number(self.conditions, "max", this, root)
            codec = with_bounds(codec, lo, hi)
        return codec

    def encode(self, this: Message, root: Message, value: Any, strict: bool) -> tuple[int, int]:
        """(raw, bits); (0, 0) when the field is omitted."""
        if self.omit(this, root):
            return 0, 0
        return encode_value(self.codec_for(this, root), root, value, strict)

    def decode(
        self, this: Message, root: Message, bits: int, pos: int, end: int
    ) -> tuple[Any, int]:
        if self.omit(this, root):
            return None, pos
        return decode_value(self.codec_for(this, root), root, bits, pos, end)


def encode_value(codec: Any, root: Message, value: Any, strict: bool) -> tuple[int, int]:
    """Any field codec's (raw, bits) for `value` (None: the codec's "no value")."""
    from pygoby.dccl.codecs.base import FixedWidthCodec

    args = (root,) if codec.reads_root else ()
    if isinstance(codec, FixedWidthCodec):
        if value is None:
            return codec.null_raw, codec.bits
        return codec.to_raw(*args, value, strict), codec.bits
    return codec.encode(*args, value, strict)


def decode_value(codec: Any, root: Message, bits: int, pos: int, end: int) -> tuple[Any, int]:
    from pygoby.dccl.codecs.base import FixedWidthCodec

    args = (root,) if codec.reads_root else ()
    if isinstance(codec, FixedWidthCodec):
        raw = codec.take(bits, pos, end, codec.bits, codec.info.name)
        return codec.from_raw(*args, raw), pos + codec.bits
    return codec.decode(*args, bits, pos, end)
