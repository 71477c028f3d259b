"""iFrontSeat: a MOOS backseat (pHelmIvP + Goby) driving a vehicle's frontseat (spec
goby-moos-apps.md section 5).

    IFRONTSEAT_DRIVER_LIBRARY=basic_simulator iFrontSeat mission.moos [AppName]
    IFRONTSEAT_DRIVER_LIBRARY=basic_simulator iFrontSeat --example_config

The driver (one vehicle's protocol) is a plug-in named by IFRONTSEAT_DRIVER_LIBRARY or the
`driver_library` field: an entry point of the `pygoby.frontseat_drivers` group, a module path
(`pkg.mod` or `pkg.mod:factory`) or an upstream library name (`pygoby.frontseat.plugins`). It
is resolved before the options are read, so that its configuration extension parses and shows
in `--example_config`. The state machine is the driver's base,
`pygoby.frontseat.interface.InterfaceBase`; the legacy variables are `pygoby.frontseat.legacy`;
this module maps the MOOS variables onto them:

* IFS_COMMAND_REQUEST goes to the driver only in INTERFACE_COMMAND; IFS_DATA_OUT and other
  processes' IFS_RAW_OUT only in LISTEN or COMMAND;
* the driver's data, responses and raw traffic are posted on IFS_DATA_IN (plus IFS_NODE_STATUS),
  IFS_COMMAND_RESPONSE, IFS_RAW_IN and IFS_RAW_OUT; IFS_STATUS every `status_period` seconds
  (0: never, Quirk Q15 fixed as documented);
* IVPHELM_STATE sets the helm state, LAT_ORIGIN/LONG_ORIGIN the driver's local grid;
* with `exit_on_error`, entering an error state stops the app with exit status 1.
"""

from __future__ import annotations

import logging
import math
import os
import sys
from collections.abc import Sequence
from typing import Any

from google.protobuf import text_format
from google.protobuf.message import Message

from pygoby.frontseat import messages as m
from pygoby.frontseat.helm import helm_state_from_ivphelm
from pygoby.frontseat.interface import FrontSeatFatalError
from pygoby.frontseat.legacy import (
    CTD_FIELDS,
    DESIRED_FIELDS,
    CtdSamples,
    DesiredCourseCommands,
    Post,
    nav_posts,
    ready_posts,
)
from pygoby.frontseat.plugins import (
    DRIVER_ENV_VAR,
    DriverLoadError,
    driver_name_from,
    find_driver,
    load_driver,
)
from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.appconfig import ConfigError, prefixed_var_names, read_configuration
from pygoby.moos.moosfile import MissionFile
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.translator import LAT_ORIGIN_VAR, LONG_ORIGIN_VAR
from pygoby.protobuf import default_loader

HELM_STATE_VAR = "IVPHELM_STATE"
LEGACY_BLACKOUT = 1.0  # s, goby3's registration interval for the DESIRED_* and CTD_* variables

# The Goby 2 ABC driver's block, `[abc_config] { ... }` directly in the ProcessConfig.
ABC_CONFIG_PROTO = "goby/moos/frontseat/abc_frontseat_driver_config.proto"
ABC_CONFIG = "abc_config"

# legacy_cfg options that need goby3's Bluefin messages, which pygoby does not have.
UNSUPPORTED_LEGACY = ("subscribe_acomms_raw", "pub_sub_bf_commands")

CONTROL_STATES = frozenset({m.INTERFACE_LISTEN, m.INTERFACE_COMMAND})

_log = logging.getLogger(__name__)


class iFrontSeat(GobyMOOSApp):  # noqa: N801 - the program's name
    config_proto = (
        "goby/moos/protobuf/iFrontSeat_config.proto",
        "goby.apps.moos.protobuf.iFrontSeatConfig",
    )
    default_name = "iFrontSeat"

    # -- configuration ---------------------------------------------------------------------

    @classmethod
    def main(cls, argv: Sequence[str] | None = None, prog: str | None = None) -> int:
        """As goby3, the driver named in the environment is loaded before the options are
        read (its configuration extension then parses and shows in --example_config)."""
        name = os.environ.get(DRIVER_ENV_VAR)
        if name:
            try:
                find_driver(name)
            except DriverLoadError as err:
                print(f"iFrontSeat: {err}", file=sys.stderr)
                return 1
        return super().main(argv, prog)

    @classmethod
    def load_config_class(cls) -> type[Message]:
        default_loader().load_file(ABC_CONFIG_PROTO)
        return super().load_config_class()

    @classmethod
    def read_config(
        cls, mission: MissionFile | None, name: str, overrides: Sequence[tuple[str, str]] = ()
    ) -> Message:
        config_class = cls.load_config_class()
        configured = _configured_driver(config_class, mission, name, overrides)
        try:
            find_driver(driver_name_from(os.environ, configured))
        except DriverLoadError as err:
            raise ConfigError(str(err)) from None
        return read_configuration(config_class, mission, name, overrides, complete=_from_goby2)

    # -- construction ----------------------------------------------------------------------

    def __init__(self, cfg: Message, **kwargs: Any) -> None:
        super().__init__(cfg, **kwargs)
        legacy = cfg.legacy_cfg
        for option in UNSUPPORTED_LEGACY:
            if getattr(legacy, option):
                raise ConfigError(
                    f"legacy_cfg {{ {option}: true }} needs goby3's Bluefin frontseat "
                    "extensions, which pygoby does not implement; remove the option"
                )
        self.var = prefixed_var_names(cfg.moos_var)
        try:
            driver = driver_name_from(os.environ, cfg.driver_library or None)
            self.interface = load_driver(driver, self._frontseat_cfg(), self.clock)
        except DriverLoadError as err:
            raise ConfigError(str(err)) from None
        # the driver's log lines (state changes, link trouble) go to the app's log
        self.interface.log = self.log.getChild(type(self.interface).__name__)
        self.log.info("frontseat driver %s (%s)", driver, type(self.interface).__name__)
        self.origin = (
            self.common.lat_origin if self.common.HasField("lat_origin") else math.nan,
            self.common.lon_origin if self.common.HasField("lon_origin") else math.nan,
        )
        self.desired = DesiredCourseCommands() if legacy.subscribe_desired else None
        self.ctd = CtdSamples() if legacy.subscribe_ctd else None
        self._connect_signals()
        self._subscribe_all()
        if self.interface.cfg.status_period > 0:
            self.register_timer(self.interface.cfg.status_period, self.post_status)

    def _frontseat_cfg(self) -> Message:
        """frontseat_cfg with what the MOOS community says: vehicle name, datum, time warp."""
        common = self.common
        fs_cfg = type(self.cfg.frontseat_cfg)()
        fs_cfg.CopyFrom(self.cfg.frontseat_cfg)
        if common.HasField("community"):
            fs_cfg.name = common.community
        if common.HasField("lat_origin") and common.HasField("lon_origin"):
            fs_cfg.origin.lat, fs_cfg.origin.lon = common.lat_origin, common.lon_origin
        fs_cfg.sim_warp_factor = common.time_warp_multiplier
        return fs_cfg

    def _connect_signals(self) -> None:
        interface = self.interface
        interface.signal_data_from_frontseat.connect(self._on_data_from_frontseat)
        interface.signal_command_response.connect(
            lambda response: self.publish_pb(self.var["command_response"], response)
        )
        interface.signal_raw_from_frontseat.connect(
            lambda raw: self.publish_pb(self.var["raw_in"], raw)
        )
        interface.signal_raw_to_frontseat.connect(
            lambda raw: self.publish_pb(self.var["raw_out"], raw)
        )
        if self.cfg.legacy_cfg.publish_fs_bs_ready:
            interface.signal_state_change.connect(lambda status: self._post(ready_posts(status)))

    def _subscribe_all(self) -> None:
        self.subscribe(self.var["command_request"], self._on_command_request)
        self.subscribe(self.var["data_to_frontseat"], self._on_data_to_frontseat)
        self.subscribe(self.var["raw_out"], self._on_raw_out)
        self.subscribe(HELM_STATE_VAR, self._on_helm_state)
        self.subscribe(LAT_ORIGIN_VAR, self._on_origin)
        self.subscribe(LONG_ORIGIN_VAR, self._on_origin)
        if self.desired is not None:
            for var in DESIRED_FIELDS:
                self.subscribe(var, self._on_desired, blackout=LEGACY_BLACKOUT)
        if self.ctd is not None:
            for var in CTD_FIELDS:
                self.subscribe(var, self._on_ctd, blackout=LEGACY_BLACKOUT)

    # -- running ---------------------------------------------------------------------------

    async def start(self, connect_timeout: float | None = None) -> None:
        await self.interface.start()
        try:
            await super().start(connect_timeout)
        except BaseException:
            await self.interface.stop()
            raise

    async def stop(self) -> None:
        await super().stop()
        await self.interface.stop()

    def loop(self) -> None:
        if self.exit_status:
            return  # stopping after a fatal error
        try:
            self.interface.do_work()
        except FrontSeatFatalError as err:
            self.log.critical("%s; exiting", err)
            self.exit_status = 1
            self.request_stop()

    def post_status(self) -> None:
        self.publish_pb(self.var["status"], self.interface.status())

    # -- MOOS -> frontseat -----------------------------------------------------------------

    def _on_command_request(self, msg: MOOSMessage) -> None:
        state = self.interface.state
        if state != m.INTERFACE_COMMAND:
            self.log.debug("%s not sent: the interface is in %s, not INTERFACE_COMMAND",
                           msg.key, m.InterfaceState.Name(state))  # fmt: skip
            return
        if (command := self.parse_pb(msg, m.CommandRequest)) is not None:
            self.interface.send_command_to_frontseat(command)

    def _on_data_to_frontseat(self, msg: MOOSMessage) -> None:
        if self._may_send(msg) and (data := self.parse_pb(msg, m.InterfaceData)) is not None:
            self.interface.send_data_to_frontseat(data)

    def _on_raw_out(self, msg: MOOSMessage) -> None:
        if msg.src == self.name:
            return  # our own post of what the driver sent
        if self._may_send(msg) and (raw := self.parse_pb(msg, m.Raw)) is not None:
            self.interface.send_raw_to_frontseat(raw)

    def _may_send(self, msg: MOOSMessage) -> bool:
        if self.interface.state in CONTROL_STATES:
            return True
        self.log.debug("%s not sent: the interface is in %s", msg.key,
                       m.InterfaceState.Name(self.interface.state))  # fmt: skip
        return False

    def _on_helm_state(self, msg: MOOSMessage) -> None:
        current = self.interface.helm_state
        state = helm_state_from_ivphelm(msg.string, msg.src, current)
        if state != current:
            self.log.info("helm state %s -> %s (%s=%r from %s)", m.HelmState.Name(current),
                          m.HelmState.Name(state), msg.key, msg.string, msg.src)  # fmt: skip
        self.interface.set_helm_state(state)  # every post counts for helm_state_timeout

    def _on_origin(self, msg: MOOSMessage) -> None:
        if not msg.is_double or not math.isfinite(msg.dval):
            self.log.warning("%s is not a finite number: %r", msg.key, msg.value)
            return
        lat, lon = self.origin
        self.origin = (msg.dval, lon) if msg.key == LAT_ORIGIN_VAR else (lat, msg.dval)
        if all(math.isfinite(v) for v in self.origin):
            self.interface.update_utm_datum(*self.origin)
            self.log.info("local grid datum now %.8f, %.8f", *self.origin)

    def _on_desired(self, msg: MOOSMessage) -> None:
        if not msg.is_double:
            self.log.warning("%s is not a number: %r", msg.key, msg.value)
            return
        assert self.desired is not None
        request = self.desired.update(msg.key, msg.dval, msg.time)
        if request is not None:
            # through the MOOSDB, so the state check of IFS_COMMAND_REQUEST applies to it too
            self.publish_pb(self.var["command_request"], request)

    def _on_ctd(self, msg: MOOSMessage) -> None:
        if not msg.is_double:
            self.log.warning("%s is not a number: %r", msg.key, msg.value)
            return
        assert self.ctd is not None
        sample = self.ctd.update(msg.key, msg.dval, msg.time)
        if sample is not None:
            self.interface.compute_missing_ctd(sample)
            self.publish_pb(self.var["data_to_frontseat"], m.InterfaceData(ctd_sample=sample))

    # -- frontseat -> MOOS -----------------------------------------------------------------

    def _on_data_from_frontseat(self, data: Message) -> None:
        self.publish_pb(self.var["data_from_frontseat"], data)
        if not data.HasField("node_status"):
            return
        status = data.node_status
        self.publish_pb(self.var["node_status"], status)
        if self.cfg.legacy_cfg.publish_nav:
            self._post(nav_posts(status))
        if self.ctd is not None:
            self.ctd.update_position(status)

    def _post(self, posts: list[Post]) -> None:
        for var, value in posts:
            self.publish(var, value)


def _configured_driver(
    config_class: type[Message],
    mission: MissionFile | None,
    name: str,
    overrides: Sequence[tuple[str, str]],
) -> str | None:
    """`driver_library` from the command line or the ProcessConfig block, read before the block
    is parsed for real (the driver's configuration extension is not loaded yet: unknown
    extensions are skipped here; any other error is reported by the real parse)."""
    for key, value in reversed(overrides):
        if key == "driver_library":
            return value
    block = mission.goby_block(name) if mission is not None else None
    if block is None:
        return None
    config = config_class()
    try:
        text_format.Merge(block.text, config, allow_unknown_extension=True)
    except text_format.ParseError:
        return None
    return config.driver_library or None


def _from_goby2(cfg: Message) -> None:
    """The Goby 2 form `[abc_config] { ... }` directly in the ProcessConfig becomes frontseat_cfg's
    basic simulator block (same fields: address, port, start position and duration)."""
    abc = cfg.DESCRIPTOR.file.pool.FindExtensionByName(ABC_CONFIG)
    if not cfg.HasExtension(abc):
        return
    old = cfg.Extensions[abc]
    sim_cfg = cfg.frontseat_cfg.Extensions[m.BASIC_SIMULATOR_CONFIG]
    if cfg.frontseat_cfg.HasExtension(m.BASIC_SIMULATOR_CONFIG):
        raise ConfigError(
            f"both [{ABC_CONFIG}] and frontseat_cfg {{ [{m.BASIC_SIMULATOR_CONFIG.full_name}] }} "
            "are given; keep one"
        )
    sim_cfg.tcp_address = old.tcp_address
    sim_cfg.tcp_port = old.tcp_port
    sim_cfg.start.lat, sim_cfg.start.lon = old.start.lat, old.start.lon
    if old.start.HasField("duration"):
        sim_cfg.start.duration = old.start.duration
    cfg.ClearExtension(abc)
    _log.warning("the Goby 2 [%s] block is read as frontseat_cfg { [%s] { %s } }", ABC_CONFIG,
                 m.BASIC_SIMULATOR_CONFIG.full_name,
                 text_format.MessageToString(sim_cfg, as_one_line=True))  # fmt: skip


def main(argv: Sequence[str] | None = None) -> int:
    return iFrontSeat.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
