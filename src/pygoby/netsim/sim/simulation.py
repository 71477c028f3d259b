"""A whole acoustic network in one process: emulators, physics, drivers, MAC and queues.

`Simulation(scenario)` builds, for every node of a `pygoby.netsim.protobuf.Scenario`, the real
stack a vehicle runs — a Micro-Modem emulator (`MicroModemModel`) on the netsim physics
(`PhysicsChannel`), the Micro-Modem driver (`MMDriver`), the TDMA `MACManager` and a
`QueueManager` with the vehicle's `NodeStatus` messages (DCCL) — and a `NetSimManager` that
feeds the channel the positions it accepts. Scripted tracks are posted to it as NavUpdates in
real-time runs (`post_positions`); discrete-event runs, where nobody else talks to it, put them
straight into the channel after the manager's checks (`set_positions`: same positions).

Everything shares one Clock, and the emulators one Timeline (what they do later: the end of a
transmission, a ping reply, a clock set). `run_virtual()` drives a `VirtualClock` as a
discrete-event simulation: the sans-I/O cores are connected in memory
(pygoby.acomms.mmsim.link.ModemLink: the driver's sentences go straight into its emulator and the
emulator's answers, parsed, into the driver's buffer) and the clock jumps to the next thing that
can happen — an emulator's timed event, a reception's delivery, a MAC slot, a position update,
periodic housekeeping — so a day of TDMA traffic runs in seconds. `pygoby.netsim.sim.realtime` runs
the same objects on the wall clock over TCP.

Events go to `on_event` (`summary()` counts them): `tx` and `rx` from the channel (see
`pygoby.netsim.sim.physics_channel`), `app_rx` when a queue delivers a status message (port of the
receiver, src, msg_t: the message's time stamp), `range` when a driver reports a ranging reply (port, src, dest, owtt list).
"""

from __future__ import annotations

import functools
import logging
import math
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.bind import bind
from pygoby.acomms.drivers.micromodem import MMDriver
from pygoby.acomms.mac import MACManager
from pygoby.acomms.mmsim import MicroModemModel
from pygoby.acomms.mmsim.link import ModemLink
from pygoby.acomms.queue import QueueManager
from pygoby.dccl import Codec
from pygoby.netsim.channel import Channel, NavFix
from pygoby.netsim.manager.core import NetSimManager
from pygoby.netsim.manager.protocol import request_class
from pygoby.netsim.sim.physics_channel import PhysicsChannel
from pygoby.netsim.sim.scenario import (
    TrackFollower,
    channel_config,
    mac_config,
    manager_config,
    modem_timing,
    node_ports,
    node_status_class,
    start_time,
)
from pygoby.protobuf.pygoby.netsim.scenario_pb2 import NodeStatus, Scenario
from pygoby.util.clock import Clock, VirtualClock
from pygoby.util.timeline import Timeline

log = logging.getLogger(__name__)

EventSink = Callable[[dict], None]
DRIVER_WHOI_MICROMODEM = acomms_pb.DriverType.DRIVER_WHOI_MICROMODEM
SLOT_EPSILON = 1e-3  # s: a MAC slot fires once the clock is past its start
STARTUP_STEP = 0.01  # s: drivers set the modem clock just after a whole second
STARTUP_LIMIT = 120.0  # s of simulated time for every driver to finish its start-up
PROGRESS_STEPS = 512  # discrete-event steps between progress reports (a report reads the clock)
MAX_EXCHANGES = 10_000  # driver <-> emulator sentences at one instant before giving up
LOCAL_IP = "127.0.0.1"


def driver_config(modem_id: int, **link) -> acomms_pb.DriverConfig:
    cfg = acomms_pb.DriverConfig(driver_type=DRIVER_WHOI_MICROMODEM, modem_id=modem_id, **link)
    cfg.Extensions[acomms_pb.MM_CONFIG].query_cfg_on_startup = False
    return cfg


def status_queue_entry(ack: bool) -> acomms_pb.QueuedMessageEntry:
    entry = acomms_pb.QueuedMessageEntry(
        protobuf_name="pygoby.netsim.protobuf.NodeStatus", ack=ack, max_queue=1, ttl=3600
    )
    Role = acomms_pb.QueuedMessageEntry.Role
    entry.role.add(type=Role.SOURCE_ID, field="src")
    entry.role.add(type=Role.DESTINATION_ID, field="dest")
    entry.role.add(type=Role.TIMESTAMP, field="time")
    return entry


@dataclass
class SimNode:
    """One vehicle: its emulator and (optionally) its in-process acomms stack."""

    modem_id: int
    port: int
    model: MicroModemModel
    track: TrackFollower | None = None
    driver: MMDriver | None = None
    mac: MACManager | None = None
    queue: QueueManager | None = None
    link: ModemLink | None = None
    received: Counter = field(default_factory=Counter)  # status messages heard, by source


@dataclass
class RunSummary:
    simulated_seconds: float
    wall_seconds: float
    events: Counter
    outcomes: Counter
    status_sent: int
    status_received: int
    external_deliveries: dict[int, int] = field(default_factory=dict)  # modem id -> packets
    interrupted: bool = False

    @property
    def speedup(self) -> float:
        return self.simulated_seconds / self.wall_seconds if self.wall_seconds > 0 else 0.0

    def lines(self) -> list[str]:
        return [
            f"simulated {self.simulated_seconds:.0f} s in {self.wall_seconds:.2f} s wall "
            f"({self.speedup:,.0f}x real time)",
            "events: " + ", ".join(f"{k} {v}" for k, v in sorted(self.events.items())),
            "receptions: " + ", ".join(f"{k} {v}" for k, v in sorted(self.outcomes.items())),
            f"status messages: {self.status_sent} queued, {self.status_received} delivered",
            *self._external_lines(),
            *(["interrupted before the end of the scenario"] if self.interrupted else []),
        ]

    def _external_lines(self) -> list[str]:
        """External stacks (e.g. pAcommsHandler with iNetSimManager): what the channel handed
        to their modems, as this side cannot see their messages."""
        if not self.external_deliveries:
            return []
        counts = ", ".join(f"modem {i}: {n}" for i, n in sorted(self.external_deliveries.items()))
        return [f"packets delivered to external stacks' modems: {counts}"]


class Simulation:
    def __init__(
        self, scenario: Scenario, clock: Clock | None = None, on_event: EventSink | None = None
    ) -> None:
        self.scenario = scenario
        self.start = start_time(scenario)
        self.clock: Clock = clock if clock is not None else VirtualClock(self.start)
        self.events: Counter = Counter()  # this run's own events (the channel counts its own)
        self.status_sent = 0
        self.manager = NetSimManager(manager_config(scenario))
        self.channel = Channel(channel_config(scenario), seed=scenario.seed)
        self.manager.on_nav(self.channel.on_environment_nav_update)
        # (in a discrete-event run a driver wakes once for $CARXP and the packet)
        self.physics = PhysicsChannel(
            self.channel,
            self.clock,
            on_event=on_event,
            detections_with_receptions=isinstance(self.clock, VirtualClock),
        )
        # every event (see the module's documentation): the channel's, and the run's own on the
        # same signal (an event is only made when someone listens)
        self.signal_event = self.physics.signal_event
        self.timeline = Timeline(self.clock)  # the emulators' timed events
        timing = modem_timing(scenario)
        self.codec = Codec(clock=self.clock)
        self.status_class = node_status_class()
        self.nodes: list[SimNode] = []
        for node, port in zip(scenario.node, node_ports(scenario), strict=True):
            track = TrackFollower(node.track, scenario) if node.HasField("track") else None
            model = MicroModemModel(
                node.modem_id,
                self.clock,
                self.physics,
                name=str(port),
                timing=timing,
                timeline=self.timeline,
            )
            self.nodes.append(SimNode(node.modem_id, port, model, track))
        self._request_id = 0
        self._wall_start = 0.0
        self._waiting: set[int] = set()  # indices of the nodes whose emulators have spoken

    # -- building stacks -------------------------------------------------------------------------

    def attach_stack(self, node: SimNode, driver: MMDriver) -> None:
        """Give a node its driver (already linked to its emulator), MAC and status queue."""
        node.driver = driver
        node.mac = MACManager(self.clock)
        traffic = self.scenario.traffic
        if traffic.status:
            node.queue = QueueManager(self.codec, self.clock)
            node.queue.set_cfg(acomms_pb.QueueManagerConfig(modem_id=node.modem_id))
            node.queue.add_queue(status_queue_entry(traffic.ack), self.status_class)
            node.queue.signal_receive.connect(functools.partial(self._status_heard, node))
            node.mac.signal_slot_start.connect(functools.partial(self._slot_started, node))
        bind(driver, node.queue, node.mac)
        driver.signal_receive.connect(functools.partial(self._modem_heard, node))

    def start_macs(self) -> None:
        """Start the run's traffic: a `node` event per node (its port and modem id, for the
        report), then every in-process stack's MAC and first status message."""
        for node in self.nodes:
            self._event(
                "node",
                t=self.clock.now(),
                port=node.port,
                modem_id=node.modem_id,
                external=node.driver is None,
            )
        for node in self.nodes:
            if node.mac is not None:
                node.mac.startup(mac_config(self.scenario, node.modem_id))
                if node.queue is not None:
                    self.queue_status(node)

    # -- traffic -------------------------------------------------------------------------------

    def queue_status(self, node: SimNode) -> None:
        assert node.queue is not None
        now = self.clock.now()
        # (the channel's latest position: every position the manager accepts, scripted or
        # from a vehicle simulator, goes there)
        reported = self.channel.position(node.port)
        if reported is None:
            return
        position = reported.at(now)
        status = self.status_class(
            src=node.modem_id,
            dest=self.scenario.traffic.status_dest,
            time=now,
            lat=position.lat,
            lon=position.lon,
            depth=max(position.depth, 0.0),
            speed=min(reported.speed, 10.0),
            heading=reported.heading % 360.0,
        )
        node.queue.push_message(status)
        self.status_sent += 1

    def _slot_started(self, node: SimNode, slot: acomms_pb.ModemTransmission) -> None:
        if slot.src == node.modem_id:  # our slot has just taken the last status: queue the next
            self.queue_status(node)

    def _status_heard(self, node: SimNode, msg: NodeStatus) -> None:
        node.received[msg.src] += 1
        self._event("app_rx", t=self.clock.now(), port=node.port, src=msg.src, msg_t=msg.time)

    def _modem_heard(self, node: SimNode, msg: acomms_pb.ModemTransmission) -> None:
        """Ranging results the driver reports (two-way pings) become `range` events."""
        if msg.type != acomms_pb.ModemTransmission.DRIVER_SPECIFIC:
            return
        owtt = msg.Extensions[acomms_pb.MM_TRANSMISSION].ranging_reply.one_way_travel_time
        if owtt:
            self._event(
                "range",
                t=self.clock.now(),
                port=node.port,
                src=msg.src,
                dest=msg.dest,
                owtt=list(owtt),
            )

    def _event(self, kind: str, **fields) -> None:
        self.events[kind] += 1
        if self.signal_event:  # (made only when someone listens)
            self.signal_event.emit({"event": kind, **fields})

    # -- positions -------------------------------------------------------------------------------

    def track_positions(self) -> list[tuple[int, NavFix]]:
        """(modem port, position now) of every node with a scripted track."""
        now = self.clock.now()
        elapsed = now - self.start
        return [(n.port, n.track.position(elapsed, now)) for n in self.nodes if n.track is not None]

    def post_positions(self) -> None:
        """One NetSimManagerRequest with every tracked node's position now (what a vehicle
        simulator sends: real-time runs, where others talk to the same manager)."""
        request = request_class()(id=self._request_id)
        self._request_id = (self._request_id + 1) % 2**31
        for port, p in self.track_positions():
            request.nav.add(
                modem_tcp_port=port,
                time=p.time,
                lat=p.lat,
                lon=p.lon,
                depth=p.depth,
                speed=p.speed,
                heading=p.heading,
            )
        if request.nav:
            outcome = self.manager.handle_request(request, LOCAL_IP)
            if outcome.response.status != outcome.response.UPDATE_ACCEPTED:
                log.warning("scripted positions refused: %s", outcome.response)

    def set_positions(self) -> None:
        """The positions `post_positions` sends, straight into the channel (discrete-event
        runs, where nobody else talks to the manager): what the manager would forward to it,
        after the manager's own checks and without the messages."""
        for port, p in self.track_positions():
            status = self.manager.check_position(port, p.lat, p.lon, p.depth, LOCAL_IP)
            if status != self.manager.accepted:
                log.warning("scripted positions refused: port %d: status %d", port, status)
                return  # the manager stops at the first refused position of a request
            self.channel.update_position(port, p)

    def summary(self) -> RunSummary:
        return RunSummary(
            simulated_seconds=self.clock.now() - self.start,
            wall_seconds=time.perf_counter() - self._wall_start,
            events=self.events
            + Counter(
                tx=self.physics.transmissions.total(),
                tx_data=self.physics.transmissions["data"],
                rx=self.physics.outcomes.total(),
            ),
            outcomes=Counter(self.physics.outcomes),
            status_sent=self.status_sent,
            status_received=self.status_received,
            external_deliveries={
                n.modem_id: self.physics.delivered[n.port] for n in self.nodes if n.driver is None
            },
        )

    @property
    def status_received(self) -> int:
        return sum(sum(n.received.values()) for n in self.nodes)

    @property
    def packets_delivered(self) -> int:
        return sum(self.physics.delivered.values())

    # -- discrete-event run ----------------------------------------------------------------------

    def build_virtual(self) -> None:
        """In-memory stacks for every node (drivers wired straight into their emulators)."""
        for index, node in enumerate(self.nodes):
            node.link = ModemLink(node.model, self._waiting, index)
            driver = MMDriver(self.clock, node.link)
            driver.startup(driver_config(node.modem_id))
            self.attach_stack(node, driver)

    def run_virtual(
        self, until: float | None = None, progress: Callable[[], None] | None = None
    ) -> RunSummary:
        """Build, start and run to `until` (default: the scenario's duration) on the virtual
        clock, jumping from event to event; `progress()` is called every few hundred steps."""
        if not isinstance(self.clock, VirtualClock):
            raise TypeError("run_virtual needs a VirtualClock")
        clock = self.clock
        self._wall_start = time.perf_counter()
        end = self.start + self.scenario.duration if until is None else until
        self.set_positions()
        self.build_virtual()
        self._start_drivers(clock)
        self.start_macs()
        period = self.scenario.position_period
        housekeeping = self.scenario.housekeeping_period
        next_position = self.start + period
        next_housekeeping = clock.now() + housekeeping
        macs = [n.mac for n in self.nodes if n.mac is not None]
        nodes, waiting, timeline = self.nodes, self._waiting, self.timeline
        # (a MAC's next slot changes only when it works, below)
        slot = min([mac.next_slot_time for mac in macs if mac.running], default=math.inf)
        steps = 0
        while True:
            now = clock.now()
            t = min(end, next_position, next_housekeeping)
            delivery = self.physics.next_event_time()
            if delivery is not None and delivery < t:
                t = delivery
            timed = timeline.next_time()
            if timed is not None and timed < t:
                t = timed
            t = min(t, slot + SLOT_EPSILON)
            clock.set(max(t, now))
            now = clock.now()
            if now >= next_position:
                self.set_positions()
                next_position += period
            self.physics.do_work()
            timeline.run_due()
            every = now >= next_housekeeping
            if every:
                next_housekeeping += housekeeping
            if every or now > slot:
                for node in nodes:
                    mac = node.mac
                    fired = mac is not None and mac.running and now > mac.next_slot_time
                    if fired:
                        mac.do_work()  # type: ignore[union-attr]  # (fired: a MAC)
                    if every and node.queue is not None:
                        node.queue.do_work()
                    if fired or every or (node.link is not None and node.link.pending):
                        self._pump(node)
                slot = min([mac.next_slot_time for mac in macs if mac.running], default=math.inf)
            else:  # only deliveries: the nodes whose emulators have spoken, in node order
                for index in sorted(waiting):
                    self._pump(nodes[index])
            if now >= end:
                return self.summary()
            if progress is not None:
                steps += 1
                if not steps % PROGRESS_STEPS:
                    progress()

    def _start_drivers(self, clock: VirtualClock) -> None:
        deadline = clock.now() + STARTUP_LIMIT
        while not all(n.driver is None or n.driver.startup_complete for n in self.nodes):
            if clock.now() > deadline:
                late = [
                    n.modem_id for n in self.nodes if n.driver and not n.driver.startup_complete
                ]
                raise RuntimeError(f"drivers of nodes {late} did not start")
            self.timeline.run_due()
            for node in self.nodes:
                self._pump(node)
            clock.advance(STARTUP_STEP)

    @staticmethod
    def _pump(node: SimNode) -> None:
        """Run the node's driver until its emulator has nothing more to say."""
        driver, link = node.driver, node.link
        if driver is None or link is None:
            return
        for _ in range(MAX_EXCHANGES):
            driver.do_work()
            if not link.pending:
                return
        log.warning("node %d: driver and emulator still talking; deferred", node.modem_id)
