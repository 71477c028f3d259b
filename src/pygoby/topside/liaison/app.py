"""liaison's MOOS client: the pages' state fed with every variable of the community, and the
web server. Run on its own (`pygoby liaison mission.moos`, pygoby.apps.liaison) or embedded in
a pAcommsHandler whose block has a `liaison` section (`Liaison.embedded`), then as a second
client of the same MOOSDB sharing pAcommsHandler's message set.
"""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path
from typing import Any

from google.protobuf.message import Message

from pygoby.errors import ConfigError
from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.appconfig import read_configuration
from pygoby.moos.moosfile import MissionFile
from pygoby.moos.translator import MoosValues, Post
from pygoby.moosacomms.acomms_config import AcommsMessageSet
from pygoby.protobuf.pygoby.apps.topside_config_pb2 import LiaisonAppConfig
from pygoby.topside.commander import CommanderError, CommandSet
from pygoby.topside.liaison.state import LiaisonState
from pygoby.topside.liaison.web import WebServer


class Liaison(GobyMOOSApp):
    config_class = LiaisonAppConfig
    cfg: LiaisonAppConfig
    default_name = "liaison"

    def __init__(
        self, cfg: LiaisonAppConfig, *, acomms: AcommsMessageSet | None = None, **kwargs: Any
    ) -> None:
        """`acomms`: the message set of the pAcommsHandler whose messages, queues and MAC cycle
        the pages show (default: the `liaison.commander.pacommshandler_name` block of the
        mission)."""
        super().__init__(cfg, **kwargs)
        web = cfg.liaison
        if acomms is None:
            acomms = AcommsMessageSet.of_app(self, web.commander.pacommshandler_name)
        try:
            self.state = LiaisonState(
                web,
                acomms.cfg,
                CommandSet.from_messages(acomms, cfg.modem_id_lookup_path),
                community=self.common.community,
                now=self.clock.now,
                publish=self._post,
                start_time=self.start_time,
                values=MoosValues(self.dynamic_vars),
            )
        except CommanderError as err:
            raise ConfigError(str(err), field="liaison.commander") from None
        self.subscribe_pattern("*", "*", self.state.handle)
        self.web = WebServer(self.state, web, self._save_dir(web.save_dir))
        # run from a mission without its block: the defaults, said once at start
        self.without_block = self.mission is not None and self.mission.goby_block(self.name) is None

    @classmethod
    def read_config(
        cls, mission: MissionFile | None, name: str, overrides: Sequence[tuple[str, str]] = ()
    ) -> Message:
        """Without a `ProcessConfig = liaison` block: the defaults (said once at start)."""
        return read_configuration(
            cls.load_config_class(), mission, name, overrides, block_optional=True
        )

    def _save_dir(self, configured: str) -> Path:
        """The Commander page's save folder: `save_dir` (relative to the mission file's
        folder), else the mission file's folder, else ./liaison_saves."""
        mission_path = self.mission.path if self.mission is not None else None
        folder = Path(mission_path).parent if mission_path is not None else None
        if configured:
            return (folder or Path.cwd()) / Path(configured).expanduser()
        return folder if folder is not None else Path("liaison_saves")

    @classmethod
    def embedded(cls, host: GobyMOOSApp, acomms: AcommsMessageSet) -> Liaison:
        """The liaison a pAcommsHandler (`host`, its block's `liaison` section) serves, as its
        own client of the host's MOOSDB, with the host's message set."""
        cfg = LiaisonAppConfig()
        cfg.common.CopyFrom(host.common)
        cfg.common.log = False
        cfg.liaison.CopyFrom(acomms.cfg.liaison)
        liaison = cls(
            cfg,
            acomms=acomms,
            name=f"{host.name}_liaison",
            mission=host.mission,
            clock=host.clock,
            host=host.client.host,
            port=host.client.port,
        )
        liaison.without_block = False  # configured by the host's `liaison` section
        return liaison

    def _post(self, post: Post) -> None:
        self.publish(post.var, post.value, src_aux=post.source_aux)

    def on_start(self) -> None:
        self.state.start_time = self.start_time

    async def start(self, connect_timeout: float | None = None) -> None:
        await super().start(connect_timeout)
        if self.without_block:
            self.log.warning(
                "no ProcessConfig = %s block in %s: serving with the defaults",
                self.name,
                (self.mission.path if self.mission else None) or "the mission",
            )
        await self.web.start()
        print(f"{self.name}: serving {self.web.url}", flush=True)
        self.log.info("serving %s", self.web.url)

    async def stop(self) -> None:
        await self.web.stop()
        await super().stop()
