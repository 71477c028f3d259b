"""The standard figures of a sweep (`pygoby netsim sweep-report`), PNG with matplotlib, and an
HTML page that shows them with the numbers behind them.

* `success_vs_range.png`: data-packet success (receptions with every frame good / packets
  sent) against the link's range, one line per data rate, with 95 % Wilson score intervals.
  Packets are pooled over the runs and links of a range bin and treated as independent
  Bernoulli trials (packets on one link in one run are correlated, so read the interval as a
  lower bound on the real uncertainty);
* `throughput_vs_nodes.png` and `latency_vs_nodes.png` (only when the node count is an axis of
  the sweep): per run, NodeStatus messages delivered per hour over all links, and their mean
  delivery latency (delivery time minus the message's time stamp), against the node count, one
  line per rate: mean over the runs, bars ±1.96 standard errors of that mean;
* `snr_vs_range.png`: every link's mean SNR (and SINR, interference included) against range.

Ranges are grouped by their distinct values (rounded to 1 m) when there are at most
`MAX_DISTINCT_RANGES` of them (a layout sweep's multiples of the spacing), else in
`RANGE_BINS` equal bins.
"""

from __future__ import annotations

import html
import math
from collections import defaultdict
from collections.abc import Iterable, Sequence
from dataclasses import dataclass
from pathlib import Path

from pygoby.util.extras import needs_extra

with needs_extra("sim", "netsim sweep reports"):
    import pyarrow as pa
    import pyarrow.parquet as pq

from pygoby.netsim.report.plots import plt, save_figure
from pygoby.netsim.sweep.store import RESULTS_FILE

Z95 = 1.959963984540054  # standard normal 97.5 % quantile
MAX_DISTINCT_RANGES = 30
RANGE_BINS = 15


def wilson_interval(successes: int, trials: int, z: float = Z95) -> tuple[float, float]:
    """Wilson score interval for a binomial proportion (Wilson 1927)."""
    if trials == 0:
        return (math.nan, math.nan)
    p = successes / trials
    denominator = 1 + z * z / trials
    centre = (p + z * z / (2 * trials)) / denominator
    half = z / denominator * math.sqrt(p * (1 - p) / trials + z * z / (4 * trials * trials))
    return (max(0.0, centre - half), min(1.0, centre + half))


def results_path(source: str | Path) -> Path:
    """The table of `source`: a sweep's output folder or the table file itself."""
    path = Path(source)
    return path / RESULTS_FILE if path.is_dir() else path


def read_results(source: str | Path) -> pa.Table:
    return pq.read_table(results_path(source))


@dataclass(frozen=True)
class SuccessPoint:
    rate: int
    range_m: float
    good: int
    sent: int

    @property
    def success(self) -> float:
        return self.good / self.sent if self.sent else math.nan

    @property
    def interval(self) -> tuple[float, float]:
        return wilson_interval(self.good, self.sent)


def _range_key(ranges: Sequence[float]):
    distinct = {round(r) for r in ranges}
    if len(distinct) <= MAX_DISTINCT_RANGES:
        return lambda r: float(round(r))
    low, high = min(ranges), max(ranges)
    width = (high - low) / RANGE_BINS or 1.0
    return lambda r: low + (min(int((r - low) / width), RANGE_BINS - 1) + 0.5) * width


def success_by_range(rows: list[dict]) -> list[SuccessPoint]:
    """Pooled success per (rate, range group) over the links that carried data."""
    links = [r for r in rows if r["sent"] > 0 and not math.isnan(r["range_m"])]
    if not links:
        return []
    key = _range_key([r["range_m"] for r in links])
    totals: dict[tuple[int, float], list[int]] = defaultdict(lambda: [0, 0])
    for r in links:
        total = totals[(r["rate"], key(r["range_m"]))]
        total[0] += r["good"]
        total[1] += r["sent"]
    return [
        SuccessPoint(rate, rng, good, sent) for (rate, rng), (good, sent) in sorted(totals.items())
    ]


@dataclass(frozen=True)
class RunFigures:
    run_id: str
    rate: int
    nodes: int
    throughput_per_hour: float
    latency_s: float  # NaN when nothing was delivered


def per_run(rows: list[dict]) -> list[RunFigures]:
    runs: dict[str, list[dict]] = defaultdict(list)
    for r in rows:
        runs[r["run_id"]].append(r)
    figures = []
    for run_id, links in runs.items():
        messages = sum(r["messages"] for r in links)
        latency = sum(r["latency_mean_s"] * r["messages"] for r in links if r["messages"])
        rates = [r["rate"] for r in links if r["rate"] >= 0]
        figures.append(
            RunFigures(
                run_id,
                max(set(rates), key=rates.count) if rates else -1,
                links[0]["nodes"],
                messages / links[0]["duration_s"] * 3600,
                latency / messages if messages else math.nan,
            )
        )
    return figures


def mean_and_halfwidth(values: Iterable[float]) -> tuple[float, float, int]:
    """Mean, 1.96 standard errors (0 for one value) and the count, NaNs left out."""
    xs = [v for v in values if not math.isnan(v)]
    if not xs:
        return (math.nan, math.nan, 0)
    mean = sum(xs) / len(xs)
    if len(xs) < 2:
        return (mean, 0.0, 1)
    variance = sum((x - mean) ** 2 for x in xs) / (len(xs) - 1)
    return (mean, Z95 * math.sqrt(variance / len(xs)), len(xs))


def _rate_label(rate: int) -> str:
    return f"rate {rate}" if rate >= 0 else "no data sent"


def plot_success_vs_range(points: list[SuccessPoint], path: Path) -> Path:
    fig, ax = plt.subplots(figsize=(8, 5))
    for rate in sorted({p.rate for p in points}):
        series = [p for p in points if p.rate == rate]
        xs = [p.range_m / 1000 for p in series]
        ys = [p.success for p in series]
        # (rounding can put an end a hair past the estimate at 0 or 1)
        low = [max(0.0, p.success - p.interval[0]) for p in series]
        high = [max(0.0, p.interval[1] - p.success) for p in series]
        ax.errorbar(xs, ys, yerr=[low, high], fmt="o-", capsize=3, label=_rate_label(rate))
    ax.set_ylim(-0.05, 1.05)
    ax.set_xlabel("range (km)")
    ax.set_ylabel("data packet success (all frames good / sent)")
    ax.set_title("Packet success vs range (95 % Wilson intervals)")
    ax.grid(True, alpha=0.3)
    ax.legend(loc="lower left")
    return save_figure(fig, path)


def _plot_vs_nodes(runs: list[RunFigures], attribute: str, ylabel: str, title: str, path: Path):
    fig, ax = plt.subplots(figsize=(8, 5))
    for rate in sorted({r.rate for r in runs}):
        by_nodes: dict[int, list[float]] = defaultdict(list)
        for r in runs:
            if r.rate == rate:
                by_nodes[r.nodes].append(getattr(r, attribute))
        nodes = sorted(by_nodes)
        stats = [mean_and_halfwidth(by_nodes[n]) for n in nodes]
        ax.errorbar(
            nodes,
            [s[0] for s in stats],
            yerr=[s[1] for s in stats],
            fmt="o-",
            capsize=3,
            label=_rate_label(rate),
        )
    ax.set_xlabel("nodes")
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend()
    return save_figure(fig, path)


def plot_snr_vs_range(rows: list[dict], path: Path) -> Path:
    links = [r for r in rows if r["received"] > 0]
    fig, ax = plt.subplots(figsize=(8, 5))
    ax.scatter(
        [r["range_m"] / 1000 for r in links],
        [r["snr_mean_db"] for r in links],
        s=10,
        alpha=0.6,
        label="SNR (ambient noise)",
    )
    ax.scatter(
        [r["range_m"] / 1000 for r in links],
        [r["sinr_mean_db"] for r in links],
        s=10,
        alpha=0.6,
        marker="x",
        label="SINR (with interference)",
    )
    ax.set_xlabel("range (km)")
    ax.set_ylabel("dB (mean over the link's data receptions)")
    ax.set_title(f"SNR vs range ({len(links)} links)")
    ax.grid(True, alpha=0.3)
    ax.legend()
    return save_figure(fig, path)


def write_sweep_report(table: pa.Table, out_dir: str | Path) -> list[Path]:
    """The figures and index.html in `out_dir`; returns their paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    rows = table.to_pylist()
    points = success_by_range(rows)
    runs = per_run(rows)
    figures = [plot_success_vs_range(points, out / "success_vs_range.png")]
    node_counts = sorted({r.nodes for r in runs})
    notes = []
    # a figure against the node count says something only when the node count was swept
    if len(node_counts) > 1:
        figures += [
            _plot_vs_nodes(
                runs,
                "throughput_per_hour",
                "NodeStatus messages delivered per hour",
                "Throughput vs node count (mean over runs, ±1.96 SE)",
                out / "throughput_vs_nodes.png",
            ),
            _plot_vs_nodes(
                runs,
                "latency_s",
                "mean message latency (s)",
                "Latency vs node count (mean over runs, ±1.96 SE)",
                out / "latency_vs_nodes.png",
            ),
        ]
    else:
        for stale in ("throughput_vs_nodes.png", "latency_vs_nodes.png"):
            (out / stale).unlink(missing_ok=True)  # from an earlier report of other results
        notes.append(
            "Throughput and latency against the node count are not drawn: every run has "
            f"{node_counts[0] if node_counts else 0} nodes (sweep layout.nodes to see them)."
        )
    figures.append(plot_snr_vs_range(rows, out / "snr_vs_range.png"))
    page = out / "index.html"
    page.write_text(_html(table, rows, runs, points, figures, notes))
    return [*figures, page]


def _html(table: pa.Table, rows, runs, points, figures, notes: Sequence[str] = ()) -> str:
    esc = html.escape
    fixed = {"run_id", "point", "replicate", "seed"}
    columns = [c for c in table.column_names if c not in fixed]
    axis_columns = columns[: columns.index("nodes")] if "nodes" in columns else []
    axes = "".join(
        f"<tr><td>{esc(c)}</td><td>{esc(', '.join(map(str, sorted(set(table.column(c).to_pylist()), key=str))))}</td></tr>"
        for c in axis_columns
    )
    success = "".join(
        f"<tr><td>{p.rate}</td><td>{p.range_m:.0f}</td><td>{p.good}</td><td>{p.sent}</td>"
        f"<td>{p.success:.3f}</td><td>{p.interval[0]:.3f} – {p.interval[1]:.3f}</td></tr>"
        for p in points
    )
    images = "".join(
        f'<figure><img src="{esc(f.name)}" alt="{esc(f.stem)}"><figcaption>{esc(f.stem)}'
        "</figcaption></figure>"
        for f in figures
    )
    seeds = len(set(table.column("seed").to_pylist()))
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>netsim sweep report</title>
<style>body{{font-family:sans-serif;margin:2em;max-width:70em}}table{{border-collapse:collapse}}
td,th{{border:1px solid #ccc;padding:2px 8px;text-align:right}}figure{{display:inline-block;margin:1em}}
img{{max-width:40em}}</style></head><body>
<h1>netsim sweep report</h1>
<p>{len(runs)} runs, {seeds} seeds, {table.num_rows} link rows.</p>
<h2>Axes</h2><table><tr><th>column</th><th>values</th></tr>{axes}</table>
<h2>Figures</h2>{"".join(f"<p>{esc(n)}</p>" for n in notes)}{images}
<h2>Packet success by rate and range</h2>
<p>Success = data packets received with every frame good / packets sent, pooled over runs and
links; interval: 95 % Wilson score.</p>
<table><tr><th>rate</th><th>range (m)</th><th>good</th><th>sent</th><th>success</th>
<th>95 % interval</th></tr>{success}</table>
</body></html>
"""
