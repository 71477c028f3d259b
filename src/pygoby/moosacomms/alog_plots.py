"""`pygoby log plot`: the figures of a mission's .alog files (after a day at sea), drawn from
`alog_series.LogSeries` with matplotlib (the `sim` extra, as netsim's reports).

* `transmissions.png`: one row per modem: what it sent (triangles) and received (ticks), by
  transmission type, over time;
* `link_quality.png`: SNR in and out (dB) and the equalizer MSE (dB) of each receiving modem's
  `$CACST` statistics over time;
* `acks.png`: acknowledged and expired messages, cumulative over time, per message type;
* `tracks.png`: each vehicle's NAV_X/NAV_Y (or NAV_LONG/NAV_LAT), start and end marked.

A figure whose data the logs do not have says so ("no data: ...") instead of being left out.
"""

from __future__ import annotations

from pathlib import Path

from pygoby.moosacomms.alog_series import AcommsVariables, LogSeries
from pygoby.util.extras import needs_extra

with needs_extra("sim", "log plots"):
    from pygoby.util.figures import no_data_figure, plt, save_figure

TYPE_COLOURS = {"DATA": "tab:blue", "ACK": "tab:olive", "DRIVER_SPECIFIC": "tab:purple"}
OTHER_COLOUR = "tab:gray"
TIME_LABEL = "seconds since the log started"


def plot_transmissions(series: LogSeries, var: AcommsVariables, path: Path) -> Path:
    title = "Transmissions (triangles) and receptions (ticks) per modem"
    modems = sorted({*series.transmissions, *series.receptions})
    if not modems:
        return no_data_figure(
            path, title, f"the logs have no ModemTransmission on {var.transmit} or {var.receive}"
        )
    row = {modem: index for index, modem in enumerate(modems)}
    fig, ax = plt.subplots(figsize=(12, 1.6 + 0.6 * len(modems)))
    labelled: set[str] = set()
    for events, offset, marker, verb in (
        (series.transmissions, -0.15, "^", "tx"),
        (series.receptions, 0.15, "|", "rx"),
    ):
        by_kind: dict[str, tuple[list[float], list[float]]] = {}
        for modem, items in events.items():
            for t, kind in items:
                xs, ys = by_kind.setdefault(kind, ([], []))
                xs.append(t)
                ys.append(row[modem] + offset)
        for kind, (xs, ys) in sorted(by_kind.items()):
            label = f"{verb} {kind}"
            ax.scatter(
                xs,
                ys,
                marker=marker,
                s=60 if marker == "|" else 30,
                color=TYPE_COLOURS.get(kind, OTHER_COLOUR),
                label=label if label not in labelled else None,
            )
            labelled.add(label)
    ax.set_yticks(
        range(len(modems)),
        [
            f"modem {m}\n{len(series.transmissions.get(m, []))} tx, "
            f"{len(series.receptions.get(m, []))} rx"
            for m in modems
        ],
    )
    ax.set_ylim(-0.6, len(modems) - 0.4)
    ax.set_xlabel(TIME_LABEL)
    ax.set_title(title)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize="small")
    ax.grid(True, axis="x", alpha=0.3)
    return save_figure(fig, path)


def plot_link_quality(series: LogSeries, var: AcommsVariables, path: Path) -> Path:
    title = "Link quality from the Micro-Modem's $CACST"
    modems = sorted(series.snr_in)
    if not modems:
        return no_data_figure(path, title, f"the logs have no $CACST in ModemRaw on {var.raw_in}")
    fig, (snr_ax, mse_ax) = plt.subplots(2, 1, figsize=(10, 6), sharex=True)
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for index, modem in enumerate(modems):
        colour = colours[index % len(colours)]
        for points, style, what in (
            (series.snr_in[modem], "o", "SNR in"),
            (series.snr_out.get(modem, []), "x", "SNR out"),
        ):
            snr_ax.plot(
                *zip(*points, strict=True), style, color=colour, ms=4, label=f"modem {modem} {what}"
            )
        mse = series.mse.get(modem, [])
        if mse:
            mse_ax.plot(*zip(*mse, strict=True), ".", color=colour, label=f"modem {modem}")
    snr_ax.set_ylabel("SNR (dB)")
    snr_ax.set_title(f"{title}: {sum(len(p) for p in series.snr_in.values())} receptions")
    snr_ax.legend(fontsize="small")
    mse_ax.set_ylabel("equalizer MSE (dB)")
    mse_ax.set_xlabel(TIME_LABEL)
    mse_ax.legend(fontsize="small")
    for ax in (snr_ax, mse_ax):
        ax.grid(True, alpha=0.3)
    return save_figure(fig, path)


def cumulative(times: list[float]) -> tuple[list[float], list[int]]:
    """Step-plot points of how many of `times` had happened by each time (from 0 at the
    first, so a single event still draws a step)."""
    ordered = sorted(times)
    return ordered[:1] + ordered, list(range(len(ordered) + 1))


def plot_acks(series: LogSeries, var: AcommsVariables, path: Path) -> Path:
    title = "Acknowledged and expired messages"
    types = sorted({*series.acked, *series.expired})
    if not types:
        return no_data_figure(path, title, f"the logs have no {var.acked} or {var.expired}")
    fig, ax = plt.subplots(figsize=(10, 5))
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for index, name in enumerate(types):
        colour = colours[index % len(colours)]
        short = name.rsplit(".", 1)[-1]
        for table, style, what in ((series.acked, "-", "acked"), (series.expired, "--", "expired")):
            times = table.get(name, [])
            if times:
                xs, ys = cumulative(times)
                ax.step(
                    xs,
                    ys,
                    style,
                    where="post",
                    color=colour,
                    label=f"{short} {what} ({len(times)})",
                )
    acked = sum(len(t) for t in series.acked.values())
    expired = sum(len(t) for t in series.expired.values())
    ax.set_title(f"{title}: {acked} acked, {expired} expired")
    ax.set_xlabel(TIME_LABEL)
    ax.set_ylabel("messages so far")
    ax.legend(fontsize="small")
    ax.grid(True, alpha=0.3)
    return save_figure(fig, path)


def plot_tracks(series: LogSeries, path: Path) -> Path:
    title = "Vehicle tracks"
    tracks = {name: track for name, track in sorted(series.tracks.items()) if track.points}
    if not tracks:
        return no_data_figure(
            path, title, "the logs have no NAV_X/NAV_Y or NAV_LAT/NAV_LONG of their vehicles"
        )
    fig, ax = plt.subplots(figsize=(8, 7))
    units = {track.units for track in tracks.values()}
    for name, track in tracks.items():
        xs, ys = zip(*track.points, strict=True)
        (line,) = ax.plot(xs, ys, "-", label=f"{name} ({track.units})")
        ax.plot(xs[0], ys[0], "o", color=line.get_color())
        ax.plot(xs[-1], ys[-1], "s", color=line.get_color())
    if units == {"m"}:
        ax.set_xlabel("NAV_X (m)")
        ax.set_ylabel("NAV_Y (m)")
        ax.set_aspect("equal", adjustable="datalim")
    elif units == {"deg"}:
        ax.set_xlabel("NAV_LONG (deg)")
        ax.set_ylabel("NAV_LAT (deg)")
    ax.set_title(f"{title} (circle: start, square: end)")
    ax.legend(fontsize="small")
    ax.grid(True, alpha=0.3)
    return save_figure(fig, path)


def write_log_plots(series: LogSeries, var: AcommsVariables, out_dir: str | Path) -> list[Path]:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    return [
        plot_transmissions(series, var, out / "transmissions.png"),
        plot_link_quality(series, var, out / "link_quality.png"),
        plot_acks(series, var, out / "acks.png"),
        plot_tracks(series, out / "tracks.png"),
    ]


def summary_lines(series: LogSeries) -> list[str]:
    """One line per figure's data, for the terminal."""
    tx = sum(len(v) for v in series.transmissions.values())
    rx = sum(len(v) for v in series.receptions.values())
    modems = sorted({*series.transmissions, *series.receptions})
    tracks = ", ".join(f"{name} ({len(t.points)} points)" for name, t in series.tracks.items())
    lines = [
        f"transmissions: {tx} sent, {rx} received, modems {', '.join(map(str, modems)) or '-'}",
        f"$CACST statistics: {sum(len(v) for v in series.snr_in.values())}",
        f"messages: {sum(len(v) for v in series.acked.values())} acked, "
        f"{sum(len(v) for v in series.expired.values())} expired",
        f"tracks: {tracks or '-'}",
    ]
    if series.skipped:
        skipped = ", ".join(f"{name} {n}" for name, n in sorted(series.skipped.items()))
        lines.append(f"values that did not parse (skipped): {skipped}")
    return lines
