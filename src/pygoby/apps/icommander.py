"""iCommander: compose and send command messages from a terminal (Goby 1.1).

    iCommander mission.moos [AppName]
    iCommander --example_config

The messages are the ones the mission's pAcommsHandler creates on a publish trigger and every
message of its Goby 1.1 XML files (`commander { pacommshandler_name }`, default
"pAcommsHandler"), plus the XML files of this block's own `dccl_cfg`/`transitional_cfg` (Goby
1.1's form) and those imported from the main menu. LatOrigin/LongOrigin give the datum of the
local x/y special; modem_id_lookup_path the modem id picker. Runs over ssh (any terminal);
Ctrl-C or Exit quits.
"""

from __future__ import annotations

import asyncio
from collections.abc import Sequence

from pygoby.errors import ConfigError
from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.translator import MoosValues, Post
from pygoby.moosacomms.acomms_config import AcommsMessageSet
from pygoby.protobuf.pygoby.apps.topside_config_pb2 import iCommanderConfig
from pygoby.topside.commander import (
    KEY_VALUE,
    MULTIPLEX,
    Commander,
    CommanderError,
    CommandSet,
    SaveFileError,
)

SEND_MULTIPLEX = 2  # pygoby.apps.protobuf.SendStyle
QUIET = 1  # goby.util.protobuf.GLogConfig.Verbosity


class iCommander(GobyMOOSApp):  # noqa: N801 - the program's name
    config_class = iCommanderConfig
    cfg: iCommanderConfig
    default_name = "iCommander"

    def __init__(
        self, cfg: iCommanderConfig, *, acomms: AcommsMessageSet | None = None, **kwargs
    ) -> None:
        super().__init__(cfg, **kwargs)
        if not (self.common.HasField("lat_origin") and self.common.HasField("lon_origin")):
            raise ConfigError(
                "LatOrigin and LongOrigin are required (local x/y -> lat/lon)",
                field="common.lat_origin",
            )
        options = cfg.commander
        self.common.verbosity = QUIET  # the terminal belongs to the screens; the log file keeps all
        if acomms is None:
            acomms = AcommsMessageSet.of_app(
                self, options.pacommshandler_name, cfg.transitional_cfg.message_file
            )
        try:
            self.commander = Commander(
                CommandSet.from_messages(acomms, cfg.modem_id_lookup_path),
                community=self.common.community,
                now=self.clock.now,
                publish=self._post,
                style=MULTIPLEX if options.send_style == SEND_MULTIPLEX else KEY_VALUE,
                force_xy_only=cfg.force_xy_only or options.force_xy_only,
                autosave_path=options.autosave_path or None,
                values=MoosValues(self.dynamic_vars),
            )
        except CommanderError as err:
            raise ConfigError(str(err), field="commander") from None
        # empty values mean none, as in Goby 1.1 (its manual's block and --example_config
        # carry `show_variable: ""` and `load: ""`)
        shown = [var for var in cfg.show_variable if var]
        # textual (pip extra `topside`) is imported here, where a missing one is reported cleanly
        from pygoby.topside.icommander import ICommanderTUI

        self.tui = ICommanderTUI(self.commander, shown, on_exit=self.request_stop)
        for var in self.commander.watched_variables:
            self.subscribe(var, self._on_ack_or_expire)
        for var in shown:
            self.subscribe(var, self._on_show)
        self._sources: set[str] = set()
        self._subscribe_sources()
        self.commander.signal_import.connect(lambda names: self._subscribe_sources())
        self.load_warnings = []
        for path in [*cfg.load, *options.load]:
            if not path:
                continue
            try:
                self.load_warnings += self.commander.load(self.find_file(path))
            except (OSError, SaveFileError) as err:
                reason = err.strerror if isinstance(err, OSError) and err.strerror else err
                raise self.config_error(
                    f"cannot open the save file {path!r}: {reason}", "load", path
                ) from None

    def _subscribe_sources(self) -> None:
        """Keep the values of the variables a send posts to (a number goes where one is)."""
        for var in sorted(self.commander.source_variables - self._sources):
            self.subscribe(var)
            self._sources.add(var)

    def _post(self, post: Post) -> None:
        self.publish(post.var, post.value, src_aux=post.source_aux)

    def _on_ack_or_expire(self, msg: MOOSMessage) -> None:
        for notice in self.commander.handle_mail(msg.key, msg.value, msg.time):
            if self.tui.is_running:
                self.tui.show_notice(notice)

    def _on_show(self, msg: MOOSMessage) -> None:
        if self.tui.is_running:
            self.tui.show_variable(msg.key, msg.value)

    async def run(self) -> None:
        """The MOOS app and the terminal UI in one loop; either one ending stops both."""
        await self.start()
        ui = asyncio.create_task(self.tui.run_async())
        stop = asyncio.create_task(self._stop_requested.wait())
        try:
            await asyncio.wait({ui, stop}, return_when=asyncio.FIRST_COMPLETED)
        finally:
            if not ui.done():
                self.tui.exit()
                await ui
            stop.cancel()
            await self.stop()


def main(argv: Sequence[str] | None = None) -> int:
    return iCommander.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
