"""The DCCL codec: load message types, encode, decode, sizes."""

from __future__ import annotations

import logging
import os
import time
from collections.abc import Callable, Iterable, Iterator
from typing import cast

from google.protobuf import message_factory
from google.protobuf.descriptor import Descriptor
from google.protobuf.message import Message

from pygoby.dccl import arithmetic
from pygoby.dccl.analyze import describe
from pygoby.dccl.compiled import CompiledType
from pygoby.dccl.compiler import compile_decoder, compile_encoder
from pygoby.dccl.conditions import DynamicConditions
from pygoby.dccl.crypto import BodyCipher
from pygoby.dccl.errors import DcclDecodeError, DcclEncodeError, DcclError, DcclLoadError
from pygoby.dccl.hashing import definition_hash, hash_codecs
from pygoby.dccl.identifier import DefaultIdCodec, is_ccl_id
from pygoby.dccl.identifier import id_codec as lookup_id_codec
from pygoby.dccl.options import message_options
from pygoby.dccl.plan import Part, Planner, root_options
from pygoby.dccl.registry import DEFAULT_REGISTRY, CodecRegistry
from pygoby.protobuf import ProtoError, ProtoLoader, initialization_errors
from pygoby.protobuf.dccl.arithmetic.protobuf.arithmetic_pb2 import ArithmeticModel
from pygoby.protobuf.descriptors import AnyDescriptor
from pygoby.util.clock import Clock
from pygoby.util.names import did_you_mean

# Exceptions that bad values or bad bytes can provoke inside generated code or codecs.
_VALUE_ERRORS = (ValueError, TypeError, OverflowError, KeyError, IndexError, UnicodeError)


log = logging.getLogger("pygoby.dccl")


class Codec:
    """Encodes and decodes DCCL messages, byte-compatible with the C++ DCCL library.

    `strict`: out-of-range values, over-long strings and bad repeat counts raise instead of being
    degraded. `passphrase`: AES-256-CTR body encryption. `clock`: the receiver's clock for
    `dccl.time` fields (defaults to the system clock). `registry`: the field codecs this Codec
    can use; by default its own copy of the defaults (`register_codec` adds to the defaults that
    Codecs made later copy; `codec.registry.register` adds to this Codec only). `trace`: log each
    field's value and bits to the `pygoby.dccl.trace` logger at DEBUG while encoding and decoding
    (types are compiled with trace hooks; without `trace` the generated code has none).
    `id_codec`: "dccl.default.id", or "dccl.ccl.id" to mix legacy CCL frames with DCCL messages
    (chosen automatically when a CCL type is loaded, see `set_id_codec`).
    """

    def __init__(
        self,
        passphrase: str | bytes | None = None,
        strict: bool = False,
        clock: Clock | None = None,
        registry: CodecRegistry | None = None,
        do_not_encrypt_ids: Iterable[int] = (),
        loader: ProtoLoader | None = None,
        trace: bool = False,
        id_codec: str = DefaultIdCodec.name,
    ) -> None:
        self.strict = strict
        self.trace = trace
        self.registry = registry if registry is not None else DEFAULT_REGISTRY.copy()
        self.loader = loader if loader is not None else ProtoLoader()
        self._now: Callable[[], float] = clock.now if clock is not None else time.time
        self._by_name: dict[str, CompiledType] = {}
        self._by_id: dict[int, CompiledType] = {}
        self._id_codec = lookup_id_codec(id_codec)
        self._conditions: DynamicConditions | None = None
        self.set_passphrase(passphrase, do_not_encrypt_ids)

    def set_passphrase(
        self, passphrase: str | bytes | None, do_not_encrypt_ids: Iterable[int] = ()
    ) -> None:
        self._cipher = BodyCipher(passphrase) if passphrase else None
        self._clear_ids = frozenset(do_not_encrypt_ids)

    def _lua(self) -> DynamicConditions:
        """This Codec's Lua state for dynamic conditions (made when a type first needs it)."""
        if self._conditions is None:
            self._conditions = DynamicConditions()
        return self._conditions

    def set_arithmetic_model(self, model: ArithmeticModel | str | os.PathLike[str]) -> None:
        """Give this Codec a `dccl.arith.protobuf.ArithmeticModel` (a message, or a TextFormat
        file) for `dccl.arithmetic` fields; set models before loading the types that use them.
        A model of the same name is replaced (adaptive ones start afresh)."""
        arithmetic.set_model(self, model)

    @property
    def id_codec(self) -> str:
        """The identifier codec's name: "dccl.default.id" or "dccl.ccl.id"."""
        return self._id_codec.name

    def set_id_codec(self, name: str) -> None:
        """Use another identifier codec; the types already loaded are compiled again for it
        (C++ DCCL unloads them instead)."""
        new = lookup_id_codec(name)
        if new is self._id_codec:
            return
        old, self._id_codec = self._id_codec, new
        loaded = [c.cls for c in self._by_name.values()]
        self._by_name.clear()
        self._by_id.clear()
        try:
            for cls in loaded:
                self.load(cls)
        except DcclError:
            self._id_codec = old
            self._by_name.clear()
            self._by_id.clear()
            for cls in loaded:
                self.load(cls)
            raise

    # ---------------------------------------------------------------- loading
    def load(self, message_type: type[Message] | AnyDescriptor) -> type[Message]:
        """Validate and compile a message type (a generated class or a descriptor)."""
        descriptor = _descriptor_of(message_type)
        if isinstance(message_type, Descriptor):
            cls = message_factory.GetMessageClass(message_type)
        else:
            cls = cast(type[Message], message_type)
        known = self._by_name.get(descriptor.full_name)
        if known is not None:
            return known.cls
        root = root_options(descriptor)
        if is_ccl_id(root.id) and self._id_codec.name != "dccl.ccl.id":
            log.info(
                "%s is a legacy CCL type: this Codec now uses the CCL identifier codec"
                " (other DCCL messages start with the byte 0x20)",
                root.name,
            )
            self.set_id_codec("dccl.ccl.id")
        compiled = self._compile(cls, descriptor)
        if compiled.id is not None:
            other = self._by_id.get(compiled.id)
            if other is not None:
                raise DcclLoadError(
                    f"{compiled.name}: id {compiled.id} is already used by {other.name}"
                )
            self._by_id[compiled.id] = compiled
        self._by_name[compiled.name] = compiled
        return cls

    def load_proto(
        self,
        path: str | os.PathLike[str],
        full_name: str,
        include_dirs: Iterable[str | os.PathLike[str]] = (),
    ) -> type[Message]:
        """Compile a .proto file at run time and load one of its message types (an unknown
        name: DcclLoadError suggesting the file's close names)."""
        try:
            file = self.loader.load_file(path, include_dirs)
        except ProtoError as exc:
            raise DcclLoadError(str(exc)) from exc
        try:
            cls = self.loader.message_class(full_name)
        except ProtoError as exc:
            defined = [d.full_name for d in _messages_of(file.message_types_by_name.values())]
            raise DcclLoadError(f"{exc}{did_you_mean(full_name, defined)}") from exc
        return self.load(cls)

    def load_proto_file(
        self, path: str | os.PathLike[str], include_dirs: Iterable[str | os.PathLike[str]] = ()
    ) -> list[type[Message]]:
        """Compile a .proto file and load each of its top-level DCCL messages (those with
        (dccl.msg) options; the others are their parts); DcclLoadError if there is none."""
        try:
            file = self.loader.load_file(path, include_dirs)
        except ProtoError as exc:
            raise DcclLoadError(str(exc)) from exc
        dccl = [d for d in file.message_types_by_name.values() if message_options(d).ListFields()]
        if not dccl:
            raise DcclLoadError(f"{path}: no message has (dccl.msg) options")
        return [self.load(self.loader.message_class(d.full_name)) for d in dccl]

    def unload(self, message_type: type[Message] | AnyDescriptor) -> None:
        descriptor = _descriptor_of(message_type)
        compiled = self._by_name.pop(descriptor.full_name, None)
        if compiled is not None and compiled.id is not None:
            self._by_id.pop(compiled.id, None)

    def loaded(self) -> list[type[Message]]:
        return [c.cls for c in self._by_name.values()]

    def _compile(self, cls: type[Message], descriptor: AnyDescriptor) -> CompiledType:
        root = root_options(descriptor)
        planner = Planner(root, self.registry, self._now, self._lua)
        head = planner.plan_root(descriptor, Part.HEAD)
        body = planner.plan_root(descriptor, Part.BODY)
        hash_fields = [*hash_codecs(head), *hash_codecs(body)]
        if hash_fields:
            full_hash = definition_hash(descriptor, head, body)
            for codec in hash_fields:
                codec.set_hash(full_hash)
        id_raw, id_bits = (0, 0) if root.id is None else self._id_codec.encode(root.id, root.name)
        head_bytes = (id_bits + head.max_size() + 7) // 8
        max_encoded = head_bytes + (body.max_size() + 7) // 8
        if max_encoded > root.max_bytes:
            raise DcclLoadError(
                f"{root.name}: the largest encoding is {max_encoded} bytes, more than"
                f" max_bytes {root.max_bytes}"
            )
        lua = self._lua() if planner.conditioned else None
        generated = {
            "encode_head": compile_encoder(
                head, root.name, Part.HEAD, id_raw, id_bits, self.trace, lua
            ),
            "encode_body": compile_encoder(body, root.name, Part.BODY, 0, 0, self.trace, lua),
            "decode_head": compile_decoder(head, root.name, Part.HEAD, self.trace, lua),
            "decode_body": compile_decoder(body, root.name, Part.BODY, self.trace, lua),
        }
        return CompiledType(
            cls=cls,
            name=root.name,
            version=root.version,
            id=root.id,
            id_bits=id_bits,
            max_bytes=root.max_bytes,
            head=head,
            body=body,
            head_bytes=head_bytes,
            encode_head=generated["encode_head"].function,
            encode_body=generated["encode_body"].function,
            decode_head=generated["decode_head"].function,
            decode_body=generated["decode_body"].function,
            source={name: g.source for name, g in generated.items()},
        )

    def compiled(self, message_type: type[Message] | AnyDescriptor | str) -> CompiledType:
        """The compiled form of a loaded type (loading it first if it is a class/descriptor)."""
        if isinstance(message_type, str):
            try:
                return self._by_name[message_type]
            except KeyError:
                raise DcclError(f"message type {message_type!r} is not loaded") from None
        descriptor = _descriptor_of(message_type)
        compiled = self._by_name.get(descriptor.full_name)
        if compiled is None:
            self.load(message_type)
            compiled = self._by_name[descriptor.full_name]
        return compiled

    # ---------------------------------------------------------------- encoding
    def encode(self, msg: Message) -> bytes:
        """Encode a message (its type is loaded on first use)."""
        compiled = self._by_name.get(msg.DESCRIPTOR.full_name) or self.compiled(type(msg))
        if not msg.IsInitialized():
            missing = ", ".join(initialization_errors(msg))
            raise DcclEncodeError(f"{compiled.name}: required fields are not set: {missing}")
        strict = self.strict
        try:
            hacc, hpos = compiled.encode_head(msg, strict)
            bacc, bpos = compiled.encode_body(msg, strict)
        except DcclError:
            raise
        except _VALUE_ERRORS as exc:
            raise DcclEncodeError(f"{compiled.name}: cannot encode: {exc}") from exc
        head = hacc.to_bytes((hpos + 7) >> 3, "little")
        body = bacc.to_bytes((bpos + 7) >> 3, "little")
        if self._cipher is not None and compiled.id not in self._clear_ids:
            body = self._cipher.apply(head, body)
        return head + body

    def size(self, msg: Message) -> int:
        """Length in bytes of `encode(msg)`."""
        return len(self.encode(msg))

    def analyze(self, message_type: type[Message] | AnyDescriptor | str) -> str:
        """A table of the type's fields: codec, part (head/body), bit sizes, and totals."""
        return describe(self.compiled(message_type))

    def definition_hash(self, message_type: type[Message] | AnyDescriptor | str) -> int:
        """The 64-bit hash of a type's DCCL definition that C++ DCCL's `load()` returns (and
        `dccl.hash` fields send masked); see pygoby.dccl.hashing."""
        compiled = self.compiled(message_type)
        return definition_hash(compiled.cls.DESCRIPTOR, compiled.head, compiled.body)

    def max_size(self, message_type: type[Message] | AnyDescriptor | str) -> int:
        return self.compiled(message_type).max_size()

    def min_size(self, message_type: type[Message] | AnyDescriptor | str) -> int:
        return self.compiled(message_type).min_size()

    # ---------------------------------------------------------------- decoding
    def read_id(self, data: bytes) -> tuple[int, int]:
        """(DCCL ID, ID width in bits) from the first bytes, by this Codec's
        identifier codec."""
        return self._id_codec.decode(data)

    def id(self, data: bytes) -> int:
        """The DCCL ID of encoded bytes (without decoding them)."""
        return self._id_codec.decode(data)[0]

    def type_of(self, data: bytes) -> type[Message]:
        return self._compiled_for(data, None).cls

    def _compiled_for(
        self, data: bytes, message_type: type[Message] | AnyDescriptor | str | None
    ) -> CompiledType:
        if message_type is not None:
            compiled = self.compiled(message_type)
            if compiled.id is not None:
                dccl_id, _ = self.read_id(data)
                if dccl_id != compiled.id:
                    raise DcclDecodeError(
                        f"bytes carry id {dccl_id}, not the id {compiled.id} of {compiled.name}"
                    )
            return compiled
        dccl_id, _ = self.read_id(data)
        found = self._by_id.get(dccl_id)
        if found is None:
            raise DcclDecodeError(f"no message type with id {dccl_id} is loaded")
        return found

    def decode(
        self, data: bytes, message_type: type[Message] | AnyDescriptor | str | None = None
    ) -> Message:
        """Decode bytes; the type comes from the ID unless given (it must be for omit_id types)."""
        return self.decode_prefix(data, message_type)[0]

    def decode_prefix(
        self, data: bytes, message_type: type[Message] | AnyDescriptor | str | None = None
    ) -> tuple[Message, int]:
        """Decode one message from the start of `data`: (message, bytes it used).

        With encryption the whole rest of `data` is the body (encrypted messages cannot be
        concatenated)."""
        data = bytes(data)
        compiled = self._compiled_for(data, message_type)
        head_bytes = compiled.head_bytes
        if len(data) < head_bytes:
            raise DcclDecodeError(
                f"{compiled.name}: {len(data)} bytes are shorter than its {head_bytes}-byte header"
            )
        msg = compiled.cls()
        head = data[:head_bytes]
        body = data[head_bytes:]
        if self._cipher is not None and compiled.id not in self._clear_ids:
            body = self._cipher.apply(head, body)
        try:
            compiled.decode_head(
                msg, int.from_bytes(head, "little"), compiled.id_bits, head_bytes * 8
            )
            used = compiled.decode_body(msg, int.from_bytes(body, "little"), 0, len(body) * 8)
        except DcclError as exc:
            raise DcclDecodeError(f"{compiled.name}: {exc}") from exc
        except _VALUE_ERRORS as exc:
            raise DcclDecodeError(f"{compiled.name}: cannot decode: {exc}") from exc
        return msg, head_bytes + (used + 7) // 8


def _messages_of(descriptors: Iterable[AnyDescriptor]) -> Iterator[AnyDescriptor]:
    """`descriptors` and every message type nested in them."""
    for descriptor in descriptors:
        yield descriptor
        yield from _messages_of(descriptor.nested_types)


def _descriptor_of(message_type: type[Message] | AnyDescriptor) -> AnyDescriptor:
    """The descriptor of a generated class, or the descriptor itself."""
    return cast(AnyDescriptor, getattr(message_type, "DESCRIPTOR", message_type))
