"""A sweep file (`pygoby.netsim.protobuf.Sweep`, TextFormat) and the runs it stands for.

`load_sweep(path)` reads and checks it; `expand(sweep)` turns it into `RunSpec`s: one per
(parameter point, replicate), each carrying the complete scenario it runs as TextFormat, the
parameter values (the results' columns) and a `run_id` that is a hash of both, so a stored run
is recognised whatever order or machine it ran in. Field paths ("mac.rate",
"node[1].track.waypoint[0].x", "layout.nodes") are resolved against the protobuf descriptors,
and values are converted to the field's type; mistakes raise `ScenarioError` (a ConfigError)
naming the sweep file, the line of the axis and the field.
"""

from __future__ import annotations

import hashlib
import itertools
import json
import math
import random
import re
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from google.protobuf import text_format
from google.protobuf.descriptor import FieldDescriptor
from google.protobuf.message import Message

from pygoby.netsim.channel.geometry import WGS84
from pygoby.netsim.errors import ScenarioError
from pygoby.netsim.sim.scenario import check_scenario, parse_scenario
from pygoby.protobuf import enum_type
from pygoby.protobuf.descriptors import AnyFieldDescriptor
from pygoby.protobuf.pygoby.netsim.scenario_pb2 import Scenario
from pygoby.protobuf.pygoby.netsim.sweep_pb2 import Axis, Layout, Sweep
from pygoby.protobuf.textconfig import merge_config_text, read_config_file

LAYOUT_PREFIX = "layout."
_SEGMENT = re.compile(r"^([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d+)\])?$")

Value = int | float | bool | str


def sweep_class() -> type[Sweep]:
    return Sweep


@dataclass(frozen=True)
class RunSpec:
    """One simulation of a sweep: what to run and the values that label its results."""

    run_id: str
    point: int  # index of the parameter point (replicates share it)
    replicate: int
    seed: int
    params: tuple[tuple[str, Value], ...]  # (column, value) per axis, in axis order
    scenario_text: str


@dataclass(frozen=True)
class AxisColumn:
    name: str
    field: str
    kind: type  # int, float, bool or str: the column's type


@dataclass(frozen=True)
class SweepPlan:
    runs: list[RunSpec]
    columns: list[AxisColumn]
    output: str


# -- loading -------------------------------------------------------------------------------------


def load_sweep(path: str | Path) -> tuple[Sweep, Scenario]:
    """(sweep, base scenario) from a sweep file. Raises ScenarioError."""
    path = Path(path)
    return parse_sweep(read_config_file(path, error=ScenarioError), path)


def parse_sweep(text: str, path: Path | None = None) -> tuple[Sweep, Scenario]:
    sweep = sweep_class()()
    merge_config_text(text, sweep, file=path, error=ScenarioError)
    if sweep.HasField("scenario") == sweep.HasField("scenario_file"):
        raise ScenarioError("give exactly one of scenario {...} and scenario_file", file=path)
    if sweep.HasField("scenario_file"):
        base_dir = path.parent if path is not None else Path.cwd()
        scenario_path = base_dir / sweep.scenario_file
        try:
            scenario_text = scenario_path.read_text()
        except OSError as exc:
            raise ScenarioError(
                f"cannot read the scenario: {exc.strerror}", file=path, field="scenario_file"
            ) from None
        try:
            base = parse_scenario(scenario_text)
        except ScenarioError as exc:
            raise exc.located(file=scenario_path) from None
    else:
        base = sweep.scenario
    if base.speed.strip().lower() != "max":
        raise ScenarioError(
            'a sweep runs scenarios on the virtual clock: speed must be "max"',
            file=path,
            field="scenario.speed",
        )
    if not sweep.axis:
        raise ScenarioError("a sweep needs at least one axis", file=path)
    if sweep.replicates < 1 or (sweep.sampling == sweep.RANDOM and sweep.random_samples < 1):
        raise ScenarioError("replicates and random_samples must be at least 1", file=path)
    return sweep, base


# -- field paths ---------------------------------------------------------------------------------


def _segments(path: str) -> list[tuple[str, int | None]]:
    parts = []
    for part in path.split("."):
        match = _SEGMENT.match(part)
        if match is None:
            raise ValueError(f"{path!r} is not a field path (like mac.rate or node[1].track)")
        parts.append((match.group(1), None if match.group(2) is None else int(match.group(2))))
    return parts


def field_descriptor(message_class_descriptor, path: str) -> AnyFieldDescriptor:
    """The descriptor of the scalar a path ends at (checked against the message type)."""
    descriptor = message_class_descriptor
    segments = _segments(path)
    field = None
    for i, (name, index) in enumerate(segments):
        field = descriptor.fields_by_name.get(name)
        if field is None:
            raise ValueError(f"{descriptor.name} has no field {name!r}")
        repeated = field.is_repeated
        if repeated != (index is not None):
            raise ValueError(
                f"{name} is {'repeated: give an index, ' + name + '[0]' if repeated else 'not repeated: no index'}"
            )
        last = i == len(segments) - 1
        if field.type == FieldDescriptor.TYPE_MESSAGE:
            if last:
                raise ValueError(
                    f"{name} is a message; the path must end at a number, enum, bool or string"
                )
            descriptor = field.message_type
        elif not last:
            raise ValueError(f"{name} is not a message")
    assert field is not None
    return field


def _repeated(target: Message, name: str, index: int):
    items = getattr(target, name)
    if index >= len(items):
        raise ValueError(f"{name}[{index}] does not exist (there are {len(items)})")
    return items


def set_field(message: Message, path: str, value: Value) -> None:
    """Set the scalar at `path` (the elements of repeated fields must exist)."""
    *parents, (name, index) = _segments(path)
    target = message
    for parent, i in parents:
        target = getattr(target, parent) if i is None else _repeated(target, parent, i)[i]
    if index is None:
        setattr(target, name, value)
    else:
        _repeated(target, name, index)[index] = value


_KINDS = {
    FieldDescriptor.CPPTYPE_INT32: int,
    FieldDescriptor.CPPTYPE_INT64: int,
    FieldDescriptor.CPPTYPE_UINT32: int,
    FieldDescriptor.CPPTYPE_UINT64: int,
    FieldDescriptor.CPPTYPE_DOUBLE: float,
    FieldDescriptor.CPPTYPE_FLOAT: float,
    FieldDescriptor.CPPTYPE_BOOL: bool,
    FieldDescriptor.CPPTYPE_STRING: str,
    FieldDescriptor.CPPTYPE_ENUM: str,  # results carry the enum's name
}


def parse_value(field: AnyFieldDescriptor, text: str) -> Value:
    """A value written as in TextFormat, as the field's Python type (enums by name)."""
    kind = _KINDS[field.cpp_type]
    text = text.strip()
    if field.cpp_type == FieldDescriptor.CPPTYPE_ENUM:
        by_name = enum_type(field).values_by_name
        if text in by_name:
            return text
        if text.lstrip("-").isdigit() and int(text) in enum_type(field).values_by_number:
            return enum_type(field).values_by_number[int(text)].name
        raise ValueError(f"{text!r} is not one of {', '.join(by_name)}")
    if kind is bool:
        if text.lower() in ("true", "t", "1"):
            return True
        if text.lower() in ("false", "f", "0"):
            return False
        raise ValueError(f"{text!r} is not true or false")
    if kind in (int, float):
        expected = "an integer" if kind is int else "a number"
        try:
            number = float(text)
        except ValueError:
            raise ValueError(f"expects {expected}, not {text!r}") from None
        if kind is float:
            return number
        if not number.is_integer():
            raise ValueError(f"expects {expected}, not {text!r}")
        return int(number)
    return text


def _field_value(field: AnyFieldDescriptor, value: Value):
    """What to assign to the protobuf field (enum names become numbers)."""
    if field.cpp_type == FieldDescriptor.CPPTYPE_ENUM:
        return enum_type(field).values_by_name[str(value)].number
    return value


# -- expansion -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Axis:
    column: AxisColumn
    descriptor: AnyFieldDescriptor
    values: tuple[Value, ...]  # GRID values (or RANDOM choices)
    span: Axis.Span | None


def _axis_line(text: str, field: str) -> int | None:
    for number, line in enumerate(text.splitlines(), 1):
        if f'"{field}"' in line:
            return number
    return None


def _axes(sweep: Sweep, base: Scenario, path: Path | None, text: str) -> list[_Axis]:
    axes, names = [], set()
    layout_descriptor = sweep.DESCRIPTOR.fields_by_name["layout"].message_type
    for axis in sweep.axis:
        where: dict[str, Any] = {
            "file": path,
            "line": _axis_line(text, axis.field),
            "field": axis.field,
        }
        try:
            if axis.field.startswith(LAYOUT_PREFIX):
                if not sweep.HasField("layout"):
                    raise ValueError("a layout axis needs a layout { } block")
                descriptor = field_descriptor(layout_descriptor, axis.field[len(LAYOUT_PREFIX) :])
            else:
                descriptor = field_descriptor(base.DESCRIPTOR, axis.field)
            if bool(axis.value) == axis.HasField("span"):
                raise ValueError("give either values or a span")
            values = tuple(parse_value(descriptor, v) for v in axis.value)
            if axis.HasField("span"):
                if _KINDS[descriptor.cpp_type] not in (int, float):
                    raise ValueError("a span needs a numeric field")
                ends = (getattr(axis.span, "from"), axis.span.to)
                if axis.span.steps < 1 or (axis.span.log and min(ends) <= 0):
                    raise ValueError("a span needs steps >= 1 (and positive ends when log)")
                values = _span_values(axis.span, _KINDS[descriptor.cpp_type])
        except ValueError as exc:
            raise ScenarioError(str(exc), **where) from None
        name = axis.name or axis.field
        seed_column = name == "seed" and axis.field == "seed"  # (the seed column itself)
        if name in names or (name in RESERVED_COLUMNS and not seed_column):
            raise ScenarioError(
                f"column {name!r} is used twice: give the axis another name", **where
            )
        names.add(name)
        column = AxisColumn(name, axis.field, _KINDS[descriptor.cpp_type])
        axes.append(_Axis(column, descriptor, values, axis.span if axis.HasField("span") else None))
    return axes


def _span_values(span: Axis.Span, kind: type) -> tuple[Value, ...]:
    low, high, steps = getattr(span, "from"), span.to, span.steps
    if steps == 1:
        points = [low]
    elif span.log:
        points = [low * (high / low) ** (i / (steps - 1)) for i in range(steps)]
    else:
        points = [low + (high - low) * i / (steps - 1) for i in range(steps)]
    if kind is int:
        return tuple(dict.fromkeys(round(p) for p in points))
    return tuple(points)


def _random_value(axis: _Axis, rng: random.Random) -> Value:
    if axis.span is None:
        return rng.choice(axis.values)
    low, high = getattr(axis.span, "from"), axis.span.to
    if axis.span.log:
        value = math.exp(rng.uniform(math.log(low), math.log(high)))
    else:
        value = rng.uniform(low, high)
    return round(value) if axis.column.kind is int else value


# Columns every results row has (see pygoby.netsim.sweep.run); axes may not reuse them.
RESERVED_COLUMNS = frozenset(
    {
        "run_id",
        "point",
        "replicate",
        "seed",
        "nodes",
        "duration_s",
        "src",
        "dest",
        "rate",
        "range_m",
        "sent",
        "frames_sent",
        "received",
        "good",
        "bad_frames",
        "not_detected",
        "receiver_busy",
        "half_duplex",
        "frames_good",
        "messages",
        "latency_mean_s",
        "latency_max_s",
        "acked",
        "snr_mean_db",
        "sinr_mean_db",
        "owtt_mean_s",
        "wall_s",
    }
)


def expand(sweep: Sweep, base: Scenario, path: Path | None = None, text: str = "") -> SweepPlan:
    """Every run of the sweep, in a fixed order (points in grid/sample order, then replicates)."""
    axes = _axes(sweep, base, path, text)
    if sweep.replicates > 1 and any(a.column.field == "seed" for a in axes):
        raise ScenarioError(
            "an axis sets seed: replicates must be 1", file=path, field="replicates"
        )
    if sweep.sampling == sweep.RANDOM:
        rng = random.Random(sweep.sampling_seed)
        points = [tuple(_random_value(a, rng) for a in axes) for _ in range(sweep.random_samples)]
    else:
        points = list(itertools.product(*(a.values for a in axes)))
    runs = []
    for index, values in enumerate(points):
        try:
            scenario = point_scenario(sweep, base, axes, values)
        except (ValueError, ScenarioError) as exc:  # (a ScenarioError is a ValueError too)
            shown = ", ".join(f"{a.column.name}={v}" for a, v in zip(axes, values, strict=True))
            field = getattr(exc, "field", None)
            reason = getattr(exc, "reason", str(exc))
            raise ScenarioError(
                f"{reason} (point {index}: {shown})",
                file=path,
                line=_axis_line(text, field) if field else None,
                field=field,
            ) from None
        params = tuple((a.column.name, v) for a, v in zip(axes, values, strict=True))
        for replicate in range(sweep.replicates):
            if not any(a.column.field == "seed" for a in axes):
                scenario.seed = sweep.first_seed + replicate
            scenario_text = text_format.MessageToString(scenario)
            runs.append(
                RunSpec(
                    run_id=run_id(params, scenario_text),
                    point=index,
                    replicate=replicate,
                    seed=scenario.seed,
                    params=params,
                    scenario_text=scenario_text,
                )
            )
    return SweepPlan(runs, [a.column for a in axes], sweep.output)


def _set_axis(message: Message, axis: _Axis, path: str, value: Value) -> None:
    try:
        set_field(message, path, _field_value(axis.descriptor, value))
    except ValueError as exc:
        raise ScenarioError(str(exc), field=axis.column.field) from None


def point_scenario(sweep: Sweep, base: Scenario, axes: list[_Axis], values) -> Scenario:
    """The scenario of one point: the layout with its axis values, then the scenario's axes."""
    scenario = type(base)()
    scenario.CopyFrom(base)
    scenario.ClearField("event_log")
    if sweep.HasField("layout"):
        layout = type(sweep.layout)()
        layout.CopyFrom(sweep.layout)
        for axis, value in zip(axes, values, strict=True):
            if axis.column.field.startswith(LAYOUT_PREFIX):
                _set_axis(layout, axis, axis.column.field[len(LAYOUT_PREFIX) :], value)
        apply_layout(scenario, layout)
    for axis, value in zip(axes, values, strict=True):
        if not axis.column.field.startswith(LAYOUT_PREFIX):
            _set_axis(scenario, axis, axis.column.field, value)
    check_scenario(scenario)
    return scenario


def apply_layout(scenario: Scenario, layout: Layout) -> None:
    """Replace the scenario's nodes by the layout's (fixed, at lat/lon around the origin)."""
    if not scenario.HasField("origin"):
        raise ValueError("a layout needs the scenario's origin")
    if layout.nodes < 1:
        raise ValueError("layout.nodes must be at least 1")
    scenario.ClearField("node")
    columns = math.ceil(math.sqrt(layout.nodes))
    for i in range(layout.nodes):
        if layout.pattern == layout.GRID:
            x, y = layout.spacing * (i % columns), layout.spacing * (i // columns)
        elif layout.pattern == layout.RING and i > 0:
            angle = 2 * math.pi * (i - 1) / (layout.nodes - 1)
            x, y = layout.spacing * math.cos(angle), layout.spacing * math.sin(angle)
        elif layout.pattern == layout.RING:
            x = y = 0.0
        else:
            x, y = layout.spacing * i, 0.0
        azimuth = math.degrees(math.atan2(x, y))
        lon, lat, _ = WGS84.fwd(scenario.origin.lon, scenario.origin.lat, azimuth, math.hypot(x, y))
        node = scenario.node.add(modem_id=layout.first_modem_id + i)
        node.track.waypoint.add(lat=lat, lon=lon, depth=layout.depth)


def run_id(params: tuple[tuple[str, Value], ...], scenario_text: str) -> str:
    digest = hashlib.sha256(json.dumps(params).encode())
    digest.update(scenario_text.encode())
    return digest.hexdigest()[:16]


def plan_sweep(path: str | Path) -> SweepPlan:
    path = Path(path)
    sweep, base = load_sweep(path)
    return expand(sweep, base, path, path.read_text())
