"""The basic frontseat simulator's line protocol: splitting, typed messages, C++ number formats."""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.frontseat.simulator.protocol import (
    Command,
    Message,
    Nav,
    SimulatorProtocolError,
    Start,
    format_g,
    format_line,
    format_round_trip,
    parse_line,
)
from tests.hypothesis_profiles import examples

FUZZ = settings(max_examples=examples(200), deadline=None)

_libc = ctypes.CDLL(ctypes.util.find_library("c"))


def c_printf_g(value: float, precision: int) -> str:
    """What C's snprintf("%.*g") prints: the formatting C++ ostreams use for doubles."""
    buffer = ctypes.create_string_buffer(64)
    _libc.snprintf(buffer, 64, b"%.*g", ctypes.c_int(precision), ctypes.c_double(value))
    return buffer.value.decode()


@pytest.mark.parametrize(
    ("value", "precision", "text"),
    [
        (260.0, 6, "260"),
        (1.5, 6, "1.5"),
        (1234567.0, 6, "1.23457e+06"),
        (1e-5, 10, "1e-05"),
        (0.1 + 0.2, 10, "0.3"),
        (-0.0, 10, "-0"),
        (42.123400441234, 10, "42.12340044"),
        (123456789012.0, 10, "1.23456789e+11"),
    ],
)
def test_format_g_prints_like_cpp_streams(value, precision, text):
    assert format_g(value, precision) == text
    assert c_printf_g(value, precision) == text


@FUZZ
@given(st.floats(allow_nan=False, allow_infinity=False), st.sampled_from([6, 10]))
def test_format_g_matches_c_printf(value, precision):
    assert format_g(value, precision) == c_printf_g(value, precision)


@FUZZ
@given(st.floats(allow_nan=False, allow_infinity=False))
def test_format_round_trip_reads_back_exactly_and_is_cpp_default_when_short(value):
    text = format_round_trip(value)
    assert float(text) == value
    if float(format_g(value, 6)) == value:
        assert text == c_printf_g(value, 6)


def test_parse_line_splits_key_and_fields_and_trims_the_line():
    msg = parse_line("  NAV,LAT:42.1234,LON:-72.5435,DEPTH:200,HEADING:223,SPEED:1.4\r\n")
    assert msg.key == "NAV"
    assert dict(msg.fields) == {
        "LAT": "42.1234",
        "LON": "-72.5435",
        "DEPTH": "200",
        "HEADING": "223",
        "SPEED": "1.4",
    }
    assert parse_line("CTRL") == Message("CTRL", {})
    assert parse_line("") == Message("", {})


def test_parse_line_keeps_the_first_of_repeated_names():
    assert parse_line("CMD,HEADING:1,HEADING:2").fields["HEADING"] == "1"


@pytest.mark.parametrize(
    "line", ["CMD,HEADING", "CMD,HEADING:1,", "START,LAT:1:2,LON:3", "NAV,,LAT:1"]
)
def test_parse_line_rejects_fields_that_are_not_name_colon_value(line):
    with pytest.raises(SimulatorProtocolError, match="not NAME:VALUE"):
        parse_line(line)


def test_parse_line_keeps_latin1_spaces_that_cpp_isspace_does_not_strip():
    assert parse_line("CTRL,STATE:IDLE\xa0").fields["STATE"] == "IDLE\xa0"


@FUZZ
@given(st.text())
def test_parse_line_raises_only_protocol_errors(line):
    try:
        msg = parse_line(line)
    except SimulatorProtocolError:
        return
    for parse in (Start.from_message, Nav.from_message, Command.from_message):
        with contextlib.suppress(SimulatorProtocolError):
            parse(msg)


_token = st.text(st.characters(blacklist_characters=",:", codec="latin-1"), max_size=8).filter(
    lambda t: t == t.strip(" \t\n\v\f\r")
)


@FUZZ
@given(_token, st.dictionaries(_token, _token, max_size=5))
def test_format_line_and_parse_line_round_trip(key, fields):
    assert parse_line(format_line(key, fields)) == Message(key, fields)


def test_start_defaults_and_goby2_form():
    assert Start.from_message(parse_line("START,LAT:42.1234,LON:-72,DURATION:600")) == Start(
        lat=42.1234,
        lon=-72.0,
        duration=600,
        freq=10,
        accel=0.5,
        hdg_rate=45.0,
        z_rate=2.0,
        warp=1,
    )


def test_start_to_line_has_all_eight_fields_in_upstream_order():
    start = Start(lat=44.0888889, lon=9.84861111, duration=600, warp=4)
    assert start.to_line() == (
        "START,LAT:44.0888889,LON:9.84861111,DURATION:600,FREQ:10,ACCEL:0.5,HDG_RATE:45,"
        "Z_RATE:2,WARP:4"
    )


@FUZZ
@given(
    st.floats(-90, 90),
    st.floats(-180, 180),
    st.integers(-(2**31), 2**31 - 1),
    st.integers(1, 2**31 - 1),
    st.floats(0, 1e6),
    st.integers(1, 1000),
)
def test_start_round_trips_exactly(lat, lon, duration, freq, rate, warp):
    start = Start(lat, lon, duration, freq, rate, rate, rate, warp)
    assert Start.from_message(parse_line(start.to_line())) == start


@pytest.mark.parametrize(
    ("line", "error"),
    [
        ("START,LON:1", "START without LAT"),
        ("START,LAT:1", "START without LON"),
        ("START,LAT:abc,LON:1", "not a decimal number"),
        ("START,LAT:nan,LON:1", "not a decimal number"),
        ("START,LAT:1e999,LON:1", "out of range"),
        ("START,LAT:91,LON:1", "not a latitude"),
        ("START,LAT:1,LON:2,FREQ:0", "FREQ must be positive"),
        ("START,LAT:1,LON:2,FREQ:10.5", "not an integer"),
        ("START,LAT:1,LON:2,WARP:-1", "WARP must be positive"),
        ("START,LAT:1,LON:2,DURATION:9999999999", "32-bit"),
        ("START,LAT:1,LON:2,HDG_RATE:-45", "HDG_RATE must be zero or positive"),
        ("START,LAT:1,LON:2,ACCEL: 1", "not a decimal number"),
    ],
)
def test_start_rejects_bad_values(line, error):
    with pytest.raises(SimulatorProtocolError, match=error):
        Start.from_message(parse_line(line))


def test_nav_prints_ten_significant_digits():
    nav = Nav(lat=42.123456789012, lon=-72.0, depth=-0.0, heading=223.0, speed=1.4)
    assert nav.to_line() == "NAV,LAT:42.12345679,LON:-72,DEPTH:-0,HEADING:223,SPEED:1.4"
    parsed = Nav.from_message(parse_line(nav.to_line()))
    assert parsed.lat == pytest.approx(42.12345679, abs=1e-12)
    assert math.copysign(1.0, parsed.depth) == -1.0


def test_command_prints_six_significant_digits():
    cmd = Command(heading=259.99999999, speed=1.5, depth=100.0)
    assert cmd.to_line() == "CMD,HEADING:260,SPEED:1.5,DEPTH:100"
    assert Command.from_message(parse_line("CMD,HEADING:260,SPEED:1.5,DEPTH:100")) == Command(
        260.0, 1.5, 100.0
    )
    with pytest.raises(SimulatorProtocolError, match="CMD without DEPTH"):
        Command.from_message(parse_line("CMD,HEADING:260,SPEED:1.5"))
