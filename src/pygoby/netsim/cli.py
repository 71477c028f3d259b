"""`pygoby netsim run SCENARIO` and `pygoby netsim report LOG -o DIR`.

`run` reads a Scenario (TextFormat, src/pygoby/protobuf/pygoby/netsim/scenario.proto), runs it
— speed "max": everything in process on a virtual clock; a number: in real time (times that
factor) with the netsim_manager and the Micro-Modem emulators on TCP — writes the event log
(JSON lines) and prints a summary (with what reached external stacks' modems). Progress
(simulated time, packets and messages delivered, speed-up) shows on stderr: a bar on a
terminal, else a line every tenth of a run that lasts. Ctrl+C ends a run early with its
summary. `report` draws PNG plots from an event log. `sweep` and `sweep-report` run and plot
parameter sweeps (pygoby.netsim.sweep.cli).
"""

from __future__ import annotations

import argparse
import asyncio
import logging
import sys

from pygoby.util.progress import RunProgress


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "netsim",
        help="acoustic network simulation: run a scenario, plot its event log",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_subcommands(parser.add_subparsers(dest="netsim_command", required=True, metavar="ACTION"))


def add_subcommands(subparsers: argparse._SubParsersAction) -> None:
    run = subparsers.add_parser("run", help="run a simulation scenario (.pb.cfg)")
    run.add_argument("scenario", help="scenario file (protobuf TextFormat)")
    run.add_argument("--event-log", help="override the scenario's event_log path")
    run.add_argument("--speed", help='override the scenario\'s speed ("max" or a factor)')
    run.add_argument("--duration", type=float, help="override the duration (simulated s)")
    run.add_argument("--seed", type=int, help="override the random seed")
    run.add_argument("-v", "--verbose", action="count", default=0)
    run.set_defaults(func=run_command)
    report = subparsers.add_parser("report", help="plot an event log to PNG files")
    report.add_argument("log", help="event log (JSON lines) written by `netsim run`")
    report.add_argument("-o", "--output", default="netsim_report", help="output directory")
    report.add_argument(
        "--window",
        help="timeline window START:END in seconds after the first event (default: the whole run)",
    )
    report.set_defaults(func=report_command)
    from pygoby.netsim.sweep.cli import add_subcommands as add_sweep_subcommands

    add_sweep_subcommands(subparsers)


def run_command(args: argparse.Namespace) -> int:
    from pygoby.netsim.report.eventlog import EventLogWriter
    from pygoby.netsim.sim.scenario import (
        ScenarioError,
        check_scenario,
        load_scenario,
        speed_factor,
    )

    level = logging.WARNING - 10 * args.verbose
    logging.basicConfig(level=level, format="%(asctime)s %(levelname)s %(name)s: %(message)s")
    try:
        scenario = load_scenario(args.scenario)
        if args.event_log is not None:
            scenario.event_log = args.event_log
        if args.speed is not None:
            scenario.speed = args.speed
        if args.duration is not None:
            scenario.duration = args.duration
        if args.seed is not None:
            scenario.seed = args.seed
        check_scenario(scenario)
        factor = speed_factor(scenario)
    except ScenarioError as exc:
        print(f"pygoby netsim run: {exc}", file=sys.stderr)
        return 1
    try:
        log = EventLogWriter(scenario.event_log)
    except OSError as exc:
        print(f"pygoby netsim run: cannot write the event log: {exc}", file=sys.stderr)
        return 1
    with log, RunProgress("simulated", scenario.duration, "s") as progress:
        if factor is None:
            from pygoby.netsim.sim.simulation import Simulation

            sim = Simulation(scenario, on_event=log)
            try:
                summary = sim.run_virtual(progress=lambda: _report(progress, sim))
            except KeyboardInterrupt:
                summary = sim.summary()
                summary.interrupted = True
        else:
            summary = asyncio.run(_run_real_time(scenario, log, progress))
    for line in summary.lines():
        print(line)
    print(f"event log: {scenario.event_log} ({log.count} events)")
    return 0


def _report(progress: RunProgress, sim) -> None:
    progress.update(
        sim.clock.now() - sim.start, packets=sim.packets_delivered, messages=sim.status_received
    )


async def _run_real_time(scenario, log, progress: RunProgress):
    from pygoby.netsim.sim.realtime import RealTimeRun
    from pygoby.util.aiorun import StopSignals

    run = RealTimeRun(scenario, on_event=log)
    async with run:
        print(f"netsim_manager on {run.host}:{run.manager_port}", flush=True)
        for node in run.sim.nodes:
            print(
                f"Micro-Modem emulator id {node.modem_id} (netsim port {node.port}) on "
                f"{run.host}:{run.emulator_port(node.modem_id)}"
                + (" with in-process driver/MAC/queue" if node.driver is not None else ""),
                flush=True,
            )
        # SIGINT/SIGTERM end the run early, with its summary and a complete event log
        with StopSignals(asyncio.get_running_loop(), run.request_stop, "pygoby netsim run"):
            return await run.run(lambda: _report(progress, run.sim))


def report_command(args: argparse.Namespace) -> int:
    from pygoby.netsim.report.eventlog import read_events
    from pygoby.netsim.report.plots import summary_lines, write_report

    window = None
    if args.window:
        try:
            start, end = (float(x) for x in args.window.split(":"))
        except ValueError:
            print("pygoby netsim report: --window must be START:END seconds", file=sys.stderr)
            return 2
        window = (start, end)
    try:
        events = read_events(args.log)
    except OSError as exc:
        print(f"pygoby netsim report: {exc}", file=sys.stderr)
        return 1
    if not events:
        print(f"pygoby netsim report: no events in {args.log}", file=sys.stderr)
        return 1
    for line in summary_lines(events):
        print(line)
    for path in write_report(events, args.output, window):
        print(f"wrote {path}")
    return 0
