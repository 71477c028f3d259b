"""One run of a sweep: the discrete-event simulation of a `RunSpec`, tallied per link.

`execute_run(spec)` is what an executor calls (in a worker process or on a cluster worker): it
parses the run's scenario, runs `Simulation.run_virtual()` with `LinkTally` as the event sink (no
event log is written) and returns a `RunResult` whose rows are the results table's: one per
ordered pair of nodes (src -> dest, every pair, traffic or not) with

* the run: run_id, point, replicate, seed, nodes, duration_s, and every axis' value;
* data packets: `rate` (of src's data packets; -1 if it sent none), `sent` and `frames_sent` by
  src (broadcasts count once per link), `received` at dest (every physical reception) split by
  outcome into `good` (all frames good), `bad_frames`, `not_detected`, `receiver_busy`,
  `half_duplex`, and `frames_good` (the leading good frames delivered);
* the link's mean `range_m`, `owtt_mean_s`, `snr_mean_db` and `sinr_mean_db` over those
  receptions (NaN without any);
* messages: `messages` (NodeStatus messages from src delivered by dest's queue),
  `latency_mean_s` / `latency_max_s` (delivery time minus the message's time stamp) and `acked`
  (acknowledgements from dest that src received whole);
* `wall_s`: the run's wall time (the only column that differs between two executions).

Everything but `wall_s` depends only on the scenario (and so on the seed): the same run gives the
same rows in any process on any machine.
"""

from __future__ import annotations

import math
import time
from collections import Counter
from dataclasses import dataclass, field

from pygoby.netsim.sim.scenario import node_ports, parse_scenario
from pygoby.netsim.sim.simulation import Simulation
from pygoby.netsim.sweep.plan import RunSpec

OUTCOMES = ("good", "bad_frames", "not_detected", "receiver_busy", "half_duplex")


@dataclass
class _Link:
    received: int = 0
    outcomes: Counter = field(default_factory=Counter)
    frames_good: int = 0
    range_sum: float = 0.0
    owtt_sum: float = 0.0
    snr_sum: float = 0.0
    sinr_sum: float = 0.0
    messages: int = 0
    latency_sum: float = 0.0
    latency_max: float = math.nan
    acked: int = 0


class LinkTally:
    """An `on_event` sink that keeps per-link counts instead of the events."""

    def __init__(self) -> None:
        self.links: dict[tuple[int, int], _Link] = {}  # (tx port, rx port)
        self.sent: Counter = Counter()  # data packets by port
        self.frames_sent: Counter = Counter()
        self.rates: dict[int, Counter] = {}  # port -> data rates used
        self.port_of_id: dict[int, int] = {}

    def link(self, tx_port: int, rx_port: int) -> _Link:
        link = self.links.get((tx_port, rx_port))
        if link is None:
            link = self.links[(tx_port, rx_port)] = _Link()
        return link

    def __call__(self, event: dict) -> None:
        kind = event["event"]
        if kind == "rx":
            if event["kind"] == "data":
                link = self.link(event["tx_port"], event["port"])
                link.received += 1
                link.outcomes[event["outcome"]] += 1
                link.frames_good += event["good_frames"]
                link.range_sum += event["range_m"]
                link.owtt_sum += event["owtt"]
                link.snr_sum += event["snr"]
                link.sinr_sum += event["sinr"]
            elif event["kind"] == "ack" and event["outcome"] == "good":
                self.link(event["port"], event["tx_port"]).acked += 1
        elif kind == "tx" and event["kind"] == "data":
            port = event["port"]
            self.sent[port] += 1
            self.frames_sent[port] += event["frames"]
            self.rates.setdefault(port, Counter())[event["rate"]] += 1
        elif kind == "app_rx":
            tx_port = self.port_of_id.get(event["src"])
            if tx_port is None:
                return
            link = self.link(tx_port, event["port"])
            latency = event["t"] - event["msg_t"]
            link.messages += 1
            link.latency_sum += latency
            link.latency_max = (
                latency if math.isnan(link.latency_max) else max(link.latency_max, latency)
            )


@dataclass(frozen=True)
class RunResult:
    run_id: str
    rows: list[dict]
    wall_s: float


def _mean(total: float, count: int) -> float:
    return total / count if count else math.nan


def execute_run(spec: RunSpec) -> RunResult:
    """Run one simulation of a sweep and tally it (see the module's docstring)."""
    started = time.perf_counter()
    scenario = parse_scenario(spec.scenario_text)
    ports = node_ports(scenario)
    ids = [n.modem_id for n in scenario.node]
    tally = LinkTally()
    tally.port_of_id = dict(zip(ids, ports, strict=True))
    Simulation(scenario, on_event=tally).run_virtual()
    wall = time.perf_counter() - started
    base = {
        "run_id": spec.run_id,
        "point": spec.point,
        "replicate": spec.replicate,
        "seed": spec.seed,
        **dict(spec.params),
        "nodes": len(ids),
        "duration_s": scenario.duration,
    }
    rows = []
    for src, tx_port in zip(ids, ports, strict=True):
        rates = tally.rates.get(tx_port)
        rate = rates.most_common(1)[0][0] if rates else -1
        for dest, rx_port in zip(ids, ports, strict=True):
            if dest == src:
                continue
            link = tally.links.get((tx_port, rx_port), _Link())
            n = link.received
            rows.append(
                {
                    **base,
                    "src": src,
                    "dest": dest,
                    "rate": rate,
                    "range_m": _mean(link.range_sum, n),
                    "sent": tally.sent[tx_port],
                    "frames_sent": tally.frames_sent[tx_port],
                    "received": n,
                    **{o: link.outcomes[o] for o in OUTCOMES},
                    "frames_good": link.frames_good,
                    "messages": link.messages,
                    "latency_mean_s": _mean(link.latency_sum, link.messages),
                    "latency_max_s": link.latency_max,
                    "acked": link.acked,
                    "snr_mean_db": _mean(link.snr_sum, n),
                    "sinr_mean_db": _mean(link.sinr_sum, n),
                    "owtt_mean_s": _mean(link.owtt_sum, n),
                    "wall_s": wall,
                }
            )
    return RunResult(spec.run_id, rows, wall)
