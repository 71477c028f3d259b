"""The MOOSDB's semantics, sans I/O: variables, subscriptions, routing, server requests.

`DBCore` is fed events (a handshake, a packet's bytes from a named client, a disconnect); what
they cause to be sent collects in each client's outgoing buffer, which the asyncio server in
`db.py` takes (`take_ready`) and writes once per event-loop iteration. Behaviour follows the
C++ MOOSDB (QUIRKS.md Q-MOOS-1 to 4): the first write fixes a variable's type (S and B differ)
and other writes are dropped silently; subscribing queues the current value at once; an interval
drops updates that come too soon; wildcard filters are tested when a variable is first written
or when the filter is registered; the DB publishes DB_TIME, DB_UPTIME, DB_CLIENTS,
DB_VARSUMMARY, DB_QOS, DB_RWSUMMARY (refreshed at most every 2 s of DB time, when a packet with
more than a T message arrives) and DB_EVENT on connect and disconnect.

The hot path is a notification: it is forwarded to its subscribers as the bytes it arrived in
(the DB's community spliced in when the publisher left it empty, as the C++ DB does), parsing
only what routing needs (key, data type, source). A variable keeps its last message as those
bytes and decodes it only when asked (a snapshot for a new subscriber, `Q ALL`, summaries).
A packet's messages are processed at one DB time (the clock is read once per packet).

Bounds (none in the C++ DB; each refusal is logged once per client): variable names and client
names at most MAX_NAME_LENGTH bytes, wildcard patterns at most MAX_PATTERN_LENGTH (MOOS names
are identifiers such as NAV_X or ACOMMS_RAW_INCOMING, a few tens of bytes) and MAX_WILDCARDS
of them per client (an app registers a handful); at most
`max_variables` variables; the stored values at most `store_budget` bytes. The summaries keep
each variable's line until the variable is written again and the sorted name list until a
variable is added, so a refresh decodes only what changed, and at most
SUMMARY_LINES_PER_REFRESH variables (a variable whose new line waits keeps its previous one).
"""

from __future__ import annotations

import itertools
import logging
import math
import struct
import time as _time

from pygoby.moos import protocol as p
from pygoby.moos.errors import MoosProtocolError
from pygoby.util.clock import Clock, WallClock

log = logging.getLogger(__name__)

REFRESH_PERIOD = 2.0
MAX_NAME_LENGTH = 256  # bytes of a variable or client name
MAX_PATTERN_LENGTH = 256  # characters of a wildcard pattern (app or variable)
MAX_WILDCARDS = 256  # wildcard registrations a client keeps (each new variable tests them all)
# ten times a large community; a `*` subscription or `Q ALL` then costs the DB at most ~0.5 s
# (~25 us a variable)
DEFAULT_MAX_VARIABLES = 20_000
# what a variable costs beside its value (measured: 100,000 variables of 20-character names,
# their index entries and summary lines grow the DB's RSS by ~100 MB)
VARIABLE_OVERHEAD = 1000
# DB_VARSUMMARY lines made per refresh (~25 us each: a burst of new variables costs at most
# ~0.1 s per refresh; the lines not made yet come in the next refreshes, the others stay)
SUMMARY_LINES_PER_REFRESH = 4000
DB_VARIABLES = ("DB_TIME", "DB_UPTIME", "DB_CLIENTS", "DB_VARSUMMARY", "DB_QOS", "DB_RWSUMMARY")
# Outgoing packets are cut at this size: mail merged over one loop iteration can be large.
MAX_OUTGOING_PACKET = 1 << 20

_HEADER = struct.Struct("<iiB")
_INT = struct.Struct("<i")
_NOTIFY = ord(p.NOTIFY)
_TIMING = ord(p.TIMING)
# the V10 layout (pygoby.moos.protocol) as the fast path reads it: the id and the two type
# bytes come as one 6-byte string
_ID_TYPES_SIZE = p.SRC_AT - p.ID_AT
_MSG_TYPE_IN_ID_TYPES = p.MSG_TYPE_AT - p.ID_AT
_DATA_TYPE_IN_ID_TYPES = p.DATA_TYPE_AT - p.ID_AT
_STRING_LENGTH_SIZE = p.STRING_LENGTH_SIZE
_TAIL_SIZE = p.MESSAGE_TAIL.size
_DOUBLE = ord(p.DOUBLE)
_NOT_SET = ord(p.NOT_SET)


class Subscription:
    """One client's subscription to one variable (interval in DB seconds; 0 = every update)."""

    __slots__ = ("client", "interval", "last_sent")

    def __init__(self, client: ClientRecord, interval: float) -> None:
        self.client = client
        self.interval = interval
        self.last_sent = 0.0


class Variable:
    """One MOOS variable; its value is the last notification as forwarded (`raw`)."""

    __slots__ = (
        "accepts",
        "community",
        "every_update",
        "key",
        "last_source",
        "name",
        "raw",
        "subscribers",
        "summary",
        "summary_of",
        "timed",
        "type_code",
        "write_rate",
        "write_time",
    )

    def __init__(self, name: str) -> None:
        self.name = name
        self.key = p.encode_text(name)
        self.type_code = _NOT_SET
        self.accepts = -1  # the type code of the writes routed without further checks
        self.raw: bytes | None = None  # None: never written (since the last DB_CLEAR)
        self.community = ""  # of a variable cleared by DB_CLEAR (the C++ DB keeps it)
        self.write_time = -1.0
        self.write_rate = 0.0
        self.last_source: _Source | None = None  # whose publisher already lists this variable
        self.subscribers: dict[str, Subscription] = {}
        # routing tables derived from `subscribers` (rebuilt when they change): the held-mail
        # appenders of interval-0 subscribers, and the subscriptions with an interval
        self.every_update: list | tuple = ()  # () until subscribed: less memory per variable
        self.timed: list[Subscription] | tuple = ()
        # the DB_VARSUMMARY line, and the value it was made from (`raw` is a new object at
        # every write, so the line is current while `summary_of is raw`)
        self.summary = ""
        self.summary_of: object = self

    @property
    def data_type(self) -> str:
        return chr(self.type_code)

    @property
    def written(self) -> bool:
        return self.raw is not None

    def message(self) -> p.MOOSMessage:
        """The stored value as a message (an empty one with defaults when never written)."""
        if self.raw is None:
            return p.MOOSMessage(p.NOTIFY, self.data_type, self.name, community=self.community)
        return p.decode_message(self.raw)[0]

    @property
    def src(self) -> str:
        return self.message().src if self.raw is not None else ""

    def snapshot(self) -> bytes:
        """The current value as the N message a new subscriber gets (id -1, dval2 -1)."""
        m = self.message()
        is_double = self.type_code == _DOUBLE
        return p.encode_message(
            p.MOOSMessage(
                p.NOTIFY,
                m.data_type,
                self.name,
                m.time,
                m.dval if is_double else -1.0,
                -1.0,
                b"" if is_double else m.sval,
                m.src,
                m.src_aux,
                m.community,
                -1,
            )
        )

    def subscribe(self, client: ClientRecord, interval: float) -> Subscription:
        sub = self.subscribers[client.name] = Subscription(client, interval)
        client.subscribed.add(self.name)
        client.rw_summary = None
        self._reroute()
        return sub

    def unsubscribe(self, name: str) -> None:
        sub = self.subscribers.pop(name, None)
        if sub is not None:
            sub.client.subscribed.discard(self.name)
            sub.client.rw_summary = None
            self._reroute()

    def _reroute(self) -> None:
        subs = self.subscribers.values()
        self.every_update = [s.client.held.append for s in subs if s.interval == 0.0]
        self.timed = [s for s in subs if s.interval != 0.0]

    def clear(self) -> int:
        """Forget the value; the bytes it held."""
        held = 0
        if self.raw is not None:
            self.community = self.message().community
            held = len(self.raw)
        self.raw = None
        self.summary_of = self  # its line is out of date (an unwritten variable's was None)
        self.accepts = -1
        self.write_time, self.write_rate = -1.0, 0.0
        return held


class ClientRecord:
    """A connected client: its held mail (queued, not yet due), its outgoing buffer (due, not
    yet written), wildcard filters, timing statistics and the variables it published."""

    __slots__ = (
        "asynchronous",
        "breaks",
        "filters",
        "held",
        "held_bytes",
        "held_counted",
        "latencies_ms",
        "name",
        "out",
        "published",
        "refused",
        "rw_summary",
        "subscribed",
    )

    def __init__(self, name: str, asynchronous: bool) -> None:
        self.name = name
        self.asynchronous = asynchronous
        self.held: list[bytes] = []  # encoded messages; the list object is never replaced
        self.out: list[bytes] = []
        self.breaks: list[int] = []  # indices in `out` that must start a packet (T echo, null)
        self.filters: dict[tuple[str, str], tuple[p.Glob, p.Glob, float]] = {}
        self.latencies_ms: list[float] = []
        self.published: set[str] = set()
        self.subscribed: set[str] = set()
        self.rw_summary: str | None = None  # its DB_RWSUMMARY entry, None when out of date
        self.refused: set[str] = set()  # the kinds of refusal already logged for it
        # the bytes of held mail: `held_bytes` counts held[:held_counted] (see held_size)
        self.held_counted = 0
        self.held_bytes = 0

    def held_size(self) -> int:
        """Bytes of mail held for this client (counting only what was added since last time;
        mail queued for several clients is counted for each)."""
        held = self.held
        if len(held) > self.held_counted:
            self.held_bytes += sum(map(len, held[self.held_counted :]))
            self.held_counted = len(held)
        return self.held_bytes

    def drop_held(self) -> None:
        self.held.clear()
        self.held_counted = self.held_bytes = 0

    def release(self, head: bytes | None = None, tail: list[bytes] | None = None) -> None:
        """Make [head] + held mail + [tail] due, as one packet (merged with mail made due
        earlier unless `head` is given: a T echo or a null must lead its packet)."""
        out = self.out
        if head is not None:
            self.breaks.append(len(out))
            out.append(head)
        if self.held:
            out += self.held
            self.drop_held()
        if tail:
            out += tail

    def take_output(self) -> bytes:
        """Everything due, as packets, in one byte string; empties the buffer."""
        out, cuts = self.out, self.breaks
        chunks: list[bytes] = []
        start = 0
        for cut in [*cuts, len(out)]:
            if cut > start:
                _append_packets(chunks, out[start:cut])
            start = cut
        self.out = []
        self.breaks = []
        return b"".join(chunks)


def _append_packets(chunks: list[bytes], msgs: list[bytes]) -> None:
    total = p.PACKET_HEADER_SIZE + sum(map(len, msgs))
    if total > MAX_OUTGOING_PACKET and len(msgs) > 1:
        half = len(msgs) // 2
        _append_packets(chunks, msgs[:half])
        _append_packets(chunks, msgs[half:])
        return
    chunks.append(_HEADER.pack(total, len(msgs), 0))
    chunks += msgs


class _Source:
    """What the DB learnt from a message's src/src_aux/community bytes, for the messages that
    follow with the same bytes (normally every message of a client's packet)."""

    __slots__ = ("forwarded", "growth", "head", "layout", "publisher", "src")

    def __init__(self, core: DBCore, data: bytes, at: int, stop: int) -> None:
        src, pos = p.read_str(data, at, stop, "src")
        if len(src) > MAX_NAME_LENGTH:  # the src is a client name: app patterns test it
            raise MoosProtocolError(
                f"src of {len(src)} bytes is longer than a name may be ({MAX_NAME_LENGTH})"
            )
        _aux, pos = p.read_str(data, pos, stop, "src_aux")
        community, pos = p.read_str(data, pos, stop, "community")
        self.head = bytes(data[at:pos])
        # msg_len, id + msg_type + data_type, these bytes, key length
        self.layout = struct.Struct(f"<i{_ID_TYPES_SIZE}s{len(self.head)}si")
        self.src = p.decode_text(src)
        self.publisher = core.clients.get(self.src)
        if community:  # bridged from another community: forwarded untouched
            self.forwarded: bytes | None = None
            self.growth = 0
        else:  # the DB fills in its own community for the empty one (its length alone)
            self.forwarded = self.head[:-_STRING_LENGTH_SIZE] + core.community_field
            self.growth = len(core.community_field) - _STRING_LENGTH_SIZE


class DBCore:
    """MOOSDB logic. Times: `clock.now()` is the DB's MOOSTime (warped epoch seconds)."""

    def __init__(
        self,
        community: str = p.DEFAULT_COMMUNITY,
        clock: Clock | None = None,
        hostname: str = "localhost",
        max_variables: int = DEFAULT_MAX_VARIABLES,
        store_budget: int | None = None,
    ) -> None:
        """`max_variables`: most variables (refused beyond); `store_budget`: most bytes of
        stored values and variables (a write beyond it is refused; None: no bound)."""
        self.community = community or p.DEFAULT_COMMUNITY
        community_bytes = p.encode_text(self.community)
        self.community_field = _INT.pack(len(community_bytes)) + community_bytes
        self.clock = clock or WallClock()
        self.hostname = hostname
        self.name = f"MOOSDB_{self.community}"
        self.start_time = self.clock.now()
        self._last_refresh = self.start_time
        self.max_variables = max_variables
        self.store_budget = store_budget if store_budget is not None else math.inf
        self.stored_bytes = 0  # the variables and their values (VARIABLE_OVERHEAD each)
        self.variables: dict[str, Variable] = {}
        self._by_key: dict[bytes, Variable] = {}
        self._sorted: list[Variable] = []  # by name, but for the variables in `_unsorted`
        self._unsorted: list[Variable] = []
        self._summary_from = 0  # where in `_sorted` the next refresh starts making lines
        for name in (*DB_VARIABLES, "DB_EVENT"):
            self._variable(name)
        self.clients: dict[str, ClientRecord] = {}
        self._ready: dict[str, ClientRecord] = {}
        own = p.encode_message(p.notify("_", 0.0, time=0.0, src=self.name))
        self._source = _Source(self, own, p.SRC_AT, len(own))

    # -- connections ---------------------------------------------------------------------------

    def connect(self, handshake: p.MOOSMessage) -> p.MOOSMessage:
        """Handle a handshake message; returns the W (accepted) or K (refused) reply, which
        the caller sends before anything else to that client."""
        now = self.clock.now()
        name = handshake.string
        if name in self.clients or not name or len(handshake.sval) > MAX_NAME_LENGTH:
            if len(handshake.sval) > MAX_NAME_LENGTH:
                reason = f"a client name is at most {MAX_NAME_LENGTH} bytes"
                name = name[:40] + "..."
            elif name:
                reason = p.name_in_use_reason(name)
            else:
                reason = "Failed to read receive client's name"
            log.warning("refusing client %r: %s", name, reason)
            return p.poison_message(reason, now)
        asynchronous = handshake.key.lower() == p.ASYNC_HANDSHAKE_KEY
        self.clients[name] = ClientRecord(name, asynchronous)
        self._relearn_source()
        self._write_own("DB_EVENT", f"connected={name}")
        self._push(exclude=name)
        return p.welcome_message(self.community, self.hostname, now, now - handshake.time)

    def disconnect(self, name: str) -> None:
        """Forget a client: its subscriptions, filters, held and unwritten mail."""
        client = self.clients.pop(name, None)
        if client is None:
            return
        self._ready.pop(name, None)
        self._relearn_source()
        for var_name in list(client.subscribed):
            self.variables[var_name].unsubscribe(name)
        self._write_own("DB_EVENT", f"disconnected={name}")
        self._push(exclude=None)

    def take_ready(self) -> list[ClientRecord]:
        """The clients with output due (each then gives it with `take_output()`)."""
        ready = list(self._ready.values())
        self._ready.clear()
        return ready

    # -- packets -------------------------------------------------------------------------------

    def process_packet(
        self, name: str, data: bytes, start: int = 0, end: int | None = None
    ) -> None:
        """Process the packet in data[start:end] from client `name` (MoosProtocolError if it is
        malformed: the messages before the fault have taken effect)."""
        client = self.clients[name]
        if end is None:
            end = len(data)
        if end - start < p.PACKET_HEADER_SIZE:
            raise MoosProtocolError(f"packet of {end - start} bytes is shorter than its header")
        total, count, _ = _HEADER.unpack_from(data, start)
        if total != end - start or count < 0:
            raise MoosProtocolError(
                f"packet header ({total} bytes, {count} messages) does not "
                f"fit the {end - start} bytes given"
            )
        now = self.clock.now()
        pos = start + p.PACKET_HEADER_SIZE
        head = None
        if not client.asynchronous:
            head = p.encode_message(p.MOOSMessage(p.NULL, p.DOUBLE, "", -1.0, now))
        elif count and end - pos >= p.MESSAGE_FIXED_SIZE and data[pos + p.MSG_TYPE_AT] == _TIMING:
            timing, pos = p.decode_message(data, pos, end)
            count -= 1
            timing.dval = now
            timing.dval2 = 0.0
            client.latencies_ms.append((now - timing.time) * 1000.0)
            del client.latencies_ms[:-50]
            head = p.encode_message(timing)
        answers: list[bytes] = []
        had_notify = self._process_messages(client, data, pos, end, count, now, answers)
        if count:  # a packet holding only a T does not refresh (vector seqs 87, 155-159)
            self._maybe_refresh(now)
        if head is not None or client.held or answers:
            client.release(head, answers)
            self._ready[name] = client
        if had_notify:
            self._push(exclude=name)

    def _push(self, exclude: str | None) -> None:
        """Make the held mail of every asynchronous client (but `exclude`) due."""
        ready = self._ready
        for other in self.clients.values():
            if other.held and other.asynchronous and other.name != exclude:
                other.release()
                ready[other.name] = other

    def _process_messages(
        self,
        client: ClientRecord | None,
        data: bytes,
        pos: int,
        end: int,
        count: int,
        now: float,
        answers: list[bytes],
    ) -> bool:
        """Apply `count` messages from data[pos:end]; True if one was a notification."""
        by_key = self._by_key
        read_int = _INT.unpack_from
        pack_int = _INT.pack
        source = self._source
        head, read_start, forwarded, growth = (
            source.head,
            source.layout.unpack_from,
            source.forwarded,
            source.growth,
        )
        key_at_offset = p.SRC_AT + len(head)
        # the layout's offsets as locals: the loop below runs for every message the DB gets
        tail_size, sval_length_in_tail = _TAIL_SIZE, p.SVAL_LENGTH_IN_TAIL
        msg_type_in, data_type_in = _MSG_TYPE_IN_ID_TYPES, _DATA_TYPE_IN_ID_TYPES
        length_size = _STRING_LENGTH_SIZE
        had_notify = False
        for _ in range(count):
            try:  # one unpack reads a notification from the remembered source up to its key
                msg_len, id_types, head_seen, key_len = read_start(data, pos)
            except struct.error:  # the layout runs past the buffer: read it the long way
                head_seen = None
            if head_seen != head:
                if end - pos < p.MESSAGE_FIXED_SIZE:
                    raise MoosProtocolError("message truncated before the end of its fixed fields")
                msg_len, _, msg_type, _ = p.MESSAGE_START.unpack_from(data, pos)
                stop = pos + msg_len
                if msg_len < p.MESSAGE_FIXED_SIZE or stop > end or msg_type != _NOTIFY:
                    self._on_other(client, p.decode_message(data, pos, end)[0], now, answers)
                    pos = stop
                    continue
                source = self._source = _Source(self, data, pos + p.SRC_AT, stop)
                head, read_start, forwarded, growth = (
                    source.head,
                    source.layout.unpack_from,
                    source.forwarded,
                    source.growth,
                )
                key_at_offset = p.SRC_AT + len(head)
                msg_len, id_types, head_seen, key_len = read_start(data, pos)
            stop = pos + msg_len
            if msg_len < p.MESSAGE_FIXED_SIZE or stop > end:
                raise MoosProtocolError(
                    f"message length {msg_len} is below "
                    f"{p.MESSAGE_FIXED_SIZE} or runs past the packet end"
                )
            if id_types[msg_type_in] != _NOTIFY:
                self._on_other(client, p.decode_message(data, pos, stop)[0], now, answers)
                pos = stop
                continue
            had_notify = True
            data_type = id_types[data_type_in]
            key_at = pos + key_at_offset
            key_end = key_at + length_size + key_len
            if key_len < 0 or key_end + tail_size > stop:
                raise MoosProtocolError(
                    f"key length {key_len} is negative or runs past the message end"
                )
            (sval_len,) = read_int(data, key_end + sval_length_in_tail)
            if sval_len < 0 or key_end + tail_size + sval_len != stop:
                raise MoosProtocolError(f"sval length {sval_len} does not end the message")
            if forwarded is None:
                raw = data[pos:stop]
            else:
                raw = b"".join((pack_int(msg_len + growth), id_types, forwarded, data[key_at:stop]))
            var = by_key.get(data[key_at + length_size : key_end])
            if var is None or var.accepts != data_type:
                var = self._first_or_mistyped_write(
                    client,
                    var,
                    data[key_at + length_size : key_end],
                    data_type,
                    source.src,
                    now,
                    len(raw),
                )
                if var is None:
                    pos = stop
                    continue
            else:
                grown = len(raw) - len(var.raw)  # type: ignore[arg-type]  # written: bytes
                if grown > 0 and self.stored_bytes + grown > self.store_budget:
                    self._refuse_store(client, var.name)
                    pos = stop
                    continue
                self.stored_bytes += grown
                if now != var.write_time:
                    if now > var.write_time:
                        var.write_rate = 0.9 * var.write_rate + 0.1 / (now - var.write_time)
                    var.write_time = now
            var.raw = raw
            if var.last_source is not source:
                var.last_source = source
                if source.publisher is not None:
                    source.publisher.published.add(var.name)
                    source.publisher.rw_summary = None
            for append in var.every_update:
                append(raw)
            for sub in var.timed:
                if now - sub.last_sent >= sub.interval:
                    sub.last_sent = now
                    sub.client.held.append(raw)
            pos = stop
        if pos != end:
            raise MoosProtocolError(
                f"{end - pos} trailing bytes after the last message of the packet"
            )
        return had_notify

    def _first_or_mistyped_write(
        self,
        client: ClientRecord | None,
        var: Variable | None,
        key: bytes,
        data_type: int,
        src: str,
        now: float,
        size: int,
    ) -> Variable | None:
        """The variable a write of `data_type` (`size` bytes) goes to, or None when the type
        lock drops it or a bound refuses it."""
        if var is None:
            var = self._new_variable(client, key)
            if var is None:
                return None
        if var.raw is None:
            if self.stored_bytes + size > self.store_budget:
                self._refuse_store(client, var.name)
                return None
            self.stored_bytes += size
            var.type_code = var.accepts = data_type
            var.write_time = now  # no write rate from a first write
            self._apply_filters_on_creation(var, src)
            return var
        log.info(
            'Attempting to update var "%s" which is type %s with data type %s by client %s',
            var.name,
            var.data_type,
            chr(data_type),
            src,
        )
        return None

    def _relearn_source(self) -> None:
        """Clients came or went: the remembered source's publisher may have changed."""
        head = self._source.head
        self._source = _Source(self, head, 0, len(head))

    def _on_other(
        self, client: ClientRecord | None, msg: p.MOOSMessage, now: float, answers: list[bytes]
    ) -> None:
        kind = msg.msg_type
        if kind == p.REGISTER:
            interval = msg.dval if math.isfinite(msg.dval) and msg.dval > 0 else 0.0
            if (
                msg.key not in self.variables
                and self._new_variable(client, p.encode_text(msg.key)) is None
            ):
                return
            self._on_register(msg.src, msg.key, interval, now)
        elif kind == p.UNREGISTER:
            var = self.variables.get(msg.key)
            if var is not None:
                var.unsubscribe(msg.src)
        elif kind == p.WILDCARD_REGISTER:
            self._on_wildcard(client, msg.src, msg.sval, now, register=True)
        elif kind == p.WILDCARD_UNREGISTER:
            self._on_wildcard(client, msg.src, msg.sval, now, register=False)
        elif kind == p.SERVER_REQUEST and client is not None:
            answers += map(p.encode_message, self._server_request(msg, now))

    # -- variables and subscriptions -----------------------------------------------------------

    def _variable(self, name: str) -> Variable:
        var = self.variables.get(name)
        if var is None:
            var = self.variables[name] = Variable(name)
            self._by_key[var.key] = var
            self._unsorted.append(var)
            self.stored_bytes += VARIABLE_OVERHEAD + len(var.key)
        return var

    def _new_variable(self, client: ClientRecord | None, key: bytes) -> Variable | None:
        """A new variable named `key`, or None (logged) when a bound refuses it."""
        if len(key) > MAX_NAME_LENGTH:
            self._refuse(
                client,
                "name",
                f"variable name of {len(key)} bytes refused (at most {MAX_NAME_LENGTH})",
            )
            return None
        if len(self.variables) >= self.max_variables:
            self._refuse(
                client,
                "max_variables",
                f"new variable {p.decode_text(key[:64])!r} refused: the DB holds "
                f"{len(self.variables)} variables (max_variables)",
            )
            return None
        if self.stored_bytes + VARIABLE_OVERHEAD + len(key) > self.store_budget:
            self._refuse_store(client, p.decode_text(key[:64]))
            return None
        return self._variable(p.decode_text(key))

    def _refuse_store(self, client: ClientRecord | None, name: str) -> None:
        self._refuse(
            client,
            "store",
            f"write to {name!r} refused: the stored variables would exceed the memory "
            f"budget of {self.store_budget:.0f} bytes",
        )

    def _refuse(self, client: ClientRecord | None, kind: str, text: str) -> None:
        """Log a refusal once per client and kind (a client repeating it is not logged again)."""
        if client is None:
            log.warning("%s", text)
        elif kind not in client.refused:
            client.refused.add(kind)
            log.warning("client %s: %s (logged once per client)", client.name, text)

    def sorted_variables(self) -> list[Variable]:
        """Every variable by name (sorted again only when variables were added)."""
        if self._unsorted:
            self._sorted += self._unsorted
            self._unsorted.clear()
            self._sorted.sort(key=_by_name)
        return self._sorted

    def _write_own(self, name: str, value: float | str) -> None:
        now = self.clock.now()
        raw = p.encode_message(p.notify(name, value, time=now, src=self.name))
        self._process_messages(None, raw, 0, len(raw), 1, now, [])

    def _on_register(self, subscriber: str, key: str, interval: float, now: float) -> None:
        client = self.clients.get(subscriber)
        if client is None or not key:
            return  # the subscriber is `src`; an empty or unknown one is ignored
        var = self._variable(key)
        sub = var.subscribe(client, interval)
        if var.written:
            client.held.append(var.snapshot())
            sub.last_sent = now

    def _on_wildcard(
        self,
        sender: ClientRecord | None,
        subscriber: str,
        sval: bytes,
        now: float,
        register: bool,
    ) -> None:
        client = self.clients.get(subscriber)
        if client is None:
            return
        app, var_pattern, interval = p.parse_wildcard_sval(sval)
        if max(len(app), len(var_pattern)) > MAX_PATTERN_LENGTH:
            self._refuse(
                sender,
                "pattern",
                f"wildcard pattern of {max(len(app), len(var_pattern))} characters refused "
                f"(at most {MAX_PATTERN_LENGTH})",
            )
            return
        if (
            register
            and (app, var_pattern) not in client.filters
            and len(client.filters) >= MAX_WILDCARDS
        ):
            self._refuse(
                sender,
                "wildcards",
                f"wildcard registration refused: {client.name} has {MAX_WILDCARDS} already",
            )
            return
        app_glob, var_glob = p.Glob(app), p.Glob(var_pattern)
        if register:
            client.filters.setdefault((app, var_pattern), (app_glob, var_glob, interval))
        for var in self.sorted_variables():  # the C++ map's order
            # `*` matches every publisher: no need to decode each value for its src
            if var_glob.match(var.name) and (app == "*" or app_glob.match(var.src)):
                if register:
                    self._on_register(subscriber, var.name, interval, now)
                else:
                    var.unsubscribe(subscriber)

    def _apply_filters_on_creation(self, var: Variable, publisher: str) -> None:
        for client in self.clients.values():
            for app_glob, var_glob, interval in client.filters.values():
                if var_glob.match(var.name) and app_glob.match(publisher):
                    var.subscribe(client, interval)
                    break

    # -- server requests -----------------------------------------------------------------------

    def _server_request(self, msg: p.MOOSMessage, now: float) -> list[p.MOOSMessage]:
        key = msg.key
        if key == "ALL":
            out = []
            for var in reversed(self.sorted_variables()):
                m = var.message()
                is_double = var.type_code == _DOUBLE
                rel = var.write_time - self.start_time if var.written else -1.0
                out.append(
                    p.MOOSMessage(
                        p.NOTIFY,
                        var.data_type,
                        var.name,
                        rel,
                        m.dval if is_double else -1.0,
                        var.write_rate,
                        b"" if is_double else m.sval,
                        m.src,
                        m.src_aux,
                        m.community,
                        msg.id,
                    )
                )
            return out
        if "VAR_SUMMARY" in key:
            names = ",".join([var.name for var in self.sorted_variables()])
            return [self._reply("VAR_SUMMARY", now, names, msg.id, community="")]
        if "PROC_SUMMARY" in key:
            out = []
            for client in self.clients.values():
                subs = "".join(f",{n}" for n in sorted(client.subscribed))
                pubs = "".join(f",{n}" for n in sorted(client.published))
                text = f"{client.name}:SUBSCRIBED={subs},PUBLISHED={pubs}"
                out.append(self._reply("PROC_SUMMARY", now - self.start_time, text, msg.id, ""))
            return out
        if "DB_CLEAR" in key:
            for var in self.variables.values():
                self.stored_bytes -= var.clear()
            for client in self.clients.values():
                client.drop_held()
            self.start_time = now
            return []
        return []

    def _reply(
        self, key: str, time: float, text: str, msg_id: int, community: str | None = None
    ) -> p.MOOSMessage:
        msg = p.notify(key, text, time=time, src=self.name, msg_id=msg_id)
        msg.community = self.community if community is None else community
        return msg

    # -- DB_* variables ------------------------------------------------------------------------

    def _maybe_refresh(self, now: float) -> None:
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
            parts.append(
                f"{c.name}={lat[-1]:.3f}:{max(lat):.3f}:{min(lat):.3f}:{sum(lat) / len(lat):.3f},"
            )
        return "".join(parts)

    def _rw_summary(self) -> str:
        parts = []
        for c in self.clients.values():
            if c.rw_summary is None:
                subscribed, published = (
                    ":".join(sorted(c.subscribed)),
                    ":".join(sorted(c.published)),
                )
                c.rw_summary = f"{c.name}={subscribed}&{published}"
            parts.append(c.rw_summary)
        return ",".join(parts)

    def _var_summary(self) -> str:
        """One line per variable, by name; at most SUMMARY_LINES_PER_REFRESH lines made again,
        taking turns from where the last refresh stopped (a variable without a line yet is
        left out until its turn)."""
        variables = self.sorted_variables()
        count = len(variables)
        budget = SUMMARY_LINES_PER_REFRESH
        start = self._summary_from % count if count else 0
        for index in itertools.chain(range(start, count), range(start)):
            var = variables[index]
            if var.summary_of is not var.raw:
                if budget == 0:
                    self._summary_from = index
                    break
                budget -= 1
                _summary_line(var)
        return "\n".join([var.summary for var in variables if var.summary])


def _by_name(var: Variable) -> str:
    return var.name


def _summary_line(var: Variable) -> str:
    """The variable's DB_VARSUMMARY line, kept in it until its next write."""
    m = var.message()
    when = _time.strftime("%H:%M:%S", _time.gmtime(var.write_time)) if var.written else "-"
    writer = m.src if var.written else "(write pending)"
    if var.type_code == _DOUBLE:
        value = f"{m.dval:.1f}"
    elif var.data_type == p.BINARY:
        value = _binary_size(len(m.sval))
    else:
        text = m.string
        value = text[:22] + "..." if len(text) > 25 else text
    var.summary = f"{var.name} {when} {writer} {var.write_rate:.1f} Hz {var.data_type} {value}"
    var.summary_of = var.raw
    return var.summary


def _binary_size(n: int) -> str:
    if n < 1024:
        return f"*binary* {n} B"
    if n < 1024 * 1024:
        return f"*binary* {n / 1024:.1f} KB"
    return f"*binary* {n / (1024 * 1024):.1f} MB"
