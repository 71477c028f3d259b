"""Compile a message plan into Python encode/decode functions (no per-field dispatch at run time).

For each part of a root message type, straight-line Python source is generated and exec'd:

    encode_part(m0, strict) -> (acc, pos)      bits accumulated LSB-first into the integer `acc`
    decode_part(m0, b, pos, end) -> pos        fields read from the integer `b` into message m0

Codec calls are bound to names in the function's namespace, named after the field they serve
(`enc_depth`, `dec_pos_lat`); fixed-width codecs are inlined as `acc |= to_raw(value) << pos`.
Nested messages are expanded inline (the plan is finite). The source is registered with
`linecache` as `<dccl TYPE FUNCTION>`, so a traceback through generated code shows its lines.
With `trace`, a variant is generated that also calls `_trace` (a `FieldTracer`) after each field.
"""

from __future__ import annotations

import dataclasses
import keyword
import linecache
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from google.protobuf.descriptor import FieldDescriptor

from pygoby.dccl.codecs.base import FixedWidthCodec
from pygoby.dccl.conditions import ConditionedField, DynamicConditions
from pygoby.dccl.errors import DcclDecodeError, DcclEncodeError
from pygoby.dccl.plan import (
    ListItem,
    MessageItem,
    MessageNode,
    Mode,
    Part,
    RepeatedItem,
    ScalarItem,
)
from pygoby.dccl.rawtext import extend_raw_strings, set_raw_string
from pygoby.dccl.trace import FieldTracer
from pygoby.protobuf.descriptors import AnyFieldDescriptor


def _truncated(where: str) -> DcclDecodeError:
    return DcclDecodeError(f"message is truncated: {where} needs bits past the end of the data")


def _too_many(where: str, n: int, limit: int) -> DcclEncodeError:
    return DcclEncodeError(f"{where}: {n} values exceed max_repeat {limit}")


def _too_few(where: str, n: int, limit: int) -> DcclEncodeError:
    return DcclEncodeError(f"{where}: {n} values are fewer than min_repeat {limit}")


def _too_many_messages(where: str, n: int, limit: int) -> DcclDecodeError:
    # C++ DCCL reserves max_repeat sub-messages and rejects a count beyond them (a count of
    # scalar values beyond max_repeat is read by both)
    return DcclDecodeError(f"{where}: a count of {n} messages exceeds max_repeat {limit}")


@dataclass(frozen=True)
class GeneratedFunction:
    function: Callable
    source: str


def _register_source(base: str, source: str) -> str:
    """Put generated source into `linecache` and return its file name, `<dccl BASE>`.

    Identical source shares one name (reloading a type adds nothing); a different source for the
    same type (another Codec's registry chose other codecs) gets `<dccl BASE #2>`, and so on."""
    lines = source.splitlines(keepends=True)
    filename, copy = f"<dccl {base}>", 1
    while (entry := linecache.cache.get(filename)) is not None and entry[2] != lines:  # type: ignore[misc]  # (size, mtime, lines, name)
        copy += 1
        filename = f"<dccl {base} #{copy}>"
    # mtime None: linecache.checkcache() keeps the entry (there is no file to compare against)
    linecache.cache[filename] = (len(source), None, lines, filename)
    return filename


def _identifier(path: str) -> str:
    """`pos.lat` -> `pos_lat`, `list[].x` -> `list_x` (field names are identifiers already)."""
    return re.sub(r"\W+", "_", path).strip("_")


def _codec_about(codec, method: str) -> str:
    info = codec.info
    return f"{type(codec).__name__}.{method} for {info.name} ({info.codec_name})"


class _Source:
    """Lines of generated code plus the namespace they refer to."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.namespace: dict[str, Any] = {
            "_truncated": _truncated,
            "_too_many": _too_many,
            "_too_few": _too_few,
            "_too_many_messages": _too_many_messages,
            "_set_raw_string": set_raw_string,
            "_extend_raw_strings": extend_raw_strings,
        }
        self.bound: list[str] = []  # "name = what" for each codec/table bound in the namespace
        self._used: set[str] = set()

    def name(self, prefix: str, path: str, value: Any = None, about: str = "") -> str:
        """A fresh identifier `PREFIX_PATH` (`_2`, `_3`... appended if taken), optionally bound
        to `value` in the namespace."""
        base = f"{prefix}_{_identifier(path)}"
        ident, copy = base, 1
        while ident in self._used:
            copy += 1
            ident = f"{base}_{copy}"
        self._used.add(ident)
        if value is not None:
            self.namespace[ident] = value
            self.bound.append(f"{ident} = {about}")
        return ident

    def add(self, indent: int, line: str) -> None:
        self.lines.append("    " * indent + line)

    def build(
        self, type_name: str, func_name: str, summary: str, traced: bool
    ) -> GeneratedFunction:
        comment = [f"# {type_name}: {summary}. Generated by pygoby.dccl from the message plan."]
        if traced:
            comment.append("# Traced variant: _trace logs each field's value and bits.")
        comment += [f"#   {line}" for line in self.bound]
        source = "\n".join([*comment, *self.lines]) + "\n"
        base = f"{type_name} {func_name}" + (" traced" if traced else "")
        filename = _register_source(base, source)
        exec(compile(source, filename, "exec"), self.namespace)
        return GeneratedFunction(self.namespace[func_name], source)


def _get(var: str, field_name: str) -> str:
    if field_name.isidentifier() and not keyword.iskeyword(field_name):
        return f"{var}.{field_name}"
    return f"getattr({var}, {field_name!r})"


def _set(var: str, field_name: str, value: str) -> str:
    if field_name.isidentifier() and not keyword.iskeyword(field_name):
        return f"{var}.{field_name} = {value}"
    return f"setattr({var}, {field_name!r}, {value})"


def _is_string(field: AnyFieldDescriptor) -> bool:
    return field.type == FieldDescriptor.TYPE_STRING


def _has(var: str, item) -> str:
    f = item.field
    if f.has_presence:
        return f"{var}.HasField({f.name!r})"
    return _get(var, f.name)  # proto3 implicit presence: set means "not the default"


class _PartCompiler:
    """What the encoder and decoder generators share: the source, names and trace hooks."""

    bits_var = ""  # the integer holding the part's bits: `acc` (encoding) or `b` (decoding)

    def __init__(
        self, type_name: str, action: str, part: Part, trace: bool, lua: DynamicConditions | None
    ) -> None:
        self.src = _Source()
        # the Codec's Lua state, for types with dynamic conditions: the generated code then also
        # keeps C++'s repeated index (`_dc.index`) up to date
        self.lua = lua
        if lua is not None:
            self.src.namespace["_dc"] = lua
        self.type_name = type_name
        self.part = part
        self.func_name = f"{action}_{part.value}"
        self.summary = f"{action} the {part.value}"
        self.tracer = FieldTracer(type_name, action, part.value) if trace else None
        if self.tracer is not None:
            self.src.namespace["_trace"] = self.tracer

    def _trace_start(self, path: str, ind: int) -> str | None:
        if self.tracer is None:
            return None
        start = self.src.name("p", path)
        self.src.add(ind, f"{start} = pos")
        return start

    def _trace_end(
        self, start: str | None, path: str, value: str, ind: int, field: AnyFieldDescriptor | None
    ) -> None:
        if start is not None:
            if field is not None:
                self.tracer.fields[path] = field  # type: ignore[union-attr]  # (start: tracing)
            self.src.add(ind, f"_trace({path!r}, {value}, {start}, pos, {self.bits_var})")

    def _trace_id(self, ind: int) -> None:
        """The id opens the head: bits 0..pos hold it, shifted left by its form bit."""
        if self.tracer is not None and self.part is Part.HEAD:
            bits = self.bits_var
            self.src.add(
                ind, f"if pos: _trace('(id)', ({bits} & (1 << pos) - 1) >> 1, 0, pos, {bits})"
            )

    def _build(self) -> GeneratedFunction:
        return self.src.build(self.type_name, self.func_name, self.summary, self.tracer is not None)

    def _conditioned(self, item, path: str, element: bool = False) -> str:
        """Bind the run-time codec choice of a field with dynamic conditions (`element`: of a
        repeated field's element, whose omission the loop decides)."""
        assert self.lua is not None
        conditions = (
            dataclasses.replace(item.conditions, omit_if=None) if element else item.conditions
        )
        field = ConditionedField(
            self.lua, conditions, item.codec, getattr(item, "required_codec", None)
        )
        return self.src.name("cond", path, field, f"conditions of {item.field.full_name}")

    def _conditions(self, item, path: str) -> str:
        """Bind a field's conditions (for `_dc.omit`/`_dc.required` calls)."""
        return self.src.name("dc", path, item.conditions, f"conditions of {item.field.full_name}")

    def _omit_guard(self, item, path: str, var: str, ind: int) -> tuple[str, int]:
        """Bind a message field's conditions; if it has omit_if, open `if not omitted:`.
        Returns the conditions' name and the indent to continue at."""
        dc = self._conditions(item, path)
        if item.conditions.omit_if is not None:
            self.src.add(ind, f"if not _dc.omit({dc}, {var}, m0):")
            ind += 1
        return dc, ind

    def _index(self, ind: int, index: str) -> None:
        """C++ DCCL's repeated index, which `this_index` reads, follows every element coded."""
        if self.lua is not None:
            self.src.add(ind, f"_dc.index = {index}")


def _null_encoding(item: RepeatedItem) -> tuple[int, int]:
    """(raw, bits) of one element with no value: a codec's encoding of nothing, or the
    minimum-size (all zero) encoding of a message."""
    codec = item.codec
    if codec is None:
        return 0, item.child_node().cpp_min_size()
    if isinstance(codec, FixedWidthCodec):
        return codec.null_raw, codec.bits
    return codec.encode(None, False)


class EncoderCompiler(_PartCompiler):
    bits_var = "acc"

    def __init__(
        self, type_name: str, part: Part, trace: bool, lua: DynamicConditions | None
    ) -> None:
        super().__init__(type_name, "encode", part, trace, lua)

    def compile(self, node: MessageNode, start_acc: int, start_pos: int) -> GeneratedFunction:
        self.src.add(0, f"def {self.func_name}(m0, strict):")
        self.src.add(1, f"acc = {start_acc}")
        self.src.add(1, f"pos = {start_pos}")
        self._trace_id(1)
        self._node(node, "m0", 1, "")
        self.src.add(1, "return acc, pos")
        return self._build()

    def _node(self, node: MessageNode, var: str, ind: int, prefix: str) -> None:
        cases: dict[str, tuple[str, int]] = {}
        for oneof in node.oneofs:
            case = self.src.name("case", prefix + oneof.name)
            index = {member: i + 1 for i, member in enumerate(oneof.members)}
            table = self.src.name(
                "oneof", prefix + oneof.name, index, f"oneof case numbers {index}"
            )
            start = self._trace_start(prefix + oneof.name, ind)
            self.src.add(ind, f"{case} = {table}.get({var}.WhichOneof({oneof.name!r}), 0)")
            if oneof.bits:
                self.src.add(ind, f"acc |= {case} << pos")
                self.src.add(ind, f"pos += {oneof.bits}")
            self._trace_end(start, f"{prefix}{oneof.name} (oneof case)", case, ind, None)
            for member, i in index.items():
                cases[member] = (case, i)
        for item in node.items:
            path = prefix + item.field.name
            if isinstance(item, ListItem):
                start = self._trace_start(path, ind)
                values = _get(var, item.field.name)
                enc = self.src.name(
                    "enc", path, item.codec.encode_list, _codec_about(item.codec, "encode_list")
                )
                self.src.add(ind, f"r, n = {enc}(list({values}), strict)")
                self.src.add(ind, "acc |= r << pos")
                self.src.add(ind, "pos += n")
                self._trace_end(start, path, values, ind, item.field)
                continue
            if isinstance(item, RepeatedItem):
                start = self._trace_start(path, ind)
                encoded = self._repeated(item, var, ind, path)
                self._trace_end(start, path, encoded, ind, item.field)
                continue
            field_ind = ind
            if item.mode is Mode.ONEOF:
                case, i = cases[item.field.name]
                self.src.add(ind, f"if {case} == {i}:")
                field_ind += 1
            present = item.mode is not Mode.OPTIONAL  # required, or the oneof's set member
            start = self._trace_start(path, field_ind)
            if isinstance(item, ScalarItem) and item.conditions is not None:
                cond = self._conditioned(item, path)
                value = _get(var, item.field.name)
                if not present:
                    value = f"({value} if {_has(var, item)} else None)"
                self.src.add(field_ind, f"r, n = {cond}.encode({var}, m0, {value}, strict)")
                self.src.add(field_ind, "acc |= r << pos")
                self.src.add(field_ind, "pos += n")
            else:
                self._singular(item, var, field_ind, present, path)
            value = _get(var, item.field.name)
            if not present:
                value = f"({value} if {_has(var, item)} else None)"
            self._trace_end(start, path, value, field_ind, item.field)

    def _write_value(self, codec, value: str, ind: int, path: str) -> None:
        root = "m0, " if codec.reads_root else ""
        if isinstance(codec, FixedWidthCodec):
            if codec.bits:
                enc = self.src.name("enc", path, codec.to_raw, _codec_about(codec, "to_raw"))
                self.src.add(ind, f"acc |= {enc}({root}{value}, strict) << pos")
                self.src.add(ind, f"pos += {codec.bits}")
        else:
            enc = self.src.name("enc", path, codec.encode, _codec_about(codec, "encode"))
            self.src.add(ind, f"r, n = {enc}({root}{value}, strict)")
            self.src.add(ind, "acc |= r << pos")
            self.src.add(ind, "pos += n")

    def _singular(self, item, var: str, ind: int, present: bool, path: str) -> None:
        value = _get(var, item.field.name)
        if isinstance(item, ScalarItem):
            codec = item.codec
            if present:
                self._write_value(codec, value, ind, path)
            elif isinstance(codec, FixedWidthCodec):
                if codec.bits:
                    root = "m0, " if codec.reads_root else ""
                    enc = self.src.name("enc", path, codec.to_raw, _codec_about(codec, "to_raw"))
                    self.src.add(ind, f"if {_has(var, item)}:")
                    self.src.add(ind + 1, f"acc |= {enc}({root}{value}, strict) << pos")
                    if codec.null_raw:
                        self.src.add(ind, "else:")
                        self.src.add(ind + 1, f"acc |= {codec.null_raw} << pos")
                    self.src.add(ind, f"pos += {codec.bits}")
            else:
                self._write_value(codec, f"({value} if {_has(var, item)} else None)", ind, path)
            return
        # built-in message codec
        child_var = self.src.name("m", path)
        conditions = item.conditions
        if conditions is not None:
            dc, ind = self._omit_guard(item, path, var, ind)
            if conditions.required_if is not None and item.presence_bit:
                # C++ asks with `this` = the sub-message (an empty one when unset)
                self.src.add(ind, f"{child_var} = {value}")
                self.src.add(ind, f"if _dc.required({dc}, {child_var}, m0):")
                self.src.add(ind + 1, f"if {var}.HasField({item.field.name!r}):")
                self._node(item.child, child_var, ind + 2, path + ".")
                self.src.add(ind + 1, "else:")
                self.src.add(ind + 2, f"pos += {item.child.cpp_min_size()}")
                self.src.add(ind, "else:")
                ind += 1
        if present:
            self.src.add(ind, f"{child_var} = {value}")
            self._node(item.child, child_var, ind, path + ".")
        elif item.presence_bit:
            self.src.add(ind, f"if {var}.HasField({item.field.name!r}):")
            self.src.add(ind + 1, "acc |= 1 << pos")
            self.src.add(ind + 1, "pos += 1")
            self.src.add(ind + 1, f"{child_var} = {value}")
            self._node(item.child, child_var, ind + 1, path + ".")
            self.src.add(ind, "else:")
            self.src.add(ind + 1, "pos += 1")
        elif item.child.max_size():
            # v2: an absent message is written as its minimum-size (all "not set") encoding
            self.src.add(ind, f"if {var}.HasField({item.field.name!r}):")
            self.src.add(ind + 1, f"{child_var} = {value}")
            self._node(item.child, child_var, ind + 1, path + ".")
            self.src.add(ind, "else:")
            self.src.add(ind + 1, f"pos += {item.child.min_size()}")

    def _element(
        self,
        item: RepeatedItem,
        var: str,
        element: str | None,
        index: str,
        ind: int,
        path: str,
        strict: str,
    ) -> None:
        """One element (None: a padding element) of a repeated field in a type with dynamic
        conditions: omitted elements take no bits."""
        conditions = item.conditions
        this = var if item.codec is not None or element is None else element
        if conditions is not None and conditions.omit_if is not None:
            dc = self._conditions(item, path)
            self.src.add(ind, f"if _dc.omit({dc}, {this}, m0, {index}): continue")
        if element is None:
            null_raw, null_bits = _null_encoding(item)
            if null_raw:
                self.src.add(ind, f"acc |= {null_raw} << pos")
            if null_bits:
                self.src.add(ind, f"pos += {null_bits}")
            return
        if item.codec is None:
            self._node(item.child_node(), element, ind, path + "[].")
        elif conditions is not None and conditions.bounds:
            cond = self._conditioned(item, path, element=True)
            self.src.add(ind, f"r, n = {cond}.encode({var}, m0, {element}, {strict})")
            self.src.add(ind, "acc |= r << pos")
            self.src.add(ind, "pos += n")
        else:
            self._write_value(item.codec, element, ind, path)

    def _repeated(self, item: RepeatedItem, var: str, ind: int, path: str) -> str:
        """Writes the field; returns the expression of the values written (for the trace)."""
        if item.max_size() == 0:
            return _get(var, item.field.name)
        where = item.field.full_name
        vals, n = self.src.name("vals", path), self.src.name("n", path)
        self.src.add(ind, f"{vals} = {_get(var, item.field.name)}")
        self.src.add(ind, f"{n} = len({vals})")
        self.src.add(ind, f"if {n} > {item.max_repeat}:")
        self.src.add(ind + 1, f"if strict: raise _too_many({where!r}, {n}, {item.max_repeat})")
        self.src.add(ind + 1, f"{vals} = {vals}[:{item.max_repeat}]")
        self.src.add(ind + 1, f"{n} = {item.max_repeat}")
        if item.min_repeat:
            self.src.add(ind, f"if strict and {n} < {item.min_repeat}:")
            self.src.add(ind + 1, f"raise _too_few({where!r}, {n}, {item.min_repeat})")
        if item.prefix_bits:
            count = f"max({n}, {item.min_repeat})" if item.min_repeat else n
            self.src.add(ind, f"acc |= ({count} - {item.min_repeat}) << pos")
            self.src.add(ind, f"pos += {item.prefix_bits}")
        element = self.src.name("m" if item.codec is None else "v", path)
        target = item.max_repeat if item.slots else item.min_repeat
        if self.lua is not None:
            index = self.src.name("i", path)
            self.src.add(ind, f"for {index}, {element} in enumerate({vals}):")
            self._index(ind + 1, index)
            self._element(item, var, element, index, ind + 1, path, strict="strict")
            if target:
                # padding elements are coded one by one too (their index, their conditions)
                self.src.add(ind, f"for {index} in range({n}, {target}):")
                self._index(ind + 1, index)
                self._element(item, var, None, index, ind + 1, path, strict="strict")
            return vals
        self.src.add(ind, f"for {element} in {vals}:")
        if item.codec is not None:
            self._write_value(item.codec, element, ind + 1, path)
        else:
            self._node(item.child_node(), element, ind + 1, path + "[].")
        # missing elements: v2 slots up to max_repeat, v3/v4 padding up to min_repeat, each the
        # element codec's "no value" (all zeros but for a few legacy CCL codecs)
        null_raw, null_bits = _null_encoding(item)
        if target and null_bits:
            self.src.add(ind, f"if {n} < {target}:")
            if null_raw:
                self.src.add(ind + 1, f"for _ in range({target} - {n}):")
                self.src.add(ind + 2, f"acc |= {null_raw} << pos")
                self.src.add(ind + 2, f"pos += {null_bits}")
            else:
                self.src.add(ind + 1, f"pos += ({target} - {n}) * {null_bits}")
        return vals


class DecoderCompiler(_PartCompiler):
    bits_var = "b"

    def __init__(
        self, type_name: str, part: Part, trace: bool, lua: DynamicConditions | None
    ) -> None:
        super().__init__(type_name, "decode", part, trace, lua)

    def compile(self, node: MessageNode) -> GeneratedFunction:
        self.src.add(0, f"def {self.func_name}(m0, b, pos, end):")
        self._trace_id(1)
        self._node(node, "m0", 1, "", checked=False)
        self.src.add(1, "return pos")
        return self._build()

    def _check(self, nbits: str | int, where: str, ind: int) -> None:
        self.src.add(ind, f"if pos + {nbits} > end: raise _truncated({where!r})")

    def _node(self, node: MessageNode, var: str, ind: int, prefix: str, checked: bool) -> None:
        if self.lua is not None:
            checked = False  # conditions change widths and omit fields: check each read
        elif not checked and node.min_size() == node.max_size() and node.max_size():
            # fixed-size message: one bounds check covers every field in it
            self._check(node.max_size(), node.descriptor.full_name, ind)
            checked = True
        cases: dict[str, tuple[str, int]] = {}
        for oneof in node.oneofs:
            case = self.src.name("case", prefix + oneof.name)
            start = self._trace_start(prefix + oneof.name, ind)
            if oneof.bits:
                if not checked:
                    self._check(oneof.bits, f"{node.descriptor.full_name}.{oneof.name}", ind)
                self.src.add(ind, f"{case} = b >> pos & {(1 << oneof.bits) - 1}")
                self.src.add(ind, f"pos += {oneof.bits}")
            else:
                self.src.add(ind, f"{case} = 0")
            self._trace_end(start, f"{prefix}{oneof.name} (oneof case)", case, ind, None)
            for i, member in enumerate(oneof.members):
                cases[member] = (case, i + 1)
        for item in node.items:
            path = prefix + item.field.name
            field_ind = ind
            if isinstance(item, (ScalarItem, MessageItem)) and item.mode is Mode.ONEOF:
                case, i = cases[item.field.name]
                self.src.add(ind, f"if {case} == {i}:")
                field_ind += 1
            start = self._trace_start(path, field_ind)
            if isinstance(item, ListItem):
                dec = self.src.name(
                    "dec", path, item.codec.decode_list, _codec_about(item.codec, "decode_list")
                )
                self.src.add(field_ind, f"values, pos = {dec}(b, pos, end)")
                self.src.add(field_ind, f"{_get(var, item.field.name)}.extend(values)")
                value = _get(var, item.field.name)
            elif isinstance(item, RepeatedItem):
                self._repeated(item, var, field_ind, path, checked)
                value = _get(var, item.field.name)
            elif isinstance(item, ScalarItem):
                self._scalar(item, var, field_ind, path, checked)
                value = "v"
            else:
                self._message(item, var, field_ind, path, checked)
                name = item.field.name
                value = f"({_get(var, name)} if {var}.HasField({name!r}) else None)"
            self._trace_end(start, path, value, field_ind, item.field)

    def _read_value(
        self, codec, target: str, ind: int, checked: bool, where: str, path: str
    ) -> None:
        """Read one value into local `target` (None when not set)."""
        root = "m0, " if codec.reads_root else ""
        if isinstance(codec, FixedWidthCodec):
            dec = self.src.name("dec", path, codec.from_raw, _codec_about(codec, "from_raw"))
            if codec.bits:
                if not checked:
                    self._check(codec.bits, where, ind)
                self.src.add(ind, f"{target} = {dec}({root}b >> pos & {(1 << codec.bits) - 1})")
                self.src.add(ind, f"pos += {codec.bits}")
            else:
                self.src.add(ind, f"{target} = {dec}({root}0)")
        else:
            dec = self.src.name("dec", path, codec.decode, _codec_about(codec, "decode"))
            self.src.add(ind, f"{target}, pos = {dec}({root}b, pos, end)")

    def _scalar(self, item: ScalarItem, var: str, ind: int, path: str, checked: bool) -> None:
        if item.conditions is not None:
            cond = self._conditioned(item, path)
            self.src.add(ind, f"v, pos = {cond}.decode({var}, m0, b, pos, end)")
        else:
            self._read_value(item.codec, "v", ind, checked, item.field.full_name, path)
        self.src.add(ind, "if v is not None:")
        if item.field.cpp_type == item.field.CPPTYPE_MESSAGE:
            self.src.add(ind + 1, f"{_get(var, item.field.name)}.CopyFrom(v)")
        elif _is_string(item.field):
            field = self.src.name(
                "field", path, item.field, f"descriptor of {item.field.full_name}"
            )
            self.src.add(ind + 1, "try:")
            self.src.add(ind + 2, _set(var, item.field.name, "v"))
            self.src.add(ind + 1, "except UnicodeDecodeError:")
            self.src.add(ind + 2, f"_set_raw_string({var}, {field}, v)")
        else:
            self.src.add(ind + 1, _set(var, item.field.name, "v"))

    def _message(self, item: MessageItem, var: str, ind: int, path: str, checked: bool) -> None:
        name = item.field.name
        child_var = self.src.name("m", path)
        conditions = item.conditions
        if conditions is not None:
            dc, ind = self._omit_guard(item, path, var, ind)
            if conditions.required_if is not None and item.presence_bit:
                # as C++: the sub-message exists (empty) while it is asked and decoded
                self.src.add(ind, f"{child_var} = {_get(var, name)}")
                self.src.add(ind, f"{child_var}.SetInParent()")
                self.src.add(ind, f"if _dc.required({dc}, {child_var}, m0):")
                self._node(item.child, child_var, ind + 1, path + ".", False)
                self.src.add(ind, f"elif pos + 1 > end: raise _truncated({item.field.full_name!r})")
                self.src.add(ind, "else:")
                self.src.add(ind + 1, "pos += 1")
                self.src.add(ind + 1, "if b >> (pos - 1) & 1:")
                self._node(item.child, child_var, ind + 2, path + ".", False)
                self.src.add(ind + 1, f"else: {var}.ClearField({name!r})")
                return
        if item.presence_bit:
            if not checked:
                self._check(1, item.field.full_name, ind)
            self.src.add(ind, "pos += 1")
            self.src.add(ind, "if b >> (pos - 1) & 1:")
            ind += 1
        if item.presence_bit or item.mode is not Mode.OPTIONAL:
            self.src.add(ind, f"{child_var} = {_get(var, name)}")
            self.src.add(ind, f"{child_var}.SetInParent()")
            self._node(item.child, child_var, ind, path + ".", checked and not item.presence_bit)
        elif item.child.max_size():
            self.src.add(ind, f"{child_var} = {_get(var, name)}")
            self._node(item.child, child_var, ind, path + ".", checked)
        else:
            return
        if item.child.codec_version == 2:
            # the v2 message codec: a sub-message in which nothing is set is absent, whether
            # the field is optional (no presence bit in v2) or required
            self.src.add(ind, f"if not {child_var}.ListFields(): {var}.ClearField({name!r})")

    def _repeated(self, item: RepeatedItem, var: str, ind: int, path: str, checked: bool) -> None:
        if item.max_size() == 0:
            return
        where = item.field.full_name
        count = self.src.name("count", path)
        container = _get(var, item.field.name)
        if item.slots:
            self.src.add(ind, f"{count} = {item.max_repeat}")
        else:
            if not checked and item.prefix_bits:
                self._check(item.prefix_bits, where, ind)
            mask = (1 << item.prefix_bits) - 1
            self.src.add(ind, f"{count} = (b >> pos & {mask}) + {item.min_repeat}")
            self.src.add(ind, f"pos += {item.prefix_bits}")
            checked = False  # the count is data-dependent
            if item.codec is None and item.max_repeat - item.min_repeat + 1 < 1 << item.prefix_bits:
                self.src.add(ind, f"if {count} > {item.max_repeat}:")
                self.src.add(
                    ind + 1, f"raise _too_many_messages({where!r}, {count}, {item.max_repeat})"
                )
        conditions = item.conditions if self.lua is not None else None
        omits = conditions is not None and conditions.omit_if is not None
        dc = self._conditions(item, path) if omits else ""
        if item.codec is not None:
            values = self.src.name("values", path)
            index = self.src.name("i", path)
            self.src.add(ind, f"{values} = []")
            self.src.add(ind, f"for {index} in range({count}):")
            self._index(ind + 1, index)
            if omits:
                self.src.add(ind + 1, f"if _dc.omit({dc}, {var}, m0, {index}): continue")
            if conditions is not None and conditions.bounds:
                cond = self._conditioned(item, path, element=True)
                self.src.add(ind + 1, f"v, pos = {cond}.decode({var}, m0, b, pos, end)")
            else:
                self._read_value(item.codec, "v", ind + 1, checked, where, path)
            self.src.add(ind + 1, f"if v is not None: {values}.append(v)")
            if _is_string(item.field):
                field = self.src.name(
                    "field", path, item.field, f"descriptor of {item.field.full_name}"
                )
                before = self.src.name("before", path)
                self.src.add(ind, f"{before} = len({container})")
                self.src.add(ind, "try:")
                self.src.add(ind + 1, f"{container}.extend({values})")
                self.src.add(ind, "except UnicodeDecodeError:")
                self.src.add(ind + 1, f"_extend_raw_strings({var}, {field}, {values}, {before})")
            else:
                self.src.add(ind, f"{container}.extend({values})")
            return
        child_var = self.src.name("m", path)
        if item.slots:
            # v2: every slot decodes into an element; each empty slot then removes the LAST one
            empties, existing = self.src.name("empties", path), self.src.name("existing", path)
            slot = self.src.name("i", path)
            self.src.add(ind, f"{empties} = 0")
            self.src.add(ind, f"{existing} = len({container})")
            self.src.add(ind, f"for {slot} in range({count}):")
            self.src.add(
                ind + 1,
                f"{child_var} = {container}[{slot}] if {slot} < {existing} else {container}.add()",
            )
            self._index(ind + 1, slot)
            if omits:
                self.src.add(ind + 1, f"if _dc.omit({dc}, {child_var}, m0, {slot}): continue")
            self._node(item.child_node(), child_var, ind + 1, path + "[].", checked)
            self.src.add(ind + 1, f"if not {child_var}.ListFields(): {empties} += 1")
            self.src.add(ind, f"for _ in range({empties}): del {container}[-1]")
        elif self.lua is not None:
            # as C++: max_repeat sub-messages exist while the elements are decoded (`this`,
            # `root` in conditions see them); the unused ones are removed afterwards
            before, slot = self.src.name("before", path), self.src.name("i", path)
            self.src.add(ind, f"{before} = len({container})")
            self.src.add(ind, f"for _ in range({item.max_repeat}): {container}.add()")
            self.src.add(ind, f"for {slot} in range({count}):")
            self._index(ind + 1, slot)
            self.src.add(ind + 1, f"{child_var} = {container}[{before} + {slot}]")
            if omits:
                self.src.add(ind + 1, f"if _dc.omit({dc}, {child_var}, m0, {slot}): continue")
            self._node(item.child_node(), child_var, ind + 1, path + "[].", checked)
            self.src.add(ind, f"del {container}[{before} + {count}:]")
        else:
            self.src.add(ind, f"for _ in range({count}):")
            self.src.add(ind + 1, f"{child_var} = {container}.add()")
            self._node(item.child_node(), child_var, ind + 1, path + "[].", checked)


def compile_encoder(
    node: MessageNode,
    type_name: str,
    part: Part,
    start_acc: int,
    start_pos: int,
    trace: bool,
    lua: DynamicConditions | None = None,
) -> GeneratedFunction:
    """`encode_PART(m0, strict) -> (acc, pos)`, starting from `start_acc` (the id) at `start_pos`.
    `lua`: the Codec's Lua state when the type has dynamic conditions."""
    return EncoderCompiler(type_name, part, trace, lua).compile(node, start_acc, start_pos)


def compile_decoder(
    node: MessageNode, type_name: str, part: Part, trace: bool, lua: DynamicConditions | None = None
) -> GeneratedFunction:
    """`decode_PART(m0, b, pos, end) -> pos`."""
    return DecoderCompiler(type_name, part, trace, lua).compile(node)
