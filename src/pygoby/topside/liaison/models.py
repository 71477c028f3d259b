"""What liaison's pages show, kept from MOOS mail (sans-I/O: fed messages and times, read as
JSON-ready snapshots). One model per page: Scope, Acomms and Map; the Commander page reads the
commander core directly.
"""

from __future__ import annotations

import bisect
import functools
import json
import math
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from google.protobuf.message import Message

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.queue.frames import unpack_frame
from pygoby.dccl import Codec, DcclError
from pygoby.dccl.ccl import remus
from pygoby.dccl.dccl1 import Dccl1Header, is_dccl1_frame, unstitch
from pygoby.moos import protocol as p
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.translator import ModemIdLookup, UTMGeodesy, dynamic_parse, parse_for_moos
from pygoby.moos.translator.keyvalue import val_from_string
from pygoby.moos.translator.techniques import MoosValue, Technique
from pygoby.protobuf import enum_type
from pygoby.protobuf.descriptors import MessageT
from pygoby.protobuf.goby.apps.moos.protobuf.pAcommsHandler_config_pb2 import (
    pAcommsHandlerConfig,
)
from pygoby.topside.errors import ScopeFilterError

RATE_WINDOW = 10.0  # seconds over which a variable's rate is measured
_TEXT = Technique.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT


def _display(value: MoosValue) -> str:
    if isinstance(value, bytes):
        return value[:64].hex() + ("..." if len(value) > 64 else "")
    if isinstance(value, float):
        return f"{value:.12g}"
    return value if len(value) <= 2048 else value[:2048] + "..."


# ---------------------------------------------------------------------------------- Scope
FILTER_MAX = 200  # characters of a Scope filter: room for a dozen variable names or globs


class ScopeFilter:
    """The Scope's `?filter=`: terms separated by spaces or commas, a variable shown when any
    term matches its name, ignoring case. A term with `*` or `?` is a MOOS glob over the whole
    name (`NAV_*`); a plain term matches anywhere in the name (`ACOMMS`). Globs never backtrack
    (`Glob`), terms are capped at FILTER_MAX characters in all, and each name's answer is kept,
    so no filter can make the Scope slow."""

    def __init__(self, text: str) -> None:
        if len(text) > FILTER_MAX:
            raise ScopeFilterError(f"a Scope filter has at most {FILTER_MAX} characters")
        terms = text.replace(",", " ").lower().split()
        self.globs = [p.Glob(t if "*" in t or "?" in t else f"*{t}*") for t in terms]
        self._answers: dict[str, bool] = {}

    def __call__(self, key: str) -> bool:
        if not self.globs:
            return True
        answer = self._answers.get(key)
        if answer is None:
            lowered = key.lower()
            answer = self._answers[key] = any(g.match(lowered) for g in self.globs)
        return answer


@dataclass
class ScopeRow:
    key: str
    value: MoosValue
    kind: str  # D (double), S (string), B (binary)
    source: str
    source_aux: str
    community: str
    time: float
    arrivals: deque[float]
    history: deque[tuple[float, float]]
    version: int = 0
    shown: tuple[int, float, str] | None = None  # (version, rate, JSON) last built


class ScopeModel:
    """Every variable seen: newest value, type, source, time, rate; numeric history."""

    def __init__(self, max_history: int = 1000, patterns: list[str] | None = None) -> None:
        self.max_history = max_history
        self.patterns = patterns or []
        self.rows: dict[str, ScopeRow] = {}
        self._keys: list[str] = []  # sorted

    def wants(self, key: str) -> bool:
        return not self.patterns or any(p.wildcard_match(pat, key) for pat in self.patterns)

    def update(self, msg: MOOSMessage) -> None:
        if msg.msg_type != p.NOTIFY or not self.wants(msg.key):
            return
        value = msg.value
        kind = "D" if isinstance(value, float) else "B" if isinstance(value, bytes) else "S"
        row = self.rows.get(msg.key)
        if row is None:
            row = self.rows[msg.key] = ScopeRow(
                msg.key,
                value,
                kind,
                msg.src,
                msg.src_aux,
                msg.community,
                msg.time,
                deque(maxlen=256),
                deque(maxlen=self.max_history),
            )
            bisect.insort(self._keys, msg.key)
        row.value, row.kind, row.time = value, kind, msg.time
        row.source, row.source_aux, row.community = msg.src, msg.src_aux, msg.community
        row.version += 1
        row.arrivals.append(msg.time)
        if isinstance(value, float) and math.isfinite(value):
            row.history.append((msg.time, value))

    def rows_json(self, now: float) -> dict[str, str]:
        """Every row as JSON text, by name in order. A row's text is rebuilt only when its value
        or rate changed, so that the live pages can send only the rows that did (the page
        works out ages from `time` and the snapshot's `now`)."""
        out = {}
        for key in self._keys:
            row = self.rows[key]
            arrivals = row.arrivals
            while arrivals and now - arrivals[0] > RATE_WINDOW:
                arrivals.popleft()
            rate = round(len(arrivals) / RATE_WINDOW, 2)
            if row.shown is None or row.shown[:2] != (row.version, rate):
                text = json.dumps(
                    {
                        "key": key,
                        "value": _display(row.value),
                        "type": row.kind,
                        "source": row.source,
                        "aux": row.source_aux,
                        "community": row.community,
                        "time": row.time,
                        "rate": rate,
                        "numeric": bool(row.history),
                    }
                )
                row.shown = (row.version, rate, text)
            out[key] = row.shown[2]
        return out

    def history(self, key: str) -> list[tuple[float, float]]:
        row = self.rows.get(key)
        return list(row.history) if row is not None else []

    def saved(self) -> object:
        """What mail changed (for `restore`: a log replay's checkpoint); pickles."""
        return self.rows

    def restore(self, saved: object) -> None:
        """Back to what `saved` gave (an unpickled copy: nothing shared with the saved one)."""
        assert isinstance(saved, dict)
        self.rows = saved
        self._keys = sorted(saved)


# ---------------------------------------------------------------------------------- Acomms
@dataclass
class QueueState:
    name: str
    dccl_id: int | None
    entry: acomms_pb.QueuedMessageEntry
    size: int = 0
    last_sent: float = 0.0
    sent: int = 0

    def priority(self, now: float) -> float:
        """The queue's priority as goby-acomms computes it, from the last send we saw."""
        ttl = self.entry.ttl
        if ttl == 0:
            return self.entry.value_base
        return self.entry.value_base * (now - self.last_sent) / ttl


def _enum_name(msg: Message, field: str) -> str:
    enum = enum_type(msg.DESCRIPTOR.fields_by_name[field])
    return enum.values_by_number[getattr(msg, field)].name


def _mm_extension(transmission: acomms_pb.ModemTransmission) -> acomms_pb.MMTransmission | None:
    if transmission.HasExtension(acomms_pb.MM_TRANSMISSION):
        return transmission.Extensions[acomms_pb.MM_TRANSMISSION]
    return None


class AcommsModel:
    """Queues, MAC cycle, the modem's recent transmissions and receptions, acks and expiries.

    `cfg` is pAcommsHandler's configuration (queues, MAC slots, variable names); `resolve`
    finds the mission's message classes (to name the DCCL messages inside frames)."""

    def __init__(
        self,
        cfg: pAcommsHandlerConfig,
        resolve: Callable[[str], type[Message]],
        now: float,
        history: int = 20,
    ) -> None:
        names = cfg.moos_var
        self.var = {
            f.name: names.prefix + getattr(names, f.name)
            for f in names.DESCRIPTOR.fields
            if f.name != "prefix"
        }
        self.modem_id = cfg.modem_id
        self._resolve = resolve
        self.codec = Codec()
        self.queues: dict[str, QueueState] = {}
        for entry in cfg.queue_cfg.message_entry:
            dccl_id = None
            try:
                cls = self.codec.load(resolve(entry.protobuf_name))
                dccl_id = self.codec.compiled(cls).id
            except Exception:
                pass
            self.queues[entry.protobuf_name] = QueueState(
                entry.protobuf_name, dccl_id, entry, last_sent=now
            )
        self.slots: list[dict[str, Any]] = [
            {
                "src": s.src,
                "dest": s.dest,
                "rate": s.rate,
                "type": acomms_pb.ModemTransmission.TransmissionType.Name(s.type),
                "seconds": s.slot_seconds,
            }
            for s in cfg.mac_cfg.slot
        ]
        self.ccl_queues = {
            q.key.id: q.name
            for q in cfg.queue_cfg.queue
            if q.HasField("key") and q.key.type == acomms_pb.QUEUE_CCL
        }
        self.slot_index: int | None = None
        self.slot_start: float | None = None
        self.tx: deque[dict] = deque(maxlen=history)
        self.rx: deque[dict] = deque(maxlen=history)
        self.timeline: deque[dict] = deque(maxlen=4 * history)
        self._handlers: dict[str, Callable[[MoosValue, float], None]] = {
            self.var["queue_size"]: self._on_qsize,
            self.var["mac_slot_start"]: self._on_slot,
            self.var["driver_transmit"]: functools.partial(self._on_modem, True),
            self.var["driver_receive"]: functools.partial(self._on_modem, False),
            self.var["queue_ack_original_msg"]: self._on_ack,
            self.var["queue_expire"]: self._on_expire,
            self.var["driver_status"]: self._on_driver_status,
        }
        self.drivers: dict[str, str] = {}  # "primary driver NAME" -> its state

    @property
    def variables(self) -> list[str]:
        return sorted(self._handlers)

    def handle(self, msg: MOOSMessage) -> None:
        handler = self._handlers.get(msg.key)
        if handler is not None and isinstance(msg.value, str | bytes):
            handler(msg.value, msg.time)

    def _parse(self, cls: type[MessageT], value: MoosValue) -> MessageT | None:
        out = cls()
        try:
            parse_for_moos(value, out)
        except Exception:
            return None
        return out

    def _on_driver_status(self, value: MoosValue, when: float) -> None:
        text = value.decode("utf-8", "replace") if isinstance(value, bytes) else str(value)
        driver, sep, state = text.partition(": ")
        if sep and len(self.drivers) < 16:  # a handful of drivers; never an unbounded table
            self.drivers[driver] = state[:500]

    def _on_qsize(self, value: MoosValue, when: float) -> None:
        size = self._parse(acomms_pb.QueueSize, value)
        if size is not None and size.HasField("dccl_id"):
            dccl_id, count = size.dccl_id, size.size
        elif (old := self._parse(acomms_pb.V1QueueSize, value)) is not None:
            if old.key.type != acomms_pb.QUEUE_DCCL:
                return  # a Goby 1.1 CCL queue: not one of the DCCL queues shown
            dccl_id, count = old.key.id, old.size  # Goby 1.1's form
        else:
            return
        for queue in self.queues.values():
            if queue.dccl_id == dccl_id:
                queue.size = count

    def _on_slot(self, value: MoosValue, when: float) -> None:
        slot = self._parse(acomms_pb.ModemTransmission, value)
        if slot is not None:
            self.slot_index = slot.slot_index if slot.HasField("slot_index") else None
            self.slot_start = slot.time / 1e6 if slot.HasField("time") else when

    def _messages_in(self, transmission: acomms_pb.ModemTransmission) -> list[str]:
        return [name for frame in transmission.frame for name in self._frame_names(bytes(frame))]

    def _frame_names(self, data: bytes) -> list[str]:
        """The types of the messages in one frame; `?` after one that does not decode."""
        if is_dccl1_frame(data):  # Goby 1.1's bytes: the types from the clear headers
            return self._dccl1_names(data)
        names: list[str] = []

        def undecodable(offset: int, _: DcclError) -> None:
            names.append(self._ccl_name(data) if offset == 0 else "?")

        for msg, _ in unpack_frame(data, lambda _: self.codec, undecodable):
            names.append(msg.DESCRIPTOR.full_name)
        return names

    def _ccl_name(self, frame: bytes) -> str:
        """A frame DCCL does not read: a CCL frame (32 bytes, its type in the first byte) is
        named after its Goby 1.1 queue (`queue { key { type: QUEUE_CCL id: 14 } name: ... }`),
        else the REMUS frame type, else `CCL 0x0e`; anything else is `?`."""
        if len(frame) != remus.FRAME_BYTES:
            return "?"
        ccl_id = frame[0]
        if ccl_id in self.ccl_queues:
            return self.ccl_queues[ccl_id]
        frame_type = remus.BY_ID.get(ccl_id)
        return f"REMUS {frame_type.__name__}" if frame_type else f"CCL 0x{ccl_id:02x}"

    def _dccl1_names(self, frame: bytes) -> list[str]:
        try:
            parts = unstitch(frame)
        except DcclError:
            return ["?"]
        by_id = {q.dccl_id: name for name, q in self.queues.items()}
        return [by_id.get(Dccl1Header.unpack(p.data).id, "?") for p in parts]

    def _on_modem(self, sent: bool, value: MoosValue, when: float) -> None:
        """ACOMMS_MODEM_TRANSMIT (sent) / ACOMMS_MODEM_RECEIVE: one row, with the modem's
        statistics ($CAXST result, $CACST SNR, Doppler, bad frames) when it gives them."""
        transmission = self._parse(acomms_pb.ModemTransmission, value)
        if transmission is None:
            return
        names = self._messages_in(transmission)
        row: dict[str, Any] = {
            "time": transmission.time / 1e6 if transmission.HasField("time") else when,
            "src": transmission.src,
            "dest": transmission.dest,
            "type": acomms_pb.ModemTransmission.TransmissionType.Name(transmission.type),
            "rate": transmission.rate,
            "frames": len(transmission.frame),
            "messages": [n.rsplit(".", 1)[-1] for n in names],
        }
        mm = _mm_extension(transmission)
        if sent:
            if mm is not None and mm.transmit_stat:
                row["mode"] = _enum_name(mm.transmit_stat[-1], "mode")
            for name in names:
                queue = self.queues.get(name)
                if queue is not None:
                    queue.last_sent, queue.sent = row["time"], queue.sent + 1
        elif mm is not None and mm.receive_stat:
            stat = mm.receive_stat[-1]
            row.update(
                snr_in=stat.snr_in,
                snr_out=stat.snr_out,
                doppler=stat.doppler,
                mse=stat.mse_equalizer,
                bad_frames=stat.number_bad_frames,
                psk_error=_enum_name(stat, "psk_error_code"),
            )
        (self.tx if sent else self.rx).appendleft(row)
        verb = "sent" if sent else "heard"
        self.timeline.appendleft(
            {
                "time": row["time"],
                "kind": "tx" if sent else "rx",
                "text": f"{verb} {row['type']} {row['src']}->{row['dest']} {', '.join(row['messages'])}",
            }
        )

    def _original(self, kind: str, value: MoosValue, when: float) -> None:
        original = dynamic_parse(value, self._resolve, _TEXT)
        name = original.DESCRIPTOR.full_name.rsplit(".", 1)[-1] if original is not None else "?"
        text = str(value).split("] ", 1)[-1] if isinstance(value, str) else ""
        newest = self.timeline[0] if self.timeline else None
        if newest is not None and (newest["kind"], newest.get("name")) == (kind, name):
            # a run of the same event for one message type (a telemetry queue expiring every
            # few seconds) is one line that counts them
            count = newest["count"] + 1
            newest.update(time=when, count=count, text=f"{name} {kind} ({count} in a row): {text}")
            return
        self.timeline.appendleft(
            {"time": when, "kind": kind, "name": name, "count": 1, "text": f"{name} {kind}: {text}"}
        )

    def _on_ack(self, value: MoosValue, when: float) -> None:
        self._original("acknowledged", value, when)

    def _on_expire(self, value: MoosValue, when: float) -> None:
        self._original("expired", value, when)

    def saved(self) -> object:
        """What mail changed (for `restore`: a log replay's checkpoint); pickles. The queues'
        configuration stays: only their counts and send times are saved."""
        queues = {name: (q.size, q.last_sent, q.sent) for name, q in self.queues.items()}
        return (
            queues,
            self.slot_index,
            self.slot_start,
            self.tx,
            self.rx,
            self.timeline,
            self.drivers,
        )

    def restore(self, saved: object) -> None:
        """Back to what `saved` gave (an unpickled copy: nothing shared with the saved one)."""
        assert isinstance(saved, tuple)
        queues, self.slot_index, self.slot_start, self.tx, self.rx, self.timeline, self.drivers = (
            saved
        )
        for name, (size, last_sent, sent) in queues.items():
            queue = self.queues[name]
            queue.size, queue.last_sent, queue.sent = size, last_sent, sent

    def snapshot(self, now: float) -> dict:
        waiting = [
            q
            for q in self.queues.values()
            if q.size > 0 and q.last_sent + q.entry.blackout_time <= now
        ]
        following = max(waiting, key=lambda q: q.priority(now), default=None)
        cycle = sum(s["seconds"] for s in self.slots)
        return {
            "modem_id": self.modem_id,
            "drivers": [f"{name}: {state}" for name, state in self.drivers.items()],
            "queues": [
                {
                    "name": q.name,
                    "dccl_id": q.dccl_id,
                    "size": q.size,
                    "ack": q.entry.ack,
                    "ttl": q.entry.ttl,
                    "value_base": q.entry.value_base,
                    "max_queue": q.entry.max_queue,
                    "priority": round(q.priority(now), 3),
                    "sent": q.sent,
                    "next": q is following,
                }
                for q in self.queues.values()
            ],
            "mac": {
                "slots": self.slots,
                "cycle_seconds": cycle,
                "current": self.slot_index,
                "into_slot": None if self.slot_start is None else round(now - self.slot_start, 1),
            },
            "tx": list(self.tx),
            "rx": list(self.rx),
            "timeline": list(self.timeline),
        }


# ---------------------------------------------------------------------------------- Map
@dataclass
class Node:
    name: str
    x: float
    y: float
    heading: float | None
    time: float
    track: deque[tuple[float, float]] = field(default_factory=deque)


def _number(text: str | None) -> float | None:
    if text is None:
        return None
    try:
        value = float(text)
    except ValueError:
        return None
    return value if math.isfinite(value) else None


class MapModel:
    """Vehicles on the local x/y plan (NAV_* of this community, key=value node reports of the
    others) and the acoustic links heard recently between them."""

    REPORT_VARS = ("NODE_REPORT", "NODE_REPORT_LOCAL")

    def __init__(
        self,
        community: str,
        geodesy: UTMGeodesy,
        modem_ids: ModemIdLookup,
        report_vars: list[str],
        receive_var: str,
        transmit_var: str,
        link_seconds: float = 120,
        max_track: int = 500,
    ) -> None:
        self.community = community
        self.geodesy = geodesy
        self.modem_ids = modem_ids
        self.report_vars = set(self.REPORT_VARS) | set(report_vars)
        self.receive_var, self.transmit_var = receive_var, transmit_var
        self.link_seconds = link_seconds
        self.max_track = max_track
        self.nodes: dict[str, Node] = {}
        self.links: dict[tuple[str, str], float] = {}
        self.own_id: int | None = None
        self._nav: dict[str, float] = {}

    @property
    def variables(self) -> list[str]:
        return sorted(
            {
                *self.report_vars,
                "NAV_X",
                "NAV_Y",
                "NAV_HEADING",
                "NAV_LAT",
                "NAV_LONG",
                "MODEM_ID",
                self.receive_var,
                self.transmit_var,
            }
        )

    def _name(self, modem_id: int) -> str:
        if modem_id == self.own_id:
            return self.community
        return self.modem_ids.name(modem_id)

    def _place(self, name: str, x: float, y: float, heading: float | None, when: float) -> None:
        node = self.nodes.get(name)
        if node is None:
            node = self.nodes[name] = Node(name, x, y, heading, when, deque(maxlen=self.max_track))
        node.x, node.y, node.time = x, y, when
        if heading is not None:
            node.heading = heading
        if not node.track or node.track[-1] != (x, y):
            node.track.append((x, y))

    def handle(self, msg: MOOSMessage) -> None:
        key, value = msg.key, msg.value
        if key == "MODEM_ID" and isinstance(value, float):
            self.own_id = int(value)
        elif key.startswith("NAV_") and isinstance(value, float):
            self._nav[key] = value
            if key in ("NAV_X", "NAV_Y", "NAV_LAT", "NAV_LONG", "NAV_HEADING") and self.community:
                self._own_position(msg.time)
        elif key in self.report_vars and isinstance(value, str):
            self._report(value, msg.time)
        elif key in (self.receive_var, self.transmit_var) and isinstance(value, str | bytes):
            self._link(key == self.receive_var, value, msg.time)

    def _own_position(self, when: float) -> None:
        nav = self._nav
        x, y = nav.get("NAV_X"), nav.get("NAV_Y")
        if (x is None or y is None) and "NAV_LAT" in nav and "NAV_LONG" in nav:
            x, y = self.geodesy.to_local(nav["NAV_LAT"], nav["NAV_LONG"])
        if x is not None and y is not None and math.isfinite(x) and math.isfinite(y):
            self._place(self.community, x, y, nav.get("NAV_HEADING"), when)

    def _report(self, text: str, when: float) -> None:
        def get(*keys: str) -> str | None:
            for key in keys:
                found = val_from_string(text, key)
                if found is not None:
                    return found
            return None

        name = get("name", "NAME")
        if name is None:
            src = _number(get("src", "modem_id"))
            if src is None:
                return
            name = self._name(int(src))
        x, y = _number(get("x", "X")), _number(get("y", "Y"))
        if x is None or y is None:
            lat, lon = _number(get("lat", "LAT")), _number(get("lon", "LON"))
            if lat is None or lon is None:
                return
            x, y = self.geodesy.to_local(lat, lon)
        heading = _number(get("heading", "HDG", "hdg"))
        self._place(name, x, y, heading, when)

    def _link(self, received: bool, value: MoosValue, when: float) -> None:
        transmission = acomms_pb.ModemTransmission()
        try:
            parse_for_moos(value, transmission)
        except Exception:
            return
        if transmission.type == acomms_pb.ModemTransmission.ACK and not received:
            return
        if self.own_id is None or transmission.src < 0:
            return
        src = self._name(transmission.src)
        dest_id = transmission.dest if not received else self.own_id
        if dest_id is None or dest_id < 0:
            return
        if received:
            self.links[(src, self.community)] = when
        elif dest_id > 0:
            self.links[(self.community, self._name(dest_id))] = when

    def saved(self) -> object:
        """What mail changed (for `restore`: a log replay's checkpoint); pickles."""
        return (self.nodes, self.links, self.own_id, self._nav)

    def restore(self, saved: object) -> None:
        """Back to what `saved` gave (an unpickled copy: nothing shared with the saved one)."""
        assert isinstance(saved, tuple)
        self.nodes, self.links, self.own_id, self._nav = saved

    def snapshot(self, now: float) -> dict:
        return {
            "community": self.community,
            "nodes": [
                {
                    "name": n.name,
                    "x": n.x,
                    "y": n.y,
                    "heading": n.heading,
                    "age": round(now - n.time, 1),
                    "track": list(n.track),
                }
                for n in self.nodes.values()
            ],
            "links": [
                {"from": a, "to": b, "age": round(now - t, 1)}
                for (a, b), t in self.links.items()
                if now - t <= self.link_seconds
            ],
        }
