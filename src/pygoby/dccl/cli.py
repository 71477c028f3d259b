"""`pygoby dccl encode|decode|analyze`: DCCL from the command line, one message per line."""

from __future__ import annotations

import argparse
import logging
import os
import sys
from collections.abc import Callable, Iterable

from google.protobuf import text_format

from pygoby.dccl.analyze import describe, generated_source
from pygoby.dccl.arithmetic import load_model_file
from pygoby.dccl.codec import Codec
from pygoby.dccl.errors import DcclError
from pygoby.dccl.libraries import builtin_library
from pygoby.dccl.trace import log as trace_log
from pygoby.errors import ConfigError
from pygoby.util.names import did_you_mean

PASSPHRASE_ENV = "PYGOBY_DCCL_PASSPHRASE"


def register(subparsers) -> None:
    parser = subparsers.add_parser("dccl", help="encode, decode and analyze DCCL messages")
    parser.add_argument("action", choices=["encode", "decode", "analyze"])
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--proto", help=".proto file defining the message")
    source.add_argument(
        "--xml",
        metavar="FILE",
        action="append",
        help="Goby 1.1 XML message set (converted to DCCL in memory; with --goby11 repeatable)",
    )
    parser.add_argument(
        "--goby11",
        action="store_true",
        help="with --xml: Goby 1.1's own bytes (DCCL1), one JSON object per line for encode",
    )
    parser.add_argument(
        "-I",
        "--include",
        action="append",
        default=[],
        metavar="DIR",
        help="include directory for imports (repeatable)",
    )
    parser.add_argument(
        "--message",
        metavar="FULL.NAME",
        help="fully qualified message name (with --xml: the XML <name>); without it: the "
        "file's only message, or decode picks each line's type by its DCCL id and names it, "
        "analyze shows every DCCL message of the file",
    )
    parser.add_argument(
        "--write-proto",
        metavar="DIR",
        help="with --xml: also write the converted .proto file into DIR",
    )
    secret = parser.add_mutually_exclusive_group()
    secret.add_argument(
        "--passphrase-file",
        metavar="FILE",
        help="encrypt/decrypt the body with the passphrase in FILE (one trailing "
        f"newline ignored); without a passphrase option, ${PASSPHRASE_ENV} is used",
    )
    secret.add_argument(
        "--passphrase",
        help="the passphrase itself (visible to every user in the process list: "
        "prefer --passphrase-file or the environment variable)",
    )
    parser.add_argument(
        "--strict", action="store_true", help="refuse out-of-range values instead of degrading them"
    )
    parser.add_argument(
        "--source",
        action="store_true",
        help="analyze: print the Python generated for the message, not the table",
    )
    parser.add_argument(
        "--trace",
        action="store_true",
        help="encode/decode: print each field's value and bits to stderr",
    )
    parser.add_argument(
        "--arithmetic-model",
        action="append",
        default=[],
        metavar="FILE",
        help="a dccl.arith.protobuf.ArithmeticModel in TextFormat for"
        " dccl.arithmetic fields (repeatable)",
    )
    parser.add_argument(
        "--library",
        action="append",
        default=[],
        metavar="LIB",
        help="a C++ DCCL codec library name (e.g. libdccl_ccl_compat.so): use"
        " pygoby's built-in equivalent (repeatable)",
    )
    parser.set_defaults(func=run)


def _load_xml(codec: Codec, args: argparse.Namespace) -> list:
    from pygoby.dccl.xml import load_message_set

    message_set = load_message_set(args.xml[0])
    classes = message_set.load_into(codec)
    if args.write_proto:
        print(f"wrote {message_set.write_proto(args.write_proto)}", file=sys.stderr)
    if args.message is None:
        return classes
    if args.message not in message_set.names:
        raise ConfigError(
            f"no message named {args.message!r}{did_you_mean(args.message, message_set.names)}",
            file=args.xml[0],
        )
    return [classes[message_set.names.index(args.message)]]


def run(args: argparse.Namespace) -> int:
    if args.write_proto and not args.xml:
        print("error: --write-proto needs --xml", file=sys.stderr)
        return 2
    if args.goby11 or (args.xml and len(args.xml) > 1):
        return _run_goby11(args)
    if not args.trace:
        return _run(args)
    # the trace goes to this command's stderr, and only while it runs (`main` may be called again
    # in one process: tests, scripts)
    handler = logging.StreamHandler(sys.stderr)
    handler.setFormatter(logging.Formatter("%(message)s"))
    trace_log.addHandler(handler)
    level = trace_log.level
    trace_log.setLevel(logging.DEBUG)
    try:
        return _run(args)
    finally:
        trace_log.removeHandler(handler)
        trace_log.setLevel(level)


def _run(args: argparse.Namespace) -> int:
    try:
        passphrase = read_passphrase(args)
        codec = Codec(passphrase=passphrase, strict=args.strict, trace=args.trace)
        for name in args.library:
            builtin_library(name).apply(codec)
        for path in args.arithmetic_model:
            codec.set_arithmetic_model(load_model_file(path))
        if args.xml:
            classes = _load_xml(codec, args)
        elif args.message is None:
            classes = codec.load_proto_file(args.proto, args.include)
        else:
            classes = [codec.load_proto(args.proto, args.message, args.include)]
    except (DcclError, ConfigError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    if args.action == "analyze":
        show = generated_source if args.source else describe
        print("\n\n".join(show(codec.compiled(c)) for c in classes))
        return 0
    if not classes:
        print("error: the file defines no DCCL message", file=sys.stderr)
        return 2
    if args.action == "encode" and len(classes) > 1:
        names = ", ".join(c.DESCRIPTOR.full_name for c in classes)
        print(f"error: --message is required to encode: the file defines {names}", file=sys.stderr)
        return 2
    cls = classes[0]
    # several types (no --message): each line's DCCL id picks its type, named in the output
    by_id = len(classes) > 1

    def encode(line: str) -> str:
        msg = cls()
        text_format.Parse(line, msg)
        return codec.encode(msg).hex()

    def decode(line: str) -> str:
        try:
            data = bytes.fromhex(line)
        except ValueError:
            raise ValueError(f"not a hex string: {line!r}") from None
        msg = codec.decode(data, None if by_id else cls)
        text = text_format.MessageToString(msg, as_one_line=True)
        return f"{msg.DESCRIPTOR.full_name}: {text}" if by_id else text

    return process_lines(sys.stdin, encode if args.action == "encode" else decode)


def _run_goby11(args: argparse.Namespace) -> int:
    from pygoby.dccl.dccl1 import Dccl1Codec
    from pygoby.dccl.dccl1.cli import run as run_dccl1
    from pygoby.dccl.xml import load_message_set

    if not args.goby11 or not args.xml:
        print("error: several --xml files need --goby11; --goby11 needs --xml", file=sys.stderr)
        return 2
    try:
        codec = Dccl1Codec(passphrase=read_passphrase(args))
        for path in args.xml:
            codec.load(load_message_set(path))
    except (DcclError, ConfigError, OSError) as exc:
        print(f"error: {exc}", file=sys.stderr)
        return 2
    names = None if args.message is None else [args.message]
    return run_dccl1(args.action, codec, names, sys.stdin)


def read_passphrase(args: argparse.Namespace) -> str | bytes | None:
    """--passphrase-file (its bytes), else --passphrase, else the environment variable."""
    if args.passphrase_file is not None:
        with open(args.passphrase_file, "rb") as file:
            secret = file.read()
        # `echo secret > FILE` adds a newline that is not part of the passphrase
        return secret.removesuffix(b"\n")
    if args.passphrase is not None:
        return args.passphrase
    return os.environ.get(PASSPHRASE_ENV) or None


def process_lines(lines: Iterable[str], convert: Callable[[str], str]) -> int:
    """One output line per input line; a bad line prints `error: reason` and the rest goes on."""
    status = 0
    for raw in lines:
        line = raw.strip()
        try:
            print(convert(line), flush=True)
        except (DcclError, text_format.ParseError, ValueError) as exc:
            print(f"error: {exc}", flush=True)
            status = 1
    return status
