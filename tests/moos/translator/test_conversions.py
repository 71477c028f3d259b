import math

import pytest

from pygoby.moos.translator.conversions import (
    as_bool,
    as_double,
    as_float,
    as_int,
    double_to_string17,
    format_double,
    format_float,
    hex_decode,
    looks_like_double,
)
from pygoby.protobuf.cpp_text import double_text as text_format_double
from pygoby.protobuf.cpp_text import float_text as text_format_float


@pytest.mark.parametrize(
    "text",
    [
        "3.5",
        "+4",
        "-2",
        "1e5",
        "3.",
        ".5",
        "00012",
        "nan",
        "NaN",
        "-nan",
        "inf",
        "INF",
        "infinity",
        "-Infinity",
    ],
)
def test_strings_posted_as_doubles(text):
    assert looks_like_double(text)


@pytest.mark.parametrize(
    "text", ["1e400", "1e", "0x1A", " 3", "3 ", "1,5", "true", "", "1_000", "\u0663"]
)
def test_strings_posted_as_strings(text):
    assert not looks_like_double(text)


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (0.1, "0.10000000000000001"),
        (550.0, "550"),
        (math.nan, "nan"),
        (-1.5, "-1.5"),
        (1e20, "1e+20"),
    ],
)
def test_double_to_string_17_digits(value, text):
    assert double_to_string17(value) == text


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (550.0, "550"),
        (1023.5, "1023.5"),
        (0.3, "0.3"),
        (1e-05, "1e-05"),
        (math.nan, "nan"),
        (1e20, "1e+20"),
        (0.1 + 0.7, "0.8"),
        (-math.inf, "-inf"),
    ],
)
def test_goby_stream_double(value, text):
    assert format_double(value) == text


def test_goby_stream_float():
    assert format_float(2.2) == "2.2"
    assert format_float(1234567.0) == "1.23457e+06"


@pytest.mark.parametrize(
    ("value", "text"),
    [
        (1.0, "1"),
        (0.1, "0.1"),
        (0.1 + 0.7, "0.79999999999999993"),
        (-0.0, "-0"),
        (1e20, "1e+20"),
        (math.inf, "inf"),
        (-math.inf, "-inf"),
        (math.nan, "nan"),
    ],
)
def test_text_format_double(value, text):
    assert text_format_double(value) == text


def test_text_format_float():
    assert text_format_float(2.2) == "2.2"
    assert text_format_float(16777216.0) == "16777216"
    assert text_format_float(16777217.0) == "16777216"  # rounded to float first
    assert text_format_float(0.1) == "0.1"
    assert text_format_float(3.14159274) == "3.14159274"


@pytest.mark.parametrize(
    ("text", "kind", "value"),
    [
        ("42", "int32", 42),
        ("+42", "int32", 42),
        ("3.5", "int32", 2**31 - 1),
        ("", "int32", 2**31 - 1),
        (" 5", "int32", 2**31 - 1),
        ("-1", "uint32", 4294967295),
        ("-1", "uint64", 2**64 - 1),
        ("4294967296", "uint32", 4294967295),
        ("-2147483648", "int32", -(2**31)),
        ("2147483648", "int32", 2**31 - 1),
        ("-9223372036854775808", "int64", -(2**63)),
    ],
)
def test_as_int(text, kind, value):
    assert as_int(text, kind) == value


def test_as_double_and_float():
    assert as_double("1.5") == 1.5
    assert math.isnan(as_double("abc"))
    assert math.isnan(as_double(""))
    assert as_double("-inf") == -math.inf
    assert math.isnan(as_float("1e39"))
    assert as_float("2.2") == pytest.approx(2.2, rel=1e-7)


@pytest.mark.parametrize(
    ("text", "value"),
    [("true", True), ("TRUE", True), ("1", True), ("false", False), ("0", False), ("yes", False)],
)
def test_as_bool(text, value):
    assert as_bool(text) is value


def test_hex_decode_is_lenient():
    assert hex_decode("0aFF") == b"\x0a\xff"
    assert hex_decode("abc") == b"\x0a\xbc"
    assert hex_decode("zz") == b"\x00"
