"""The message plan: which fields go where, with which codec.

A root message is planned twice, once for the HEAD part and once for the BODY part. A plan is a
tree of items in wire order; sizes, header validation, `analyze` and the code generator
(`compiler.py`) all read it.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from dataclasses import dataclass, field
from enum import Enum

from google.protobuf.descriptor import FieldDescriptor

from pygoby.dccl.codecs.base import FieldCodec, FieldInfo, RepeatedFieldCodec, field_category
from pygoby.dccl.conditions import DynamicConditions, FieldConditions
from pygoby.dccl.errors import DcclLoadError
from pygoby.dccl.options import field_options, message_options
from pygoby.dccl.registry import CodecRegistry, DefaultMessageCodec
from pygoby.protobuf import message_type
from pygoby.protobuf.dccl.option_extensions_pb2 import DCCLFieldOptions
from pygoby.protobuf.descriptors import AnyDescriptor, AnyFieldDescriptor

log = logging.getLogger("pygoby.dccl")


class Part(Enum):
    HEAD = "head"
    BODY = "body"


class Mode(Enum):
    REQUIRED = "required"  # no "not set" state
    OPTIONAL = "optional"  # a "not set" state (zero raw value or presence bit)
    ONEOF = "oneof"  # required encoding, written only when it is the oneof's set member


@dataclass
class Oneof:
    name: str
    members: list[str]

    @property
    def bits(self) -> int:
        return (len(self.members)).bit_length()  # ceil_log2(len + 1)


@dataclass
class ScalarItem:
    """A singular field written by a field codec (any type, incl. messages with a user codec)."""

    field: AnyFieldDescriptor
    codec: FieldCodec
    mode: Mode
    oneof: Oneof | None = None
    conditions: FieldConditions | None = None
    # the required-encoding twin of `codec`, when `required_if` decides at run time
    required_codec: FieldCodec | None = None

    def min_size(self) -> int:
        return self.codec.min_size()

    def max_size(self) -> int:
        return self.codec.max_size()


@dataclass
class MessageItem:
    """A singular embedded message handled by a built-in message codec."""

    field: AnyFieldDescriptor
    child: MessageNode
    mode: Mode
    presence_bit: bool
    oneof: Oneof | None = None
    conditions: FieldConditions | None = None

    def min_size(self) -> int:
        return 1 if self.presence_bit else self.child.min_size()

    def max_size(self) -> int:
        return self.presence_bit + self.child.max_size()


@dataclass
class RepeatedItem:
    """A repeated field: count prefix + elements (V >= 3) or max_repeat slots (V = 2)."""

    field: AnyFieldDescriptor
    max_repeat: int
    min_repeat: int
    slots: bool  # v2: always max_repeat optional-encoded slots, no prefix
    codec: FieldCodec | None = None  # element codec (None for built-in message elements)
    child: MessageNode | None = None
    conditions: FieldConditions | None = None  # omit_if per element; min/max per element

    @property
    def prefix_bits(self) -> int:
        return 0 if self.slots else (self.max_repeat - self.min_repeat).bit_length()

    def element_min(self) -> int:
        return self.codec.min_size() if self.codec else self.child_node().min_size()

    def element_max(self) -> int:
        return self.codec.max_size() if self.codec else self.child_node().max_size()

    def child_node(self) -> MessageNode:
        assert self.child is not None  # (a repeated message field: no codec, a child)
        return self.child

    def min_size(self) -> int:
        count = self.max_repeat if self.slots else self.min_repeat
        return self.prefix_bits + count * self.element_min()

    def max_size(self) -> int:
        return self.prefix_bits + self.max_repeat * self.element_max()


@dataclass
class ListItem:
    """A repeated field coded as a whole by a `RepeatedFieldCodec` (e.g. dccl.arithmetic)."""

    field: AnyFieldDescriptor
    codec: RepeatedFieldCodec

    def min_size(self) -> int:
        return self.codec.min_size()

    def max_size(self) -> int:
        return self.codec.max_size()


Item = ScalarItem | MessageItem | RepeatedItem | ListItem


@dataclass
class MessageNode:
    descriptor: AnyDescriptor
    codec_version: int  # version of the message codec handling this message
    items: list[Item] = field(default_factory=list)
    oneofs: list[Oneof] = field(default_factory=list)  # case fields written first (v4 BODY)
    resets: frozenset[str] = frozenset()  # see cpp_min_size

    def min_size(self) -> int:
        fixed = sum(i.min_size() for i in self.items if getattr(i, "oneof", None) is None)
        return fixed + sum(o.bits for o in self.oneofs)

    def max_size(self) -> int:
        fixed = sum(i.max_size() for i in self.items if getattr(i, "oneof", None) is None)
        for oneof in self.oneofs:
            members = [i.max_size() for i in self.items if getattr(i, "oneof", None) is oneof]
            fixed += oneof.bits + max(members, default=0)
        return fixed

    def cpp_min_size(self) -> int:
        """The minimum size as C++ DCCL's v3/v4 message codecs compute it, which is what they
        write for a message without value (a padding element, an absent message made
        required by `required_if`): its running total restarts at 0 at each field with an
        omit_if, only_if or required_if condition. Equal to `min_size()` without conditions."""
        if not self.resets:
            return self.min_size()
        total = sum(o.bits for o in self.oneofs)
        for item in self.items:
            if item.field.name in self.resets:
                total = 0
            elif getattr(item, "oneof", None) is None:
                total += item.min_size()
        return total


@dataclass
class RootOptions:
    name: str
    version: int
    codec_group: str | None
    id: int | None  # None when omit_id
    max_bytes: int


def root_options(descriptor: AnyDescriptor) -> RootOptions:
    opts = message_options(descriptor)
    name = descriptor.full_name
    if not opts.HasField("codec_version"):
        raise DcclLoadError(f"{name}: missing (dccl.msg).codec_version")
    if opts.codec_version not in (2, 3, 4):
        raise DcclLoadError(f"{name}: codec_version must be 2, 3 or 4 (is {opts.codec_version})")
    if not opts.HasField("max_bytes"):
        raise DcclLoadError(f"{name}: missing (dccl.msg).max_bytes")
    dccl_id: int | None = None
    if not opts.omit_id:
        if not opts.HasField("id"):
            raise DcclLoadError(f"{name}: missing (dccl.msg).id (or set omit_id: true)")
        # the range an id may take depends on the identifier codec (pygoby.dccl.identifier)
        dccl_id = opts.id
    group = opts.codec_group if opts.HasField("codec_group") else None
    return RootOptions(name, opts.codec_version, group, dccl_id, opts.max_bytes)


class Planner:
    """Builds the plan of one root message type for one part."""

    def __init__(
        self,
        root: RootOptions,
        registry: CodecRegistry,
        now: Callable[[], float],
        lua: Callable[[], DynamicConditions] | None = None,
    ) -> None:
        self.root = root
        self.registry = registry
        self.now = now
        self.default_name = root.codec_group or f"dccl.default{root.version}"
        self.lua = lua  # the Codec's Lua state (made on first use) for dynamic conditions
        self.conditioned = False  # some field has dynamic conditions

    def plan_root(self, descriptor: AnyDescriptor, part: Part) -> MessageNode:
        opts = message_options(descriptor)
        name = opts.codec if opts.HasField("codec") else self.default_name
        _, entry = self.registry.resolve(name, self.root.version, "message")
        if not isinstance(entry, DefaultMessageCodec):
            raise DcclLoadError(f"{descriptor.full_name}: the root needs a built-in message codec")
        node = self._plan_message(descriptor, part, None, entry.version, ())
        if part is Part.HEAD:
            self._check_fixed(node)
        return node

    def _codec_name(self, f: AnyFieldDescriptor, fopts: DCCLFieldOptions) -> str:
        if fopts.HasField("codec"):
            return fopts.codec
        if f.cpp_type == FieldDescriptor.CPPTYPE_MESSAGE:
            sub = message_options(message_type(f))
            if sub.HasField("codec"):
                return sub.codec
        return self.default_name

    def _included(
        self,
        f: AnyFieldDescriptor,
        fopts: DCCLFieldOptions,
        part: Part,
        forced: Part | None,
        version: int,
        v2_message: bool,
    ):
        if forced is not None:
            return forced is part
        if version == 2 and v2_message:
            return True  # v2 default sub-messages are entered in both passes
        return fopts.in_head == (part is Part.HEAD)

    def _plan_message(
        self,
        descriptor: AnyDescriptor,
        part: Part,
        forced: Part | None,
        version: int,
        stack: tuple[str, ...],
    ) -> MessageNode:
        if descriptor.full_name in stack:
            raise DcclLoadError(
                f"{descriptor.full_name}: recursive message types cannot be encoded"
            )
        stack = (*stack, descriptor.full_name)
        node = MessageNode(descriptor, version)
        oneofs = {}
        for decl in descriptor.oneofs:
            if len(decl.fields) == 1 and decl.name == "_" + decl.fields[0].name:
                continue  # proto3 `optional` (a synthetic oneof), not a real oneof
            if version != 4:
                raise DcclLoadError(
                    f"{descriptor.full_name}: oneof {decl.name} needs the codec version 4 message codec"
                )
            if forced is Part.HEAD:
                raise DcclLoadError(
                    f"{descriptor.full_name}: oneof {decl.name} inside a message placed in the header"
                )
            oneofs[decl.name] = Oneof(decl.name, [f.name for f in decl.fields])
        if part is Part.BODY:
            node.oneofs = list(oneofs.values())
        if version >= 3:
            node.resets = frozenset(
                f.name
                for f in descriptor.fields
                if (c := FieldConditions.of(f, field_options(f))) is not None
                and (c.omit_if is not None or c.required_if is not None)
            )
        for f in descriptor.fields:
            item = self._plan_field(f, part, forced, version, stack, oneofs)
            if item is not None:
                node.items.append(item)
        return node

    def _plan_field(
        self, f: AnyFieldDescriptor, part, forced, version, stack, oneofs
    ) -> Item | None:
        fopts = field_options(f)
        where = f.full_name
        oneof = None
        if f.containing_oneof is not None and f.containing_oneof.name in oneofs:
            oneof = oneofs[f.containing_oneof.name]
            if fopts.in_head:
                raise DcclLoadError(f"{where}: a oneof member cannot be in_head")
        if fopts.omit:
            return None
        conditions = FieldConditions.of(f, fopts)
        if conditions is not None:
            if self.lua is None:
                raise DcclLoadError(f"{where}: dynamic_conditions need a Codec's Lua state")
            self.lua().compile(conditions)
            self.conditioned = True
        category = field_category(f)
        name = self._codec_name(f, fopts)
        resolved, entry = self.registry.resolve(name, self.root.version, category)
        v2_message = isinstance(entry, DefaultMessageCodec) and entry.version == 2
        if not self._included(f, fopts, part, forced, version, v2_message):
            if (
                part is Part.BODY
                and forced is None
                and version >= 3
                and fopts.in_head
                and stack[1:]
            ):
                log.warning(
                    "%s is in_head inside a sub-message that is not in the header: it is never"
                    " sent (as in DCCL); mark the message field in_head to send it",
                    where,
                )
            return None
        repeated = f.is_repeated
        # conditions that apply: omit_if on a singular field only in the v3/v4 message codecs
        # (C++'s v2 codec does not look), required_if only for codec versions 3 and 4
        singular = (
            None if conditions is None else conditions.for_singular(version, self.root.version)
        )
        if isinstance(entry, DefaultMessageCodec):
            child_forced = forced
            if fopts.HasField("in_head"):
                child_forced = Part.HEAD if fopts.in_head else Part.BODY
            child = self._plan_message(message_type(f), part, child_forced, entry.version, stack)
            if repeated:
                return self._repeated(f, fopts, child=child, conditions=conditions)
            mode = self._mode(f, oneof)
            presence = entry.version >= 3 and mode is Mode.OPTIONAL
            return MessageItem(
                f,
                child,
                mode,
                presence,
                oneof,
                singular
                if mode is Mode.OPTIONAL or singular is None
                else singular.without_required(),
            )
        if repeated:
            info = self._info(f, fopts, category, resolved, required=self.root.version >= 3)
            codec = entry(info)
            if isinstance(codec, RepeatedFieldCodec):
                return ListItem(f, codec)
            return self._repeated(f, fopts, codec=codec, conditions=conditions)
        mode = self._mode(f, oneof)
        info = self._info(f, fopts, category, resolved, required=mode is not Mode.OPTIONAL)
        item = ScalarItem(f, entry(info), mode, oneof)
        if singular is not None:
            if mode is not Mode.OPTIONAL:
                singular = singular.without_required()
            item.conditions = singular
            if singular.required_if is not None:  # type: ignore[union-attr]  # (set just above)
                required = self._info(f, fopts, category, resolved, required=True)
                item.required_codec = entry(required)
        return item

    def _mode(self, f: AnyFieldDescriptor, oneof: Oneof | None) -> Mode:
        if oneof is not None:
            return Mode.ONEOF
        if f.is_required:
            return Mode.REQUIRED
        return Mode.OPTIONAL

    def _info(
        self,
        f: AnyFieldDescriptor,
        fopts: DCCLFieldOptions,
        category: str,
        codec_name: str,
        required: bool,
    ) -> FieldInfo:
        return FieldInfo(
            descriptor=f,
            options=fopts,
            category=category,
            required=required,
            version=self.root.version,
            codec_name=codec_name,
            now=self.now,
            registry=self.registry,
        )

    def _repeated(
        self,
        f: AnyFieldDescriptor,
        fopts: DCCLFieldOptions,
        codec=None,
        child=None,
        conditions=None,
    ) -> RepeatedItem:
        if not fopts.HasField("max_repeat"):
            raise DcclLoadError(f"{f.full_name}: repeated field needs (dccl.field).max_repeat")
        if fopts.max_repeat < 1:
            raise DcclLoadError(f"{f.full_name}: max_repeat must be at least 1")
        if fopts.max_repeat < fopts.min_repeat:
            raise DcclLoadError(f"{f.full_name}: max_repeat is less than min_repeat")
        return RepeatedItem(
            f,
            max_repeat=fopts.max_repeat,
            min_repeat=fopts.min_repeat,
            slots=self.root.version == 2,
            codec=codec,
            child=child,
            conditions=conditions,
        )

    def _check_fixed(self, node: MessageNode) -> None:
        """Header fields must have a fixed size (the decoder derives the header length)."""
        for item in node.items:
            if isinstance(item, MessageItem) and not item.presence_bit:
                self._check_fixed(item.child)
            elif item.min_size() != item.max_size():
                raise DcclLoadError(
                    f"{item.field.full_name}: a header field must have a fixed size"
                    f" ({item.min_size()}..{item.max_size()} bits)"
                )
