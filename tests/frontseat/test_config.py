"""iFrontSeat's configuration as library code (pygoby.frontseat.config), without the app or
MOOS: the driver read before the block is parsed, the environment winning, the Goby 2
`[abc_config]` form, refused legacy options and frontseat_cfg completed from `common`."""

from __future__ import annotations

import pytest

from pygoby.frontseat import config as fs_config
from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.plugins import DRIVER_ENV_VAR, DriverLoadError
from pygoby.moos.appconfig import ConfigError
from pygoby.protobuf import builtin_class

from .scripted_driver import ScriptedFrontSeat

SCRIPTED = "tests.frontseat.scripted_driver"


@pytest.fixture(scope="module")
def config_class():
    fs_config.load_goby2_extensions()
    return builtin_class(
        "goby/moos/protobuf/iFrontSeat_config.proto", "goby.apps.moos.protobuf.iFrontSeatConfig"
    )


def test_configured_driver_from_overrides_then_block(config_class):
    block = 'driver_library: "abc"\nfrontseat_cfg { [some.unknown_extension] { x: 1 } }'
    assert fs_config.configured_driver(config_class, block, []) == "abc"
    overrides = [("driver_library", "first"), ("driver_library", "last")]
    assert fs_config.configured_driver(config_class, block, overrides) == "last"
    assert fs_config.configured_driver(config_class, None, []) is None
    assert fs_config.configured_driver(config_class, "driver_library: ", []) is None  # bad text
    assert fs_config.configured_driver(config_class, "frontseat_cfg { }", []) is None


def test_import_configured_driver_environment_wins(config_class):
    block = 'driver_library: "no_such_driver"'
    fs_config.import_configured_driver(config_class, block, env={DRIVER_ENV_VAR: SCRIPTED})
    with pytest.raises(ConfigError, match="'no_such_driver'.*drivers found: abc"):
        fs_config.import_configured_driver(config_class, block, env={})
    with pytest.raises(ConfigError, match=DRIVER_ENV_VAR):
        fs_config.import_configured_driver(config_class, None, env={})


def test_import_driver_from_environment():
    fs_config.import_driver_from_environment({})
    fs_config.import_driver_from_environment({DRIVER_ENV_VAR: SCRIPTED})
    with pytest.raises(DriverLoadError, match="no_such_driver"):
        fs_config.import_driver_from_environment({DRIVER_ENV_VAR: "no_such_driver"})


def test_goby2_abc_config_migrates_once(config_class, caplog):
    cfg = config_class()
    abc = cfg.DESCRIPTOR.file.pool.FindExtensionByName(fs_config.ABC_CONFIG)
    old = cfg.Extensions[abc]
    old.tcp_address, old.tcp_port = "localhost", 54322
    old.start.lat, old.start.lon = 44.5, 9.5
    fs_config.migrate_goby2_abc_config(cfg)
    sim = cfg.frontseat_cfg.Extensions[frontseat_pb.BASIC_SIMULATOR_CONFIG]
    assert (sim.tcp_address, sim.tcp_port) == ("localhost", 54322)
    assert (sim.start.lat, sim.start.lon) == (44.5, 9.5)
    assert not sim.start.HasField("duration") and not cfg.HasExtension(abc)
    assert "Goby 2 [abc_config] block is read as" in caplog.text
    unchanged = config_class()
    unchanged.CopyFrom(cfg)
    fs_config.migrate_goby2_abc_config(cfg)  # nothing left to migrate
    assert cfg == unchanged
    cfg.Extensions[abc].tcp_port = 1
    with pytest.raises(ConfigError, match="both \\[abc_config\\] and frontseat_cfg"):
        fs_config.migrate_goby2_abc_config(cfg)


def test_frontseat_config_takes_name_datum_and_warp_from_common(config_class):
    cfg = config_class()
    cfg.frontseat_cfg.status_period = 7
    cfg.common.time_warp_multiplier = 4
    cfg.common.lat_origin = 42.0
    only_lat = fs_config.frontseat_config(cfg.frontseat_cfg, cfg.common)
    assert not only_lat.HasField("origin") and not only_lat.HasField("name")
    assert only_lat.status_period == 7 and only_lat.sim_warp_factor == 4
    cfg.common.lon_origin, cfg.common.community = -70.0, "auv"
    full = fs_config.frontseat_config(cfg.frontseat_cfg, cfg.common)
    assert (full.name, full.origin.lat, full.origin.lon) == ("auv", 42.0, -70.0)
    assert not cfg.frontseat_cfg.HasField("name")  # the configuration itself is not changed


def test_load_configured_driver(config_class):
    cfg = config_class(driver_library=SCRIPTED)
    cfg.common.community = "auv"
    name, driver = fs_config.load_configured_driver(cfg, env={})
    assert name == SCRIPTED and isinstance(driver, ScriptedFrontSeat) and driver.cfg.name == "auv"
    with pytest.raises(ConfigError, match="no_such_driver"):
        fs_config.load_configured_driver(cfg, env={DRIVER_ENV_VAR: "no_such_driver"})
