"""InterfaceBase.compute_missing(NodeStatus) and update_utm_datum (spec goby-moos-apps.md 5.7),
checked against PROJ directly through pyproj's EPSG UTM definitions."""

from __future__ import annotations

import logging
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from pyproj import Geod, Transformer

from pygoby.frontseat import messages as frontseat_pb
from pygoby.util.clock import VirtualClock
from tests.hypothesis_profiles import examples

from .scripted_driver import ScriptedFrontSeat

ORIGIN = (42.5, -70.5)  # UTM zone 19 north


def make(origin=ORIGIN, **cfg_fields) -> ScriptedFrontSeat:
    cfg = frontseat_pb.Config(**cfg_fields)
    if origin is not None:
        cfg.origin.lat, cfg.origin.lon = origin
    return ScriptedFrontSeat(cfg, VirtualClock(1_700_000_000.0))


def epsg_local(lat: float, lon: float, origin=ORIGIN, epsg: int = 32619) -> tuple[float, float]:
    """(x, y) of a point on the UTM grid of `origin`, straight from PROJ's EPSG definition."""
    to_utm = Transformer.from_crs("EPSG:4326", f"EPSG:{epsg}", always_xy=True)
    e0, n0 = to_utm.transform(origin[1], origin[0])
    e, n = to_utm.transform(lon, lat)
    return e - e0, n - n0


def global_status(lat: float, lon: float, depth: float | None = None):
    status = frontseat_pb.NodeStatus()
    status.global_fix.lat, status.global_fix.lon = lat, lon
    if depth is not None:
        status.global_fix.depth = depth
    return status


def local_status(x: float, y: float, z: float | None = None):
    status = frontseat_pb.NodeStatus()
    status.local_fix.x, status.local_fix.y = x, y
    if z is not None:
        status.local_fix.z = z
    return status


def test_local_fix_from_global_fix_matches_proj() -> None:
    driver = make()
    status = global_status(42.51, -70.48, depth=12.5)
    driver.compute_missing(status)
    x, y = epsg_local(42.51, -70.48)
    assert status.local_fix.x == pytest.approx(x, abs=1e-6)
    assert status.local_fix.y == pytest.approx(y, abs=1e-6)
    # grid distance = ellipsoidal distance x UTM scale (about 0.9998, 123 km off the central
    # meridian); the grid is rotated by the meridian convergence, so y < the 1.11 km northing
    _, _, metres = Geod(ellps="WGS84").inv(ORIGIN[1], ORIGIN[0], -70.48, 42.51)
    grid = math.hypot(status.local_fix.x, status.local_fix.y)
    assert grid == pytest.approx(metres * 0.9998, rel=1e-4)
    assert status.local_fix.z == -12.5


def test_global_fix_from_local_fix_matches_proj() -> None:
    driver = make()
    status = local_status(-2500.0, 4000.0, z=-30.0)
    driver.compute_missing(status)
    from_utm = Transformer.from_crs("EPSG:32619", "EPSG:4326", always_xy=True)
    to_utm = Transformer.from_crs("EPSG:4326", "EPSG:32619", always_xy=True)
    e0, n0 = to_utm.transform(ORIGIN[1], ORIGIN[0])
    lon, lat = from_utm.transform(e0 - 2500.0, n0 + 4000.0)
    assert status.global_fix.lat == pytest.approx(lat, abs=1e-10)
    assert status.global_fix.lon == pytest.approx(lon, abs=1e-10)
    assert status.global_fix.depth == 30.0


def test_origin_maps_to_zero() -> None:
    driver = make()
    status = global_status(*ORIGIN)
    driver.compute_missing(status)
    assert status.local_fix.x == pytest.approx(0, abs=1e-6)
    assert status.local_fix.y == pytest.approx(0, abs=1e-6)


def test_southern_hemisphere_uses_the_origin_zone() -> None:
    origin = (-33.86, 151.21)  # zone 56; offsets are the same as on the +south grid
    driver = make(origin=origin)
    status = global_status(-33.9, 151.3)
    driver.compute_missing(status)
    x, y = epsg_local(-33.9, 151.3, origin=origin, epsg=32756)
    assert status.local_fix.x == pytest.approx(x, abs=1e-6)
    assert status.local_fix.y == pytest.approx(y, abs=1e-6)
    assert y < 0


@settings(max_examples=examples(100), deadline=None)
@given(x=st.floats(-50_000, 50_000), y=st.floats(-50_000, 50_000))
def test_round_trip_local_global_local(x: float, y: float) -> None:
    driver = make()
    first = local_status(x, y)
    driver.compute_missing(first)
    back = global_status(first.global_fix.lat, first.global_fix.lon)
    driver.compute_missing(back)
    assert back.local_fix.x == pytest.approx(x, abs=1e-5)
    assert back.local_fix.y == pytest.approx(y, abs=1e-5)


def test_depth_and_z_only_when_set() -> None:
    driver = make()
    status = global_status(42.5, -70.5)
    driver.compute_missing(status)
    assert not status.local_fix.HasField("z")
    status = local_status(10.0, 20.0)
    driver.compute_missing(status)
    assert not status.global_fix.HasField("depth")


def test_name_type_and_time_filled_from_config_and_clock() -> None:
    driver = make(name="auv1", type=frontseat_pb.VehicleType.Value("GLIDER"))
    status = global_status(42.5, -70.5)
    driver.compute_missing(status)
    assert status.name == "auv1"
    assert status.type == frontseat_pb.VehicleType.Value("GLIDER")
    assert status.time == 1_700_000_000.0


def test_type_default_is_auv_and_given_values_are_kept() -> None:
    driver = make(name="auv1")
    status = global_status(42.5, -70.5)
    status.name, status.type, status.time = "other", frontseat_pb.VehicleType.Value("USV"), 5.0
    driver.compute_missing(status)
    assert (status.name, status.type, status.time) == (
        "other",
        frontseat_pb.VehicleType.Value("USV"),
        5.0,
    )
    fresh = global_status(42.5, -70.5)
    driver.compute_missing(fresh)
    assert fresh.type == frontseat_pb.VehicleType.Value("AUV")


def test_both_fixes_present_are_left_alone() -> None:
    driver = make()
    status = global_status(42.6, -70.4, depth=3)
    status.local_fix.x, status.local_fix.y, status.local_fix.z = 1.0, 2.0, -5.0
    driver.compute_missing(status)
    assert (status.global_fix.lat, status.global_fix.lon, status.global_fix.depth) == (
        42.6,
        -70.4,
        3,
    )
    assert (status.local_fix.x, status.local_fix.y, status.local_fix.z) == (1.0, 2.0, -5.0)


def test_neither_fix_warns_and_changes_no_position(caplog) -> None:
    driver = make(name="auv1")
    status = frontseat_pb.NodeStatus()
    with caplog.at_level(logging.WARNING):
        driver.compute_missing(status)
    assert "neither global_fix nor local_fix" in caplog.text
    assert not status.HasField("global_fix") and not status.HasField("local_fix")
    assert status.name == "auv1"  # the rest is still filled in


def test_update_utm_datum_recentres_the_grid() -> None:
    driver = make()
    driver.update_utm_datum(43.0, -70.0)
    status = global_status(43.0, -70.0)
    driver.compute_missing(status)
    assert status.local_fix.x == pytest.approx(0, abs=1e-6)
    assert status.local_fix.y == pytest.approx(0, abs=1e-6)
    with pytest.raises(ValueError):
        driver.update_utm_datum(math.nan, -70.0)


def test_without_a_datum_the_fix_is_not_converted(caplog) -> None:
    driver = make(origin=None)
    status = global_status(42.5, -70.5, depth=4)
    with caplog.at_level(logging.WARNING):
        driver.compute_missing(status)
    assert not status.HasField("local_fix")
    assert "no UTM datum" in caplog.text
    driver.update_utm_datum(*ORIGIN)
    driver.compute_missing(status)
    assert status.local_fix.z == -4
    assert status.IsInitialized() is False  # pose/speed are the driver's to set
    status.pose.heading, status.speed.over_ground = 90, 1.5
    assert status.IsInitialized()
