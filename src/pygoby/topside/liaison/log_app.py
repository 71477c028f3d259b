"""liaison over a recorded mission (`pygoby liaison --log FILE.alog [--mission M.moos]`): the
Scope, Acomms and Map pages of the log at the time its slider shows, served without a MOOSDB.

With `--mission`, the mission's pAcommsHandler block names the acomms variables and their
message types (as `pygoby log convert --mission` does), its `ProcessConfig = liaison` block (if
any) configures the pages, and its Community is the vehicle the log's NAV_* are. Without it,
pAcommsHandler's default names and the community of the log's MOOSDB (its MOOSDB_<community>
posts; else the log file's name).
"""

from __future__ import annotations

import asyncio
import os
from pathlib import Path

from pygoby.moos.appconfig import read_configuration
from pygoby.moos.moosfile import MissionFile
from pygoby.moos.translator import Post
from pygoby.moosacomms.acomms_config import AcommsMessageSet, read_acomms_config
from pygoby.protobuf.goby.apps.moos.protobuf.pAcommsHandler_config_pb2 import pAcommsHandlerConfig
from pygoby.protobuf.pygoby.apps.topside_config_pb2 import LiaisonAppConfig, LiaisonConfig
from pygoby.topside.commander import CommandSet
from pygoby.topside.errors import CommanderError, LogFileError
from pygoby.topside.liaison.log_feed import (
    DEFAULT_SPACING,
    MAX_CHECKPOINTS,
    MAX_SNAPSHOTS,
    LogFeed,
    LogIndex,
    LogPlayer,
)
from pygoby.topside.liaison.state import LiaisonState
from pygoby.topside.liaison.web import WebServer
from pygoby.util.clock import Clock, WallClock


def _no_posting(post: Post) -> None:
    raise CommanderError("liaison is replaying a log: there is no MOOSDB to post to")


def open_replay(
    log_path: str | os.PathLike[str],
    mission_path: str | os.PathLike[str] | None = None,
    *,
    spacing: float = DEFAULT_SPACING,
    max_checkpoints: int = MAX_CHECKPOINTS,
    max_snapshots: int = MAX_SNAPSHOTS,
) -> tuple[LogFeed, LiaisonConfig]:
    """The pages' state over the log at `log_path` (at its start) and the pages' configuration
    (the mission's `liaison` block, else the defaults). PygobyError (LogFileError,
    ConfigError) for a log or mission that cannot be used."""
    if mission_path is not None and not Path(mission_path).is_file():
        raise LogFileError(f"{mission_path}: no such mission file")
    index = LogIndex.build(log_path, spacing, max_checkpoints)
    mission = MissionFile.read(mission_path) if mission_path is not None else None
    cfg = read_configuration(LiaisonAppConfig, mission, "liaison", block_optional=True)
    block = cfg.liaison.commander.pacommshandler_name
    if mission is not None and mission.goby_block(block) is not None:
        acomms_cfg = read_acomms_config(mission, block)
        messages = AcommsMessageSet.load(acomms_cfg, mission.find_file, mission.search_dirs())
    else:
        messages = AcommsMessageSet.load(pAcommsHandlerConfig())
    community = cfg.common.community or index.community or index.path.stem
    state = LiaisonState(
        cfg.liaison,
        messages.cfg,
        CommandSet.from_messages(messages),
        community=community,
        now=lambda: index.log_start + feed.time,
        publish=_no_posting,
        start_time=index.log_start,
    )
    feed = LogFeed(index, state, community, max_snapshots)
    return feed, cfg.liaison


class LogLiaison:
    """The pages over the log at `log_path`, served on `port` (the configuration's otherwise;
    0: any free port). `clock` moves the log time while playing (a VirtualClock in tests)."""

    def __init__(
        self,
        log_path: str | os.PathLike[str],
        mission_path: str | os.PathLike[str] | None = None,
        *,
        port: int | None = None,
        clock: Clock | None = None,
    ) -> None:
        self.feed, web = open_replay(log_path, mission_path)
        self.index, self.state = self.feed.index, self.feed.state
        if port is not None:
            web.http_port = port
        self.clock = clock or WallClock()
        self.player = LogPlayer(self.feed, self.clock)
        # no save folder: the Commander page is off in log mode
        self.web = WebServer(self.state, web, None, player=self.player)

    async def __aenter__(self) -> LogLiaison:
        await self.web.start()
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.web.stop()
        self.feed.close()

    async def serve_forever(self) -> None:
        async with self:
            index = self.index
            print(
                f"liaison: {index.path.name}: {index.entries} entries over {index.end_time:.1f} s"
                + (f", {index.bad_lines} damaged lines skipped" if index.bad_lines else ""),
                flush=True,
            )
            print(f"liaison: serving {self.web.url}", flush=True)
            await asyncio.Event().wait()  # until cancelled (SIGINT/SIGTERM)
