"""liaison: the community in a web browser (Scope, Commander, Acomms, Map), after goby3's
goby_liaison, on a MOOS community with pAcommsHandler.

    pygoby liaison mission.moos [AppName]      (ProcessConfig = liaison, optional)
    pygoby liaison --example_config

The messages the Commander page can send, the queues and the MAC cycle come from the mission's
pAcommsHandler block (`liaison { commander { pacommshandler_name } }`). pAcommsHandler serves
the same pages itself when its block has a `liaison { ... }` section. Serves on 127.0.0.1 by
default; any other address requires the access token printed at start-up.
"""

from __future__ import annotations

from google.protobuf.message import Message

from pygoby.apps.pacommshandler import pAcommsHandler
from pygoby.errors import ConfigError
from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.translator import Post
from pygoby.protobuf import builtin_class
from pygoby.topside.commander import CommanderError, CommandSet
from pygoby.topside.liaison import LiaisonState, WebServer

CONFIG = ("pygoby/apps/topside_config.proto", "pygoby.apps.protobuf.LiaisonAppConfig")


def acomms_config(app: GobyMOOSApp, block: str) -> Message:
    """The pAcommsHandler configuration named `block` in the app's mission file."""
    if app.mission is None:
        raise ConfigError(f"{app.name} needs the mission file with the {block} ProcessConfig")
    return pAcommsHandler.read_config(app.mission, block)


def command_set(app: GobyMOOSApp, cfg: Message, lookup_path: str) -> CommandSet:
    find = app.find_file
    return CommandSet.from_pacommshandler(cfg, find, find(lookup_path) if lookup_path else "")


class Liaison(GobyMOOSApp):
    config_proto = CONFIG
    default_name = "liaison"

    def __init__(self, cfg: Message, *, acomms_cfg: Message | None = None, **kwargs) -> None:
        super().__init__(cfg, **kwargs)
        web = cfg.liaison
        if acomms_cfg is None:
            acomms_cfg = acomms_config(self, web.commander.pacommshandler_name)
        try:
            self.state = LiaisonState(
                web, acomms_cfg, command_set(self, acomms_cfg, cfg.modem_id_lookup_path),
                community=self.common.community, now=self.clock.now, publish=self._post,
                start_time=self.start_time,
            )  # fmt: skip
        except CommanderError as err:
            raise ConfigError(str(err), field="liaison.commander") from None
        self.subscribe_pattern("*", "*", self.state.handle)
        self.web = WebServer(self.state, web.http_address, web.http_port, web.token,
                             1.0 / web.update_freq if web.update_freq > 0 else 1.0)  # fmt: skip

    @classmethod
    def embedded(cls, acomms: pAcommsHandler) -> Liaison:
        """The liaison a pAcommsHandler with a `liaison` block serves, as its own MOOS client."""
        cfg = builtin_class(*CONFIG)()
        cfg.common.CopyFrom(acomms.common)
        cfg.common.log = False
        cfg.liaison.CopyFrom(acomms.cfg.liaison)
        return cls(cfg, acomms_cfg=acomms.cfg, name=f"{acomms.name}_liaison", mission=acomms.mission,
                   clock=acomms.clock, host=acomms.client.host, port=acomms.client.port)  # fmt: skip

    def _post(self, post: Post) -> None:
        self.publish(post.var, post.value, src_aux=post.source_aux)

    def on_start(self) -> None:
        self.state.start_time = self.start_time

    async def start(self, connect_timeout: float | None = None) -> None:
        await super().start(connect_timeout)
        await self.web.start()
        print(f"{self.name}: serving {self.web.url}", flush=True)
        self.log.info("serving %s", self.web.url)

    async def stop(self) -> None:
        await self.web.stop()
        await super().stop()


def main(argv=None) -> int:
    return Liaison.main(argv, prog="liaison")


if __name__ == "__main__":
    raise SystemExit(main())
