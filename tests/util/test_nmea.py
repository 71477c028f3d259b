"""NMEA parse/print with checksums, against the spec's computed examples (acomms.md §7.1)."""

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.util.errors import NMEAChecksumError, NMEAError, NMEAFormatError
from pygoby.util.nmea import (
    NMEASentence,
    checksum,
    parse_int,
    parse_ints,
    printed,
    with_checksum,
    with_checksum_of_parts,
)

SPEC_EXAMPLES = [
    "$CCCFG,SRC,1*31", "$CCCYC,0,1,2,0,1,1*5A", "$CCTMS,2019-12-02T03:02:37Z,0*7A",
    "$CCCFG,CST,1*37", "$CCCFG,REV,1*32", "$CCCFG,RXP,1*29", "$CCCFG,ALL,0*33",
    "$CCMSC,1,1,0*41", "$CCCFQ,SRC*3A", "$CCTMQ,0*54", "$CCCFQ,TOP*33", "$CCCFQ,ALL*39",
    "$CADRQ,120000,1,2,1,32,1*44", "$CCTXD,1,2,1,0102030405*7B",
    "$CARXD,1,2,1,1,0102030405*62", "$CCTXD,1,2,1,*7A", "$CACYC,0,1,2,0,1,1*58",
    "$CAACK,2,1,1,1*48", "$CCMPC,1,2*5D",
]  # fmt: skip


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


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=80))
def test_fuzz_parse_only_raises_nmea_errors(text):
    try:
        sentence = NMEASentence.parse(text)
    except NMEAError:
        return
    assert NMEASentence.parse(sentence.message()) == sentence


@settings(max_examples=200, deadline=None)
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


@settings(max_examples=200, deadline=None)
@given(st.lists(FIELD_VALUES, max_size=10))
def test_build_formats_every_kind_of_value_by_the_field_rule(values):
    s = NMEASentence.build("$CCTXD", values)
    assert s.fields == ("$CCTXD", *map(reference_field_text, values))
    body = ",".join(s.fields)
    cs = 0
    for ch in body[1:]:
        cs ^= ord(ch)
    assert s.message() == f"{body}*{cs:02X}"


@settings(max_examples=200, deadline=None)
@given(
    st.sampled_from(["$CCTXD", "!AIVDM", "$CA", " $CARXD", "$CAöXD", "CCCFG"]),
    st.lists(st.text(alphabet=st.characters(max_codepoint=300), max_size=6), max_size=6),
)
def test_a_printed_text_parses_to_what_parsing_it_gives(token, texts):
    """`printed` remembers a text so that parsing it needs no work: the result (or the error)
    must be exactly what parsing the text from scratch gives, whatever the fields (commas,
    reserved characters, non-ASCII, a bad token, surrounding spaces)."""
    sentence = NMEASentence((token, *texts))
    try:
        text = with_checksum(",".join(sentence.fields))
    except UnicodeEncodeError:  # (a checksum is only defined for ASCII)
        with pytest.raises(UnicodeEncodeError):
            printed(sentence)
        return
    assert printed(sentence) == text
    try:  # (the same line with its terminator: not the printed text, so parsed from scratch)
        expected = NMEASentence.parse(text + "\r\n")
    except NMEAError as exc:
        with pytest.raises(type(exc)):
            NMEASentence.parse(text)
        return
    assert NMEASentence.parse(text) == expected
    assert NMEASentence.parse(text) == expected  # (once more: now from the parse memory)


def test_a_sentence_of_parts_is_the_sentence_of_its_fields():
    tail = ("0", "1000", "-15", "0.0")
    tail_text = ",".join(tail)
    sentence = NMEASentence.of_parts(
        ("$CACST", "1", "221523.4567"), tail, tail_text, checksum(tail_text)
    )
    whole = NMEASentence(("$CACST", "1", "221523.4567", *tail))
    assert sentence == whole and sentence.message() == whole.message()
    assert NMEASentence.parse(printed(sentence)) is sentence


@pytest.mark.parametrize("bad", ["a*b", "a\rb", "a\nb", "*"])
def test_build_refuses_reserved_characters_in_any_field(bad):
    with pytest.raises(NMEAFormatError, match="reserved"):
        NMEASentence.build("$CCTXD", [1, bad, 2])


@settings(max_examples=200, deadline=None)
@given(st.text(alphabet=st.characters(max_codepoint=127), max_size=300))
def test_checksum_is_the_xor_of_every_character(body):
    expected = 0
    for ch in body:
        expected ^= ord(ch)
    assert checksum(body) == expected


@settings(max_examples=200, deadline=None)
@given(
    st.text(alphabet=st.characters(min_codepoint=32, max_codepoint=126), max_size=60),
    st.text(alphabet=st.characters(min_codepoint=32, max_codepoint=126), max_size=200),
)
def test_checksum_of_parts_is_the_checksum_of_the_whole(head, tail):
    head = "$" + head
    assert with_checksum_of_parts(head, tail, checksum(tail)) == with_checksum(head + tail)


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


def test_as_ints_and_the_remembered_message():
    sentence = NMEASentence.parse("$CCCYC,0,1,2,0,1,1")
    assert sentence.as_ints(1, 7) == [0, 1, 2, 0, 1, 1] and sentence.as_ints(5, 5) == []
    assert sentence.message() == sentence.message() == "$CCCYC,0,1,2,0,1,1*5A"  # spec example
    assert sentence == NMEASentence.parse("$CCCYC,0,1,2,0,1,1*5A")  # the kept text is no field
    assert hash(sentence) == hash(NMEASentence(sentence.fields))


def test_a_recurring_line_parses_the_same_and_a_bad_one_fails_every_time():
    first = NMEASentence.parse("$CARXP,0*44\r\n")
    assert NMEASentence.parse("$CARXP,0*44\r\n") == first == NMEASentence.parse(" $CARXP,0*44")
    assert first.fields == ("$CARXP", "0")
    for _ in range(3):
        with pytest.raises(NMEAChecksumError):
            NMEASentence.parse("$CARXP,0*45")


INT_TEXTS = st.one_of(
    st.integers(-(10**12), 10**12).map(str),
    st.sampled_from(["0", "-0", "+5", "007", " 3 ", "1_000", "٣", "", "x", "1.5", "0x10"]),
    st.text(max_size=6),
)


@settings(max_examples=200, deadline=None)
@given(st.lists(INT_TEXTS, max_size=8))
def test_parse_int_and_parse_ints_are_int_with_a_memory(texts):
    def reference(text):
        try:
            return int(text)
        except ValueError:
            return ValueError

    def ours(text):
        try:
            return parse_int(text)
        except ValueError:
            return ValueError

    for _ in range(2):  # the second time through the memory
        assert [ours(t) for t in texts] == [reference(t) for t in texts]
        expected = [reference(t) for t in texts]
        if ValueError in expected:
            with pytest.raises(ValueError):
                parse_ints(texts)
        else:
            assert parse_ints(texts) == expected
