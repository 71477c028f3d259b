"""Hypothesis strategies for DCCL messages, derived from the (dccl.field) options."""

from __future__ import annotations

import math

from google.protobuf.descriptor import Descriptor, FieldDescriptor
from google.protobuf.message import Message
from hypothesis import strategies as st

from pygoby.dccl.codecs.base import INTEGER_CATEGORIES, field_category
from pygoby.dccl.codecs.numeric import f32
from pygoby.dccl.options import field_options

TEXT = st.text(alphabet="abcdefghijklmnopqrstuvwxyz0123456789 -_", min_size=1)


def resolution(f: FieldDescriptor) -> float:
    opts = field_options(f)
    if opts.HasField("resolution"):
        return opts.resolution
    return math.pow(10.0, -opts.precision)


def _scalar(f: FieldDescriptor, now: float) -> st.SearchStrategy:
    opts = field_options(f)
    category = field_category(f)
    if opts.codec.startswith("dccl.time") or opts.codec == "_time":
        seconds = st.integers(int(now) - 40000, int(now) + 40000)
        if category == "double":
            return seconds.map(float)
        return seconds.map(lambda t: t * 1_000_000)  # 64-bit integer times are microseconds
    if category == "bool":
        return st.booleans()
    if category == "enum":
        return st.sampled_from([v.number for v in f.enum_type.values])
    if category == "string":
        return TEXT.filter(lambda s: len(s) <= opts.max_length)
    if category == "bytes":
        return st.binary(min_size=1, max_size=opts.max_length)
    if category == "message":
        return message_strategy(f.message_type, now)
    # stay one step inside the bounds: a value on a bound may round out of range (spec §7.4)
    if category in INTEGER_CATEGORIES:
        return st.integers(math.ceil(opts.min), math.floor(opts.max))
    res = resolution(f)
    lo, hi = opts.min + res, opts.max - res
    if lo > hi:
        lo = hi = (opts.min + opts.max) / 2
    values = st.floats(lo, hi, allow_nan=False)
    return values.map(f32) if category == "float" else values


def message_strategy(desc: Descriptor, now: float = 1_700_000_000.0) -> st.SearchStrategy:
    from google.protobuf import message_factory

    cls = message_factory.GetMessageClass(desc)
    members: dict[str, list[FieldDescriptor]] = {}
    singles = {}
    for f in desc.fields:
        opts = field_options(f)
        if opts.omit or opts.codec.startswith(("dccl.static", "_static")):
            continue
        value = _scalar(f, now)
        if f.containing_oneof is not None:
            members.setdefault(f.containing_oneof.name, []).append(f)
            continue
        if f.is_repeated:
            value = st.lists(value, min_size=opts.min_repeat, max_size=opts.max_repeat)
        elif not f.is_required:
            value = st.none() | value
        singles[f.name] = value
    oneof_choices = [
        st.none()
        | st.sampled_from(fs).flatmap(
            lambda f, now=now: _scalar(f, now).map(lambda v, f=f: (f.name, v))
        )
        for fs in members.values()
    ]

    def build(parts) -> Message:
        fields, chosen = parts
        kwargs = {k: v for k, v in fields.items() if v is not None}
        for pick in chosen:
            if pick is not None:
                kwargs[pick[0]] = pick[1]
        return cls(**kwargs)

    return st.tuples(st.fixed_dictionaries(singles), st.tuples(*oneof_choices)).map(build)


def has_leaf(msg: Message) -> bool:
    """True if some non-message field is set at any depth (v2's notion of "present")."""
    for f, value in msg.ListFields():
        if field_category(f) != "message":
            return True
        values = value if f.is_repeated else [value]
        if any(has_leaf(v) for v in values):
            return True
    return False


def assert_close(original: Message, decoded: Message, version: int) -> None:
    """decoded equals original up to each numeric field's resolution (spec §7)."""
    for f in original.DESCRIPTOR.fields:
        opts = field_options(f)
        if opts.omit or opts.codec.startswith(("dccl.static", "_static")):
            continue
        if f.is_repeated:
            a, b = list(getattr(original, f.name)), list(getattr(decoded, f.name))
            if version == 2 and field_category(f) == "message" and not all(map(has_leaf, a)):
                continue  # v2: each empty element removes the last one (spec §11.2)
            assert len(a) == len(b), f.name
            pairs = zip(a, b, strict=True)
        else:
            if not original.HasField(f.name):
                assert not decoded.HasField(f.name), f.name
                continue
            sub = getattr(original, f.name)
            if version == 2 and field_category(f) == "message" and not has_leaf(sub):
                continue  # v2 has no presence bit: an empty sub-message reads as absent (§12)
            assert decoded.HasField(f.name), f.name
            pairs = [(getattr(original, f.name), getattr(decoded, f.name))]
        category = field_category(f)
        for x, y in pairs:
            if category == "message":
                assert_close(x, y, version)
            elif category in ("double", "float") or (
                category in INTEGER_CATEGORIES and resolution(f) >= 1
            ):
                tolerance = resolution(f) / 2 * 1.0001 + 1e-6 * abs(x)
                assert abs(x - y) <= tolerance, (f.name, x, y)
            elif category == "bytes" and version < 4 and "var_bytes" not in opts.codec:
                assert y == x + bytes(opts.max_length - len(x)), f.name
            else:
                assert x == y, (f.name, x, y)
