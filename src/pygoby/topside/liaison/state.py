"""Everything liaison's pages show, fed with MOOS mail (no I/O): the Scope, Acomms and Map
models and the commander core, with JSON-ready views for the web layer."""

from __future__ import annotations

import pickle
import zlib
from collections.abc import Callable, Mapping

from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.translator import MoosValue, Post
from pygoby.protobuf.goby.apps.moos.protobuf.pAcommsHandler_config_pb2 import pAcommsHandlerConfig
from pygoby.protobuf.pygoby.apps.topside_config_pb2 import LiaisonConfig
from pygoby.topside.commander import (
    KEY_VALUE,
    MULTIPLEX,
    Commander,
    CommandSet,
    Draft,
    Notice,
    Outgoing,
    SentRecord,
)
from pygoby.topside.liaison.models import AcommsModel, MapModel, ScopeModel

SEND_MULTIPLEX = 2  # pygoby.apps.protobuf.SendStyle


def field_view(draft: Draft) -> list[dict]:
    return [
        {
            "name": spec.name,
            "kind": spec.kind,
            "type": spec.proto_type,
            "editable": spec.editable,
            "required": spec.required,
            "describe": spec.describe(),
            "value": draft.value(spec.name),
            "enum": list(spec.enum_values),
            "source": spec.source,
            "automatic": spec.automatic_from,
        }
        for spec in draft.type.fields
    ]


def record_view(record: SentRecord) -> dict:
    return {
        "id": record.record_id,
        "type": record.type.short_name,
        "time": record.time,
        "status": record.status,
        "status_time": record.status_time,
        "text": record.text,
        "posts": [f"{p.var}: {p.value!s}" for p in record.posts],
    }


def outgoing_view(outgoing: Outgoing) -> dict:
    return {"posts": outgoing.lines(), "warnings": outgoing.warnings}


def grouped_notices(notices: list[Notice]) -> list[str]:
    """Newest first; a run of notices of one kind for one message type (a telemetry queue's
    expiry every few seconds) is one entry that counts them and keeps the newest's text."""
    runs: list[tuple[Notice, int]] = []
    for notice in reversed(notices):
        if runs and (runs[-1][0].kind, runs[-1][0].type_name) == (notice.kind, notice.type_name):
            runs[-1] = (runs[-1][0], runs[-1][1] + 1)
        else:
            runs.append((notice, 1))
    return [
        notice.banner() + (f"\n ({count} in a row; the newest shown)" if count > 1 else "")
        for notice, count in runs
    ]


class LiaisonState:
    """`handle(msg)` for every MOOS message; `page(name, now)` and `scope` for the pages."""

    def __init__(
        self,
        cfg: LiaisonConfig,
        acomms_cfg: pAcommsHandlerConfig,  # of the community
        commands: CommandSet,
        *,
        community: str,
        now: Callable[[], float],
        publish: Callable[[Post], None],
        start_time: float,
        values: Mapping[str, MoosValue] | None = None,
    ) -> None:
        """`values`: the newest value of every variable (the commander posts a number where a
        variable holds doubles)."""
        self.now = now
        self.start_time = start_time
        commander_cfg = cfg.commander
        self.commander = Commander(
            commands,
            community=community,
            now=now,
            publish=publish,
            style=MULTIPLEX if commander_cfg.send_style == SEND_MULTIPLEX else KEY_VALUE,
            force_xy_only=commander_cfg.force_xy_only,
            autosave_path=commander_cfg.autosave_path or None,
            values=values,
        )
        self.scope = ScopeModel(cfg.max_history_items, list(cfg.scope_subscription))
        self.acomms = AcommsModel(acomms_cfg, commands.resolve, start_time)
        names = acomms_cfg.moos_var
        self.map = MapModel(
            community,
            commands.geodesy,
            commands.modem_ids,
            list(cfg.node_report_var),
            names.prefix + names.driver_receive,
            names.prefix + names.driver_transmit,
            cfg.link_seconds,
            cfg.max_track_points,
        )
        self.commands_listed = {name for name in commander_cfg.command if name}  # "": none
        self.load_warnings: list[str] = []
        for path in commander_cfg.load:
            if path:  # empty means none, as in Goby 1.1
                self.load_warnings += self.commander.load(path)

    def handle(self, msg: MOOSMessage) -> None:
        self.show(msg)
        if msg.time >= self.start_time:  # older acks are not ours (Goby's stale-mail rule)
            self.commander.handle_mail(msg.key, msg.value, msg.time)

    def show(self, msg: MOOSMessage) -> None:
        """The Scope, Acomms and Map pages' part of `handle` (all a log replay updates: the
        commander's acks are for the commands this liaison sent)."""
        self.scope.update(msg)
        self.acomms.handle(msg)
        self.map.handle(msg)

    def save_pages(self) -> bytes:
        """The Scope, Acomms and Map models' state, compressed (a log replay's checkpoint)."""
        saved = (self.scope.saved(), self.acomms.saved(), self.map.saved())
        return zlib.compress(pickle.dumps(saved, pickle.HIGHEST_PROTOCOL), 1)

    def restore_pages(self, saved: bytes) -> None:
        """Back to the pages' state `save_pages` gave."""
        scope, acomms, nodes = pickle.loads(
            zlib.decompress(saved)
        )  # our own bytes, never a client's
        self.scope.restore(scope)
        self.acomms.restore(acomms)
        self.map.restore(nodes)

    def page(self, name: str, now: float) -> dict:
        """The Commander, Acomms or Map page's view (the Scope's is `scope.rows_json`)."""
        views = {
            "commander": self.commander_view,
            "acomms": self.acomms.snapshot,
            "map": self.map.snapshot,
        }
        return views[name](now)

    def commander_view(self, now: float) -> dict:
        commander = self.commander
        return {
            "records": [record_view(r) for r in reversed(commander.records[-50:])],
            "notices": grouped_notices(commander.notices[-200:])[:20],
        }

    def commander_types(self) -> list[dict]:
        """Every sendable message; `command`: offered without "show all" (those of the
        configuration's `command` list, else the ones it triggers by publishing)."""
        listed = self.commands_listed
        return [
            {
                "name": t.name,
                "short": t.short_name,
                "ack": t.ack,
                "trigger": t.trigger_var,
                "command": bool({t.name, t.short_name} & listed) if listed else t.command,
            }
            for t in self.commander.commands.types.values()
        ]
