"""The empirical channel's pieces against independent implementations, and the BELLHOP model.

Independent implementations used (tolerances stated per test):

* BELLHOP (Acoustics Toolbox, run in process by `pelagic`): its own Thorp and Francois-Garrison
  volume attenuation, read from the imaginary part of the direct arrival's delay;
* arlpy 1.9.3 `arlpy.uwa.soundspeed` (Mackenzie 1981) and `arlpy.uwa.absorption`
  (Francois-Garrison), recorded in data/arlpy_uwa.json (arlpy pins numpy < 2, so it runs outside
  this environment; recorded with repr precision);
* the python `seawater` package's `svel` (UNESCO 1983), recorded in data/seawater_svel.json.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest

from pygoby.netsim.channel.absorption import francois_garrison, thorp, thorp_coa
from pygoby.netsim.channel.propagation import BellhopLoss, BellhopSettings
from pygoby.netsim.channel.soundspeed import t68_from_t90, unesco_1983
from pygoby.netsim.sim.scenario import channel_config, parse_scenario
from pygoby.netsim.sim.simulation import Simulation
from pygoby.util.ocean import mackenzie_1981

pelagic = pytest.importorskip("pelagic")  # (installed by `make test`: pygoby[dev])
DATA = Path(__file__).parent / "data"
NEPER_DB = 20 * math.log10(math.e)


def bellhop_attenuation(volume, f_hz: float) -> float:
    """dB/km of BELLHOP's volume attenuation: the direct arrival's amplitude decay
    exp(-2 pi f Im(tau)) over 1, 2 and 4 km in deep isovelocity water (the same at each)."""
    case = {
        "pelagic": 2,
        "model": "bellhop",
        "title": "attenuation",
        "frequency": f_hz,
        "interpolation": "c_linear",
        "attenuation": {"volume": volume},
        "media": [{"to": 5000.0, "ssp": [[0, 1500], [5000, 1500]], "mesh": 0}],
        "surface": "vacuum",
        "bottom": {"type": "halfspace", "cp": 1600, "rho": 1.6, "ap": 0.1},
        "source": {"depth": [2500.0]},
        "receivers": {"depth": [2500.0], "range": [1000.0, 2000.0, 4000.0]},
        "bellhop": {
            "run": "arrivals",
            "beam": "geometric_hat_cartesian",
            "angles": {"from": -30, "to": 30, "count": 601},
            "box": {"depth": 5001.0, "range": 5000.0},
        },
    }
    arrivals = pelagic.bellhop.Case.from_dict(case).run().arrivals
    per_km = set()
    for i, range_m in enumerate(arrivals.ranges_m):
        first, last = int(arrivals.arrival_offset[i]), int(arrivals.arrival_offset[i + 1])
        direct = [
            j
            for j in range(first, last)
            if arrivals.top_bounces[j] == 0 and arrivals.bottom_bounces[j] == 0
        ]
        assert direct, f"no direct arrival at {range_m} m"
        im_tau = abs(float(arrivals.attenuation_time_s[direct[0]]))
        per_km.add(round(NEPER_DB * 2 * math.pi * f_hz * im_tau / (range_m / 1000), 9))
    assert len(per_km) == 1, per_km  # attenuation proportional to range
    return per_km.pop()


FREQUENCIES_KHZ = (1.0, 3.5, 10.0, 25.0, 50.0)


@pytest.mark.parametrize("f_khz", FREQUENCIES_KHZ)
def test_thorp_against_bellhop(f_khz):
    """BELLHOP's Thorp is the Jensen et al. ("COA") form: `thorp_coa` to 1e-6 relative. Our
    default `thorp` (Stojanovic's form) differs from it only by the published coefficients,
    3.3e-3 - 3e-3 + (3e-4 - 2.75e-4) f^2 dB/km: checked to 1e-6 dB/km."""
    bellhop = bellhop_attenuation("thorp", f_khz * 1000)
    assert thorp_coa(f_khz) == pytest.approx(bellhop, rel=1e-6)
    assert bellhop - thorp(f_khz) == pytest.approx(3e-4 + 2.5e-5 * f_khz**2, abs=1e-6)


@pytest.mark.parametrize("f_khz", FREQUENCIES_KHZ)
@pytest.mark.parametrize(
    "T, S, D, pH", [(10, 35, 100, 8.0), (4, 34.5, 1000, 7.8), (27, 35, 10, 8.1), (22, 30, 0, 8.2)]
)
def test_francois_garrison_against_bellhop(f_khz, T, S, D, pH):
    """BELLHOP's Francois-Garrison volume attenuation: 1e-6 relative."""
    volume = {"type": "francois_garrison", "temperature": T, "salinity": S, "ph": pH, "depth": D}
    assert francois_garrison(f_khz, T, S, D, pH) == pytest.approx(
        bellhop_attenuation(volume, f_khz * 1000), rel=1e-6
    )


def test_francois_garrison_against_arlpy():
    """arlpy.uwa.absorption over 288 cases (1-50 kHz, 4-27 degC, 30-35 ppt, 0-1000 m, pH
    7.7-8.1): 1e-12 relative (the same formula; only float rounding differs)."""
    cases = json.loads((DATA / "arlpy_uwa.json").read_text())["absorption"]
    assert len(cases) == 288
    for c in cases:
        ours = francois_garrison(c["f_hz"] / 1000, c["T"], c["S"], c["D"], c["pH"])
        assert ours == pytest.approx(c["db_per_km"], rel=1e-12), c


def test_mackenzie_against_arlpy():
    """arlpy.uwa.soundspeed (Mackenzie 1981) over 48 cases (2-27 degC, 25-40 ppt, 0-4000 m):
    1e-9 m/s."""
    cases = json.loads((DATA / "arlpy_uwa.json").read_text())["soundspeed"]
    assert len(cases) == 48
    for c in cases:
        assert mackenzie_1981(c["T"], c["S"], c["D"]) == pytest.approx(c["c"], abs=1e-9), c


def test_unesco_against_seawater():
    """seawater.svel (UNESCO 1983, ITS-90 input converted to IPTS-68) over 64 cases (0-40 ppt,
    0-40 degC, 0-10000 dbar): 1e-9 m/s."""
    cases = json.loads((DATA / "seawater_svel.json").read_text())["svel"]
    assert len(cases) == 64
    for c in cases:
        ours = unesco_1983(c["S"], t68_from_t90(c["T90"]), c["P_dbar"])
        assert ours == pytest.approx(c["c"], abs=1e-9), c


# -- the BELLHOP propagation model -----------------------------------------------------------------


def free_field_model(**overrides) -> BellhopLoss:
    """Deep isovelocity water with a bottom matched to it (no reflection): only the direct
    path and its surface image remain."""
    settings = {
        "water_depth": 5000.0,
        "bottom_speed": 1500.0,
        "bottom_density": 1.0,
        "bottom_attenuation": 0.0,
        "max_range": 4000.0,
        "range_step": 100.0,
        "depth_step": 250.0,
        "source_depth_step": 50.0,
        "beams": 1000,
    }
    settings.update(overrides)
    return BellhopLoss(BellhopSettings(**settings), sound_speed=1500.0, spreading=2.0)


def test_bellhop_loss_is_direct_path_plus_surface_image():
    """Incoherent loss between nodes at 1000 m depth: -10 log10(1/r1^2 + 1/r2^2) (r1 direct,
    r2 surface-reflected) within 0.05 dB, on the grid and interpolated between its points."""
    model = free_field_model()
    for r in (250.0, 700.0, 1000.0, 1550.0, 2500.0, 3900.0):
        r2 = math.hypot(r, 2000.0)
        expected = -10 * math.log10(1 / r**2 + 1 / r2**2)
        assert model.loss(25000.0, 1000.0, 1000.0, r) == pytest.approx(expected, abs=0.05), r
    assert model.traced == 1  # one field for the one source depth and frequency


def test_bellhop_fields_are_cached_per_source_depth_bin_and_frequency():
    model = free_field_model(cached_fields=2)
    model.loss(25000.0, 1000.0, 1000.0, 500.0)
    model.loss(25000.0, 1010.0, 900.0, 800.0)  # the same 50 m bin
    assert model.traced == 1
    model.loss(25000.0, 1040.0, 900.0, 800.0)  # the next bin
    model.loss(10000.0, 1000.0, 900.0, 800.0)  # another carrier
    assert model.traced == 3
    model.loss(25000.0, 1000.0, 900.0, 800.0)  # dropped (least recently used of 2)
    assert model.traced == 4


def test_bellhop_loss_outside_the_grid():
    model = free_field_model()
    edge = model.loss(25000.0, 1000.0, 1000.0, 4000.0)
    # beyond max_range: the channel's spreading law (k = 2) from the grid's edge
    assert model.loss(25000.0, 1000.0, 1000.0, 8000.0) == pytest.approx(edge + 20 * math.log10(2))
    # inside the first range step: spherical spreading
    first = model.loss(25000.0, 1000.0, 1000.0, 100.0)
    assert model.loss(25000.0, 1000.0, 1000.0, 10.0) == pytest.approx(first - 20.0, abs=1e-9)


def test_bad_bellhop_settings_are_configuration_errors():
    from pygoby.netsim.errors import ScenarioError

    bad = SCENARIO.format(
        model="BELLHOP", bellhop="water_depth: 100 ssp { a: 0 b: 1500 } ssp { a: 50 b: 1500 }"
    )
    with pytest.raises(ScenarioError, match="channel.propagation: bellhop: the ssp must run"):
        parse_scenario(bad)
    with pytest.raises(ValueError, match="ssp must run from 0 m to the deepest bottom"):
        BellhopLoss(BellhopSettings(ssp=((0, 1500), (50, 1500)), water_depth=100))
    with pytest.raises(ValueError, match="must be positive"):
        BellhopLoss(BellhopSettings(range_step=0))


SCENARIO = """duration: 300 origin {{ lat: 42 lon: -70 }}
channel {{ spreading: 2 propagation {{ model: {model} bellhop {{ {bellhop} }} }} }}
mac {{ slot_seconds: 10 rate: 1 }}
node {{ modem_id: 1 track {{ waypoint {{ x: 0 depth: 1000 }} }} }}
node {{ modem_id: 2 track {{ waypoint {{ x: 1500 depth: 1000 }} }} }}
"""
FREE_FIELD = (
    "water_depth: 5000 bottom_speed: 1500 bottom_density: 1 bottom_attenuation: 0 "
    "max_range: 4000 range_step: 100 depth_step: 250 beams: 1000"
)


def test_a_scenario_with_the_bellhop_model():
    """The channel's received level is SL - (BELLHOP loss + Thorp absorption) for every packet."""
    scenario = parse_scenario(SCENARIO.format(model="BELLHOP", bellhop=FREE_FIELD))
    events = []
    sim = Simulation(scenario, on_event=events.append)
    sim.run_virtual()
    rx = [e for e in events if e["event"] == "rx" and e["kind"] == "data"]
    assert rx and all(e["outcome"] == "good" for e in rx)
    model = sim.channel.config.propagation
    assert model.traced == 1
    for e in rx:
        r = e["range_m"]
        expected = 185 - (
            -10 * math.log10(1 / r**2 + 1 / math.hypot(r, 2000) ** 2) + thorp(25) * r / 1000
        )
        assert e["rl"] == pytest.approx(expected, abs=0.06)
    empirical = parse_scenario(SCENARIO.format(model="EMPIRICAL", bellhop=""))
    assert channel_config(empirical).propagation is None


def test_the_environment_channel_of_a_manager_can_use_bellhop():
    from google.protobuf import text_format

    from pygoby.netsim.channel.settings import channel_config_from_proto, channel_settings_class

    settings = text_format.Parse(
        "water { temperature: 8 sound_speed_formula: UNESCO_1983 latitude: 42 } "
        "propagation { model: BELLHOP bellhop { water_depth: 60 depth_step: 10 } }",
        channel_settings_class()(),
    )
    config, _ = channel_config_from_proto(settings)
    ssp = config.propagation.ssp
    assert ssp[0][0] == 0 and ssp[-1][0] == 60 and len(ssp) == 7  # the formula, every 10 m
    assert ssp[-1][1] == pytest.approx(config.sound_speed(60.0))
