"""Transmission loss by BELLHOP ray tracing (the optional propagation model of an environment).

The default model is the empirical spreading law of `levels.transmission_loss`
(``ChannelConfig.propagation = None``). `BellhopLoss` replaces its spreading part: BELLHOP (the
Acoustics Toolbox ray tracer, run in process by the `pelagic` package, a compiled core with no
Fortran toolchain or external binary) traces the sound-speed profile and bathymetry of the
environment once per (carrier frequency, source-depth bin) and keeps the loss on a grid of
receiver ranges and depths; a packet's loss is interpolated in that grid (in dB; linear in
depth and in log range),
so a long simulation traces rays once per source depth, not per packet. The environment's
absorption (Thorp, Francois-Garrison, ...) is added by the channel along the slant range as for
the empirical model (BELLHOP's own volume attenuation is off, so the two models share it).

Geometry and limits: the environment is 2-D (range, depth), the same along every azimuth; a
source depth is rounded to `source_depth_step`; depths are kept 1 m inside the water column;
below the first grid range the loss follows spherical spreading from it, beyond `max_range` it
grows by the channel's spreading law; a shadow (no ray) is capped at `MAX_LOSS_DB`.
"""

from __future__ import annotations

import logging
import math
import warnings
from collections import OrderedDict
from collections.abc import Sequence
from dataclasses import dataclass, field

from pygoby.netsim.channel.soundspeed import SoundSpeedProfile
from pygoby.protobuf.pygoby.netsim.propagation_pb2 import Bellhop, Propagation
from pygoby.util.errors import MissingExtraError
from pygoby.util.extras import needs_extra

log = logging.getLogger(__name__)

MAX_LOSS_DB = 300.0  # a shadow zone: nothing gets through
EDGE_M = 1.0  # depths are kept this far inside the water column


@dataclass(frozen=True)
class BellhopSettings:
    """pygoby.netsim.protobuf.Bellhop (see propagation.proto for the meanings)."""

    ssp: tuple[tuple[float, float], ...] = ()
    water_depth: float = 100.0
    bathymetry: tuple[tuple[float, float], ...] = ()
    bottom_speed: float = 1600.0
    bottom_density: float = 1.6
    bottom_attenuation: float = 0.1
    max_range: float = 10000.0
    range_step: float = 50.0
    depth_step: float = 5.0
    source_depth_step: float = 5.0
    beams: int = 2000
    run: str = "incoherent"
    cached_fields: int = 64

    @classmethod
    def from_proto(cls, msg: Bellhop) -> BellhopSettings:
        return cls(
            ssp=tuple((p.a, p.b) for p in msg.ssp),
            water_depth=msg.water_depth,
            bathymetry=tuple((p.a, p.b) for p in msg.bathymetry),
            bottom_speed=msg.bottom_speed,
            bottom_density=msg.bottom_density,
            bottom_attenuation=msg.bottom_attenuation,
            max_range=msg.max_range,
            range_step=msg.range_step,
            depth_step=msg.depth_step,
            source_depth_step=msg.source_depth_step,
            beams=msg.beams,
            run=msg.Run.Name(msg.run).lower(),
            cached_fields=msg.cached_fields,
        )

    @property
    def deepest(self) -> float:
        return max([self.water_depth] if not self.bathymetry else [d for _, d in self.bathymetry])


@dataclass
class LossGrid:
    """Loss (dB, without absorption) on a uniform grid: `loss[i][j]` at depths[i], ranges[j]
    (ranges > 0), interpolated linearly in depth and in log(range)."""

    ranges: list[float]
    depths: list[float]
    loss: list[list[float]]
    seconds: float = 0.0  # what BELLHOP took (wall)
    cpu_seconds: float = 0.0  # (this process' CPU time meanwhile)

    def at(self, depth: float, range_m: float) -> float:
        """Interpolated inside the grid (the caller handles ranges outside it)."""
        depths, ranges = self.depths, self.ranges
        depth = min(max(depth, depths[0]), depths[-1])
        di = _cell(depths, depth)
        ri = _cell(ranges, range_m)
        fd = (depth - depths[di]) / (depths[di + 1] - depths[di]) if len(depths) > 1 else 0.0
        # in log range: exact for a power law (spreading), the bulk of the curvature
        fr = math.log(range_m / ranges[ri]) / math.log(ranges[ri + 1] / ranges[ri])
        row0, row1 = self.loss[di], self.loss[min(di + 1, len(depths) - 1)]
        near = row0[ri] + (row0[ri + 1] - row0[ri]) * fr
        far = row1[ri] + (row1[ri + 1] - row1[ri]) * fr
        return near + (far - near) * fd


def _cell(axis: list[float], value: float) -> int:
    """Index of the lower corner of the cell of a uniform axis that holds value."""
    if len(axis) < 2:
        return 0
    step = axis[1] - axis[0]
    return min(max(int((value - axis[0]) / step), 0), len(axis) - 2)


@dataclass
class BellhopLoss:
    """The BELLHOP transmission-loss model of one environment (see the module docstring)."""

    settings: BellhopSettings
    sound_speed: float | SoundSpeedProfile = 1500.0
    spreading: float = 1.5
    _fields: OrderedDict = field(default_factory=OrderedDict, repr=False)
    traced: int = 0  # fields computed
    tracing_seconds: float = 0.0  # wall time of those
    tracing_cpu_seconds: float = 0.0

    def __post_init__(self) -> None:
        s = self.settings
        if s.range_step <= 0 or s.depth_step <= 0 or s.source_depth_step <= 0 or s.beams < 1:
            raise ValueError(
                "bellhop: range_step, depth_step, source_depth_step and beams must be positive"
            )
        if s.max_range < 2 * s.range_step or s.deepest <= 2 * EDGE_M:
            raise ValueError(
                "bellhop: max_range must span two range steps and the water must be deeper than 2 m"
            )
        if s.ssp and (s.ssp[0][0] > 0 or s.ssp[-1][0] < s.deepest):
            raise ValueError(
                f"bellhop: the ssp must run from 0 m to the deepest bottom ({s.deepest:g} m)"
            )
        self.ssp = list(s.ssp) if s.ssp else self._sampled_profile()
        try:  # checked now: a missing package is a configuration error
            with needs_extra("bellhop", "the BELLHOP model"):
                import pelagic  # noqa: F401
        except MissingExtraError as exc:
            raise ValueError(str(exc)) from None

    def _sampled_profile(self) -> list[tuple[float, float]]:
        deepest, c = self.settings.deepest, self.sound_speed
        if isinstance(c, (int, float)):
            return [(0.0, float(c)), (deepest, float(c))]
        steps = max(1, math.ceil(deepest / self.settings.depth_step))
        return [(deepest * i / steps, c(deepest * i / steps)) for i in range(steps + 1)]

    def source_depth_bin(self, depth: float) -> float:
        step = self.settings.source_depth_step
        top = (
            self.settings.bathymetry[0][1]
            if self.settings.bathymetry
            else self.settings.water_depth
        )
        return min(max(round(depth / step) * step, EDGE_M), top - EDGE_M)

    def loss(
        self, carrier_hz: float, source_depth: float, receiver_depth: float, slant_range: float
    ) -> float:
        """Loss in dB (without absorption) between nodes at these depths and slant range."""
        grid = self.grid(carrier_hz, self.source_depth_bin(source_depth))
        dz = receiver_depth - source_depth
        horizontal = math.sqrt(max(slant_range * slant_range - dz * dz, 0.0))
        first, last = grid.ranges[0], grid.ranges[-1]
        if horizontal < first:  # spherical spreading inside the first grid range
            near = math.hypot(first, dz)
            return grid.at(receiver_depth, first) - 20 * math.log10(near / max(slant_range, 1.0))
        if horizontal > last:
            edge = math.hypot(last, dz)
            return grid.at(receiver_depth, last) + self.spreading * 10 * math.log10(
                slant_range / edge
            )
        return grid.at(receiver_depth, horizontal)

    def grid(self, carrier_hz: float, source_depth: float) -> LossGrid:
        """The loss grid for a source depth (already binned), traced on first use."""
        key = (carrier_hz, source_depth)
        grid = self._fields.get(key)
        if grid is not None:
            self._fields.move_to_end(key)
            return grid
        grid = self.trace(carrier_hz, source_depth)
        self.traced += 1
        self.tracing_seconds += grid.seconds
        self.tracing_cpu_seconds += grid.cpu_seconds
        self._fields[key] = grid
        while len(self._fields) > self.settings.cached_fields:
            self._fields.popitem(last=False)
        return grid

    def case(
        self,
        carrier_hz: float,
        source_depth: float,
        ranges: Sequence[float],
        depths: Sequence[float],
    ) -> dict:
        """The pelagic (BELLHOP JSON v2) case for one source depth."""
        s = self.settings
        bottom: dict = {
            "type": "halfspace",
            "cp": s.bottom_speed,
            "rho": s.bottom_density,
            "ap": s.bottom_attenuation,
        }
        if s.bathymetry:
            bottom["shape"] = {"points": [list(p) for p in s.bathymetry]}
        return {
            "pelagic": 2,
            "model": "bellhop",
            "title": "pygoby netsim",
            "frequency": carrier_hz,
            "interpolation": "c_linear",
            "media": [{"to": s.deepest, "ssp": [list(p) for p in self.ssp], "mesh": 0}],
            "surface": "vacuum",
            "bottom": bottom,
            "source": {"depth": [source_depth]},
            "receivers": {"depth": list(depths), "range": list(ranges)},
            "bellhop": {
                "run": s.run,
                "beam": "geometric_hat_cartesian",
                "angles": {"from": -89.0, "to": 89.0, "count": s.beams},
                "box": {"depth": s.deepest * 1.01, "range": s.max_range * 1.01 + s.range_step},
            },
        }

    def trace(self, carrier_hz: float, source_depth: float) -> LossGrid:
        import time

        import numpy as np
        import pelagic

        s = self.settings
        count = int(s.max_range / s.range_step)
        ranges = [s.range_step * (i + 1) for i in range(count)]
        rows = max(1, math.ceil((s.deepest - 2 * EDGE_M) / s.depth_step))
        depths = [EDGE_M + (s.deepest - 2 * EDGE_M) * i / rows for i in range(rows + 1)]
        started, cpu_started = time.perf_counter(), time.process_time()
        with warnings.catch_warnings(record=True) as caught:
            warnings.simplefilter("always")
            try:
                result = pelagic.bellhop.Case.from_dict(
                    self.case(carrier_hz, source_depth, ranges, depths)
                ).run()
            except pelagic.PelagicError as exc:
                raise ValueError(f"BELLHOP: {exc}") from None
        for warning in caught:
            log.info("BELLHOP: %s", warning.message)
        with np.errstate(divide="ignore"):
            loss = np.minimum(result.field.transmission_loss()[0], MAX_LOSS_DB)
        seconds, cpu = time.perf_counter() - started, time.process_time() - cpu_started
        log.debug(
            "BELLHOP field for %g Hz, source at %g m: %d x %d in %.2f s",
            carrier_hz,
            source_depth,
            len(depths),
            len(ranges),
            seconds,
        )
        return LossGrid(ranges, depths, loss.astype(float).tolist(), seconds, cpu)


def propagation_model(msg: Propagation | None, sound_speed, spreading: float) -> BellhopLoss | None:
    """The model a `pygoby.netsim.protobuf.Propagation` asks for (None: empirical).
    Raises ValueError."""
    if msg is None or msg.model == msg.EMPIRICAL:
        return None
    return BellhopLoss(BellhopSettings.from_proto(msg.bellhop), sound_speed, spreading)
