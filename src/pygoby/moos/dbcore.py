"""The MOOSDB's semantics, sans I/O: variables, subscriptions, routing, server requests.

`DBCore` is fed events (a handshake, a packet of messages from a named client, a disconnect)
and returns what to send to whom; the asyncio server in `db.py` owns the sockets and timeouts.
Behaviour follows the C++ MOOSDB (spec moos.md sections 8-13): the first write fixes a
variable's type (S and B differ) and other writes are dropped silently; subscribing queues the
current value at once; an interval drops updates that come too soon; wildcard filters are
tested when a variable is first written or when the filter is registered; the DB publishes
DB_TIME, DB_UPTIME, DB_CLIENTS, DB_VARSUMMARY, DB_QOS, DB_RWSUMMARY (refreshed at most every
2 s of DB time, when a packet with more than a T message arrives) and DB_EVENT on connect and
disconnect.
"""

from __future__ import annotations

import logging
import math
import time as _time
from dataclasses import dataclass, field

from pygoby.moos import protocol as p
from pygoby.util.clock import Clock, WallClock

log = logging.getLogger(__name__)

REFRESH_PERIOD = 2.0
DB_VARIABLES = ("DB_TIME", "DB_UPTIME", "DB_CLIENTS", "DB_VARSUMMARY", "DB_QOS", "DB_RWSUMMARY")


@dataclass(slots=True)
class Subscription:
    interval: float
    last_sent: float = 0.0


@dataclass(slots=True)
class Variable:
    name: str
    data_type: str = p.NOT_SET
    dval: float = -1.0
    sval: bytes = b""
    time: float = -1.0
    src: str = ""
    src_aux: str = ""
    community: str = ""
    write_time: float = -1.0
    writes: int = 0
    write_rate: float = 0.0
    writers: set[str] = field(default_factory=set)
    subscribers: dict[str, Subscription] = field(default_factory=dict)

    def snapshot(self) -> p.MOOSMessage:
        """The current value as the N message a new subscriber gets."""
        is_double = self.data_type == p.DOUBLE
        return p.MOOSMessage(
            p.NOTIFY, self.data_type, self.name, self.time, self.dval if is_double else -1.0,
            -1.0, b"" if is_double else self.sval, self.src, self.src_aux, self.community, -1,
        )  # fmt: skip

    def clear(self) -> None:
        self.dval, self.sval, self.time, self.src, self.src_aux = -1.0, b"", -1.0, "", ""
        self.write_time, self.writes, self.write_rate = -1.0, 0, 0.0
        self.writers.clear()


@dataclass(slots=True)
class ClientRecord:
    name: str
    asynchronous: bool
    held: list[p.MOOSMessage] = field(default_factory=list)
    filters: dict[tuple[str, str], float] = field(default_factory=dict)
    latencies_ms: list[float] = field(default_factory=list)
    published: set[str] = field(default_factory=set)


class DBCore:
    """MOOSDB logic. Times: `clock.now()` is the DB's MOOSTime (warped epoch seconds)."""

    def __init__(
        self, community: str = p.DEFAULT_COMMUNITY, clock: Clock | None = None,
        hostname: str = "localhost",
    ) -> None:  # fmt: skip
        self.community = community or p.DEFAULT_COMMUNITY
        self.clock = clock or WallClock()
        self.hostname = hostname
        self.name = f"MOOSDB_{self.community}"
        self.start_time = self.clock.now()
        self._last_refresh = self.start_time
        self.variables: dict[str, Variable] = {n: Variable(n) for n in DB_VARIABLES}
        self.variables["DB_EVENT"] = Variable("DB_EVENT")
        self.clients: dict[str, ClientRecord] = {}

    # -- connections ---------------------------------------------------------------------------

    def connect(self, handshake: p.MOOSMessage) -> p.MOOSMessage:
        """Handle a handshake message; returns the W (accepted) or K (refused) reply."""
        now = self.clock.now()
        name = handshake.string
        if name in self.clients or not name:
            reason = p.name_in_use_reason(name) if name else "Failed to read receive client's name"
            log.warning("refusing client %r: %s", name, reason)
            return p.poison_message(reason, now)
        asynchronous = handshake.key.lower() == p.ASYNC_HANDSHAKE_KEY
        self.clients[name] = ClientRecord(name, asynchronous)
        self._write_own("DB_EVENT", f"connected={name}")
        return p.welcome_message(self.community, self.hostname, now, now - handshake.time)

    def disconnect(self, name: str) -> dict[str, list[p.MOOSMessage]]:
        """Forget a client: its subscriptions, filters and held mail. Returns pushes."""
        if self.clients.pop(name, None) is None:
            return {}
        for var in self.variables.values():
            var.subscribers.pop(name, None)
        self._write_own("DB_EVENT", f"disconnected={name}")
        return self.collect_pushes(exclude=None)

    # -- packets -------------------------------------------------------------------------------

    def process_packet(
        self, name: str, msgs: list[p.MOOSMessage]
    ) -> dict[str, list[p.MOOSMessage]]:
        """Process one packet from client `name`; returns {client: messages to send}."""
        client = self.clients[name]
        reply: list[p.MOOSMessage] = []
        if client.asynchronous:
            if msgs and msgs[0].msg_type == p.TIMING:
                echo = msgs[0].copy()
                echo.dval = self.clock.now()
                echo.dval2 = 0.0
                client.latencies_ms.append((echo.dval - echo.time) * 1000.0)
                del client.latencies_ms[:-50]
                reply.append(echo)
                msgs = msgs[1:]
        else:
            reply.append(p.MOOSMessage(p.NULL, p.DOUBLE, "", -1.0, self.clock.now()))
        answers: list[p.MOOSMessage] = []
        had_notify = False
        for msg in msgs:
            kind = msg.msg_type
            if kind == p.NOTIFY:
                had_notify = True
                self._on_notify(msg)
            elif kind == p.REGISTER:
                interval = msg.dval if math.isfinite(msg.dval) and msg.dval > 0 else 0.0
                self._on_register(msg.src, msg.key, interval)
            elif kind == p.UNREGISTER:
                var = self.variables.get(msg.key)
                if var is not None:
                    var.subscribers.pop(msg.src, None)
            elif kind == p.WILDCARD_REGISTER:
                self._on_wildcard(msg.src, msg.sval, register=True)
            elif kind == p.WILDCARD_UNREGISTER:
                self._on_wildcard(msg.src, msg.sval, register=False)
            elif kind == p.SERVER_REQUEST:
                answers.extend(self._server_request(msg))
        if msgs:  # a packet holding only a T does not refresh (vector seqs 87, 155-159)
            self._maybe_refresh()
        reply.extend(client.held)
        client.held = []
        reply.extend(answers)
        out: dict[str, list[p.MOOSMessage]] = {}
        if had_notify:
            out = self.collect_pushes(exclude=name)
        if reply:
            out[name] = reply
        return out

    def collect_pushes(self, exclude: str | None) -> dict[str, list[p.MOOSMessage]]:
        """Take the held mail of every asynchronous client (except `exclude`) for pushing."""
        out = {}
        for other in self.clients.values():
            if other.held and other.asynchronous and other.name != exclude:
                out[other.name] = other.held
                other.held = []
        return out

    # -- notify / register ---------------------------------------------------------------------

    def _variable(self, name: str) -> Variable:
        var = self.variables.get(name)
        if var is None:
            var = self.variables[name] = Variable(name)
        return var

    def _on_notify(self, msg: p.MOOSMessage) -> None:
        var = self._variable(msg.key)
        now = self.clock.now()
        if var.writes == 0:
            var.data_type = msg.data_type
            self._apply_filters_on_creation(var, msg.src)
        elif msg.data_type != var.data_type:
            log.info(
                'Attempting to update var "%s" which is type %s with data type %s by client %s',
                var.name, var.data_type, msg.data_type, msg.src,
            )  # fmt: skip
            return
        if msg.data_type == p.DOUBLE:
            var.dval = msg.dval
        else:
            var.sval = msg.sval
        if not msg.community:
            msg.community = self.community
        if var.writes and now > var.write_time:
            var.write_rate = 0.9 * var.write_rate + 0.1 / (now - var.write_time)
        var.time, var.src, var.src_aux, var.community = msg.time, msg.src, msg.src_aux, msg.community
        var.write_time = now
        var.writes += 1
        var.writers.add(msg.src)
        publisher = self.clients.get(msg.src)
        if publisher is not None:
            publisher.published.add(var.name)
        for sub_name, sub in var.subscribers.items():
            if sub.interval == 0.0 or now - sub.last_sent >= sub.interval:
                sub.last_sent = now
                client = self.clients.get(sub_name)
                if client is not None:
                    client.held.append(msg)

    def _write_own(self, name: str, value: float | str) -> None:
        self._on_notify(p.notify(name, value, time=self.clock.now(), src=self.name))

    def _on_register(self, subscriber: str, key: str, interval: float) -> None:
        client = self.clients.get(subscriber)
        if client is None or not key:
            return  # the subscriber is `src`; an empty or unknown one is ignored
        var = self._variable(key)
        sub = var.subscribers[subscriber] = Subscription(interval)
        if var.writes > 0:
            client.held.append(var.snapshot())
            sub.last_sent = self.clock.now()

    def _on_wildcard(self, subscriber: str, sval: bytes, register: bool) -> None:
        client = self.clients.get(subscriber)
        if client is None:
            return
        app, var_pattern, interval = p.parse_wildcard_sval(sval)
        if register:
            client.filters.setdefault((app, var_pattern), interval)
        for var in sorted(self.variables.values(), key=lambda v: v.name):  # the C++ map's order
            if p.wildcard_match(var_pattern, var.name) and p.wildcard_match(app, var.src):
                if register:
                    self._on_register(subscriber, var.name, interval)
                else:
                    var.subscribers.pop(subscriber, None)

    def _apply_filters_on_creation(self, var: Variable, publisher: str) -> None:
        for client in self.clients.values():
            for (app, var_pattern), interval in client.filters.items():
                if p.wildcard_match(var_pattern, var.name) and p.wildcard_match(app, publisher):
                    var.subscribers[client.name] = Subscription(interval)
                    break

    # -- server requests -----------------------------------------------------------------------

    def _server_request(self, msg: p.MOOSMessage) -> list[p.MOOSMessage]:
        key = msg.key
        now = self.clock.now()
        if key == "ALL":
            out = []
            for var in sorted(self.variables.values(), key=lambda v: v.name, reverse=True):
                rel = var.write_time - self.start_time if var.writes else -1.0
                out.append(p.MOOSMessage(
                    p.NOTIFY, var.data_type, var.name, rel, var.dval, var.write_rate, var.sval,
                    var.src, var.src_aux, var.community, msg.id,
                ))  # fmt: skip
            return out
        if "VAR_SUMMARY" in key:
            names = ",".join(sorted(self.variables))
            return [self._reply("VAR_SUMMARY", now, names, msg.id, community="")]
        if "PROC_SUMMARY" in key:
            out = []
            for client in self.clients.values():
                subs = "".join(f",{n}" for n in self._subscribed(client.name))
                pubs = "".join(f",{n}" for n in sorted(client.published))
                text = f"{client.name}:SUBSCRIBED={subs},PUBLISHED={pubs}"
                out.append(self._reply("PROC_SUMMARY", now - self.start_time, text, msg.id, ""))
            return out
        if "DB_CLEAR" in key:
            for var in self.variables.values():
                var.clear()
            for client in self.clients.values():
                client.held = []
            self.start_time = now
            return []
        return []

    def _reply(
        self, key: str, time: float, text: str, msg_id: int, community: str | None = None
    ) -> p.MOOSMessage:
        msg = p.notify(key, text, time=time, src=self.name, msg_id=msg_id)
        msg.community = self.community if community is None else community
        return msg

    def _subscribed(self, name: str) -> list[str]:
        return sorted(v.name for v in self.variables.values() if name in v.subscribers)

    # -- DB_* variables ------------------------------------------------------------------------

    def _maybe_refresh(self) -> None:
        now = self.clock.now()
        if now - self._last_refresh <= REFRESH_PERIOD:
            return
        self._last_refresh = now
        self._write_own("DB_TIME", now)
        self._write_own("DB_UPTIME", now - self.start_time)
        # the C++ DB lists clients in reverse name order (vector seqs 44, 77)
        self._write_own("DB_CLIENTS", "".join(f"{n}," for n in sorted(self.clients, reverse=True)))
        self._write_own("DB_VARSUMMARY", self._var_summary())
        if self.clients and all(c.latencies_ms for c in self.clients.values()):
            self._write_own("DB_QOS", self._qos())
        self._write_own("DB_RWSUMMARY", self._rw_summary())

    def _qos(self) -> str:
        parts = []
        for c in self.clients.values():
            lat = c.latencies_ms
            parts.append(f"{c.name}={lat[-1]:.3f}:{max(lat):.3f}:{min(lat):.3f}:{sum(lat) / len(lat):.3f},")
        return "".join(parts)

    def _rw_summary(self) -> str:
        return ",".join(
            f"{c.name}={':'.join(self._subscribed(c.name))}&{':'.join(sorted(c.published))}"
            for c in self.clients.values()
        )

    def _var_summary(self) -> str:
        lines = []
        for var in sorted(self.variables.values(), key=lambda v: v.name):
            when = _time.strftime("%H:%M:%S", _time.gmtime(var.write_time)) if var.writes else "-"
            writer = var.src if var.writes else "(write pending)"
            if var.data_type == p.DOUBLE:
                value = f"{var.dval:.1f}"
            elif var.data_type == p.BINARY:
                value = _binary_size(len(var.sval))
            else:
                text = p.decode_text(var.sval)
                value = text[:22] + "..." if len(text) > 25 else text
            lines.append(f"{var.name} {when} {writer} {var.write_rate:.1f} Hz {var.data_type} {value}")
        return "\n".join(lines)


def _binary_size(n: int) -> str:
    if n < 1024:
        return f"*binary* {n} B"
    if n < 1024 * 1024:
        return f"*binary* {n / 1024:.1f} KB"
    return f"*binary* {n / (1024 * 1024):.1f} MB"
