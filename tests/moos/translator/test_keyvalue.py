import logging
import math

import pytest

from pygoby.moos.translator import keyvalue
from pygoby.moos.translator.keyvalue import val_from_string


def test_serialize_flat_fields_in_declaration_order(msgs):
    report = msgs.BasicNodeReport(Name="unicorn", x=550, y=1023.5, heading=240, repeat=[1, -1])
    assert keyvalue.serialize(report) == "Name=unicorn,x=550,y=1023.5,heading=240,repeat={1,-1}"


def test_serialize_everything(full_test_msg):
    msg = full_test_msg
    assert keyvalue.serialize(msg) == (
        "double_default_optional=1.1,float_default_optional=2.2,int32_default_optional=3,"
        "int64_default_optional=-4,uint32_default_optional=5,uint64_default_optional=6,"
        "sint32_default_optional=-7,sint64_default_optional=8,fixed32_default_optional=9,"
        "fixed64_default_optional=10,sfixed32_default_optional=11,sfixed64_default_optional=-12,"
        "bool_default_optional=true,string_default_optional=abc123,"
        "bytes_default_optional=00112233aabbcc1234,enum_default_optional=ENUM_C,"
        "msg_default_optional_val=13.3,msg_default_optional_msg=090000000000002c40,"
        "double_default_required=15.1,float_default_required=16.2,int32_default_required=17,"
        "int64_default_required=-18,uint32_default_required=19,uint64_default_required=20,"
        "sint32_default_required=-21,sint64_default_required=22,fixed32_default_required=23,"
        "fixed64_default_required=24,sfixed32_default_required=25,sfixed64_default_required=-26,"
        "bool_default_required=true,string_default_required=abc123,"
        "bytes_default_required=00112233aabbcc1234,enum_default_required=ENUM_C,"
        "msg_default_required_val=27.3,msg_default_required_msg=090000000000003c40,"
        "double_default_repeat={29.1,44.1},float_default_repeat={30.2,45.2},"
        "int32_default_repeat={31,46},int64_default_repeat={-32,-47},uint32_default_repeat={33,48},"
        "uint64_default_repeat={34,49},sint32_default_repeat={-35,-50},"
        "sint64_default_repeat={36,51},fixed32_default_repeat={37,52},"
        "fixed64_default_repeat={38,53},sfixed32_default_repeat={39,54},"
        "sfixed64_default_repeat={-40,-55},bool_default_repeat={true,true},"
        "string_default_repeat={abc123,abc123},bytes_default_repeat={ffeedd12,00aabbcc},"
        "enum_default_repeat={ENUM_C,ENUM_C},msg_default_repeat_val={42.3,57.3},"
        "msg_default_repeat_msg={090000000000804540,090000000000004d40}"
    )


def test_round_trip_everything(msgs, full_test_msg):
    msg = full_test_msg
    out = msgs.TestMsg()
    keyvalue.parse(keyvalue.serialize(msg), out)
    assert out.SerializeToString() == msg.SerializeToString()


def test_submessage_prints_unset_subfields_as_defaults(msgs):
    msg = msgs.TestMsg()
    msg.msg_default_optional.msg.sval = "Hi"
    assert keyvalue.serialize(msg) == "msg_default_optional_val=0,msg_default_optional_msg=12024869"


def test_parse_lower_cases_string_values(msgs):
    out = msgs.BasicNodeReport()
    keyvalue.parse("NAME=UniCorn,X=5", out)
    assert out.Name == "unicorn"
    assert out.x == 5


def test_parse_key_must_start_a_pair(msgs):
    out = msgs.BasicNodeReport()
    keyvalue.parse("foox=1,x=2", out)
    assert out.x == 2
    out = msgs.BasicNodeReport()
    keyvalue.parse("a=1, x=2", out)
    assert not out.HasField("x")


def test_parse_failures_give_nan_and_int_max(msgs):
    out = msgs.TestMsg()
    keyvalue.parse(
        "double_default_optional=abc,int32_default_optional=3.5,uint32_default_optional=-1", out
    )
    assert math.isnan(out.double_default_optional)
    assert out.int32_default_optional == 2147483647
    assert out.uint32_default_optional == 4294967295


def test_parse_enum_and_unknown_enum(msgs, caplog):
    out = msgs.TestMsg()
    with caplog.at_level(logging.WARNING):
        keyvalue.parse("enum_default_optional=enum_b,enum_default_required=ENUM_Z", out)
    assert out.enum_default_optional == 2
    assert not out.HasField("enum_default_required")
    assert "'enum_z' is not a value of enum pygoby.test.translator.Enum1" in caplog.text


def test_short_enum_round_trip_and_middle_removal(msgs):
    deploy = msgs.Deploy(deploy_mode=1, mode=1, modes=[1, 2])
    text = keyvalue.serialize(deploy, use_short_enum=True)
    # `mode_` is removed wherever it occurs first, not only as a prefix (goby3 behaviour).
    assert (
        text == "deploy_mode=RETURN,mode=DEPLOY_RETURN,modes={DEPLOY_MODE_RETURN,DEPLOY_MODE_STAY}"
    )
    out = msgs.Deploy()
    keyvalue.parse("deploy_mode=stay,modes={stay}", out, use_short_enum=True)
    assert out.deploy_mode == 2
    assert out.modes[:] == []  # MODES_STAY is not a value: skipped


def test_virtual_fields_appended(msgs, Entry):
    def Alg(name, out, primary, refs=()):
        return Entry.PublishSerializer.Algorithm(
            name=name, output_virtual_field=out, primary_field=primary, reference_field=refs
        )

    report = msgs.BasicNodeReport(x=550, y=1023.5, heading=-90)
    algorithms = [
        Alg("subtract", 105, 202, [3]),
        Alg("add", 104, 202, [3]),
        Alg("angle_0_360", 103, 201),
        Alg("to_upper", 103, 201),
    ]
    assert keyvalue.serialize(report, algorithms) == (
        "x=550,y=1023.5,heading=-90,angle_0_360+to_upper(heading)=270,add(x)=1573.5,subtract(x)=-473.5"
    )
    assert (
        keyvalue.serialize(msgs.BasicNodeReport(), [Alg("add", 104, 202, [3])])
        == ",add(x)=0.000000000000000"
    )


def test_unknown_keys_warn(msgs, caplog):
    out = msgs.BasicNodeReport()
    with caplog.at_level(logging.WARNING):
        keyvalue.parse("x=1,colour=red,junk,add(x)=3,repeat={1,2}", out, where="NODE")
    assert out.x == 1
    assert out.repeat[:] == [1, 2]
    assert (
        "NODE: unknown key(s) 'colour' ignored for pygoby.test.translator.BasicNodeReport"
        in caplog.text
    )
    assert "1 segment(s) without '=' ignored" in caplog.text
    caplog.clear()
    with caplog.at_level(logging.WARNING):
        keyvalue.parse("x=2,colour=blue,size=3", msgs.BasicNodeReport(), where="NODE")
    assert "'colour'" not in caplog.text  # reported once per variable and key
    assert "unknown key(s) 'size'" in caplog.text


@pytest.mark.parametrize(
    ("text", "key", "value"),
    [
        ("foo=1,bar={2,3,4,5},pig=3", "bar", "2,3,4,5"),
        ("foo=1,bar={2,3,4,5},pig=3", "pig", "3"),
        ("foo=1,o=2", "o", "2"),
        ("foo=1", "o", None),
        ("FOO=1", "foo", "1"),
        ("a={1,2", "a", "1,2"),
        ("a=", "a", ""),
    ],
)
def test_val_from_string(text, key, value):
    assert val_from_string(text, key) == value
