"""iFrontSeat: a MOOS backseat (pHelmIvP + Goby) driving a vehicle's frontseat.

    IFRONTSEAT_DRIVER_LIBRARY=basic_simulator iFrontSeat mission.moos [AppName]
    IFRONTSEAT_DRIVER_LIBRARY=basic_simulator iFrontSeat --example_config

The driver (one vehicle's protocol) is a plug-in named by IFRONTSEAT_DRIVER_LIBRARY or the
`driver_library` field: an entry point of the `pygoby.frontseat_drivers` group, a module path
(`pkg.mod` or `pkg.mod:factory`) or an upstream library name (`pygoby.frontseat.plugins`). It
is resolved before the options are read, so that its configuration extension parses and shows
in `--example_config` (`pygoby.frontseat.config`, with the Goby 2 `[abc_config]` form). The
state machine is the driver's base, `pygoby.frontseat.interface.InterfaceBase`; the rules for
the backseat's variables are `pygoby.frontseat.backseat`; this module maps the MOOS variables
onto them:

* IFS_COMMAND_REQUEST goes to the driver only in INTERFACE_COMMAND; IFS_DATA_OUT and other
  processes' IFS_RAW_OUT only in LISTEN or COMMAND;
* the driver's data, responses and raw traffic are posted on IFS_DATA_IN (plus IFS_NODE_STATUS),
  IFS_COMMAND_RESPONSE, IFS_RAW_IN and IFS_RAW_OUT; IFS_STATUS every `status_period` seconds
  (0: never, as documented; goby3 posts it every iteration: QUIRKS.md Q-APPS-15);
* IVPHELM_STATE sets the helm state, LAT_ORIGIN/LONG_ORIGIN the driver's local grid;
* legacy_cfg: DESIRED_* and CTD_* become IFS_COMMAND_REQUEST / IFS_DATA_OUT; with
  `pub_sub_bf_commands`, BUOYANCY_CONTROL, TRIM_CONTROL, FRONTSEAT_BHVOFF, FRONTSEAT_SILENT and
  BACKSEAT_ABORT become Bluefin command requests and the driver's trim/buoyancy status
  TRIM_REPORT / BUOYANCY_REPORT; with `subscribe_acomms_raw`, ACOMMS_RAW_INCOMING/OUTGOING
  (ModemRaw) become IFS_DATA_OUT with the Bluefin micro_modem_raw_in/out (rules:
  `pygoby.frontseat.legacy`);
* with `exit_on_error`, entering an error state stops the app with exit status 1.
"""

from __future__ import annotations

import functools
import math
import os
import sys
from collections.abc import Sequence
from typing import Any, cast

from google.protobuf.message import Message

from pygoby.frontseat import config as fs_config
from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.backseat import HELM_STATE_VAR, Backseat
from pygoby.frontseat.errors import DriverLoadError, FrontSeatFatalError
from pygoby.frontseat.legacy import (
    ACOMMS_RAW_VARS,
    BLUEFIN_COMMAND_VARS,
    CTD_FIELDS,
    DESIRED_FIELDS,
    Post,
    modem_raw_data,
    ready_posts,
)
from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.appconfig import prefixed_var_names, read_configuration
from pygoby.moos.moosfile import MissionFile
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.translator import LAT_ORIGIN_VAR, LONG_ORIGIN_VAR
from pygoby.protobuf.goby.moos.protobuf.iFrontSeat_config_pb2 import iFrontSeatConfig

LEGACY_BLACKOUT = 1.0  # s, goby3's registration interval for the DESIRED_* and CTD_* variables


class iFrontSeat(GobyMOOSApp):  # noqa: N801 - the program's name
    config_class = iFrontSeatConfig
    cfg: iFrontSeatConfig
    default_name = "iFrontSeat"
    # the frontseat link is served through a MOOSDB outage (its lines read, the helm's
    # silence noticed); what the interface posts meanwhile is delivered when the DB is back
    iterate_without_comms = True

    # -- configuration ---------------------------------------------------------------------

    @classmethod
    def main(
        cls, argv: Sequence[str] | None = None, prog: str | None = None, command: str | None = None
    ) -> int:
        """As goby3, the driver named in the environment is loaded before the options are
        read (its configuration extension then parses and shows in --example_config)."""
        try:
            fs_config.import_driver_from_environment(os.environ)
        except DriverLoadError as err:
            print(f"iFrontSeat: {err}", file=sys.stderr)
            return 1
        return super().main(argv, prog, command)

    @classmethod
    def load_config_class(cls) -> type[iFrontSeatConfig]:
        fs_config.load_goby2_extensions()
        return cast(type[iFrontSeatConfig], super().load_config_class())

    @classmethod
    def read_config(
        cls, mission: MissionFile | None, name: str, overrides: Sequence[tuple[str, str]] = ()
    ) -> Message:
        config_class = cls.load_config_class()
        block = mission.goby_block(name) if mission is not None else None
        fs_config.import_configured_driver(config_class, block.text if block else None, overrides)
        return read_configuration(
            config_class, mission, name, overrides, complete=fs_config.migrate_goby2_abc_config
        )

    # -- construction ----------------------------------------------------------------------

    def __init__(self, cfg: iFrontSeatConfig, **kwargs: Any) -> None:
        super().__init__(cfg, **kwargs)
        self.var = prefixed_var_names(cfg.moos_var)
        driver, self.interface = fs_config.load_configured_driver(cfg, os.environ, self.clock)
        # the driver's log lines (state changes, link trouble) go to the app's log
        self.interface.log = self.log.getChild(type(self.interface).__name__)
        self.log.info("frontseat driver %s (%s)", driver, type(self.interface).__name__)
        common = self.common
        origin = (
            common.lat_origin if common.HasField("lat_origin") else math.nan,
            common.lon_origin if common.HasField("lon_origin") else math.nan,
        )
        self.backseat = Backseat(self.interface, cfg.legacy_cfg, origin, self.log)
        self._connect_signals()
        self._subscribe_all()
        if self.interface.cfg.status_period > 0:
            self.register_timer(self.interface.cfg.status_period, self.post_status)

    def _connect_signals(self) -> None:
        interface = self.interface
        interface.signal_data_from_frontseat.connect(self._on_data_from_frontseat)
        for signal, var in (
            (interface.signal_command_response, "command_response"),
            (interface.signal_raw_from_frontseat, "raw_in"),
            (interface.signal_raw_to_frontseat, "raw_out"),
        ):
            signal.connect(functools.partial(self.publish_pb, self.var[var]))
        if self.cfg.legacy_cfg.publish_fs_bs_ready:
            interface.signal_state_change.connect(lambda status: self._post(ready_posts(status)))

    def _subscribe_all(self) -> None:
        self.subscribe(self.var["command_request"], self._on_command_request)
        self.subscribe(self.var["data_to_frontseat"], self._on_data_to_frontseat)
        self.subscribe(self.var["raw_out"], self._on_raw_out)
        self.subscribe(HELM_STATE_VAR, self._on_helm_state)
        self.subscribe(LAT_ORIGIN_VAR, self._on_origin)
        self.subscribe(LONG_ORIGIN_VAR, self._on_origin)
        if self.backseat.desired_course is not None:
            for var in DESIRED_FIELDS:
                self.subscribe(var, self._on_desired, blackout=LEGACY_BLACKOUT)
        if self.backseat.ctd_samples is not None:
            for var in CTD_FIELDS:
                self.subscribe(var, self._on_ctd, blackout=LEGACY_BLACKOUT)
        if self.cfg.legacy_cfg.subscribe_acomms_raw:
            for var in ACOMMS_RAW_VARS:
                self.subscribe(var, self._on_acomms_raw)
        if self.backseat.bluefin_commands is not None:
            for var in BLUEFIN_COMMAND_VARS:
                self.subscribe(var, self._on_bluefin_command)

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
            self.fail(str(err))

    def post_status(self) -> None:
        self.publish_pb(self.var["status"], self.interface.status())

    # -- MOOS -> frontseat -----------------------------------------------------------------

    def _on_command_request(self, msg: MOOSMessage) -> None:
        if (
            self.backseat.may_command(msg.key)
            and (command := self.parse_pb(msg, frontseat_pb.CommandRequest)) is not None
        ):
            self.interface.send_command_to_frontseat(command)

    def _on_data_to_frontseat(self, msg: MOOSMessage) -> None:
        if (
            self.backseat.may_send(msg.key)
            and (data := self.parse_pb(msg, frontseat_pb.InterfaceData)) is not None
        ):
            self.interface.send_data_to_frontseat(data)

    def _on_raw_out(self, msg: MOOSMessage) -> None:
        if msg.src == self.name:
            return  # our own post of what the driver sent
        if (
            self.backseat.may_send(msg.key)
            and (raw := self.parse_pb(msg, frontseat_pb.Raw)) is not None
        ):
            self.interface.send_raw_to_frontseat(raw)

    def _on_helm_state(self, msg: MOOSMessage) -> None:
        self.backseat.helm_state(msg.string, msg.src)

    def _on_origin(self, msg: MOOSMessage) -> None:
        if not msg.is_double or not math.isfinite(msg.dval):
            self.log.warning("%s is not a finite number: %r", msg.key, msg.value)
        elif msg.key == LAT_ORIGIN_VAR:
            self.backseat.set_origin(lat=msg.dval)
        else:
            self.backseat.set_origin(lon=msg.dval)

    def _on_desired(self, msg: MOOSMessage) -> None:
        if (
            self._is_number(msg)
            and (request := self.backseat.desired(msg.key, msg.dval, msg.time)) is not None
        ):
            # through the MOOSDB, so the state check of IFS_COMMAND_REQUEST applies to it too
            self.publish_pb(self.var["command_request"], request)

    def _on_ctd(self, msg: MOOSMessage) -> None:
        if (
            self._is_number(msg)
            and (data := self.backseat.ctd(msg.key, msg.dval, msg.time)) is not None
        ):
            self.publish_pb(self.var["data_to_frontseat"], data)

    def _on_acomms_raw(self, msg: MOOSMessage) -> None:
        if (raw := self.parse_pb(msg, frontseat_pb.ModemRaw)) is not None:
            data = modem_raw_data(raw, ACOMMS_RAW_VARS[msg.key])
            self.publish_pb(self.var["data_to_frontseat"], data)

    def _on_bluefin_command(self, msg: MOOSMessage) -> None:
        text, number = ("", msg.dval) if msg.is_double else (msg.string, None)
        if (request := self.backseat.bluefin_command(msg.key, text, number)) is not None:
            self.publish_pb(self.var["command_request"], request)

    def _is_number(self, msg: MOOSMessage) -> bool:
        if not msg.is_double:
            self.log.warning("%s is not a number: %r", msg.key, msg.value)
        return msg.is_double

    # -- frontseat -> MOOS -----------------------------------------------------------------

    def _on_data_from_frontseat(self, data: frontseat_pb.InterfaceData) -> None:
        self.publish_pb(self.var["data_from_frontseat"], data)
        if data.HasField("node_status"):
            self.publish_pb(self.var["node_status"], data.node_status)
        self._post(self.backseat.legacy_posts(data))

    def _post(self, posts: list[Post]) -> None:
        for var, value in posts:
            self.publish(var, value)


def main(argv: Sequence[str] | None = None) -> int:
    return iFrontSeat.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
