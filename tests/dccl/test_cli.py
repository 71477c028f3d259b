"""`pygoby dccl` run as a real command."""

from __future__ import annotations

import subprocess
import sys

from tests.dccl.vectors import DCCL_VECTORS

PROTO = str(DCCL_VECTORS / "example.proto")


def pygoby(*args: str, stdin: str = "") -> subprocess.CompletedProcess:
    return subprocess.run(
        [sys.executable, "-m", "pygoby.cli", *args], input=stdin, capture_output=True, text=True,
        timeout=60,
    )


def test_encode_lines_with_a_bad_line_in_the_middle() -> None:
    out = pygoby("dccl", "encode", "--proto", PROTO, "--message", "example.Tiny",
                 stdin="a: 5 b: 3 c: true\nnot text format\na: 9\n")
    lines = out.stdout.splitlines()
    assert lines[0] == "042501"
    assert lines[1].startswith("error: ") and "not" in lines[1]
    assert lines[2] == "040000"
    assert out.returncode == 1


def test_strict_encode_reports_the_field() -> None:
    out = pygoby("dccl", "encode", "--strict", "--proto", PROTO, "--message", "example.Tiny",
                 stdin="a: 9\n")
    assert out.stdout.startswith("error: example.Tiny.a: value 9 is out of range")
    assert out.returncode == 1


def test_decode_with_passphrase() -> None:
    out = pygoby("dccl", "decode", "--proto", PROTO, "--message", "example.LongId",
                 "--passphrase", "my secret", stdin="d10723025d66fced5d\n")
    assert out.returncode == 0
    assert out.stdout.startswith('src: 3 dest: 17 payload: "\\001\\002" t: ')


def test_decode_all_good_exits_zero_and_bad_hex_is_reported() -> None:
    good = pygoby("dccl", "decode", "--proto", PROTO, "--message", "example.Tiny", stdin="042501\n")
    assert (good.returncode, good.stdout) == (0, "a: 5 b: 3 c: true\n")
    bad = pygoby("dccl", "decode", "--proto", PROTO, "--message", "example.Tiny", stdin="04zz\n0425\n")
    assert bad.stdout.splitlines()[0] == "error: not a hex string: '04zz'"
    assert "truncated" in bad.stdout.splitlines()[1]
    assert bad.returncode == 1


def test_analyze_prints_the_field_table() -> None:
    out = pygoby("dccl", "analyze", "--proto", PROTO, "--message", "example.Example")
    assert out.returncode == 0
    assert "total:  6..28 bytes (max_bytes 64)" in out.stdout
    assert "pos.lat      body  dccl.default4           25" in out.stdout


def test_unknown_message_is_a_clear_error() -> None:
    out = pygoby("dccl", "analyze", "--proto", PROTO, "--message", "example.Nope")
    assert out.returncode == 2
    assert "unknown message type 'example.Nope'" in out.stderr
