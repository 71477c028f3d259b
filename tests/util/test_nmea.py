"""NMEA parse/print with checksums, against the spec's computed examples (acomms.md §7.1)."""

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.util.errors import NMEAChecksumError, NMEAError, NMEAFormatError
from pygoby.util.nmea import (
    NMEASentence,
    checksum,
    with_checksum,
)
from tests.hypothesis_profiles import examples

SPEC_EXAMPLES = [
    "$CCCFG,SRC,1*31",
    "$CCCYC,0,1,2,0,1,1*5A",
    "$CCTMS,2019-12-02T03:02:37Z,0*7A",
    "$CCCFG,CST,1*37",
    "$CCCFG,REV,1*32",
    "$CCCFG,RXP,1*29",
    "$CCCFG,ALL,0*33",
    "$CCMSC,1,1,0*41",
    "$CCCFQ,SRC*3A",
    "$CCTMQ,0*54",
    "$CCCFQ,TOP*33",
    "$CCCFQ,ALL*39",
    "$CADRQ,120000,1,2,1,32,1*44",
    "$CCTXD,1,2,1,0102030405*7B",
    "$CARXD,1,2,1,1,0102030405*62",
    "$CCTXD,1,2,1,*7A",
    "$CACYC,0,1,2,0,1,1*58",
    "$CAACK,2,1,1,1*48",
    "$CCMPC,1,2*5D",
]


@pytest.mark.parametrize("line", SPEC_EXAMPLES)
def test_spec_examples_parse_and_print_identically(line):
    sentence = NMEASentence.parse(line + "\r\n")
    assert sentence.message() == line


def test_build_and_fields():
    s = NMEASentence.build("CCTXD", [1, 2, True, b"\x01\x02\x03\x04\x05"])
    assert s.message() == "$CCTXD,1,2,1,0102030405*7B"
    assert (s.talker_id, s.sentence_id, s.as_int(1), s[4]) == ("CC", "TXD", 1, "0102030405")


def test_checksum_optional_on_input():
    assert NMEASentence.parse("$CACYC,0,1,2,0,1,1").message() == "$CACYC,0,1,2,0,1,1*58"
    assert with_checksum("$CACYC,0,1,2,0,1,1") == "$CACYC,0,1,2,0,1,1*58"


@pytest.mark.parametrize(
    "line, error",
    [
        ("$CCCYC,0,1,2,0,1,1*5B", NMEAChecksumError),
        ("CCCYC,0,1,2", NMEAFormatError),
        ("$CCCY,0,1", NMEAFormatError),
        ("$CCCYC,0*ZZ", NMEAFormatError),
        ("$CCCYC,0*5", NMEAFormatError),
        ("$CCCYC,é", NMEAFormatError),
        ("", NMEAFormatError),
    ],
)
def test_bad_lines_raise_specific_errors(line, error):
    with pytest.raises(error):
        NMEASentence.parse(line)


def test_as_int_on_bad_field():
    with pytest.raises(NMEAFormatError):
        NMEASentence.parse("$CADRQ,x").as_int(1)
    with pytest.raises(NMEAFormatError):
        NMEASentence.parse("$CADRQ,1").as_int(5)


@settings(max_examples=examples(200), deadline=None)
@given(st.text(max_size=80))
def test_fuzz_parse_only_raises_nmea_errors(text):
    try:
        sentence = NMEASentence.parse(text)
    except NMEAError:
        return
    assert NMEASentence.parse(sentence.message()) == sentence


@settings(max_examples=examples(200), deadline=None)
@given(
    st.text(alphabet="ABCDEFGHIJKLMNOPQRSTUVWXYZ", min_size=5, max_size=5),
    st.lists(st.text(alphabet="0123456789abcdefXYZ.-:T ", max_size=12), max_size=8),
)
def test_fuzz_round_trip(token, values):
    s = NMEASentence.build(token, values)
    assert NMEASentence.parse(s.message()) == s


FIELD_VALUES = st.one_of(
    st.integers(),
    st.booleans(),
    st.binary(max_size=8),
    st.floats(allow_nan=False),
    st.text(alphabet="0123456789abcdefXYZ.-:T ", max_size=12),
)


def reference_field_text(value) -> str:
    """The documented field rule: booleans 1/0, bytes as hex, anything else str()."""
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, bytes):
        return value.hex()
    return str(value)


@settings(max_examples=examples(200), deadline=None)
@given(st.lists(FIELD_VALUES, max_size=10))
def test_build_formats_every_kind_of_value_by_the_field_rule(values):
    s = NMEASentence.build("$CCTXD", values)
    assert s.fields == ("$CCTXD", *map(reference_field_text, values))
    body = ",".join(s.fields)
    cs = 0
    for ch in body[1:]:
        cs ^= ord(ch)
    assert s.message() == f"{body}*{cs:02X}"


@pytest.mark.parametrize("bad", ["a*b", "a\rb", "a\nb", "*"])
def test_build_refuses_reserved_characters_in_any_field(bad):
    with pytest.raises(NMEAFormatError, match="reserved"):
        NMEASentence.build("$CCTXD", [1, bad, 2])


@settings(max_examples=examples(200), deadline=None)
@given(st.text(alphabet=st.characters(max_codepoint=127), max_size=300))
def test_checksum_is_the_xor_of_every_character(body):
    expected = 0
    for ch in body:
        expected ^= ord(ch)
    assert checksum(body) == expected


@pytest.mark.parametrize(
    "line, start, stop",
    [("$CCCYC,0,1,2,x,1,1", 2, 7), ("$CCCYC,0,1,2", 2, 7), ("$CCCYC,0,1,2,3.5,1", 1, 5)],
)
def test_as_ints_gives_the_error_of_the_first_bad_field(line, start, stop):
    sentence = NMEASentence.parse(line)
    with pytest.raises(NMEAFormatError) as expected:
        [sentence.as_int(i) for i in range(start, stop)]
    with pytest.raises(
        NMEAFormatError, match=str(expected.value).replace("$", r"\$").replace("*", r"\*")
    ):
        sentence.as_ints(start, stop)


def test_as_ints_and_message():
    sentence = NMEASentence.parse("$CCCYC,0,1,2,0,1,1")
    assert sentence.as_ints(1, 7) == [0, 1, 2, 0, 1, 1] and sentence.as_ints(5, 5) == []
    assert sentence.message() == sentence.message() == "$CCCYC,0,1,2,0,1,1*5A"  # spec example
    assert sentence == NMEASentence.parse("$CCCYC,0,1,2,0,1,1*5A")
    assert hash(sentence) == hash(NMEASentence(sentence.fields))


@pytest.mark.parametrize(
    "field, low, high, ok",
    [
        ("5", 0, 8, True),
        ("9", 0, 8, False),
        ("-1", 0, None, False),
        ("40000000", None, 8, False),
        ("9" * 30, 0, 2**31, False),
        ("0", 0, 0, True),
    ],
)
def test_as_int_range_checks(field, low, high, ok):
    sentence = NMEASentence.parse(f"$CACYC,{field}")
    if ok:
        assert sentence.as_int(1, low, high) == int(field)
    else:
        with pytest.raises(NMEAFormatError, match="out of range"):
            sentence.as_int(1, low, high)


@pytest.mark.parametrize("field", ["nan", "inf", "-0.5", "31"])
def test_as_float_range_refuses_nan_and_values_outside(field):
    with pytest.raises(NMEAFormatError, match="out of range"):
        NMEASentence.parse(f"$CAMPR,{field}").as_float(1, 0.0, 30.0)
    assert NMEASentence.parse("$CAMPR,1.5").as_float(1, 0.0, 30.0) == 1.5
