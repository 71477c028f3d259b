from google.protobuf import descriptor_pb2

from pygoby.moos.translator.textformat import message_text
from pygoby.protobuf.cpp_text import c_escape


def test_cpp_single_line_example_from_spec():
    field = descriptor_pb2.FieldDescriptorProto(name='x"y', number=3)
    field.options.packed = True
    assert message_text(field) == 'name: "x\\"y" number: 3 options { packed: true } '


def test_empty_message_is_empty_string(msgs):
    assert message_text(msgs.BasicNodeReport()) == ""


def test_fields_in_number_order_with_trailing_space(msgs):
    report = msgs.BasicNodeReport(Name="unicorn", x=550, y=1023.5, heading=240, repeat=[1, -1])
    assert (
        message_text(report)
        == 'Name: "unicorn" y: 1023.5 repeat: 1 repeat: -1 heading: 240 x: 550 '
    )


def test_doubles_use_15_then_17_digits(msgs):
    report = msgs.BasicNodeReport(x=0.1 + 0.7, y=-0.0, speed=1e20)
    assert message_text(report) == "y: -0 speed: 1e+20 x: 0.79999999999999993 "


def test_escapes_and_octal():
    assert c_escape(b"a\nb\r\t\"'\\\x01\xff ") == "a\\nb\\r\\t\\\"\\'\\\\\\001\\377 "


def test_nested_and_enum_and_bytes(msgs):
    msg = msgs.TestMsg(enum_default_optional=2, bytes_default_optional=b"\x00\xff")
    msg.msg_default_optional.msg.val = 14
    msg.msg_default_repeat.add()
    assert message_text(msg) == (
        'bytes_default_optional: "\\000\\377" enum_default_optional: ENUM_B '
        "msg_default_optional { msg { val: 14 } } msg_default_repeat { } "
    )


def test_string_with_utf8_is_octal_escaped(msgs):
    assert message_text(msgs.BasicNodeReport(Name="é")) == 'Name: "\\303\\251" '
