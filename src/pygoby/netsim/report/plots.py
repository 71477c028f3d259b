"""Plots of a simulation's event log (`pygoby netsim report LOG -o DIR`), with matplotlib.

* `success_vs_range.png`: share of data packets received with every frame good, per range bin,
  with the number of receptions per bin underneath;
* `success_vs_snr.png`: the same against the SNR and the SINR (interference included);
* `timeline.png`: one row per node: its transmissions as bars (by packet kind) and what it heard
  as ticks coloured by outcome, nodes labelled by modem id, over a time window (default: the
  whole run).

Only `rx` events of data packets count for the success plots (control packets — cycle-init,
ACK, ping — are short and would mix two populations).
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pygoby.util.extras import needs_extra

with needs_extra("sim", "netsim reports"):
    from pygoby.util.figures import plt, save_figure

KIND_COLOURS = {
    "data": "tab:blue",
    "cycle": "tab:purple",
    "ack": "tab:olive",
    "ping": "tab:orange",
    "ping_reply": "tab:brown",
    "mini": "tab:gray",
}
OUTCOME_COLOURS = {
    "good": "tab:green",
    "bad_frames": "tab:red",
    "receiver_busy": "tab:pink",
    "half_duplex": "black",
    "not_detected": "lightgray",
}
SNR_BIN_DB = 2.0


@dataclass
class Binned:
    centres: list[float]
    success: list[float]  # NaN where a bin is empty
    counts: list[int]


def bin_success(
    values: Sequence[float], good: Sequence[bool], bins: int = 20, width: float | None = None
) -> Binned:
    """Success fraction of `good` in `bins` equal bins of `values` (or bins `width` wide)."""
    if not values:
        return Binned([], [], [])
    low, high = min(values), max(values)
    if width is not None:
        low = math.floor(low / width) * width
        bins = max(1, math.ceil((high - low) / width + 1e-9))
        high = low + bins * width
    width = (high - low) / bins if high > low else 1.0
    totals: Counter[Any] = Counter()
    oks: Counter[Any] = Counter()
    for value, ok in zip(values, good, strict=True):
        index = min(int((value - low) / width), bins - 1)
        totals[index] += 1
        oks[index] += ok
    n = bins if high > low else 1
    return Binned(
        centres=[low + (i + 0.5) * width for i in range(n)],
        success=[oks[i] / totals[i] if totals[i] else math.nan for i in range(n)],
        counts=[totals[i] for i in range(n)],
    )


def data_receptions(events: list[dict]) -> list[dict]:
    return [e for e in events if e.get("event") == "rx" and e.get("kind") == "data"]


def _success_axes(ax, count_ax, binned: Binned, label: str, colour: str, width: float) -> None:
    ax.plot(binned.centres, binned.success, "o-", color=colour, label=label)
    count_ax.bar(binned.centres, binned.counts, width=width * 0.9, color=colour, alpha=0.35)


def plot_success_vs_range(events: list[dict], path: Path) -> Path:
    rx = data_receptions(events)
    ranges = [e["range_m"] / 1000 for e in rx]
    binned = bin_success(ranges, [e["outcome"] == "good" for e in rx])
    fig, (ax, count_ax) = plt.subplots(
        2, 1, figsize=(8, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1]}
    )
    width = binned.centres[1] - binned.centres[0] if len(binned.centres) > 1 else 0.1
    _success_axes(ax, count_ax, binned, "all frames good", "tab:blue", width)
    ax.set_ylim(-0.05, 1.05)
    ax.set_ylabel("packet success rate")
    ax.set_title(f"Data packet success vs range ({len(rx)} receptions)")
    ax.grid(True, alpha=0.3)
    count_ax.set_xlabel("range (km)")
    count_ax.set_ylabel("receptions")
    return save_figure(fig, path)


def plot_success_vs_snr(events: list[dict], path: Path) -> Path:
    rx = data_receptions(events)
    fig, (ax, count_ax) = plt.subplots(
        2, 1, figsize=(8, 6), sharex=True, gridspec_kw={"height_ratios": [3, 1]}
    )
    for key, label, colour in (
        ("snr", "SNR (no interference)", "tab:blue"),
        ("sinr", "SINR (with interference)", "tab:red"),
    ):
        values = [e[key] for e in rx]
        binned = bin_success(values, [e["outcome"] == "good" for e in rx], width=SNR_BIN_DB)
        _success_axes(ax, count_ax, binned, label, colour, SNR_BIN_DB)
    ax.set_ylim(-0.05, 1.05)
    ax.set_ylabel("packet success rate")
    ax.set_title(f"Data packet success vs SNR ({len(rx)} receptions, {SNR_BIN_DB:g} dB bins)")
    ax.legend(loc="lower right")
    ax.grid(True, alpha=0.3)
    count_ax.set_xlabel("dB")
    count_ax.set_ylabel("receptions")
    return save_figure(fig, path)


def node_labels(events: list[dict]) -> dict[int, str]:
    """Modem port -> "modem <id>": from the run's `node` events, else from what each port sent
    (logs of older runs); a port that never sent stays "port <n>"."""
    ids: dict[int, int] = {}
    for e in events:
        if e.get("event") == "node":
            ids[e["port"]] = e["modem_id"]
        elif e.get("event") == "tx" and "src" in e:
            ids.setdefault(e["port"], e["src"])
    ports = {e["port"] for e in events if e.get("event") in ("tx", "rx", "node")}
    return {p: f"modem {ids[p]}" if p in ids else f"port {p}" for p in ports}


def timeline_window(
    events: list[dict], window: tuple[float, float] | None
) -> tuple[float, tuple[float, float]]:
    """(time of the first event, (start, end) in seconds after it): `window`, else the run."""
    times = [e["t"] for e in events if "t" in e]
    t0 = min(times) if times else 0.0
    if window is not None:
        return t0, window
    return t0, (0.0, max(max(times, default=t0) - t0, 1.0))


def plot_timeline(events: list[dict], path: Path, window: tuple[float, float] | None) -> Path:
    """Transmissions per node; `window` is (start, end) in seconds after the first event
    (default: the whole run)."""
    t0, (start, end) = timeline_window(events, window)
    labels = node_labels(events)
    ports = sorted(labels, key=lambda p: (labels[p].startswith("port"), _number(labels[p]), p))
    row = {port: i for i, port in enumerate(ports)}
    fig, ax = plt.subplots(figsize=(12, 1.2 + 0.45 * max(len(ports), 1)))
    bars: dict[str, list[tuple[float, float, int]]] = {}
    for e in events:
        if e.get("event") == "tx" and start <= e["t"] - t0 <= end:
            bars.setdefault(e["kind"], []).append((e["t"] - t0, e["duration"], row[e["port"]]))
    for kind, spans in sorted(bars.items()):
        for i, (x, width, r) in enumerate(spans):
            ax.broken_barh(
                [(x, width)],
                (r - 0.35, 0.4),
                color=KIND_COLOURS.get(kind, "k"),
                label=f"tx {kind}" if i == 0 else None,
            )
    heard: dict[str, tuple[list[float], list[float]]] = {}
    for e in events:
        if e.get("event") == "rx" and start <= e["arrival"] - t0 <= end:
            xs, ys = heard.setdefault(e["outcome"], ([], []))
            xs.append(e["arrival"] - t0)
            ys.append(row[e["port"]] + 0.25)
    for outcome, (xs, ys) in sorted(heard.items()):
        ax.scatter(
            xs,
            ys,
            marker="|",
            s=120,
            color=OUTCOME_COLOURS.get(outcome, "k"),
            label=f"rx {outcome}",
        )
    ax.set_yticks(range(len(ports)), [labels[p] for p in ports])
    ax.set_ylim(-0.6, len(ports) - 0.2)
    ax.set_xlim(start, end)
    ax.set_ylabel("node")
    ax.set_xlabel("seconds since the first event")
    ax.set_title("Transmissions (bars) and receptions (ticks) per node")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    ax.grid(True, axis="x", alpha=0.3)
    return save_figure(fig, path)


def _number(label: str) -> int:
    return int(label.rsplit(" ", 1)[1])


def write_report(
    events: list[dict], out_dir: str | Path, window: tuple[float, float] | None = None
) -> list[Path]:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return [
        plot_success_vs_range(events, out / "success_vs_range.png"),
        plot_success_vs_snr(events, out / "success_vs_snr.png"),
        plot_timeline(events, out / "timeline.png", window),
    ]


def summary_lines(events: list[dict]) -> list[str]:
    kinds = Counter(e["event"] for e in events)
    outcomes = Counter(e["outcome"] for e in events if e["event"] == "rx")
    rx = data_receptions(events)
    good = sum(e["outcome"] == "good" for e in rx)
    lines = [
        "events: " + ", ".join(f"{k} {v}" for k, v in sorted(kinds.items())),
        "receptions: " + ", ".join(f"{k} {v}" for k, v in sorted(outcomes.items())),
    ]
    if rx:
        lines.append(f"data packets: {good}/{len(rx)} received whole ({good / len(rx):.1%})")
    overlapped = [e for e in events if e["event"] == "rx" and e.get("collision")]
    if overlapped:
        lost = sum(e["outcome"] != "good" for e in overlapped)
        lines.append(f"collisions: {len(overlapped)} receptions overlapped by another, {lost} lost")
    ranges = [e for e in events if e["event"] == "range"]
    if ranges:
        lines.append(f"ranging replies: {len(ranges)}")
    return lines
