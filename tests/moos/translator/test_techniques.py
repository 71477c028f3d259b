import pytest

from pygoby.moos.translator import (
    Technique,
    TranslatorConfigError,
    TranslatorError,
    dynamic_parse,
    moos_technique_from_config,
    parse_for_moos,
    parse_protobuf,
    serialize_for_moos,
    serialize_protobuf,
)

T = Technique
NAME = "pygoby.test.translator.BasicNodeReport"


@pytest.fixture
def report(msgs):
    return msgs.BasicNodeReport(Name="unicorn", x=550, y=1023.5)


def test_text_format(report):
    assert serialize_protobuf(report, T.TECHNIQUE_PROTOBUF_TEXT_FORMAT) == (
        'Name: "unicorn" y: 1023.5 x: 550 '
    )


def test_prefixed_text(report, msgs):
    assert serialize_protobuf(report, T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT) == (
        f'@PB[{NAME}] Name: "unicorn" y: 1023.5 x: 550 '
    )
    assert serialize_protobuf(
        msgs.BasicNodeReport(), T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT
    ) == (f"@PB[{NAME}] ")


def test_native_hex_is_lowercase(msgs):
    assert (
        serialize_protobuf(msgs.BasicNodeReport(Name="\xff"), T.TECHNIQUE_PROTOBUF_NATIVE_HEX)
        == "0a02c3bf"
    )
    assert serialize_protobuf(
        msgs.BasicNodeReport(y=1), T.TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_HEX
    ) == (f"@PB[{NAME}] 19000000000000f03f")


def test_native_encoded_is_bytes(report):
    assert (
        serialize_protobuf(report, T.TECHNIQUE_PROTOBUF_NATIVE_ENCODED)
        == report.SerializeToString()
    )
    assert serialize_protobuf(report, T.TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_ENCODED) == (
        f"@PB[{NAME}] ".encode() + report.SerializeToString()
    )


@pytest.mark.parametrize("technique", [t for t in T if t not in (3, 4)])
def test_round_trip_every_protobuf_technique(technique, report, msgs):
    out = msgs.BasicNodeReport(speed=3)
    parse_protobuf(serialize_protobuf(report, technique), out, technique)
    assert out == report  # parsing replaces the whole message


def test_parse_hex_accepts_upper_case_and_odd_length(msgs):
    out = msgs.BasicNodeReport()
    parse_protobuf("19000000000000F03F", out, T.TECHNIQUE_PROTOBUF_NATIVE_HEX)
    assert out.y == 1.0


def test_prefixed_parsers_accept_bare_bodies(report, msgs):
    out = msgs.BasicNodeReport()
    parse_protobuf(
        'Name: "unicorn" y: 1023.5 x: 550', out, T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT
    )
    assert out == report


def test_prefixed_empty_body_clears(msgs):
    out = msgs.BasicNodeReport(x=1)
    parse_protobuf(f"@PB[{NAME}]", out, T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT)
    assert out == msgs.BasicNodeReport()


def test_prefixed_wrong_type_is_an_error(msgs):
    out = msgs.BasicNodeReport(x=1)
    with pytest.raises(
        TranslatorError,
        match="Expected: pygoby.test.translator.BasicNodeReport, received: other.Type",
    ):
        parse_protobuf("@PB[other.Type] x: 1", out, T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT)
    assert out.x == 1


def test_prefixed_without_bracket_is_an_error(msgs):
    with pytest.raises(TranslatorError, match="Incorrectly formatted"):
        parse_protobuf(
            "@PB[foo x: 1", msgs.BasicNodeReport(), T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT
        )


def test_bad_text_leaves_message_untouched(msgs):
    out = msgs.BasicNodeReport(x=7)
    with pytest.raises(TranslatorError, match="cannot parse"):
        parse_protobuf("x: 1 nonsense: {", out, T.TECHNIQUE_PROTOBUF_TEXT_FORMAT)
    assert out == msgs.BasicNodeReport(x=7)


def test_bad_binary_is_an_error(msgs):
    with pytest.raises(TranslatorError, match="cannot decode"):
        parse_protobuf(b"\xff\xff\xff", msgs.BasicNodeReport(), T.TECHNIQUE_PROTOBUF_NATIVE_ENCODED)


def test_dynamic_parse_uses_header_type(report, msgs):
    resolve = {NAME: msgs.BasicNodeReport}.__getitem__
    for technique in (
        T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT,
        T.TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_HEX,
        T.TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_ENCODED,
    ):
        assert dynamic_parse(serialize_protobuf(report, technique), resolve, technique) == report
    assert (
        dynamic_parse("@PB[unknown.Type] x: 1", resolve, T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT)
        is None
    )
    assert dynamic_parse('Name: "x"', resolve, T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT) is None
    assert dynamic_parse(f"@PB[{NAME}] x: 1", resolve, T.TECHNIQUE_PROTOBUF_TEXT_FORMAT) is None


def test_serialize_for_moos_default_is_prefixed_text(report, msgs):
    text = serialize_for_moos(report)
    assert text == f'@PB[{NAME}] Name: "unicorn" y: 1023.5 x: 550 '
    out = msgs.BasicNodeReport()
    parse_for_moos(text, out)
    assert out == report


def test_serialize_for_moos_rejects_csv_and_format(report):
    for technique in (T.TECHNIQUE_FORMAT, T.TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS):
        with pytest.raises(TranslatorConfigError):
            serialize_for_moos(report, technique)
        with pytest.raises(TranslatorConfigError):
            parse_for_moos("", report, technique)


class _Common:
    def __init__(self, **fields):
        self._fields = fields

    def HasField(self, name):
        return name in self._fields

    def __getattr__(self, name):
        return self._fields[name]


def test_moos_technique_selection():
    assert moos_technique_from_config(None) == T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT
    assert moos_technique_from_config(_Common()) == T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT
    assert moos_technique_from_config(_Common(use_binary_protobuf=True)) == (
        T.TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_ENCODED
    )
    assert moos_technique_from_config(_Common(use_binary_protobuf=False)) == (
        T.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT
    )
    assert (
        moos_technique_from_config(_Common(use_binary_protobuf=True, moos_parser_technique=6))
        == T.TECHNIQUE_PROTOBUF_NATIVE_HEX
    )
    with pytest.raises(TranslatorConfigError, match="Non-PROTOBUF"):
        moos_technique_from_config(_Common(moos_parser_technique=3))
