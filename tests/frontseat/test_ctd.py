"""CTD sample completion (spec goby-moos-apps.md 5.7) against the published check values.

Check values (N. P. Fofonoff and R. C. Millard Jr., "Algorithms for computation of fundamental
properties of seawater", UNESCO Tech. Pap. Mar. Sci. 44, 1983):
* PSS-78: S = 35 at R = 1, T = 15 degC, p = 0 (the scale's definition); S = 37.246 at
  R = 1.2, 20 degC, 2000 dbar; S = 27.995 at R = 0.65, 5 degC, 1500 dbar (as listed in the
  R package wql's ec2pss documentation, search.r-project.org/CRAN/refmans/wql/html/ec2pss.html);
  S = 40.0000 at R = 1.888091, 40 degC, 10000 dbar (UNESCO 44's SAL78 check value).
* Depth: 9712.653 m at 10000 dbar, latitude 30 deg (UNESCO 44 / Saunders & Fofonoff, as quoted
  by the US JGOFS data office, usjgofs.whoi.edu/datasys/depth-calculated.html).
* EOS-80: sigma = 59.82037 kg/m^3 at S = 40, 40 degC, 10000 dbar (UNESCO 44 SVAN check value),
  and UNESCO 44's in-situ density table (from UNESCO Report 38), e.g. 1027.67547 kg/m^3 at
  S = 35, 5 degC, 0 dbar (reproduced in the R package oce's swRho documentation).
* Mackenzie (1981), J. Acoust. Soc. Am. 70(3) 807-812: 1550.744 m/s at 25 degC, S 35, 1000 m.
"""

from __future__ import annotations

import logging
import math

import gsw
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.ctd import (
    compute_missing_ctd,
    conductivity_ratio,
    density_anomaly,
    depth_from_pressure,
    mackenzie_sound_speed,
    practical_salinity,
)
from pygoby.util.clock import VirtualClock
from tests.hypothesis_profiles import examples

from .scripted_driver import ScriptedFrontSeat

CTD = frontseat_pb.CTDSample
PA_PER_DBAR = 1e4


@pytest.mark.parametrize(
    ("ratio", "t", "p", "salinity", "tol"),
    [
        (1.0, 15.0, 0.0, 35.0, 1e-6),
        (1.2, 20.0, 2000.0, 37.246, 5e-4),
        (0.65, 5.0, 1500.0, 27.995, 5e-4),
        (1.888091, 40.0, 10000.0, 40.0000, 5e-5),
    ],
)
def test_pss78_check_values(ratio, t, p, salinity, tol) -> None:
    assert practical_salinity(ratio, t, p) == pytest.approx(salinity, abs=tol)


def test_pss78_zero_trap() -> None:
    assert practical_salinity(4e-4, 10.0, 0.0) == 0.0
    assert practical_salinity(0.0, 10.0, 100.0) == 0.0


@settings(max_examples=examples(200), deadline=None)
@given(
    ratio=st.floats(0.1, 1.4),
    t90=st.floats(-2.0, 35.0),
    p=st.floats(0.0, 10000.0),
)
def test_pss78_agrees_with_gsw(ratio, t90, p) -> None:
    """TEOS-10's GSW implements PSS-78 too (on ITS-90 input; PSS-78 is defined on IPTS-68)."""
    expected = float(gsw.SP_from_C(ratio * 42.914, t90, p))
    if expected < 2.0:  # GSW switches to the Hill et al. (1986) low-salinity extension
        return
    assert practical_salinity(ratio, t90 * 1.00024, p) == pytest.approx(expected, abs=1e-9)


def test_conductivity_ratio_from_siemens_per_metre() -> None:
    assert conductivity_ratio(4.2914) == pytest.approx(1.0)


def test_depth_check_value() -> None:
    assert depth_from_pressure(10000.0, 30.0) == pytest.approx(9712.653, abs=5e-4)
    assert depth_from_pressure(0.0, 45.0) == 0.0
    # more gravity towards the poles: the same pressure is a shallower depth
    assert depth_from_pressure(1000.0, 80.0) < depth_from_pressure(1000.0, 0.0)


def test_density_anomaly_check_value() -> None:
    assert density_anomaly(40.0, 40.0, 10000.0) == pytest.approx(59.82037, abs=1e-5)


@pytest.mark.parametrize(
    ("s", "t", "p", "rho"),
    [
        (0.0, 5.0, 0.0, 999.96675),
        (0.0, 5.0, 10000.0, 1044.12802),
        (0.0, 25.0, 0.0, 997.04796),
        (0.0, 25.0, 10000.0, 1037.90204),
        (35.0, 5.0, 0.0, 1027.67547),
        (35.0, 5.0, 10000.0, 1069.48914),
        (35.0, 25.0, 0.0, 1023.34306),
        (35.0, 25.0, 10000.0, 1062.53817),
    ],
)
def test_eos80_density_table(s, t, p, rho) -> None:
    assert density_anomaly(s, t, p) + 1000.0 == pytest.approx(rho, abs=1e-5)


def test_mackenzie_check_value_and_range() -> None:
    assert mackenzie_sound_speed(25.0, 35.0, 1000.0) == pytest.approx(1550.744, abs=1e-3)
    assert mackenzie_sound_speed(30.0, 40.0, 8000.0) > 0  # the range is inclusive
    for args in [(31.0, 35.0, 10.0), (-2.5, 35.0, 10.0), (10.0, 24.9, 10.0), (10.0, 41.0, 10.0)]:
        assert math.isnan(mackenzie_sound_speed(*args))
    for args in [(10.0, 35.0, -0.1), (10.0, 35.0, 8000.5), (math.nan, 35.0, 10.0)]:
        assert math.isnan(mackenzie_sound_speed(*args))


def sample(**fields):
    ctd = CTD(time=1.0, **fields)
    return ctd


def test_compute_missing_fills_everything_from_c_t_p_and_latitude() -> None:
    ctd = sample(conductivity=4.2914, temperature=15.0, pressure=0.0)
    ctd.global_fix.lat, ctd.global_fix.lon = 42.0, -70.0
    compute_missing_ctd(ctd)
    assert ctd.salinity == pytest.approx(35.0, abs=1e-6)
    assert ctd.global_fix.depth == 0.0
    assert ctd.sound_speed == pytest.approx(1506.6, abs=0.1)  # Mackenzie at 15 degC, 35, 0 m
    assert ctd.density == pytest.approx(1000.0 + density_anomaly(35.0, 15.0, 0.0))
    assert 1025.9 < ctd.density < 1026.0  # in-situ density, not sigma
    assert ctd.salinity_algorithm == CTD.UNESCO_44_PREKIN_AND_LEWIS_1980
    assert ctd.sound_speed_algorithm == CTD.MACKENZIE_1981
    assert ctd.density_algorithm == CTD.UNESCO_38_MILLERO_AND_POISSON_1981
    assert ctd.IsInitialized()


def test_pressure_is_in_pascal() -> None:
    ctd = sample(conductivity=1.888091 * 4.2914, temperature=40.0, pressure=10000 * PA_PER_DBAR)
    ctd.global_fix.lat, ctd.global_fix.lon = 30.0, 0.0
    compute_missing_ctd(ctd)
    assert ctd.salinity == pytest.approx(40.0, abs=5e-5)
    assert ctd.global_fix.depth == pytest.approx(9712.653, abs=5e-4)
    assert ctd.density == pytest.approx(1059.82037, abs=1e-4)
    # 40 degC and 9.7 km are outside Mackenzie's ranges
    assert math.isnan(ctd.sound_speed)
    assert ctd.sound_speed_algorithm == CTD.MACKENZIE_1981


def test_present_values_are_kept() -> None:
    ctd = sample(
        conductivity=4.0,
        temperature=10.0,
        pressure=1e5,
        salinity=33.0,
        sound_speed=1490.0,
        density=1025.5,
    )
    ctd.global_fix.lat, ctd.global_fix.lon, ctd.global_fix.depth = 10.0, 20.0, 9.5
    before = ctd.SerializeToString()
    compute_missing_ctd(ctd)
    assert ctd.SerializeToString() == before
    assert not ctd.HasField("salinity_algorithm")


def test_given_salinity_and_depth_feed_the_rest() -> None:
    ctd = sample(temperature=25.0, pressure=1000 * PA_PER_DBAR, salinity=35.0)
    ctd.global_fix.lat, ctd.global_fix.lon, ctd.global_fix.depth = 0.0, 0.0, 1000.0
    compute_missing_ctd(ctd)
    assert ctd.sound_speed == pytest.approx(1550.744, abs=1e-3)
    assert ctd.global_fix.depth == 1000.0
    assert not ctd.HasField("salinity_algorithm")
    assert ctd.density == pytest.approx(1000.0 + density_anomaly(35.0, 25.0, 1000.0))


def test_out_of_range_sound_speed_is_nan_with_a_warning(caplog) -> None:
    ctd = sample(temperature=31.0, pressure=0.0, salinity=35.0)
    ctd.global_fix.lat, ctd.global_fix.lon = 0.0, 0.0
    with caplog.at_level(logging.WARNING):
        compute_missing_ctd(ctd)
    assert math.isnan(ctd.sound_speed)
    assert "Mackenzie" in caplog.text
    assert math.isfinite(ctd.density)


def test_unknown_latitude_gives_nan_depth() -> None:
    """The legacy CTD path has NaN lat/lon until the first NodeStatus."""
    ctd = sample(conductivity=4.2914, temperature=15.0, pressure=5e4)
    ctd.global_fix.lat, ctd.global_fix.lon = math.nan, math.nan
    compute_missing_ctd(ctd)
    assert math.isnan(ctd.global_fix.depth)
    assert math.isnan(ctd.sound_speed)
    assert ctd.salinity == pytest.approx(practical_salinity(1.0, 15.0, 5.0))


def test_no_conductivity_and_no_salinity(caplog) -> None:
    ctd = sample(temperature=10.0, pressure=0.0)
    ctd.global_fix.lat, ctd.global_fix.lon = 0.0, 0.0
    with caplog.at_level(logging.WARNING):
        compute_missing_ctd(ctd)
    assert math.isnan(ctd.salinity)
    assert "neither salinity nor conductivity" in caplog.text
    assert math.isnan(ctd.density)
    assert not ctd.HasField("salinity_algorithm")


def test_interface_base_delegates() -> None:
    driver = ScriptedFrontSeat(frontseat_pb.Config(), VirtualClock(0))
    ctd = sample(conductivity=4.2914, temperature=15.0, pressure=0.0)
    ctd.global_fix.lat, ctd.global_fix.lon = 42.0, -70.0
    driver.compute_missing_ctd(ctd)
    assert ctd.salinity == pytest.approx(35.0, abs=1e-6)
    assert ctd.IsInitialized()
