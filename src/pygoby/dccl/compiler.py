"""Compile a message plan into Python encode/decode functions (no per-field dispatch at run time).

For each part of a root message type, straight-line Python source is generated and exec'd:

    encode_part(m0, strict) -> (acc, pos)      bits accumulated LSB-first into the integer `acc`
    decode_part(m0, b, pos, end) -> pos        fields read from the integer `b` into message m0

Codec calls are bound to names in the function's namespace; fixed-width codecs are inlined as
`acc |= to_raw(value) << pos`. Nested messages are expanded inline (the plan is finite).
"""

from __future__ import annotations

import keyword
from collections.abc import Callable
from typing import Any

from pygoby.dccl.codecs.base import FixedWidthCodec
from pygoby.dccl.errors import DcclDecodeError, DcclEncodeError
from pygoby.dccl.plan import MessageItem, MessageNode, Mode, Oneof, RepeatedItem, ScalarItem


def _truncated(where: str) -> DcclDecodeError:
    return DcclDecodeError(f"message is truncated: {where} needs bits past the end of the data")


def _too_many(where: str, n: int, limit: int) -> DcclEncodeError:
    return DcclEncodeError(f"{where}: {n} values exceed max_repeat {limit}")


def _too_few(where: str, n: int, limit: int) -> DcclEncodeError:
    return DcclEncodeError(f"{where}: {n} values are fewer than min_repeat {limit}")


class _Source:
    """Lines of generated code plus the namespace they refer to."""

    def __init__(self) -> None:
        self.lines: list[str] = []
        self.namespace: dict[str, Any] = {
            "_truncated": _truncated,
            "_too_many": _too_many,
            "_too_few": _too_few,
        }
        self._counter = 0

    def name(self, prefix: str, value: Any = None) -> str:
        self._counter += 1
        ident = f"{prefix}{self._counter}"
        if value is not None:
            self.namespace[ident] = value
        return ident

    def add(self, indent: int, line: str) -> None:
        self.lines.append("    " * indent + line)

    def build(self, func_name: str) -> Callable:
        code = "\n".join(self.lines)
        exec(compile(code, f"<dccl {func_name}>", "exec"), self.namespace)  # noqa: S102
        return self.namespace[func_name]


def _get(var: str, field_name: str) -> str:
    if field_name.isidentifier() and not keyword.iskeyword(field_name):
        return f"{var}.{field_name}"
    return f"getattr({var}, {field_name!r})"


def _set(var: str, field_name: str, value: str) -> str:
    if field_name.isidentifier() and not keyword.iskeyword(field_name):
        return f"{var}.{field_name} = {value}"
    return f"setattr({var}, {field_name!r}, {value})"


def _has(var: str, item) -> str:
    f = item.field
    if f.has_presence:
        return f"{var}.HasField({f.name!r})"
    return _get(var, f.name)  # proto3 implicit presence: set means "not the default"


class EncoderCompiler:
    def __init__(self) -> None:
        self.src = _Source()
        self.depth = 0

    def compile(self, node: MessageNode, func_name: str, start_acc: int, start_pos: int) -> Callable:
        self.src.add(0, f"def {func_name}(m0, strict):")
        self.src.add(1, f"acc = {start_acc}")
        self.src.add(1, f"pos = {start_pos}")
        self._node(node, "m0", 1)
        self.src.add(1, "return acc, pos")
        return self.src.build(func_name)

    def _node(self, node: MessageNode, var: str, ind: int) -> None:
        cases: dict[str, tuple[str, int]] = {}
        for oneof in node.oneofs:
            case = self.src.name("case")
            index = {member: i + 1 for i, member in enumerate(oneof.members)}
            table = self.src.name("oneof", index)
            self.src.add(ind, f"{case} = {table}.get({var}.WhichOneof({oneof.name!r}), 0)")
            if oneof.bits:
                self.src.add(ind, f"acc |= {case} << pos")
                self.src.add(ind, f"pos += {oneof.bits}")
            for member, i in index.items():
                cases[member] = (case, i)
        for item in node.items:
            if isinstance(item, RepeatedItem):
                self._repeated(item, var, ind)
                continue
            if item.mode is Mode.ONEOF:
                case, i = cases[item.field.name]
                self.src.add(ind, f"if {case} == {i}:")
                self._singular(item, var, ind + 1, present=True)
            else:
                self._singular(item, var, ind, present=item.mode is Mode.REQUIRED)

    def _write_value(self, codec, value: str, ind: int) -> None:
        if isinstance(codec, FixedWidthCodec):
            if codec.bits:
                enc = self.src.name("enc", codec.to_raw)
                self.src.add(ind, f"acc |= {enc}({value}, strict) << pos")
                self.src.add(ind, f"pos += {codec.bits}")
        else:
            enc = self.src.name("enc", codec.encode)
            self.src.add(ind, f"r, n = {enc}({value}, strict)")
            self.src.add(ind, "acc |= r << pos")
            self.src.add(ind, "pos += n")

    def _singular(self, item, var: str, ind: int, present: bool) -> None:
        value = _get(var, item.field.name)
        if isinstance(item, ScalarItem):
            codec = item.codec
            if present:
                self._write_value(codec, value, ind)
            elif isinstance(codec, FixedWidthCodec):
                if codec.bits:
                    enc = self.src.name("enc", codec.to_raw)
                    self.src.add(ind, f"if {_has(var, item)}:")
                    self.src.add(ind + 1, f"acc |= {enc}({value}, strict) << pos")
                    self.src.add(ind, f"pos += {codec.bits}")
            else:
                self._write_value(codec, f"({value} if {_has(var, item)} else None)", ind)
            return
        # built-in message codec
        child_var = self._child_var()
        if present:
            self.src.add(ind, f"{child_var} = {value}")
            self._node(item.child, child_var, ind)
        elif item.presence_bit:
            self.src.add(ind, f"if {var}.HasField({item.field.name!r}):")
            self.src.add(ind + 1, "acc |= 1 << pos")
            self.src.add(ind + 1, "pos += 1")
            self.src.add(ind + 1, f"{child_var} = {value}")
            self._node(item.child, child_var, ind + 1)
            self.src.add(ind, "else:")
            self.src.add(ind + 1, "pos += 1")
        elif item.child.max_size():
            # v2: an absent message is written as its minimum-size (all "not set") encoding
            self.src.add(ind, f"if {var}.HasField({item.field.name!r}):")
            self.src.add(ind + 1, f"{child_var} = {value}")
            self._node(item.child, child_var, ind + 1)
            self.src.add(ind, "else:")
            self.src.add(ind + 1, f"pos += {item.child.min_size()}")

    def _child_var(self) -> str:
        self.depth += 1
        return f"m{self.depth}"

    def _repeated(self, item: RepeatedItem, var: str, ind: int) -> None:
        if item.max_size() == 0:
            return
        where = item.field.full_name
        vals, n = self.src.name("vals"), self.src.name("n")
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
        element = self.src.name("v")
        self.src.add(ind, f"for {element} in {vals}:")
        if item.codec is not None:
            self._write_value(item.codec, element, ind + 1)
        else:
            self._node(item.child, element, ind + 1)
        # missing elements: v2 slots up to max_repeat, v3/v4 padding up to min_repeat, all zeros
        target = item.max_repeat if item.slots else item.min_repeat
        if target and item.element_min():
            self.src.add(ind, f"if {n} < {target}:")
            self.src.add(ind + 1, f"pos += ({target} - {n}) * {item.element_min()}")


class DecoderCompiler:
    def __init__(self) -> None:
        self.src = _Source()
        self.depth = 0

    def compile(self, node: MessageNode, func_name: str) -> Callable:
        self.src.add(0, f"def {func_name}(m0, b, pos, end):")
        self._node(node, "m0", 1, checked=False)
        self.src.add(1, "return pos")
        return self.src.build(func_name)

    def _check(self, nbits: str | int, where: str, ind: int) -> None:
        self.src.add(ind, f"if pos + {nbits} > end: raise _truncated({where!r})")

    def _node(self, node: MessageNode, var: str, ind: int, checked: bool) -> None:
        if not checked and node.min_size() == node.max_size() and node.max_size():
            # fixed-size message: one bounds check covers every field in it
            self._check(node.max_size(), node.descriptor.full_name, ind)
            checked = True
        cases: dict[str, tuple[str, int]] = {}
        for oneof in node.oneofs:
            case = self.src.name("case")
            if oneof.bits:
                if not checked:
                    self._check(oneof.bits, f"{node.descriptor.full_name}.{oneof.name}", ind)
                self.src.add(ind, f"{case} = b >> pos & {(1 << oneof.bits) - 1}")
                self.src.add(ind, f"pos += {oneof.bits}")
            else:
                self.src.add(ind, f"{case} = 0")
            for i, member in enumerate(oneof.members):
                cases[member] = (case, i + 1)
        for item in node.items:
            if isinstance(item, RepeatedItem):
                self._repeated(item, var, ind, checked)
            elif isinstance(item, ScalarItem):
                if item.mode is Mode.ONEOF:
                    case, i = cases[item.field.name]
                    self.src.add(ind, f"if {case} == {i}:")
                    self._scalar(item, var, ind + 1, checked)
                else:
                    self._scalar(item, var, ind, checked)
            else:
                self._message(item, var, ind, checked, cases)

    def _read_value(self, codec, target: str, ind: int, checked: bool, where: str) -> None:
        """Read one value into local `target` (None when not set)."""
        if isinstance(codec, FixedWidthCodec):
            dec = self.src.name("dec", codec.from_raw)
            if codec.bits:
                if not checked:
                    self._check(codec.bits, where, ind)
                self.src.add(ind, f"{target} = {dec}(b >> pos & {(1 << codec.bits) - 1})")
                self.src.add(ind, f"pos += {codec.bits}")
            else:
                self.src.add(ind, f"{target} = {dec}(0)")
        else:
            dec = self.src.name("dec", codec.decode)
            self.src.add(ind, f"{target}, pos = {dec}(b, pos, end)")

    def _scalar(self, item: ScalarItem, var: str, ind: int, checked: bool) -> None:
        self._read_value(item.codec, "v", ind, checked, item.field.full_name)
        self.src.add(ind, "if v is not None:")
        if item.field.cpp_type == item.field.CPPTYPE_MESSAGE:
            self.src.add(ind + 1, f"{_get(var, item.field.name)}.CopyFrom(v)")
        else:
            self.src.add(ind + 1, _set(var, item.field.name, "v"))

    def _message(self, item: MessageItem, var: str, ind: int, checked: bool, cases) -> None:
        name = item.field.name
        child_var = self._child_var()
        if item.mode is Mode.ONEOF:
            case, i = cases[name]
            self.src.add(ind, f"if {case} == {i}:")
            ind += 1
        if item.presence_bit:
            if not checked:
                self._check(1, item.field.full_name, ind)
            self.src.add(ind, "pos += 1")
            self.src.add(ind, "if b >> (pos - 1) & 1:")
            ind += 1
        if item.presence_bit or item.mode is not Mode.OPTIONAL:
            self.src.add(ind, f"{child_var} = {_get(var, name)}")
            self.src.add(ind, f"{child_var}.SetInParent()")
            self._node(item.child, child_var, ind, checked and not item.presence_bit)
        elif item.child.max_size():
            # v2: no presence bit; a sub-message in which nothing is set is absent
            self.src.add(ind, f"{child_var} = {_get(var, name)}")
            self._node(item.child, child_var, ind, checked)
            self.src.add(ind, f"if not {child_var}.ListFields(): {var}.ClearField({name!r})")

    def _child_var(self) -> str:
        self.depth += 1
        return f"m{self.depth}"

    def _repeated(self, item: RepeatedItem, var: str, ind: int, checked: bool) -> None:
        if item.max_size() == 0:
            return
        where = item.field.full_name
        count = self.src.name("count")
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
        if item.codec is not None:
            values = self.src.name("values")
            self.src.add(ind, f"{values} = []")
            self.src.add(ind, f"for _ in range({count}):")
            self._read_value(item.codec, "v", ind + 1, checked, where)
            self.src.add(ind + 1, f"if v is not None: {values}.append(v)")
            self.src.add(ind, f"{container}.extend({values})")
            return
        child_var = self._child_var()
        if item.slots:
            # v2: every slot decodes into an element; each empty slot then removes the LAST one
            empties, existing = self.src.name("empties"), self.src.name("existing")
            self.src.add(ind, f"{empties} = 0")
            self.src.add(ind, f"{existing} = len({container})")
            self.src.add(ind, f"for i in range({count}):")
            self.src.add(
                ind + 1, f"{child_var} = {container}[i] if i < {existing} else {container}.add()"
            )
            self._node(item.child, child_var, ind + 1, checked)
            self.src.add(ind + 1, f"if not {child_var}.ListFields(): {empties} += 1")
            self.src.add(ind, f"for _ in range({empties}): del {container}[-1]")
        else:
            self.src.add(ind, f"for _ in range({count}):")
            self.src.add(ind + 1, f"{child_var} = {container}.add()")
            self._node(item.child, child_var, ind + 1, checked)


def compile_encoder(node: MessageNode, func_name: str, start_acc: int, start_pos: int) -> Callable:
    return EncoderCompiler().compile(node, func_name, start_acc, start_pos)


def compile_decoder(node: MessageNode, func_name: str) -> Callable:
    return DecoderCompiler().compile(node, func_name)


__all__ = ["compile_decoder", "compile_encoder", "Oneof"]
