"""Driver loading (spec goby-moos-apps.md 5.1): entry points, upstream library names, module
paths, and the errors for everything else."""

from __future__ import annotations

from importlib.metadata import entry_points

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.plugins import (
    DRIVER_ENV_VAR,
    ENTRY_POINT_GROUP,
    DriverLoadError,
    available_drivers,
    canonical_name,
    driver_name_from,
    find_driver,
    load_driver,
)
from pygoby.util.clock import VirtualClock
from tests.hypothesis_profiles import examples

from .scripted_driver import ScriptedFrontSeat

TEST_MODULE = "tests.frontseat.scripted_driver"


def cfg():
    return frontseat_pb.Config(name="auv1", require_helm=False)


@pytest.fixture
def scripted_entry_point(monkeypatch, tmp_path):
    """The installed entry points plus two of a distribution installed for the test (found on
    sys.path, as pip-installed driver packages are): the test driver module and a broken one."""
    dist_info = tmp_path / "pygoby_test_drivers-1.0.dist-info"
    dist_info.mkdir()
    (dist_info / "METADATA").write_text(
        "Metadata-Version: 2.1\nName: pygoby-test-drivers\nVersion: 1.0\n"
    )
    (dist_info / "entry_points.txt").write_text(
        f"[{ENTRY_POINT_GROUP}]\n"
        f"scripted = {TEST_MODULE}:frontseat_driver_load\n"
        "broken = tests.frontseat.no_such_module:x\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))


def test_pygoby_registers_its_drivers() -> None:
    """pyproject's entry points are installed (pip install -e .)."""
    assert {"abc", "basic_simulator"} <= set(available_drivers())
    found = {ep.name: ep for ep in entry_points(group=ENTRY_POINT_GROUP)}
    for name in ("abc", "basic_simulator"):
        assert found[name].value == "pygoby.frontseat.drivers.abc:frontseat_driver_load"


def test_load_by_entry_point(scripted_entry_point) -> None:
    clock = VirtualClock(5.0)
    driver = load_driver("scripted", cfg(), clock)
    assert isinstance(driver, ScriptedFrontSeat)
    assert driver.clock is clock and driver.start_time == 5.0
    assert driver.cfg.name == "auv1" and driver.cfg.require_helm is False


def test_load_by_upstream_library_name(scripted_entry_point) -> None:
    driver = load_driver("libgoby_frontseat_scripted.so.30", cfg())
    assert isinstance(driver, ScriptedFrontSeat)


def test_entry_point_that_cannot_load(scripted_entry_point) -> None:
    with pytest.raises(DriverLoadError, match="cannot load frontseat driver 'broken'"):
        load_driver("broken", cfg())


@pytest.mark.parametrize(
    ("given_name", "expect"),
    [
        ("libgoby_frontseat_basic_simulator.so.30", "basic_simulator"),
        ("libgoby_frontseat_basic_simulator.so", "basic_simulator"),
        ("/usr/lib/x86_64-linux-gnu/libgoby_frontseat_bluefin.so.30.0.1", "bluefin"),
        ("  libgoby_frontseat_abc.so.25 ", "abc"),
        ("basic_simulator", "basic_simulator"),
        ("pkg.mod:factory", "pkg.mod:factory"),
        ("libgoby_frontseat_.so", "libgoby_frontseat_.so"),
        ("libsomething_else.so.30", "libsomething_else.so.30"),
    ],
)
def test_canonical_name(given_name, expect) -> None:
    assert canonical_name(given_name) == expect


def test_load_by_module_path_default_factory() -> None:
    driver = load_driver(TEST_MODULE, cfg())
    assert isinstance(driver, ScriptedFrontSeat)


def test_load_by_module_path_and_attribute() -> None:
    driver = load_driver(f"{TEST_MODULE}:ScriptedFrontSeat", cfg(), VirtualClock(1.0))
    assert isinstance(driver, ScriptedFrontSeat)
    assert driver.start_time == 1.0


def test_find_driver_imports_without_constructing(scripted_entry_point) -> None:
    from . import scripted_driver

    assert find_driver("scripted") is scripted_driver.frontseat_driver_load
    assert find_driver("libgoby_frontseat_scripted.so.30") is scripted_driver.frontseat_driver_load
    assert find_driver(f"{TEST_MODULE}:not_a_driver") is scripted_driver.not_a_driver
    with pytest.raises(DriverLoadError, match="drivers found: .*abc"):
        find_driver("libgoby_frontseat_iver.so.30")


def test_factory_returning_no_driver() -> None:
    with pytest.raises(DriverLoadError, match="returned NoneType, not an InterfaceBase"):
        load_driver(f"{TEST_MODULE}:not_a_driver", cfg())


def test_module_without_factory() -> None:
    with pytest.raises(DriverLoadError, match="no 'frontseat_driver_load' factory"):
        load_driver("tests.frontseat.test_plugins", cfg())
    with pytest.raises(DriverLoadError, match="no 'missing' factory"):
        load_driver(f"{TEST_MODULE}:missing", cfg())
    with pytest.raises(DriverLoadError, match="not callable"):
        load_driver(f"{TEST_MODULE}:frontseat_pb", cfg())  # the module's messages import


def test_factory_that_raises() -> None:
    with pytest.raises(DriverLoadError, match="failed to start"):
        load_driver(f"{TEST_MODULE}:ScriptedFrontSeat", "not a Config")


@pytest.mark.parametrize(
    "name", ["iver", "libgoby_frontseat_iver.so.30", "no_such_pkg.driver", "not a name!", ""]
)
def test_wrong_name_lists_the_drivers_found(name) -> None:
    with pytest.raises(DriverLoadError) as info:
        load_driver(name, cfg())
    message = str(info.value)
    assert "drivers found: " in message
    assert "abc" in message and "basic_simulator" in message


def test_module_with_broken_import_is_reported(tmp_path, monkeypatch) -> None:
    (tmp_path / "broken_fs_driver.py").write_text("import no_such_dependency_xyz\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    with pytest.raises(
        DriverLoadError, match="cannot import frontseat driver module 'broken_fs_driver'"
    ):
        load_driver("broken_fs_driver", cfg())


def test_driver_name_from_environment_wins() -> None:
    env = {DRIVER_ENV_VAR: " libgoby_frontseat_basic_simulator.so.30 "}
    assert driver_name_from(env, "abc") == "libgoby_frontseat_basic_simulator.so.30"
    assert driver_name_from({}, "abc") == "abc"
    assert driver_name_from({DRIVER_ENV_VAR: ""}, "abc") == "abc"
    assert driver_name_from({DRIVER_ENV_VAR: "basic_simulator"}, None) == "basic_simulator"


@pytest.mark.parametrize(("env", "config"), [({}, None), ({}, ""), ({DRIVER_ENV_VAR: "  "}, " ")])
def test_driver_name_missing(env, config) -> None:
    with pytest.raises(DriverLoadError, match=DRIVER_ENV_VAR) as info:
        driver_name_from(env, config)
    assert "abc" in str(info.value) and "basic_simulator" in str(info.value)


def test_basic_simulator_driver_loads_when_installed() -> None:
    """The real ABC / basic simulator driver through its entry point (once it exists)."""
    pytest.importorskip("pygoby.frontseat.drivers.abc")
    config = cfg()
    sim = config.Extensions[frontseat_pb.BASIC_SIMULATOR_CONFIG]
    sim.tcp_address, sim.start.lat, sim.start.lon = "127.0.0.1", 42.5, -70.5
    for name in ("basic_simulator", "abc", "libgoby_frontseat_basic_simulator.so.30"):
        driver = load_driver(name, config, VirtualClock(0.0))
        assert type(driver).__module__ == "pygoby.frontseat.drivers.abc"


@settings(max_examples=examples(200), deadline=None)
@given(name=st.text(), config=st.one_of(st.none(), st.text()))
def test_names_never_raise_anything_else(name, config) -> None:
    assert isinstance(canonical_name(name), str)
    try:
        chosen = driver_name_from({DRIVER_ENV_VAR: name}, config)
    except DriverLoadError:
        assert not name.strip() and not (config and config.strip())
    else:
        assert chosen in (name.strip(), (config or "").strip())
