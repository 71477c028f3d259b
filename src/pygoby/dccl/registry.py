"""The codec registry: codec name + field type family -> codec factory."""

from __future__ import annotations

from collections.abc import Callable, Iterable
from dataclasses import dataclass
from typing import TypeVar

from pygoby.dccl.arithmetic import ArithmeticCodec
from pygoby.dccl.ccl.codecs import CCL_FIELD_CODECS
from pygoby.dccl.codecs.base import ALL_CATEGORIES, NUMERIC_CATEGORIES, FieldCodec, FieldInfo
from pygoby.dccl.codecs.boolean import BoolCodec
from pygoby.dccl.codecs.enum import EnumCodec, EnumCodecV2
from pygoby.dccl.codecs.hash import HashCodec
from pygoby.dccl.codecs.native_protobuf import NativeProtobufCodec
from pygoby.dccl.codecs.numeric import NumericCodec
from pygoby.dccl.codecs.presence import make_presence_codec
from pygoby.dccl.codecs.static import StaticCodec
from pygoby.dccl.codecs.strings import FixedBytesCodec, StringCodecV2, StringCodecV3, VarBytesCodec
from pygoby.dccl.codecs.time import TimeCodec
from pygoby.dccl.errors import DcclLoadError

CodecFactory = Callable[[FieldInfo], FieldCodec]
T = TypeVar("T")


@dataclass(frozen=True)
class DefaultMessageCodec:
    """Marker: message-typed fields handled by the built-in message codec of a version."""

    version: int


class CodecRegistry:
    """Maps (name, type family) to a codec factory. Users add their own with `register`.

    Each Codec has its own (a copy of `DEFAULT_REGISTRY` unless given one), so a codec registered
    for one application's messages cannot change how another Codec in the process encodes."""

    def __init__(self) -> None:
        self._entries: dict[tuple[str, str], CodecFactory | DefaultMessageCodec] = {}
        self._state: dict[type, object] = {}

    def register(
        self, name: str, categories: Iterable[str], factory: CodecFactory | DefaultMessageCodec
    ) -> None:
        """Register `factory` under `name` for the given type families (see `ALL_CATEGORIES`)."""
        for category in categories:
            if category not in ALL_CATEGORIES:
                raise ValueError(f"unknown field type family {category!r}")
            self._entries[(name, category)] = factory

    def copy(self) -> CodecRegistry:
        """The same codecs, with state of its own (e.g. no arithmetic models)."""
        other = CodecRegistry()
        other._entries = dict(self._entries)
        return other

    def shared_state(self, kind: type[T]) -> T:
        """The one `kind()` object that the codecs of this registry share (created on first
        use), e.g. the arithmetic models of a Codec (C++ DCCL's codec-specific data)."""
        state = self._state.get(kind)
        if state is None:
            state = self._state[kind] = kind()
        return state  # type: ignore[return-value]

    def resolve(
        self, name: str, version: int, category: str
    ) -> tuple[str, CodecFactory | DefaultMessageCodec]:
        """Find a codec by name: a name not ending in a digit tries name + version first."""
        candidates = [name] if name[-1:].isdigit() else [f"{name}{version}", name]
        for candidate in candidates:
            entry = self._entries.get((candidate, category))
            if entry is not None:
                return candidate, entry
        raise DcclLoadError(f"no codec named {name!r} for {category} fields")

    def create(self, name: str, info: FieldInfo) -> FieldCodec:
        _, factory = self.resolve(name, info.version, info.category)
        if isinstance(factory, DefaultMessageCodec):
            raise DcclLoadError(f"{info.name}: {name} is a message codec")
        return factory(info)


def _default_scalar_codecs(version: int) -> dict[str, CodecFactory]:
    codecs: dict[str, CodecFactory] = dict.fromkeys(NUMERIC_CATEGORIES, NumericCodec)
    codecs["bool"] = BoolCodec
    if version == 2:
        codecs.update(enum=EnumCodecV2, string=StringCodecV2, bytes=FixedBytesCodec)
    elif version == 3:
        codecs.update(enum=EnumCodec, string=StringCodecV3, bytes=FixedBytesCodec)
    else:
        codecs.update(enum=EnumCodec, string=VarBytesCodec, bytes=VarBytesCodec)
    return codecs


def _build_default_registry() -> CodecRegistry:
    registry = CodecRegistry()
    time_types = ("double", "int64", "uint64")
    static_types = ("string", "bytes", "int32", "int64", "uint32", "uint64", "float", "double")
    for version in (2, 3, 4):
        for category, factory in _default_scalar_codecs(version).items():
            registry.register(f"dccl.default{version}", [category], factory)
        registry.register(f"dccl.default{version}", ["message"], DefaultMessageCodec(version))
        registry.register(f"dccl.time{version}", time_types, TimeCodec)
        registry.register(f"dccl.static{version}", static_types, StaticCodec)
        registry.register(f"dccl.hash{version}", ["uint32"], HashCodec)
        if version >= 3:
            scalars = ALL_CATEGORIES - {"message"}
            registry.register(f"dccl.presence{version}", scalars, make_presence_codec)
            registry.register(f"dccl.presence{version}", ["message"], DefaultMessageCodec(version))
            registry.register(f"dccl.var_bytes{version}", ["string", "bytes"], VarBytesCodec)
    registry.register("_time", time_types, TimeCodec)
    registry.register("_static", static_types, StaticCodec)
    for name, (categories, factory) in CCL_FIELD_CODECS.items():
        registry.register(name, categories, factory)
    arithmetic_types = (*NUMERIC_CATEGORIES, "bool", "enum")
    registry.register("dccl.arithmetic", arithmetic_types, ArithmeticCodec)
    registry.register("_arithmetic", arithmetic_types, ArithmeticCodec)
    registry.register("dccl.native_protobuf", arithmetic_types, NativeProtobufCodec)
    registry.register("dccl.native_protobuf", ["message"], DefaultMessageCodec(4))
    return registry


DEFAULT_REGISTRY = _build_default_registry()


def register_codec(name: str, categories: Iterable[str], factory: CodecFactory) -> None:
    """Register a user codec in the defaults, which each Codec created afterwards copies into its
    own registry (a Codec that exists already is not changed: use `codec.registry.register` for
    one Codec). A field selects it with `(dccl.field).codec = "name"`."""
    DEFAULT_REGISTRY.register(name, categories, factory)
