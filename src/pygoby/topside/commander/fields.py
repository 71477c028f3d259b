"""What an operator may type into one field of a command: the field's DCCL limits, read from the
message descriptor, and the checks a value must pass (as it is typed, and when it is sent).

A value is kept as the text the operator typed; the placeholders of `specials` (`_time`,
`_y:300`, ...) are texts too and are only replaced when the message is sent.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from google.protobuf.descriptor import FieldDescriptor

from pygoby.dccl.options import field_options
from pygoby.moos.translator.fields import enum_name
from pygoby.protobuf import enum_type, message_type
from pygoby.protobuf.descriptors import INTEGER_FIELD_TYPES, AnyFieldDescriptor
from pygoby.topside.commander import specials
from pygoby.topside.errors import FieldValueError

_FD = FieldDescriptor
_UNSIGNED = {_FD.TYPE_UINT32, _FD.TYPE_UINT64, _FD.TYPE_FIXED32, _FD.TYPE_FIXED64}
_FLOAT_TYPES = {_FD.TYPE_DOUBLE, _FD.TYPE_FLOAT}


def _kind(field: AnyFieldDescriptor, codec: str) -> str:
    if codec == "_static" or codec.startswith("dccl.static"):
        return "static"
    if field.type in INTEGER_FIELD_TYPES:
        return "int"
    if field.type in _FLOAT_TYPES:
        return "float"
    return {
        _FD.TYPE_BOOL: "bool",
        _FD.TYPE_STRING: "string",
        _FD.TYPE_BYTES: "bytes",
        _FD.TYPE_ENUM: "enum",
    }.get(field.type, "message")


def _number_text(value: float) -> str:
    return f"{value:.15g}"


@dataclass(frozen=True)
class FieldSpec:
    """One field of a command message as the operator sees it.

    `source` is the MOOS variable an operator's value is posted to; `automatic_from` names the
    variable pAcommsHandler fills the field from instead (then the operator cannot set it);
    both empty: nothing fills the field (it keeps its default)."""

    name: str
    number: int
    kind: str  # int, float, bool, string, bytes, enum, static, message
    proto_type: str
    required: bool = False
    repeated: bool = False
    minimum: float | None = None
    maximum: float | None = None
    precision: int | None = None
    max_length: int | None = None
    max_repeat: int | None = None
    enum_values: tuple[str, ...] = ()
    static_value: str | None = None
    default: str = ""
    description: str = ""
    source: str = ""
    automatic_from: str = ""

    @classmethod
    def from_descriptor(
        cls,
        field: AnyFieldDescriptor,
        source: str = "",
        automatic_from: str = "",
        *,
        path: str = "",
        required: bool | None = None,
        short_enum: bool = False,
        elements_of: AnyFieldDescriptor | None = None,
    ) -> FieldSpec:
        """`path`: the name inside the command (`pose.x` for a sub-message's field);
        `required`: whether the message needs it (a required field of an optional sub-message
        does not); `short_enum`: enum values without their `FIELD_` prefix (use_short_enum);
        `elements_of`: the repeated sub-message whose elements hold the field (`track.x`
        takes one value per element, as a repeated field does)."""
        options = field_options(field)
        repeat = field_options(elements_of) if elements_of is not None else options
        kind = _kind(field, options.codec)
        numeric = kind in ("int", "float")
        type_name = (
            message_type(field).full_name
            if field.type == _FD.TYPE_MESSAGE
            else enum_type(field).full_name
            if field.type == _FD.TYPE_ENUM
            else _TYPE_NAMES.get(field.type, "?")
        )
        default = ""
        if field.has_default_value and kind not in ("message", "static"):
            value = field.default_value
            default = (
                enum_name(field, value, short_enum)
                if kind == "enum"
                else str(value).lower()
                if kind == "bool"
                else _number_text(value)
                if numeric
                else str(value)
            )
        return cls(
            name=path or field.name,
            number=field.number,
            kind=kind,
            proto_type=type_name,
            required=field.is_required if required is None else required,
            repeated=field.is_repeated or elements_of is not None,
            minimum=options.min if numeric and options.HasField("min") else None,
            maximum=options.max if numeric and options.HasField("max") else None,
            precision=(options.precision if kind == "float" else None),
            max_length=options.max_length if options.HasField("max_length") else None,
            max_repeat=repeat.max_repeat if repeat.HasField("max_repeat") else None,
            enum_values=tuple(
                enum_name(field, v.number, short_enum) for v in enum_type(field).values
            )
            if kind == "enum"
            else (),
            static_value=options.static_value if kind == "static" else None,
            default=default,
            description=options.description,
            source=source,
            automatic_from=automatic_from,
        )

    # ------------------------------------------------------------------ what the operator sees
    @property
    def editable(self) -> bool:
        return bool(self.source) and self.kind not in ("static", "message")

    def describe(self) -> str:
        """The information line of the editing screen: type and DCCL limits."""
        if self.kind == "static":
            return f"(static) you cannot change the value of this field: {self.static_value}"
        if self.kind == "message":
            what = "repeated sub-messages" if self.repeated else "recursive or deeper sub-messages"
            return f"({self.proto_type}) {what} cannot be composed here"
        if self.automatic_from:
            return f"({self.kind}) filled by pAcommsHandler from {self.automatic_from}"
        if not self.source:
            return f"({self.kind}) pAcommsHandler reads no MOOS variable for this field"
        parts = []
        if self.minimum is not None:
            parts.append(f"min: {_number_text(self.minimum)}")
        if self.maximum is not None:
            parts.append(f"max: {_number_text(self.maximum)}")
        if self.precision is not None and (self.minimum is not None or self.precision):
            parts.append(f"precision: {self.precision}")
        if self.max_length is not None:
            parts.append(f"max length: {self.max_length} chars")
        if self.enum_values:
            parts.append("one of " + ", ".join(self.enum_values))
        if self.kind == "bool":
            parts.append("true or false")
        if self.repeated:
            limit = f"up to {self.max_repeat} " if self.max_repeat else ""
            parts.append(f"{limit}values separated by commas")
        text = f"({self.kind}) " + ", ".join(parts)
        return text.rstrip(", ").rstrip()

    # ------------------------------------------------------------------ checks
    def check(self, text: str, *, partial: bool = False) -> None:
        """Raise FieldValueError unless `text` is a value of this field. With `partial`, a
        prefix of a valid value passes too (what is being typed: `-`, `1.`, `_y:`)."""
        if not self.editable:
            raise FieldValueError(f"{self.name}: {self.describe()}")
        if text == "":
            return
        values = _split_repeated(text) if self.repeated else [text]
        if self.max_repeat and len(values) > self.max_repeat:
            raise FieldValueError(f"{self.name}: at most {self.max_repeat} values")
        for value in values:
            self._check_one(value.strip() if self.repeated else value, partial)

    def _check_one(self, text: str, partial: bool) -> None:
        name = self.name
        if self.kind in ("int", "float"):
            if specials.is_placeholder(text, partial=partial):
                return
            if partial and text in ("-", "+", ".", "-.", "+."):
                if text.startswith("-") and self.minimum is not None and self.minimum >= 0:
                    raise FieldValueError(f"{name}: the minimum is {_number_text(self.minimum)}")
                return
            if partial and self.kind == "float" and text[-1:] in ("e", "E", "-", "+"):
                text = text.rstrip("eE+-") or "0"
            self._check_number(text)
        elif self.kind == "bool":
            lowered = text.lower()
            options = ("true", "false", "1", "0")
            if not (
                lowered in options or (partial and any(o.startswith(lowered) for o in options))
            ):
                raise FieldValueError(f"{name}: true or false")
        elif self.kind == "enum":
            upper = text.upper()
            names = [v.upper() for v in self.enum_values]
            if not (upper in names or (partial and any(n.startswith(upper) for n in names))):
                raise FieldValueError(f"{name}: one of {', '.join(self.enum_values)}")
        elif self.kind == "string":
            if self.max_length is not None and len(text.encode()) > self.max_length:
                raise FieldValueError(f"{name}: at most {self.max_length} characters")
        elif self.kind == "bytes":
            try:
                data = bytes.fromhex(text + ("0" if partial and len(text) % 2 else ""))
            except ValueError:
                raise FieldValueError(f"{name}: hexadecimal bytes (e.g. 0a1b)") from None
            if self.max_length is not None and len(data) > self.max_length:
                raise FieldValueError(f"{name}: at most {self.max_length} bytes")

    def _check_number(self, text: str) -> None:
        name = self.name
        try:
            value = int(text, 10) if self.kind == "int" else float(text)
        except ValueError:
            what = "an integer" if self.kind == "int" else "a number"
            raise FieldValueError(f"{name}: {text!r} is not {what}") from None
        if isinstance(value, float) and not math.isfinite(value):
            raise FieldValueError(f"{name}: {text!r} is not a finite number")
        if self.minimum is not None and value < self.minimum:
            raise FieldValueError(
                f"{name}: {text} is below the minimum {_number_text(self.minimum)}"
            )
        if self.maximum is not None and value > self.maximum:
            raise FieldValueError(
                f"{name}: {text} is above the maximum {_number_text(self.maximum)}"
            )
        if self.kind == "int" and self.proto_type.startswith("uint") and value < 0:
            raise FieldValueError(f"{name}: {text} is negative (unsigned field)")
        if self.precision is not None and self.kind == "float" and "e" not in text.lower():
            decimals = len(text.partition(".")[2])
            if decimals > max(self.precision, 0):
                raise FieldValueError(
                    f"{name}: at most {max(self.precision, 0)} decimals (precision "
                    f"{self.precision})"
                )


def _split_repeated(text: str) -> list[str]:
    return text.strip("{}").split(",")


_TYPE_NAMES = {
    getattr(_FD, name): name.removeprefix("TYPE_").lower()
    for name in dir(_FD)
    if name.startswith("TYPE_")
}
