"""iCommander's "specials": placeholders typed into numeric fields and replaced
when the message is sent.

* `_time`: the current time (UNIX seconds).
* local x/y in metres -> latitude/longitude with the mission's datum: the last Goby 1 code
  writes `_y:<metres>` into the latitude field and `_x:<metres>` into the longitude field and
  pairs them in order of appearance; the Goby 1.1 manual writes `y(lat)1:<metres>` /
  `x(lon)1:<metres>`, the number pairing them. Both are accepted (and kept as typed in save
  files).

"Community" and "modem id" insert plain values when chosen, so they need no placeholder.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Sequence

from pygoby.topside.errors import SpecialError

TIME = "_time"
_XY = re.compile(r"^(?:_(?P<axis>[xy])|(?P<axis1>[xy])\((?:lat|lon)\)(?P<pair>\d+)):(?P<value>.*)$")
_PREFIXES = (TIME, "_x:", "_y:", "x(lon)", "y(lat)")
_NUMBERING = re.compile(r"[xy]\((?:lat|lon)\)\d*")


def is_placeholder(text: str, *, partial: bool = False) -> bool:
    """Is `text` a placeholder (or, with `partial`, the beginning of one)?"""
    if text == TIME:
        return True
    match = _XY.match(text)
    if match is not None:
        value = match["value"]
        if partial and value in ("", "-", "+", ".", "-."):
            return True
        try:
            float(value)
        except ValueError:
            return False
        return True
    if not partial or not text:
        return False
    return any(p.startswith(text) for p in _PREFIXES) or bool(_NUMBERING.fullmatch(text))


def xy_placeholder(axis: str, metres: str = "", pair: int | None = None) -> str:
    """The placeholder text for a y (latitude) or x (longitude) field."""
    if pair is None:
        return f"_{axis}:{metres}"
    return f"{axis}({'lat' if axis == 'y' else 'lon'}){pair}:{metres}"


def lat_lon_pairs(names: Sequence[str]) -> list[tuple[int, int]]:
    """(latitude index, longitude index) pairs of neighbouring fields whose names contain
    "lat" and "lon" (how Goby 1's iCommander found where the x of a y goes)."""
    pairs = []
    used: set[int] = set()
    lowered = [n.lower() for n in names]
    for i, name in enumerate(lowered):
        if "lat" not in name or i in used:
            continue
        for j in (i + 1, i - 1):
            if 0 <= j < len(lowered) and j not in used and "lon" in lowered[j]:
                pairs.append((i, j))
                used.update((i, j))
                break
    return pairs


def substitute(
    values: Sequence[str], now: float, to_geo: Callable[[float, float], tuple[float, float]]
) -> list[str]:
    """`values` with every placeholder replaced: `_time` by `now`, x/y pairs by the
    longitude/latitude `to_geo(x, y) -> (lat, lon)` gives. Other values are returned as they
    are."""
    out = list(values)
    pending: dict[str, list[tuple[int, float]]] = {"x": [], "y": []}
    numbered: dict[int, dict[str, tuple[int, float]]] = {}
    for index, text in enumerate(values):
        if text == TIME:
            out[index] = repr(float(now))
            continue
        match = _XY.match(text)
        if match is None:
            continue
        try:
            metres = float(match["value"])
        except ValueError:
            raise SpecialError(f"{text!r}: metres expected after the colon") from None
        if match["axis"]:
            pending[match["axis"]].append((index, metres))
        else:
            numbered.setdefault(int(match["pair"]), {})[match["axis1"]] = (index, metres)
    pairs = list(zip(pending["y"], pending["x"], strict=False))
    if len(pending["y"]) != len(pending["x"]):
        raise SpecialError("every _y: (latitude) needs an _x: (longitude) and the reverse")
    for number, pair in sorted(numbered.items()):
        if set(pair) != {"x", "y"}:
            raise SpecialError(f"y(lat){number} and x(lon){number} must both be given")
        pairs.append((pair["y"], pair["x"]))
    for (y_index, y), (x_index, x) in pairs:
        lat, lon = to_geo(x, y)
        out[y_index], out[x_index] = repr(lat), repr(lon)
    return out
