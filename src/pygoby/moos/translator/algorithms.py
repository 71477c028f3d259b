"""Translator algorithms (Goby 1 "message algorithms"): string in, string out.

Values travel as strings. Numeric algorithms read them as doubles (`true`/`false` count as
1/0, anything else is NaN) and print their double results with Goby's value rule (see
`render_double`), which e.g. prints 0.5 as `0.500000000000000`.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

from google.protobuf.message import Message

from pygoby.moos.translator.conversions import lexical_double, significant_digits
from pygoby.moos.translator.errors import TranslatorConfigError
from pygoby.util.geodesy import UTMGeodesy
from pygoby.util.modem_id import ModemIdLookup
from pygoby.util.ocean import mackenzie_1981


def numeric(text: str) -> float:
    """DCCLMessageVal's double view of a string."""
    if text == "true":
        return 1.0
    if text == "false":
        return 0.0
    value = lexical_double(text)
    return math.nan if value is None else value


def render_double(value: float, precision: int = 15) -> str:
    """DCCLMessageVal's double -> string: fixed with `precision` decimals when
    log10(|d|) + precision <= 15 (so every |d| <= 1 at precision 15), else %.<precision>g."""
    if math.isnan(value):
        return "nan"
    magnitude = math.log10(abs(value)) if value != 0 else -math.inf
    if magnitude + precision <= 15:
        return f"{value:.{precision}f}"
    return f"{value:.{precision}g}"


def _wrap(value: float, low: float) -> float:
    """Add/subtract 360 until value is in [low, low + 360) (as goby does, step by step)."""
    if not math.isfinite(value):
        return math.nan
    if abs(value) > 1e6:
        value = math.fmod(value, 360.0)
    while value < low:
        value += 360.0
    while value >= low + 360.0:
        value -= 360.0
    return value


def _power_to_db(x: float) -> float:
    if x == 0:
        return -math.inf
    return 10.0 * math.log10(x) if x > 0 else math.nan


def _db_to_power(x: float) -> float:
    try:
        return 10.0 ** (x / 10.0)
    except OverflowError:
        return math.inf


def _nmea_angle(x: float, degree_digits: int) -> str:
    # goby3's floor-based split into degrees and minutes, reproduced as is: negative input gives
    # odd strings (apply abs first; QUIRKS.md Q-APPS-23).
    if not math.isfinite(x):
        return "nan"
    degrees = math.floor(x)
    minutes_full = (x - degrees) * 60.0
    minutes = math.floor(minutes_full)
    fraction = math.floor((minutes_full - minutes) * 10000.0)
    return f"{degrees:0{degree_digits}d}{minutes:02d}.{fraction:04d}"


def _nmea_time(t: float) -> str:
    if not math.isfinite(t):
        return "nan"
    micros = math.floor(t * 1e6 + 0.5) % 86_400_000_000
    seconds, micro = divmod(micros, 1_000_000)
    return f"{seconds // 3600:02d}{seconds // 60 % 60:02d}{seconds % 60:02d}.{micro:06d}"


def mackenzie_soundspeed(t: float, s: float, d: float) -> float:
    """Mackenzie (1981) sound speed (m/s); NaN outside T in [-2, 30], S in [25, 40], D in [0, 8000]."""
    if not (-2 <= t <= 30 and 25 <= s <= 40 and 0 <= d <= 8000):
        return math.nan
    return mackenzie_1981(t, s, d)


def _round_decimals(value: float, decimals: int) -> float:
    if not math.isfinite(value):
        return value
    scale = 10.0**decimals
    return math.floor(value * scale + 0.5) / scale


@dataclass(frozen=True)
class Algorithm:
    name: str
    needs_references: bool
    run: Callable[[str, Sequence[str]], str]


class AlgorithmRegistry:
    """The algorithms available to one translator (modem-id ones only with a lookup table).

    The UTM datum can be changed at run time (LAT_ORIGIN/LONG_ORIGIN) with `set_datum`.
    """

    def __init__(
        self,
        lat_origin: float = 0.0,
        lon_origin: float = 0.0,
        modem_ids: ModemIdLookup | None = None,
    ) -> None:
        self.geodesy = UTMGeodesy(lat_origin, lon_origin)
        self.modem_ids = modem_ids
        self._algorithms: dict[str, Algorithm] = {}
        self._register_builtin()

    def set_datum(self, lat_origin: float, lon_origin: float) -> None:
        self.geodesy = UTMGeodesy(lat_origin, lon_origin)

    def names(self) -> list[str]:
        return sorted(self._algorithms)

    def find(self, name: str) -> Algorithm | None:
        return self._algorithms.get(name)

    def unknown_reason(self, name: str) -> str:
        """Why `name` is not an algorithm of this registry."""
        hint = ""
        if name in ("modem_id2name", "modem_id2type", "name2modem_id"):
            hint = " (needs modem_id_lookup_path)"
        return f"unknown algorithm {name!r}{hint}"

    def run(self, name: str, value: str, references: Sequence[str] = ()) -> str:
        algorithm = self._algorithms.get(name)
        # goby3 ignores an algorithm it does not know: the value passes through unchanged
        # (QUIRKS.md Q-APPS-26).
        return value if algorithm is None else algorithm.run(value, references)

    def _add(self, name: str, run: Callable[[str, Sequence[str]], str], refs: bool = False) -> None:
        self._algorithms[name] = Algorithm(name, refs, run)

    def _simple_numeric(self, name: str, fn: Callable[[float], float]) -> None:
        self._add(name, lambda v, _r: render_double(fn(numeric(v))))

    def _register_builtin(self) -> None:
        self._add("to_upper", lambda v, _r: v.upper())
        self._add("to_lower", lambda v, _r: v.lower())
        self._simple_numeric("angle_0_360", lambda x: _wrap(x, 0.0))
        self._simple_numeric("angle_-180_180", lambda x: _wrap(x, -180.0))
        self._simple_numeric("abs", abs)
        self._simple_numeric("power_to_dB", _power_to_db)
        self._simple_numeric("dB_to_power", _db_to_power)
        self._add("lat2hemisphere_initial", lambda v, _r: "S" if numeric(v) < 0 else "N")
        self._add("lon2hemisphere_initial", lambda v, _r: "W" if numeric(v) < 0 else "E")
        self._add("lat2nmea_lat", lambda v, _r: _nmea_angle(numeric(v), 2))
        self._add("lon2nmea_lon", lambda v, _r: _nmea_angle(numeric(v), 3))
        self._add("unix_time2nmea_time", lambda v, _r: _nmea_time(numeric(v)))
        self._add(
            "add", lambda v, r: render_double(numeric(v) + sum(numeric(x) for x in r)), refs=True
        )
        self._add(
            "subtract",
            lambda v, r: render_double(numeric(v) - sum(numeric(x) for x in r)),
            refs=True,
        )
        self._add("TSD_to_soundspeed", self._soundspeed, refs=True)
        self._add("lat2utm_y", self._lat2utm_y, refs=True)
        self._add("lon2utm_x", self._lon2utm_x, refs=True)
        self._add("utm_x2lon", self._utm_x2lon, refs=True)
        self._add("utm_y2lat", self._utm_y2lat, refs=True)
        if self.modem_ids is not None:
            self._add("modem_id2name", self._modem_id2name)
            self._add("modem_id2type", self._modem_id2type)
            lookup = self.modem_ids
            self._add("name2modem_id", lambda v, _r: str(lookup.modem_id(v)))

    @staticmethod
    def _reference(name: str, refs: Sequence[str], count: int) -> list[float]:
        if len(refs) < count:
            raise TranslatorConfigError(f"algorithm {name!r} needs {count} reference field(s)")
        return [numeric(r) for r in refs[:count]]

    def _soundspeed(self, value: str, refs: Sequence[str]) -> str:
        salinity, depth = self._reference("TSD_to_soundspeed", refs, 2)
        return render_double(mackenzie_soundspeed(numeric(value), salinity, depth), 3)

    def _lat2utm_y(self, value: str, refs: Sequence[str]) -> str:
        (lon,) = self._reference("lat2utm_y", refs, 1)
        return render_double(self.geodesy.to_local(numeric(value), lon)[1])

    def _lon2utm_x(self, value: str, refs: Sequence[str]) -> str:
        (lat,) = self._reference("lon2utm_x", refs, 1)
        return render_double(self.geodesy.to_local(lat, numeric(value))[0])

    def _utm_x2lon(self, value: str, refs: Sequence[str]) -> str:
        (y,) = self._reference("utm_x2lon", refs, 1)
        lon = self.geodesy.to_geo(numeric(value), y)[1]
        return render_double(_round_decimals(lon, 11))

    def _utm_y2lat(self, value: str, refs: Sequence[str]) -> str:
        (x,) = self._reference("utm_y2lat", refs, 1)
        lat = self.geodesy.to_geo(x, numeric(value))[0]
        return render_double(_round_decimals(lat, 12))

    @staticmethod
    def _modem_id(value: str) -> int | None:
        """The id a modem_id2* algorithm looks up; None leaves the value unchanged (goby3
        throws on an empty value or one beyond an unsigned int: QUIRKS.md Q-APPS-11)."""
        if not (value.isascii() and value.isdigit()) or significant_digits(value) > 10:
            return None
        modem_id = int(value)
        return modem_id if modem_id < 2**32 else None

    def _modem_id2name(self, value: str, _refs: Sequence[str]) -> str:
        assert self.modem_ids is not None  # (registered only with a lookup)
        modem_id = self._modem_id(value)
        return value if modem_id is None else self.modem_ids.name(modem_id)

    def _modem_id2type(self, value: str, _refs: Sequence[str]) -> str:
        assert self.modem_ids is not None  # (registered only with a lookup)
        modem_id = self._modem_id(value)
        return value if modem_id is None else self.modem_ids.type(modem_id)


def run_publish_algorithms(msg: Message, algorithms, registry: AlgorithmRegistry) -> dict[int, str]:
    """Run publish-side algorithms on `msg`; returns {output_virtual_field: value}.

    Algorithms with the same output field chain in declaration order (the later ones take the
    previous output). An algorithm whose primary field is missing or repeated is skipped.
    """
    from pygoby.moos.translator.textformat import field_value_text

    descriptor = msg.DESCRIPTOR
    outputs: dict[int, str] = {}
    for algorithm in algorithms:
        primary = descriptor.fields_by_number.get(algorithm.primary_field)
        if primary is None or primary.is_repeated:
            continue
        if algorithm.output_virtual_field in outputs:
            value = outputs[algorithm.output_virtual_field]
        else:
            value = field_value_text(primary, getattr(msg, primary.name)).strip('"')
        references = []
        for number in algorithm.reference_field:
            field = descriptor.fields_by_number.get(number)
            if field is None or field.is_repeated:
                raise TranslatorConfigError(
                    f"algorithm {algorithm.name!r}: reference field {number} of "
                    f"{descriptor.full_name} is missing or repeated (must be optional or required)"
                )
            references.append(field_value_text(field, getattr(msg, field.name)))
        outputs[algorithm.output_virtual_field] = registry.run(algorithm.name, value, references)
    return outputs
