"""Simulation scenarios: the `pygoby.netsim.protobuf.Scenario` TextFormat file and what it means.

`load_scenario(path)` / `parse_scenario(text)` read and check a scenario (ScenarioError with the
reason). The helpers turn it into the parts of a run: `channel_config` (the physics),
`manager_config` (a netsim_manager accepting every node from 127.0.0.1), `mac_config` (one
node's TDMA cycle), `node_ports`, and `TrackFollower`s that give a node's position at any time.
The schema is documented in src/pygoby/protobuf/pygoby/netsim/scenario.proto.
"""

from __future__ import annotations

import bisect
import dataclasses
import math
import time
from dataclasses import dataclass
from pathlib import Path

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.mmsim.timing import DEFAULT_TIMING, ModemTiming
from pygoby.netsim.channel import Band, ChannelConfig, NavFix
from pygoby.netsim.channel.geometry import WGS84
from pygoby.netsim.channel.settings import (
    absorption_of,
    propagation_of,
    protocol_model_of,
    sound_speed_of,
)
from pygoby.netsim.errors import ScenarioError
from pygoby.netsim.manager.config import config_class as manager_config_class
from pygoby.protobuf import initialization_errors
from pygoby.protobuf.goby.acomms.protobuf.amac_config_pb2 import MACConfig
from pygoby.protobuf.netsim.messages.manager_config_pb2 import NetSimManagerConfig
from pygoby.protobuf.pygoby.netsim.scenario_pb2 import NodeStatus, Scenario, Track, Waypoint
from pygoby.protobuf.textconfig import check_config_values, merge_config_text, read_config_file

FIRST_MODEM_PORT = 62000
VIRTUAL_START = 1_700_000_000.0  # default start of a "max"-speed run (repeatable)
MAC_FIXED_DECENTRALIZED = acomms_pb.MACType.MAC_FIXED_DECENTRALIZED


def scenario_class() -> type[Scenario]:
    return Scenario


def node_status_class() -> type[NodeStatus]:
    return NodeStatus


def load_scenario(path: str | Path) -> Scenario:
    return parse_scenario(read_config_file(path, error=ScenarioError), path)


def parse_scenario(text: str, file: str | Path | None = None) -> Scenario:
    scenario = scenario_class()()
    merge_config_text(text, scenario, file=file, error=ScenarioError)
    check_config_values(scenario, text, file=file, error=ScenarioError)
    try:
        check_scenario(scenario)
    except ScenarioError as err:
        raise err.located(file=file) from None
    return scenario


def check_scenario(scenario: Scenario) -> None:
    if not scenario.IsInitialized():
        missing = ", ".join(initialization_errors(scenario))
        raise ScenarioError(f"scenario is missing required fields: {missing}")
    if not scenario.node:
        raise ScenarioError("a scenario needs at least one node")
    speed_factor(scenario)  # raises on a bad speed
    if scenario.duration <= 0:
        raise ScenarioError("duration must be positive")
    ids = [n.modem_id for n in scenario.node]
    if len(set(ids)) != len(ids):
        raise ScenarioError(f"duplicate modem_id in {ids}")
    if any(not 1 <= i <= 127 for i in ids):
        raise ScenarioError("modem_id must be within 1..127")
    ports = node_ports(scenario)
    if len(set(ports)) != len(ports):
        raise ScenarioError(f"duplicate modem_tcp_port in {ports}")
    for node in scenario.node:
        if node.HasField("track"):
            TrackFollower(node.track, scenario)  # raises on a bad track
        elif speed_factor(scenario) is None:
            raise ScenarioError(f"node {node.modem_id} needs a track with speed max")
    if scenario.position_period <= 0 or scenario.housekeeping_period <= 0:
        raise ScenarioError("position_period and housekeeping_period must be positive")
    if scenario.channel.position_staleness <= scenario.position_period:
        raise ScenarioError("channel.position_staleness must exceed position_period")
    modem_timing(scenario)  # raises on a bad duration table
    if scenario.channel.HasField("propagation"):
        channel_config(scenario)  # raises on bad propagation settings (nothing is traced yet)


def speed_factor(scenario: Scenario) -> float | None:
    """None for "max" (virtual clock), else the real-time factor."""
    text = scenario.speed.strip().lower()
    if text == "max":
        return None
    try:
        factor = float(text)
    except ValueError:
        raise ScenarioError(f'speed must be "max" or a number, not {scenario.speed!r}') from None
    if not factor > 0 or math.isinf(factor):
        raise ScenarioError(f"speed factor must be positive, not {scenario.speed!r}")
    return factor


def start_time(scenario: Scenario) -> float:
    if scenario.HasField("start_time"):
        return scenario.start_time
    return VIRTUAL_START if speed_factor(scenario) is None else time.time()


def node_ports(scenario: Scenario) -> list[int]:
    return [
        n.modem_tcp_port if n.HasField("modem_tcp_port") else FIRST_MODEM_PORT + i
        for i, n in enumerate(scenario.node)
    ]


def channel_config(scenario: Scenario) -> ChannelConfig:
    c = scenario.channel
    sound_speed = sound_speed_of(c)
    try:
        propagation = propagation_of(c, sound_speed)
    except ValueError as exc:
        raise ScenarioError(str(exc), field="channel.propagation") from None
    return ChannelConfig(
        sound_speed=sound_speed,
        absorption=absorption_of(c),
        propagation=propagation,
        source_level=c.source_level,
        spreading=c.spreading,
        noise_level=c.noise_level if c.HasField("noise_level") else None,
        shipping=c.shipping,
        wind=c.wind,
        band=Band(c.carrier_hz, c.bandwidth_hz),
        half_duplex=c.half_duplex,
        receiver_lock=c.receiver_lock,
        protocol_model=protocol_model_of(c),
        decode_latency=c.decode_latency,
        position_staleness=c.position_staleness,
    )


def modem_timing(scenario: Scenario) -> ModemTiming:
    """The emulators' duration table: the defaults with the scenario's `modem_timing` over them."""
    t = scenario.modem_timing
    rates = dict(DEFAULT_TIMING.rates)
    for entry in t.rate:
        spec = rates.get(entry.rate)
        if spec is None:
            raise ScenarioError(f"modem_timing: there is no Micro-Modem rate {entry.rate}")
        lead = entry.lead if entry.HasField("lead") else spec.lead
        per_frame = entry.per_frame if entry.HasField("per_frame") else spec.per_frame
        if lead < 0 or per_frame < 0 or lead + per_frame <= 0:
            raise ScenarioError(f"modem_timing: rate {entry.rate} needs a positive duration")
        rates[entry.rate] = dataclasses.replace(spec, lead=lead, per_frame=per_frame)
    others = {
        name: getattr(t, name)
        for name in ("mini_packet", "ping", "nav_ping", "tmq_reply")
        if t.HasField(name)
    }
    if any(value <= 0 for value in others.values()):
        raise ScenarioError(f"modem_timing: durations must be positive: {others}")
    if t.HasField("baud"):
        others["baud"] = t.baud
    return dataclasses.replace(DEFAULT_TIMING, rates=rates, **others)


def manager_config(scenario: Scenario, endpoint_ip: str = "127.0.0.1") -> NetSimManagerConfig:
    """A netsim_manager configuration for the scenario's nodes (one environment, whole Earth)."""
    cfg = manager_config_class()()
    for port in node_ports(scenario):
        cfg.sim_env_pair.add(modem_tcp_port=port, endpoint_ip_address=endpoint_ip, environment_id=0)
    cfg.env_bounds.add(
        environment_id=0,
        lat_min=-90,
        lat_max=90,
        lon_min=-180,
        lon_max=180,
        depth_min=0,
        depth_max=12000,
    )
    rt = scenario.real_time
    cfg.manager_tcp_port = 0 if rt.ephemeral_ports else rt.manager_tcp_port
    cfg.listen_address = rt.listen_address
    return cfg


def mac_config(scenario: Scenario, modem_id: int) -> MACConfig:
    """The scenario's TDMA cycle for one node (the same slots at every node)."""
    cfg = acomms_pb.MACConfig()
    cfg.CopyFrom(scenario.mac)
    cfg.modem_id = modem_id
    if not scenario.mac.HasField("type"):
        cfg.type = MAC_FIXED_DECENTRALIZED
    if not cfg.slot:
        for node in scenario.node:
            cfg.slot.add(
                src=node.modem_id,
                dest=scenario.traffic.status_dest,
                rate=cfg.rate,
                type=acomms_pb.ModemTransmission.DATA,
                slot_seconds=cfg.slot_seconds,
                ack_requested=scenario.traffic.ack,
            )
    return cfg


# -- tracks ---------------------------------------------------------------------------------------


@dataclass(frozen=True)
class _Fix:
    t: float  # seconds after the start
    lat: float
    lon: float
    depth: float


class TrackFollower:
    """A node's scripted position at any time (UNIX seconds, given the run's start time)."""

    def __init__(self, track: Track, scenario: Scenario) -> None:
        if not track.waypoint:
            raise ScenarioError("a track needs at least one waypoint")
        self.fixes = [self._fix(w, scenario) for w in track.waypoint]
        times = [f.t for f in self.fixes]
        if times != sorted(times) or len(set(times)) != len(times):
            raise ScenarioError(f"track waypoint times must increase: {times}")
        self.speed = track.speed
        self.heading = track.heading
        self._times = times

    @staticmethod
    def _fix(w: Waypoint, scenario: Scenario) -> _Fix:
        if w.HasField("lat") and w.HasField("lon"):
            lat, lon = w.lat, w.lon
        elif w.HasField("x") or w.HasField("y"):
            if not scenario.HasField("origin"):
                raise ScenarioError("waypoints in x/y need the scenario's origin")
            lon, lat, _ = WGS84.fwd(scenario.origin.lon, scenario.origin.lat, 90.0, w.x)
            lon, lat, _ = WGS84.fwd(lon, lat, 0.0, w.y)
        else:
            raise ScenarioError("a waypoint needs lat and lon, or x/y")
        if not (-90 <= lat <= 90 and -180 <= lon <= 180 and w.depth >= 0):
            raise ScenarioError(f"waypoint out of range: lat {lat}, lon {lon}, depth {w.depth}")
        return _Fix(w.t, lat, lon, w.depth)

    def position(self, elapsed: float, now: float) -> NavFix:
        """The position `elapsed` seconds after the start, stamped with `now`."""
        fixes = self.fixes
        if len(fixes) == 1:
            f = fixes[0]
            if not self.speed:  # a fixed node: what dead-reckoning below gives, in one step
                return NavFix(f.lat, f.lon, f.depth, now, self.speed, self.heading)
            start = NavFix(f.lat, f.lon, f.depth, now - elapsed + f.t, self.speed, self.heading)
            return start.at(now)
        i = bisect.bisect_right(self._times, elapsed)
        if i == 0 or i == len(fixes):  # before the first or after the last: hold
            f = fixes[0 if i == 0 else -1]
            return NavFix(f.lat, f.lon, f.depth, now)
        a, b = fixes[i - 1], fixes[i]
        azimuth, _, distance = WGS84.inv(a.lon, a.lat, b.lon, b.lat)
        fraction = (elapsed - a.t) / (b.t - a.t)
        lon, lat, _ = WGS84.fwd(a.lon, a.lat, azimuth, distance * fraction)
        return NavFix(
            lat,
            lon,
            a.depth + (b.depth - a.depth) * fraction,
            now,
            speed=distance / (b.t - a.t),
            heading=azimuth % 360.0,
        )
