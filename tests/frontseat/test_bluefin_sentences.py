"""The Bluefin SPI sentence formats: time of day, positions, numbers, sentences; and no input
makes the parser or the driver's reader raise anything but the NMEA errors it handles."""

from __future__ import annotations

import contextlib
import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.frontseat.bluefin import sentences
from pygoby.util.errors import NMEAChecksumError, NMEAError
from tests.hypothesis_profiles import examples

from .bluefin_scenario import T0, driver_on_memory


def test_time_of_day_has_exactly_three_decimals_truncated():
    assert sentences.time_of_day(T0) == "221320.000"
    assert sentences.time_of_day(T0 + 3661.2349) == "231421.234"
    assert sentences.time_of_day(0.0) == "000000.000"


@given(st.floats(min_value=0, max_value=4e9))
def test_time_of_day_round_trips_on_the_same_day(t):
    text = sentences.time_of_day(t)
    back = sentences.parse_time_of_day(text, t)
    assert back is not None and 0 <= t - back < 0.001 + 1e-6


@pytest.mark.parametrize("text", ["", "12345", "ab3456.0", "256000", "120000.x"])
def test_a_bad_time_of_day_reads_as_none(text):
    assert sentences.parse_time_of_day(text, T0) is None


def test_positions_are_degrees_and_decimal_minutes():
    assert sentences.latitude(44.0888889) == ("4405.3333", "N")
    assert sentences.longitude(-9.84861111) == ("00950.9167", "W")
    assert sentences.latitude(-0.5) == ("0030.0000", "S")
    assert sentences.parse_angle("4405.3333", "N", 2, "S") == pytest.approx(44.0888883)
    assert sentences.parse_angle("00950.9167", "W", 3, "W") == pytest.approx(-9.8486117)
    assert math.isnan(sentences.parse_angle("", "N", 2, "S"))
    with pytest.raises(NMEAError):
        sentences.parse_angle("44x5.1", "N", 2, "S")


@given(st.floats(min_value=-89.99, max_value=89.99), st.floats(min_value=-179.99, max_value=179.99))
def test_positions_round_trip_to_a_ten_thousandth_of_a_minute(lat, lon):
    text, hemisphere = sentences.latitude(lat)
    assert sentences.parse_angle(text, hemisphere, 2, "S") == pytest.approx(lat, abs=2e-6)
    text, hemisphere = sentences.longitude(lon)
    assert sentences.parse_angle(text, hemisphere, 3, "W") == pytest.approx(lon, abs=2e-6)


def test_numbers_as_cpp_lexical_cast_prints_them():
    assert [sentences.number(v) for v in (0, 1.5, 0.1, 180.0, -2)] == [
        "0",
        "1.5",
        "0.10000000000000001",
        "180",
        "-2",
    ]


def test_build_splits_text_at_commas_and_adds_the_checksum():
    sentence = sentences.build("$BPSTS", ("221320.000", 1, "a,b"))
    assert sentence.fields == ("$BPSTS", "221320.000", "1", "a", "b")
    assert sentence.message() == "$BPSTS,221320.000,1,a,b*6A"
    assert sentences.parse(sentence.message()) == sentence
    with pytest.raises(NMEAError):
        sentences.build("$BPMSG", ("bad*star",))


@given(
    st.sampled_from(["$BPRMB", "$BFNVG", "$BFACK", "$BPLOG"]),
    st.lists(
        st.one_of(
            st.integers(-(10**6), 10**6),
            st.floats(allow_nan=False, allow_infinity=False),
            st.text(
                st.characters(min_codepoint=32, max_codepoint=126, exclude_characters="*,$"),
                max_size=8,
            ),
        ),
        max_size=12,
    ),
)
def test_build_then_parse_round_trips(token, values):
    sentence = sentences.build(token, values)
    again = sentences.parse(sentence.message())
    assert again == sentence
    numbers = [v for v in values if not isinstance(v, str)]
    parsed = [
        float(f) for f, v in zip(again.fields[1:], values, strict=True) if not isinstance(v, str)
    ]
    assert parsed == [float(v) for v in numbers]


def test_a_wrong_checksum_is_refused_but_a_raw_out_checksum_is_only_replaced():
    with pytest.raises(NMEAChecksumError):
        sentences.parse("$BFMSC,221320.000,go*00")
    assert sentences.parse_unchecked("$BPMSG,hello*00").message() == "$BPMSG,hello*05"


@settings(max_examples=examples(300))
@given(st.text(max_size=120))
def test_the_parser_raises_only_nmea_errors(text):
    with contextlib.suppress(NMEAError):
        sentences.parse(text)


_FIELD = st.one_of(
    st.just(""),
    st.from_regex(r"-?[0-9]{1,7}(\.[0-9]{1,4})?", fullmatch=True),
    st.sampled_from(["N", "S", "E", "W", "Running", "ACK", "RMB", "LOG", "nan", "inf", "1", "0"]),
    st.text(
        st.characters(min_codepoint=32, max_codepoint=126, exclude_characters="*,"), max_size=6
    ),
)


@settings(max_examples=examples(150))
@given(
    st.sampled_from(
        [
            "ACK",
            "NVG",
            "NVR",
            "RVL",
            "DVL",
            "CTD",
            "MSC",
            "SHT",
            "MBS",
            "MIS",
            "MBE",
            "CTL",
            "BOY",
            "TRM",
            "SVS",
            "TOP",
            "XYZ",
        ]
    ),
    st.lists(_FIELD, max_size=14),
)
def test_the_driver_reads_any_bluefin_sentence_without_raising(kind, fields):
    driver, link, _ = driver_on_memory()
    driver.do_work()  # connected: the start-up requests are queued
    link.feed(sentences.build(f"$BF{kind}", fields).message() + "\r\n")
    driver.do_work()
    driver.do_work()
