"""The arithmetic-coding field codec `dccl.arithmetic` (C++ DCCL's libdccl_arithmetic).

A field says `(dccl.field).codec = "dccl.arithmetic"` and `(dccl.field).(arithmetic).model =
"NAME"` (import "dccl/arithmetic/protobuf/arithmetic_extensions.proto"). The model, a
`dccl.arith.protobuf.ArithmeticModel`, is given to the Codec before the type is loaded:

    codec.set_arithmetic_model(model)            # a message, or
    codec.set_arithmetic_model(load_model_file("model.txt"))   # TextFormat file

Models belong to one Codec; an adaptive model (`is_adaptive: true`) changes with every symbol
coded, separately for encoding and decoding, for the life of the Codec (as in C++).

The coder is the integer arithmetic coder of Witten, Neal and Cleary (CACM 1987) with 32-bit
code values, as C++ DCCL implements it, bit for bit: symbol -2 is "end of list" (EOF), -1 "out of
range", 0..n-1 the model's symbols; a value maps to the symbol of the nearest `value_bound`
(nearness judged on squared values, as the reference does). A repeated field is coded as a
whole (no count prefix), a singular field as a list of at most one value.

Where C++ DCCL 4.2 cannot read back what it writes, pygoby writes what its decoder reads:
* a value nearest to the top `value_bound` (which belongs to no symbol): C++ loops forever;
  pygoby codes the last symbol;
* `eof_frequency: 0` with fewer values than max_repeat: C++ writes one fill symbol (taken from a
  frequency's value, not its position) and stops, so no decoder can read the message; pygoby
  fills every remaining slot with the most probable symbol, which C++ decodes;
* an out-of-range value with `out_of_range_frequency: 0` ends the list (as the model's own
  documentation says): C++ writes EOF but then goes on writing the following values, which
  shifts every later field for any decoder; pygoby stops at the EOF;
* NaN is out of range (C++ reads past the bounds);
* an absent optional singular field decodes as unset (C++ fails the whole decode).
"""

from __future__ import annotations

import bisect
import math
import os
from typing import Any

from google.protobuf import text_format
from google.protobuf.message import Message

from pygoby.dccl.ccl.fields import cvtt32, cvtt64
from pygoby.dccl.codecs.base import FieldInfo, RepeatedFieldCodec
from pygoby.dccl.codecs.numeric import f32
from pygoby.dccl.errors import DcclDecodeError, DcclError, DcclLoadError
from pygoby.dccl.options import field_extension
from pygoby.protobuf import enum_type, initialization_errors
from pygoby.protobuf.dccl.arithmetic.protobuf.arithmetic_extensions_pb2 import ArithmeticOptions
from pygoby.protobuf.dccl.arithmetic.protobuf.arithmetic_pb2 import ArithmeticModel

EOF_SYMBOL = -2
OUT_OF_RANGE_SYMBOL = -1
CODE_VALUE_BITS = 32
MAX_FREQUENCY = (1 << (CODE_VALUE_BITS - 2)) - 1
TOP = (1 << CODE_VALUE_BITS) - 1
HALF = 1 << (CODE_VALUE_BITS - 1)
FIRST_QTR = HALF >> 1
THIRD_QTR = HALF + FIRST_QTR
_U64 = (1 << 64) - 1
_U32 = (1 << 32) - 1
_NAN = float("nan")


def model_class() -> type[ArithmeticModel]:
    return ArithmeticModel


def load_model_file(path: str | os.PathLike[str]) -> ArithmeticModel:
    """An ArithmeticModel from a TextFormat file (`--arithmetic-model FILE`)."""
    try:
        with open(path) as f:
            return text_format.Parse(f.read(), model_class()())
    except (OSError, text_format.ParseError) as exc:
        raise DcclLoadError(f"{os.fspath(path)}: cannot read an ArithmeticModel: {exc}") from None


class Model:
    """A validated model with its encoder and decoder frequency tables."""

    ENCODER, DECODER = 0, 1

    def __init__(self, user: ArithmeticModel) -> None:
        def invalid(why: str) -> DcclLoadError:
            return DcclLoadError(f"invalid arithmetic model {user.name!r}: {why}")

        if not user.IsInitialized():
            raise DcclLoadError(f"invalid arithmetic model: missing {initialization_errors(user)}")
        self.user = user
        self.name = user.name
        self.bounds = list(user.value_bound)
        self.frequency = list(user.frequency)
        self.adaptive = user.is_adaptive
        self.eof_frequency = user.eof_frequency
        self.out_of_range_frequency = user.out_of_range_frequency
        if any(f == 0 for f in self.frequency):
            raise invalid("all frequencies must be nonzero")
        if not self.frequency:
            raise invalid("no symbols (frequency is empty)")
        cumulative, total = [], 0
        for freq in (self.eof_frequency, self.out_of_range_frequency, *self.frequency):
            total += freq
            cumulative.append(total)
        if total > MAX_FREQUENCY:
            raise invalid(f"the sum of all frequencies must not exceed {MAX_FREQUENCY}")
        if len(self.bounds) != len(self.frequency) + 1:
            raise invalid("value_bound must have exactly one more entry than frequency")
        if any(b >= a for a, b in zip(self.bounds[1:], self.bounds, strict=False)):
            raise invalid("value_bound must be strictly increasing")
        # cumulative frequency up to and including each symbol, indexed by symbol + 2
        self.tables = [cumulative, list(cumulative)]
        self.max_symbol = len(self.frequency) - 1
        # the symbol written for "no more values" when EOF has no frequency
        self.fill_symbol = self.frequency.index(max(self.frequency))

    def total(self, state: int) -> int:
        return self.tables[state][-1]

    def value_to_symbol(self, value: float) -> int:
        bounds = self.bounds
        if not bounds[0] <= value <= bounds[-1]:  # NaN too
            return OUT_OF_RANGE_SYMBOL
        upper = bisect.bisect_right(bounds, value)
        if upper == len(bounds):
            return self.max_symbol  # the top bound itself: the last symbol (see module doc)
        lower = upper - 1 if upper else upper
        square = value * value
        lower_diff = abs(bounds[lower] * bounds[lower] - square)
        upper_diff = abs(bounds[upper] * bounds[upper] - square)
        symbol = lower if lower_diff < upper_diff else upper
        return min(symbol, self.max_symbol)

    def symbol_to_value(self, symbol: int) -> float:
        return _NAN if symbol == OUT_OF_RANGE_SYMBOL else self.bounds[symbol]

    def interval(self, symbol: int, state: int) -> tuple[int, int]:
        table = self.tables[state]
        i = symbol + 2
        return (table[i - 1] if i else 0), table[i]

    def symbol_for(self, cumulative: int, cumulative_high: int, state: int) -> tuple[int, int]:
        """The symbols whose intervals hold the low and high cumulative frequency (the
        reference's lookup, including its answer 0 when none does)."""
        table = self.tables[state]
        first = 0
        for i, c in enumerate(table):
            if cumulative < c:
                first = i - 2
                break
        if first == self.max_symbol or table[first + 2] > cumulative_high:
            return first, first
        return first, first + 1

    def update(self, symbol: int, state: int) -> None:
        if self.adaptive:
            table = self.tables[state]
            for i in range(symbol + 2, len(table)):
                table[i] += 1


class ModelManager:
    """The arithmetic models of one Codec, by name."""

    def __init__(self) -> None:
        self._models: dict[str, Model] = {}

    def set_model(self, model: ArithmeticModel) -> None:
        """Add or replace a model (fresh frequency tables for adaptive ones)."""
        self._models[model.name] = Model(model)

    def find(self, name: str) -> Model:
        try:
            return self._models[name]
        except KeyError:
            raise DcclError(f"no arithmetic model called {name!r} is set") from None

    def names(self) -> list[str]:
        return sorted(self._models)


def model_manager(info_or_registry: Any) -> ModelManager:
    registry = getattr(info_or_registry, "registry", info_or_registry)
    return registry.shared_state(ModelManager)


def _to_wire(category: str):
    """The field value as the coder's double (C++ static_cast<double>)."""
    if category == "bool":
        return lambda v: 1.0 if v else 0.0
    return float


def _from_wire(category: str, info: FieldInfo):
    """The coder's double as the field type (x86-64 conversions, NaN included)."""
    if category == "double":
        return lambda x: x
    if category == "float":
        return f32
    if category == "bool":
        return lambda x: x != 0.0  # NaN is true
    if category == "int32":
        return cvtt32
    if category == "int64":
        return cvtt64
    if category == "uint32":
        return lambda x: cvtt64(x) & _U32
    if category == "uint64":
        return lambda x: (
            (
                cvtt64(x - 9223372036854775808.0) ^ (1 << 63)
                if x >= 9223372036854775808.0
                else cvtt64(x)
            )
            & _U64
        )
    if category == "enum":
        known = {v.number for v in enum_type(info.descriptor).values}
        # an unknown number makes the element "not set" (dropped)
        return lambda x: n if (n := cvtt32(x)) in known else None
    raise DcclLoadError(f"{info.name}: dccl.arithmetic cannot code {category} fields")


class ArithmeticCodec(RepeatedFieldCodec):
    """dccl.arithmetic for int*, uint*, double, float, bool and enum fields."""

    def __init__(self, info: FieldInfo) -> None:
        super().__init__(info)
        options = field_extension(info.options, ArithmeticOptions, 1001)
        if not options.HasField("model"):
            raise DcclLoadError(f"{info.name}: missing (dccl.field).arithmetic.model")
        self.model_name = options.model
        self.models = model_manager(info)
        try:
            self.models.find(self.model_name)
        except DcclError:
            raise DcclLoadError(
                f"{info.name}: no arithmetic model called {self.model_name!r} is set (give it"
                " with Codec.set_arithmetic_model or --arithmetic-model before loading)"
            ) from None
        self.max_repeat = info.options.max_repeat if info.descriptor.is_repeated else 1
        self.to_wire = _to_wire(info.category)
        self.from_wire = _from_wire(info.category, info)

    @property
    def model(self) -> Model:
        return self.models.find(self.model_name)

    # ------------------------------------------------------------------ sizes
    def max_size(self) -> int:
        model = self.model
        total = model.total(Model.ENCODER)
        oor = model.out_of_range_frequency or MAX_FREQUENCY
        lowest = float(min(oor, *model.frequency))
        n = self.max_repeat
        least_probable = math.ceil(n * (math.log2(total) - math.log2(lowest)))
        eof = model.eof_frequency
        with_eof = (
            math.ceil(n * math.log2(total) - (n - 1) * math.log2(lowest) - math.log2(eof))
            if eof
            else 0
        )
        return max(with_eof, least_probable) + 1

    def min_size(self) -> int:
        model = self.model
        if model.adaptive:
            return 0  # the decoder reads from the first bit on
        total = model.total(Model.ENCODER)
        oor = model.out_of_range_frequency or 1
        eof = model.eof_frequency
        empty = math.ceil(math.log2(total) - math.log2(eof)) if eof else _U32
        highest = float(max(oor, *model.frequency))
        most_probable = math.ceil(self.max_repeat * (math.log2(total) - math.log2(highest)))
        return min(empty, most_probable)

    def describe(self) -> str:
        return f"arithmetic model {self.model_name!r}"

    # ------------------------------------------------------------------ encoding
    def encode_list(self, values: list, strict: bool) -> tuple[int, int]:
        model = self.model
        state = Model.ENCODER
        to_wire = self.to_wire
        low, high, follow = 0, TOP, 0
        acc = pos = 0  # the bits written, first bit lowest (DCCL bit order)

        def emit(bit: int) -> None:
            nonlocal acc, pos, follow
            acc |= bit << pos
            pos += 1
            if follow:
                if not bit:
                    acc |= ((1 << follow) - 1) << pos
                pos += follow
                follow = 0

        n = len(values)
        for index in range(self.max_repeat):
            symbol = EOF_SYMBOL
            if index < n:
                symbol = model.value_to_symbol(to_wire(values[index]))
            if symbol == OUT_OF_RANGE_SYMBOL and model.out_of_range_frequency == 0:
                symbol = EOF_SYMBOL
            ends = symbol == EOF_SYMBOL
            if ends and model.eof_frequency == 0:
                symbol, ends = model.fill_symbol, False
            span = high - low + 1
            c_low, c_high = model.interval(symbol, state)
            total = model.total(state)
            high = low + span * c_high // total - 1
            low += span * c_low // total
            model.update(symbol, state)
            while True:
                if high < HALF:
                    emit(0)
                elif low >= HALF:
                    emit(1)
                    low -= HALF
                    high -= HALF
                elif low >= FIRST_QTR and high < THIRD_QTR:
                    follow += 1
                    low -= FIRST_QTR
                    high -= FIRST_QTR
                else:
                    break
                low <<= 1
                high = high << 1 | 1
            if ends:
                break
        # the fewest bits that pin down the final interval
        if low == 0:
            if high != TOP or follow:
                emit(0)
        elif high == TOP:
            emit(1)
        else:
            follow += 1
            emit(0 if low < FIRST_QTR else 1)
        # DCCL writes the first coder bit first: the coder's bit string is already in that order
        return acc, pos

    def encode(self, value: Any, strict: bool) -> tuple[int, int]:
        return self.encode_list([] if value is None else [value], strict)

    # ------------------------------------------------------------------ decoding
    def decode_list(self, bits: int, pos: int, end: int) -> tuple[list, int]:
        model = self.model
        state = Model.DECODER
        start = pos
        have = self.min_size()  # the reference hands the codec its minimum size first
        if start + have > end:
            raise DcclDecodeError(f"message is truncated: {self.info.name} needs bits past the end")
        value = 0
        # the first 32 bits held, first bit as the most significant
        for k in range(min(have, CODE_VALUE_BITS)):
            value |= (bits >> (start + k) & 1) << (CODE_VALUE_BITS - 1 - k)
        offset = CODE_VALUE_BITS - have
        low, high = 0, TOP
        values: list = []
        from_wire = self.from_wire
        for _ in range(self.max_repeat):
            span = high - low + 1
            total = model.total(state)
            while True:
                value_high = (value + (1 << offset) - 1) & _U64 if offset > 0 else value
                c_freq = (((value - low + 1) * total - 1) & _U64) // span & _U32
                c_freq_high = (((value_high - low + 1) * total - 1) & _U64) // span & _U32
                symbol, other = model.symbol_for(c_freq, c_freq_high, state)
                if symbol == other:
                    break
                # ambiguous: read one more bit
                if start + have >= end:
                    raise DcclDecodeError(
                        f"message is truncated: {self.info.name} needs bits past the end"
                    )
                bit = bits >> (start + have) & 1
                have += 1
                offset -= 1
                value = (value | bit << (offset & 63)) & _U64  # x86 masks the shift count
            c_low, c_high = model.interval(symbol, state)
            high = (low + span * c_high // total - 1) & _U64
            low = (low + span * c_low // total) & _U64
            model.update(symbol, state)
            if symbol == EOF_SYMBOL:
                break
            decoded = from_wire(model.symbol_to_value(symbol))
            if decoded is not None:
                values.append(decoded)
            while True:
                if high < HALF:
                    pass
                elif low >= HALF:
                    value = (value - HALF) & _U64
                    low -= HALF
                    high -= HALF
                elif low >= FIRST_QTR and high < THIRD_QTR:
                    value = (value - FIRST_QTR) & _U64
                    low -= FIRST_QTR
                    high -= FIRST_QTR
                else:
                    break
                low = (low << 1) & _U64
                high = (high << 1 | 1) & _U64
                value = (value << 1) & _U64
                offset += 1
        return values, start + have

    def decode(self, bits: int, pos: int, end: int) -> tuple[Any, int]:
        values, pos = self.decode_list(bits, pos, end)
        return (values[0] if values else None), pos


def set_model(codec: Any, model: ArithmeticModel | str | os.PathLike[str]) -> None:
    """Give `codec` (a pygoby.dccl.Codec) an arithmetic model: an ArithmeticModel message or
    the path of a TextFormat file holding one (C++: ModelManager::set_model)."""
    if not isinstance(model, Message):
        model = load_model_file(model)
    model_manager(codec.registry).set_model(model)
