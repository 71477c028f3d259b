"""`pygoby log`: look at, cut, convert and replay MOOS .alog files (pLogger's).

  pygoby log grep FILE VAR... [--source S]       lines of these variables (VAR* = prefix)
  pygoby log summary FILE                        per variable: lines, first/last time, rate, sources
  pygoby log clip FILE T0 T1 -o OUT.alog         the entries between two log times
  pygoby log convert FILE... -o OUT.parquet [-j N] [--mission M.moos]
                                                 one row per message (.parquet, .csv, .jsonl)
  pygoby log plot FILE... -o DIR [--mission M.moos]
                                                 acomms figures: tx/rx per modem, SNR/MSE,
                                                 acked/expired messages, vehicle tracks (PNG)
  pygoby log replay FILE --port P [--warp W]     post the messages into a MOOSDB, original spacing

Damaged lines are skipped; their count is printed on stderr. (The command line lives with the
apps: `--mission` wires the .alog tools of moos to moosacomms' decoding.)
"""

from __future__ import annotations

import argparse
import asyncio
import functools
import sys
from collections.abc import Callable
from pathlib import Path

from pygoby.errors import ConfigError
from pygoby.moos.alog.files import AlogFile
from pygoby.moos.alog.tools import LogToolError

Command = Callable[[argparse.Namespace], int]


def reporting_errors(command: Command) -> Command:
    """Missing inputs, unwritable outputs, no MOOSDB to replay into (TimeoutError is an
    OSError) and refused requests: one line on stderr, status 1."""

    @functools.wraps(command)
    def run(args: argparse.Namespace) -> int:
        inputs = getattr(args, "files", None) or [args.file]
        missing = [name for name in inputs if not Path(name).is_file()]
        if missing:
            print(f"pygoby log: no such file: {', '.join(missing)}", file=sys.stderr)
            return 1
        try:
            return command(args)
        except (LogToolError, ConfigError, OSError) as err:
            print(f"pygoby log: {err}", file=sys.stderr)
            return 1

    return run


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "log",
        help="MOOS .alog files: grep, summary, clip, convert, plot, replay",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    actions = parser.add_subparsers(dest="log_command", required=True, metavar="ACTION")

    grep = actions.add_parser(
        "grep", help="print the lines of some variables as the file has them (aloggrep -q)"
    )
    grep.add_argument("file")
    grep.add_argument("variables", nargs="+", metavar="VAR", help="name, or prefix ending in *")
    grep.add_argument("--source", action="append", default=[], help="only from this source")
    grep.set_defaults(func=grep_command)

    summary = actions.add_parser("summary", help="per-variable counts and rates (alogscan)")
    summary.add_argument("file")
    summary.set_defaults(func=summary_command)

    clip = actions.add_parser("clip", help="keep the entries between two log times (alogclip)")
    clip.add_argument("file")
    clip.add_argument("t0", type=float, help="from this time (s since LOGSTART)")
    clip.add_argument("t1", type=float, help="to this time (s since LOGSTART)")
    clip.add_argument("-o", "--output", required=True, help="the .alog to write")
    clip.set_defaults(func=clip_command)

    convert = actions.add_parser("convert", help="to Parquet, CSV or JSON lines")
    convert.add_argument("files", nargs="+", metavar="FILE")
    convert.add_argument("-o", "--output", required=True, help="OUT.parquet, OUT.csv or OUT.jsonl")
    convert.add_argument(
        "-j",
        "--jobs",
        type=int,
        default=1,
        metavar="N",
        help="convert up to N files at once, in parallel processes (the output is the same)",
    )
    convert.add_argument(
        "--mission",
        metavar="FILE.moos",
        help="decode the acomms variables of this mission's pAcommsHandler (and the DCCL "
        "messages in their frames) and its translator variables into columns",
    )
    convert.add_argument(
        "--block", default="pAcommsHandler", help="its ProcessConfig (default %(default)s)"
    )
    convert.set_defaults(func=convert_command)

    plot = actions.add_parser("plot", help="acomms figures of a mission's logs (PNG)")
    plot.add_argument("files", nargs="+", metavar="FILE", help="one .alog per vehicle")
    plot.add_argument("-o", "--output", required=True, metavar="DIR", help="write the PNGs here")
    plot.add_argument(
        "--mission",
        metavar="FILE.moos",
        help="its pAcommsHandler's variable names and modem id (default: pAcommsHandler's)",
    )
    plot.add_argument(
        "--block", default="pAcommsHandler", help="its ProcessConfig (default %(default)s)"
    )
    plot.set_defaults(func=plot_command)

    replay = actions.add_parser("replay", help="post a log's messages into a MOOSDB (uPlayBack)")
    replay.add_argument("file")
    replay.add_argument("--host", default="127.0.0.1")
    replay.add_argument("--port", type=int, required=True)
    replay.add_argument("--warp", type=float, default=1.0, help="play this many times faster")
    replay.add_argument("--from", dest="start", type=float, default=0.0, help="start at log time")
    replay.add_argument("--only", nargs="+", default=[], metavar="VAR", help="only these (VAR*)")
    replay.set_defaults(func=replay_command)


def _report_bad_lines(log: AlogFile) -> None:
    if log.reader.bad_lines:
        print(
            f"{log.path}: {log.reader.bad_lines} damaged lines skipped "
            f"(the first at line {log.reader.first_bad_line})",
            file=sys.stderr,
        )
    if log.unresolved_binary:
        print(
            f"{log.path}: {log.unresolved_binary} binary values not found in the .blog",
            file=sys.stderr,
        )


@reporting_errors
def grep_command(args: argparse.Namespace) -> int:
    from pygoby.moos.alog.tools import grep, write_lines

    log = AlogFile(args.file)
    write_lines((entry.line for entry in grep(log, args.variables, args.source)), sys.stdout)
    _report_bad_lines(log)
    return 0


@reporting_errors
def summary_command(args: argparse.Namespace) -> int:
    from pygoby.moos.alog.tools import summarize, summary_lines

    log = AlogFile(args.file)
    table = summarize(log)
    print("\n".join(summary_lines(log, table)))
    _report_bad_lines(log)
    return 0


@reporting_errors
def clip_command(args: argparse.Namespace) -> int:
    from pygoby.moos.alog.tools import clip

    log = AlogFile(args.file)
    with open(args.output, "w", encoding="utf-8", errors="surrogateescape") as out:
        count = clip(log, args.t0, args.t1, out)
    print(f"{args.output}: {count} entries")
    _report_bad_lines(log)
    return 0


@reporting_errors
def convert_command(args: argparse.Namespace) -> int:
    from pygoby.moos.alog.tools import convert, decoded_columns

    def progress(rows: int) -> None:
        if sys.stderr.isatty():
            sys.stderr.write(f"\r{rows} rows")

    decoder = None
    columns = None
    undecodable = None
    if args.mission is not None:
        from pygoby.moosacomms.alog_decode import MissionDecoder  # only when asked for

        # configuration errors now, not in a worker; the first pass over the files (the
        # columns) sees every value once, so its decoder counts the undecodable ones
        first_pass = MissionDecoder(args.mission, args.block)
        columns = decoded_columns(args.files, first_pass)
        undecodable = first_pass.undecodable
        decoder = functools.partial(MissionDecoder, args.mission, args.block)
    count = convert(
        args.files, args.output, progress, jobs=args.jobs, decoder=decoder, columns=columns
    )
    if sys.stderr.isatty():
        sys.stderr.write("\n")
    print(f"{args.output}: {count} rows")
    if undecodable:
        counts = ", ".join(f"{name} {n}" for name, n in sorted(undecodable.items()))
        print(f"values left undecoded (kept raw): {counts}", file=sys.stderr)
    return 0


@reporting_errors
def plot_command(args: argparse.Namespace) -> int:
    # matplotlib (the sim extra) first: a missing extra is said before the logs are read
    from pygoby.moosacomms.alog_plots import summary_lines, write_log_plots
    from pygoby.moosacomms.alog_series import AcommsVariables, log_series

    variables = AcommsVariables.of_mission(args.mission, args.block)
    series = log_series(args.files, variables)
    for path in write_log_plots(series, variables, args.output):
        print(path)
    print("\n".join(summary_lines(series)))
    return 0


@reporting_errors
def replay_command(args: argparse.Namespace) -> int:
    from pygoby.moos.alog.tools import print_progress, replay

    log = AlogFile(args.file)
    progress = print_progress() if sys.stderr.isatty() else None
    count = asyncio.run(
        replay(
            log,
            args.host,
            args.port,
            warp=args.warp,
            start=args.start,
            only=args.only,
            progress=progress,
        )
    )
    print(f"{count} messages posted")
    _report_bad_lines(log)
    return 0
