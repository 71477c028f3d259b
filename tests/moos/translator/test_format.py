import logging
import math

import pytest

from pygoby.moos.translator import TranslatorConfigError
from pygoby.moos.translator import format as fmt
from pygoby.moos.translator.algorithms import AlgorithmRegistry
from pygoby.moos.translator.boostformat import FloatArg, IntArg, boost_format, parse_format

REPEAT = [1, -1, 2, -2, 3, -3, 4, -4, 5, -5, 6, -6]
NODE_FORMAT = "NAME=%1%,X=%202%,Y=%3%,HEADING=%201%,REPEAT={%10%}"
INDEXED = ",REPEAT={" + ",".join(f"%10.{i}%" for i in range(12)) + "}"


@pytest.fixture
def report(msgs):
    return msgs.BasicNodeReport(Name="unicorn", x=550, y=1023.5, heading=240, repeat=REPEAT)


def test_serialize_node_report(report):
    assert fmt.serialize(report, NODE_FORMAT + INDEXED) == (
        "NAME=unicorn,X=550,Y=1023.5,HEADING=240,REPEAT={1,-1,2,-2,3,-3,4,-4,5,-5,6,-6},"
        "REPEAT={1,-1,2,-2,3,-3,4,-4,5,-5,6,-6}"
    )


def test_parse_node_report_round_trip(report, msgs):
    out = msgs.BasicNodeReport()
    fmt.parse(fmt.serialize(report, NODE_FORMAT + INDEXED), out, NODE_FORMAT + INDEXED)
    assert out.SerializeToString() == report.SerializeToString()


def test_unset_fields_render_defaults_and_missing_numbers_render_unknown(msgs):
    assert fmt.serialize(msgs.BasicNodeReport(), "%1%|%3%|%10%|%5%|%203%") == "|0||unknown|"


def test_first_declared_field_counts_for_max_field_number(msgs):
    # Name (declared first) has the largest number here; goby3 would render it empty (Q9).
    msg = msgs.Deploy(deploy_mode=1, destination=3)
    assert fmt.serialize(msg, "%1%,%4%") == "DEPLOY_MODE_RETURN,3"


def test_submessage_directives(msgs):
    msg = msgs.TestMsg()
    msg.msg_default_optional.val = 19.998
    assert fmt.serialize(msg, "em.val=%17:1%") == "em.val=19.998"
    out = msgs.TestMsg()
    fmt.parse("em.val=19.998", out, "em.val=%17:1%")
    assert out.SerializePartialToString() == msg.SerializePartialToString()


SUB_FORMAT = (
    "em0.val=%117.0:1%,1uint64=%106.1%,0uint64=%106.0%.2uint64=%106.2%:em1.val=%117.1:1%,"
    "dbl0=%101.0%,dbl1=%101.1%,dbl2=%101.2%,dbl3=%101.3%,em0.em1.val=%37:2:1%"
)


def test_repeated_submessages_and_past_the_end(msgs):
    msg = msgs.TestMsg()
    msg.msg_default_repeat.add().val = 21.123
    msg.msg_default_repeat.add().val = 100.5
    msg.msg_default_required.msg.val = 45
    msg.uint64_default_repeat.extend([0, 100, 200])
    text = fmt.serialize(msg, SUB_FORMAT)
    assert text == (
        "em0.val=21.123,1uint64=100,0uint64=0.2uint64=200:em1.val=100.5,dbl0=nan,dbl1=nan,"
        "dbl2=nan,dbl3=nan,em0.em1.val=45"
    )
    out = msgs.TestMsg()
    fmt.parse(text, out, SUB_FORMAT)
    msg.double_default_repeat.extend([math.nan] * 4)
    assert out.SerializePartialToString() == msg.SerializePartialToString()


def test_past_the_end_sentinels(msgs):
    msg = msgs.TestMsg()
    assert fmt.serialize(
        msg, "%103.0% %104.0% %105.0% %106.0% %102.0% %113.0% %114.0%|%116.0%"
    ) == ("2147483647 9223372036854775807 4294967295 18446744073709551615 nan false |ENUM_A")


def test_value_rendering(msgs):
    msg = msgs.TestMsg(
        bool_default_optional=True,
        bytes_default_optional=b"\x01\xab",
        enum_default_optional=2,
        float_default_optional=1.0 / 3,
        double_default_optional=1e-05,
    )
    msg.msg_default_optional.val = 1
    assert fmt.serialize(msg, "%13% %15% %16% %2% %1% %17%") == (
        "true 01ab ENUM_B 0.333333 1e-05 09000000000000f03f"
    )


def test_repeated_delimiter_whole_string_on_output_any_char_on_input(msgs):
    msg = msgs.BasicNodeReport(repeat=[1, 2, 3])
    assert fmt.serialize(msg, "%10%", repeated_delimiter=";:") == "1;:2;:3"
    out = msgs.BasicNodeReport()
    fmt.parse("4;5:6", out, "%10%", repeated_delimiter=";:")
    assert out.repeat[:] == [4, 5, 6]


def test_printf_specs_and_forced_precision(msgs):
    msg = msgs.TestMsg(
        double_default_optional=1.23456789,
        int32_default_optional=42,
        int64_default_optional=-1,
        string_default_optional="ab",
    )
    assert fmt.serialize(msg, "%1$.3f|%3$05d|%3$x|%|3$8||%1$10.2f|%14$-4s|%4$x") == (
        "1.234567890000000|00042|2a|      42|1.234567890000000|ab  |ffffffffffffffff"
    )
    assert fmt.serialize(msg, "100%% %3%") == "100% 42"


def test_moos_var_names_can_be_formats(report):
    assert fmt.serialize(report, "NODE_REPORT_%1%") == "NODE_REPORT_unicorn"


def test_parse_is_case_insensitive_on_literals_and_keeps_value_case(msgs):
    out = msgs.BasicNodeReport()
    fmt.parse("name=UNICORN,x=5", out, "NAME=%1%,X=%202%")
    assert out.Name == "UNICORN"
    assert out.x == 5


def test_parse_empty_value_gives_nan_and_int_max(msgs):
    out = msgs.TestMsg()
    fmt.parse("", out, "%1%")
    assert math.isnan(out.double_default_optional)
    out = msgs.TestMsg()
    fmt.parse("", out, "%3%")
    assert out.int32_default_optional == 2147483647


def test_parse_repeated_enums_append(msgs):
    out = msgs.TestMsg()
    fmt.parse("ENUM_A,enum_c", out, "%116%")
    assert out.enum_default_repeat[:] == [1, 3]


def test_parse_short_enum(msgs):
    out = msgs.Deploy()
    fmt.parse("stay", out, "%1%", use_short_enum=True)
    assert out.deploy_mode == 2


def test_parse_bytes_as_text_and_submessage_hex(msgs):
    # goby3's FORMAT create puts the text itself in a bytes field (its publish and key=value
    # create use hex); an embedded message is hex of its encoding.
    out = msgs.TestMsg()
    fmt.parse("01ab;09000000000000f03f;é", out, "%15%;%17%;%115%")
    assert out.bytes_default_optional == b"01ab"
    assert out.msg_default_optional.val == 1
    assert out.bytes_default_repeat[:] == ["é".encode()]
    assert fmt.serialize(out, "%15%") == "30316162"


def test_a_literal_missing_from_the_input_skips_nothing_and_parsing_goes_on(msgs):
    # goby3's scanner: a format character that does not occur leaves the input as it is; one
    # that occurs drops the input through it ('e' of "hello" -> "llo").
    out = msgs.BasicNodeReport()
    mismatch = fmt.parse("hello", out, "NAME=%1%")
    assert out.Name == "llo"
    assert mismatch == fmt.FormatMismatch("n", 0, 0)
    assert str(mismatch) == "no 'n' (format character 0) in the input after character 0"


def test_an_empty_input_fills_fields_as_goby3_leaves_them(msgs):
    # goby3's as<T>("") gives NaN for floating point and the type's maximum for integers;
    # a repeated index pads with the field's default value.
    out = msgs.BasicNodeReport()
    mismatch = fmt.parse("", out, "depth:=%6%;t=%200%;r=%10.2%")
    assert math.isnan(out.depth)
    assert math.isnan(out.time)
    assert out.repeat[:] == [0, 0, 2**31 - 1]
    assert mismatch == fmt.FormatMismatch("d", 0, 0)


def test_the_first_missing_literal_is_reported_after_what_matched(msgs):
    out = msgs.BasicNodeReport()
    mismatch = fmt.parse("x=550,y", out, "x=%202%,y=%3%;n=%1%")
    assert out.x == 550
    assert math.isnan(out.y)  # "" after the last match
    assert out.Name == ""
    assert mismatch == fmt.FormatMismatch("=", 9, 7)


def test_a_whole_match_reports_nothing(msgs):
    assert fmt.parse("x=550,y=3", msgs.BasicNodeReport(), "x=%202%,y=%3%") is None


def test_adjacent_directives_read_the_same_input(msgs):
    # goby3: the second directive's value starts where the first one's did (nothing is
    # consumed between them).
    out = msgs.BasicNodeReport()
    assert fmt.parse("12", out, "%202%%3%") is None
    assert (out.x, out.y) == (12, 12)


def test_parse_unknown_enum_warns(msgs, caplog):
    out = msgs.TestMsg()
    with caplog.at_level(logging.WARNING):
        fmt.parse("ENUM_Q", out, "%16%")
    assert not out.HasField("enum_default_optional")
    assert "is not a value of enum" in caplog.text


@pytest.mark.parametrize(
    ("format_string", "message"),
    [
        ("%99%", "Bad field: 99"),
        ("%x%", "Bad specifier: x"),
        ("a%%b%1%", "empty directive"),
        ("%3:1%", "Invalid ':' syntax"),
        ("%117:1%", "Invalid '.' syntax"),
        ("%1", "unterminated"),
    ],
)
def test_bad_parse_formats_rejected_up_front(msgs, format_string, message):
    with pytest.raises(TranslatorConfigError, match=message):
        fmt.check_parse_format(msgs.TestMsg.DESCRIPTOR, format_string)


@pytest.mark.parametrize(
    ("format_string", "message"),
    [
        ("%3:1%", "Invalid ':' syntax"),
        ("%117:1%", "Invalid '.' syntax"),
        ("%1$q", "bad directive"),
        ("%1% %s", "mixes positional"),
        ("100%", "bad directive"),
    ],
)
def test_bad_serialize_formats_rejected_up_front(msgs, format_string, message):
    with pytest.raises(TranslatorConfigError, match=message):
        fmt.check_serialize_format(msgs.TestMsg.DESCRIPTOR, format_string)


def test_boost_format_subset():
    items = parse_format("%1%-%2$+d-%|3$6|-%2$#x-%3$e-%4%")
    assert boost_format(items, ["a", IntArg(255, 32), FloatArg(1.5, 15)]) == (
        "a-+255-   1.5-0xff-1.500000000000000e+00-"
    )
    assert boost_format(parse_format("%s,%d"), ["x", IntArg(-3, 32)]) == "x,-3"
    assert boost_format(parse_format("%1$5.1s|"), ["hello"]) == "    h|"


def test_an_integer_beyond_pythons_digit_limit_is_one_warning_and_the_maximum(msgs, caplog):
    # goby3's as<int32> of an out-of-range integer gives INT32_MAX; Python's int() refuses
    # strings of more than 4300 digits, which must not escape as a traceback.
    out = msgs.BasicNodeReport()
    with caplog.at_level(logging.WARNING):
        assert fmt.parse("9" * 5000 + ";-" + "9" * 5000, out, "%10.0%;%10.1%") is None
    assert out.repeat[:] == [2**31 - 1, 2**31 - 1]
    assert [r.getMessage() for r in caplog.records] == [
        "field repeat: a 5000-digit integer is out of range; set to the int32 maximum as goby3 "
        "does",
        "field repeat: a 5001-digit integer is out of range; set to the int32 maximum as goby3 "
        "does",
    ]


@pytest.mark.parametrize(
    ("directive", "printed"),
    [
        # An algorithm's output is a string to Boost.Format: the conversion character and a
        # precision do not change it (goby3 prints %101$.6lf of utm_x2lon in full) ...
        ("%101%", "-70.94887000425"),
        ("%101$.6lf", "-70.94887000425"),
        ("%101$lf", "-70.94887000425"),
        ("%101$.3f", "-70.94887000425"),
        ("%101$e", "-70.94887000425"),
        ("%101$.2E", "-70.94887000425"),
        ("%101$g", "-70.94887000425"),
        ("%101$d", "-70.94887000425"),
        ("%101$x", "-70.94887000425"),
        ("%101$s", "-70.94887000425"),
        ("%|101$|", "-70.94887000425"),
        ("%|101$.3f|", "-70.94887000425"),
        ("%101$+f", "-70.94887000425"),
        ("%100$+f", "42.352720906492"),  # showpos does nothing to a string
        # ... except `s` with a precision (at most that many characters) and `c` (one)
        ("%101$.3s", "-70"),
        ("%|101$.2s|", "-7"),
        ("%101$.0s", ""),
        ("%101$c", "-"),
        ("%100$C", "4"),
        # width and the padding flags apply
        ("%101$20f", "     -70.94887000425"),
        ("%101$-20s|", "-70.94887000425     |"),
        ("%101$020f", "00000-70.94887000425"),
        ("%101$-020f|", "-70.94887000425     |"),
        ("%100$ f", " 42.352720906492"),
        ("%101$ f", "-70.94887000425"),
        ("%100$+ f", "42.352720906492"),
        ("%101$10f", "-70.94887000425"),  # already wider than 10
        # a number field printed with s/c is cut the same way
        ("%202$.2s", "10"),
        ("%202$c", "1"),
        ("%202$5.2s", "   10"),
    ],
)
def test_printf_directives_on_algorithm_outputs_print_as_goby3(msgs, Entry, directive, printed):
    algorithm = Entry.PublishSerializer.Algorithm
    algorithms = [
        algorithm(
            name="utm_x2lon", output_virtual_field=101, primary_field=202, reference_field=[3]
        ),
        algorithm(
            name="utm_y2lat", output_virtual_field=100, primary_field=3, reference_field=[202]
        ),
    ]
    report = msgs.BasicNodeReport(x=100, y=300)
    registry = AlgorithmRegistry(42.35, -70.95)
    assert fmt.serialize(report, directive, algorithms=algorithms, registry=registry) == printed
