"""iFrontSeat's configuration, usable without the app.

* The driver is imported before the configuration is parsed, so that its configuration
  extension parses and shows in `--example_config`: `import_driver_from_environment(env)` (as
  goby3, $IFRONTSEAT_DRIVER_LIBRARY), then `import_configured_driver(config_class, block_text,
  overrides, env)` (the environment, else `driver_library` from the command line or the
  ProcessConfig block, read before the block is parsed for real).
* `migrate_goby2_abc_config(cfg)`: the Goby 2 form `[abc_config] { ... }` directly in the
  ProcessConfig becomes frontseat_cfg's basic simulator block (`load_goby2_extensions()` makes
  the form parse).
* `load_configured_driver(cfg, env, clock)`: the driver of an iFrontSeatConfig, made from
  frontseat_cfg completed by `frontseat_config(frontseat_cfg, common)` with what the MOOS
  community says (vehicle name, datum, time warp).

Every problem is a ConfigError saying what to change.
"""

from __future__ import annotations

import logging
import os
from collections.abc import Mapping, Sequence
from typing import Any

from google.protobuf import text_format

from pygoby.errors import ConfigError
from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.errors import DriverLoadError
from pygoby.frontseat.interface import InterfaceBase
from pygoby.frontseat.plugins import (
    DRIVER_ENV_VAR,
    driver_name_from,
    find_driver,
    load_driver,
)
from pygoby.protobuf import default_loader
from pygoby.protobuf.goby.moos.frontseat import abc_frontseat_driver_config_pb2
from pygoby.protobuf.goby.moos.protobuf.goby_moos_app_pb2 import GobyMOOSAppConfig
from pygoby.protobuf.goby.moos.protobuf.iFrontSeat_config_pb2 import iFrontSeatConfig
from pygoby.util.clock import Clock

# The Goby 2 ABC driver's block, `[abc_config] { ... }` directly in the ProcessConfig.
ABC_CONFIG_PROTO = "goby/moos/frontseat/abc_frontseat_driver_config.proto"
ABC_CONFIG = "abc_config"

_log = logging.getLogger(__name__)


# -- the driver, before the configuration is parsed ------------------------------------------


def import_driver_from_environment(env: Mapping[str, str] = os.environ) -> None:
    """Import the driver named by $IFRONTSEAT_DRIVER_LIBRARY, if set (DriverLoadError if there
    is no such driver)."""
    name = env.get(DRIVER_ENV_VAR)
    if name:
        find_driver(name)


def configured_driver(
    config_class: type[iFrontSeatConfig],
    block_text: str | None,
    overrides: Sequence[tuple[str, str]],
) -> str | None:
    """`driver_library` from the command line or the ProcessConfig block, read before the block
    is parsed for real (the driver's configuration extension is not loaded yet: unknown
    extensions are skipped here; any other error is reported by the real parse)."""
    for key, value in reversed(overrides):
        if key == "driver_library":
            return value
    if block_text is None:
        return None
    config = config_class()
    try:
        text_format.Merge(block_text, config, allow_unknown_extension=True)
    except text_format.ParseError:
        return None
    return config.driver_library or None


def import_configured_driver(
    config_class: type[iFrontSeatConfig],
    block_text: str | None,
    overrides: Sequence[tuple[str, str]] = (),
    env: Mapping[str, str] = os.environ,
) -> None:
    """Import the driver iFrontSeat will load (the environment wins over the configuration);
    ConfigError naming the installed drivers if there is none or no such driver."""
    configured = configured_driver(config_class, block_text, overrides)
    try:
        find_driver(driver_name_from(env, configured))
    except DriverLoadError as err:
        raise ConfigError(str(err)) from None


# -- older and unsupported forms ----------------------------------------------------------------


def load_goby2_extensions() -> None:
    """Make `[abc_config] { ... }` parse in an iFrontSeatConfig block."""
    default_loader().load_file(ABC_CONFIG_PROTO)  # (its generated module: no protoc)


def migrate_goby2_abc_config(cfg: iFrontSeatConfig) -> None:
    """The Goby 2 form `[abc_config] { ... }` directly in the ProcessConfig becomes frontseat_cfg's
    basic simulator block (same fields: address, port, start position and duration)."""
    abc = abc_frontseat_driver_config_pb2.abc_config
    if not cfg.HasExtension(abc):
        return
    old = cfg.Extensions[abc]
    sim_cfg = cfg.frontseat_cfg.Extensions[frontseat_pb.BASIC_SIMULATOR_CONFIG]
    if cfg.frontseat_cfg.HasExtension(frontseat_pb.BASIC_SIMULATOR_CONFIG):
        raise ConfigError(
            f"both [{ABC_CONFIG}] and frontseat_cfg {{ [{frontseat_pb.BASIC_SIMULATOR_CONFIG.full_name}] }} "
            "are given; keep one"
        )
    sim_cfg.tcp_address = old.tcp_address
    sim_cfg.tcp_port = old.tcp_port
    sim_cfg.start.lat, sim_cfg.start.lon = old.start.lat, old.start.lon
    if old.start.HasField("duration"):
        sim_cfg.start.duration = old.start.duration
    cfg.ClearExtension(abc)
    _log.warning(
        "the Goby 2 [%s] block is read as frontseat_cfg { [%s] { %s } }",
        ABC_CONFIG,
        frontseat_pb.BASIC_SIMULATOR_CONFIG.full_name,
        text_format.MessageToString(sim_cfg, as_one_line=True),
    )


# -- the driver, from the parsed configuration -----------------------------------------------


def frontseat_config(
    frontseat_cfg: frontseat_pb.Config, common: GobyMOOSAppConfig
) -> frontseat_pb.Config:
    """frontseat_cfg with what the MOOS community says (`common`, a GobyMOOSAppConfig): vehicle
    name, datum, time warp."""
    fs_cfg = type(frontseat_cfg)()
    fs_cfg.CopyFrom(frontseat_cfg)
    if common.HasField("community"):
        fs_cfg.name = common.community
    if common.HasField("lat_origin") and common.HasField("lon_origin"):
        fs_cfg.origin.lat, fs_cfg.origin.lon = common.lat_origin, common.lon_origin
    fs_cfg.sim_warp_factor = common.time_warp_multiplier
    return fs_cfg


def load_configured_driver(
    cfg: Any, env: Mapping[str, str] = os.environ, clock: Clock | None = None
) -> tuple[str, InterfaceBase]:
    """(driver name, driver) for an iFrontSeatConfig: the driver named by the environment or
    `driver_library`, made from `frontseat_config(cfg.frontseat_cfg, cfg.common)`."""
    try:
        name = driver_name_from(env, cfg.driver_library or None)
        return name, load_driver(name, frontseat_config(cfg.frontseat_cfg, cfg.common), clock)
    except DriverLoadError as err:
        raise ConfigError(str(err)) from None
