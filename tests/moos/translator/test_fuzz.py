"""Every parse direction fed with arbitrary input: either a message or a TranslatorError,
never another exception, and a failed create never yields a message."""

import contextlib

import pytest
from google.protobuf import text_format
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pygoby.moos.translator import (
    Technique,
    Translator,
    TranslatorError,
    keyvalue,
    parse_protobuf,
    serialize_protobuf,
)
from pygoby.moos.translator import format as fmt
from pygoby.moos.translator.keyvalue import val_from_string
from tests.hypothesis_profiles import examples

SETTINGS = settings(
    max_examples=examples(200),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
TEST_MSG = "pygoby.test.translator.TestMsg"

# Text built from the characters the formats care about, plus anything else.
format_alphabet = st.sampled_from(list("0123456789abcdeABCDE=,{}%:.;-+ _xyn\x00é\n\"'\\"))
structured_text = st.lists(format_alphabet, max_size=60).map("".join)
any_text = st.one_of(st.text(max_size=80), structured_text)
# Binary strings (decoded with surrogate escapes) after keys that land in string fields.
binary_after_key = st.builds(
    lambda key, tail: key + tail,
    st.sampled_from([b"", b"string_default_optional=", b"string_default_repeat={", b"x=1,"]),
    st.binary(max_size=40),
)
any_value = st.one_of(any_text, binary_after_key, st.floats(allow_nan=True))

PARSE_FORMATS = [
    "%1%",
    "%101%",
    "%116%",
    "x=%3%,y=%4%;%114%",
    "em0.val=%117.0:1%,u=%106.1%,e=%37:2:3%,%15%|%17%",
    "%113.2%/%2%/%16%/%13%/%35%",
]


@pytest.mark.parametrize("technique", [1, 2, 5, 6, 7, 8])
def test_protobuf_techniques_never_crash(msgs, technique):
    @SETTINGS
    @given(value=st.one_of(any_text, st.binary(max_size=80)))
    def check(value):
        out = msgs.TestMsg(int32_default_optional=7)
        before = out.SerializePartialToString()
        try:
            parse_protobuf(value, out, technique)
        except TranslatorError:
            assert out.SerializePartialToString() == before  # untouched on failure

    check()


@SETTINGS
@given(text=any_text)
def test_keyvalue_parse_never_crashes(msgs, text):
    with contextlib.suppress(TranslatorError):
        keyvalue.parse(text, msgs.TestMsg())


@SETTINGS
@given(text=any_text, format_string=st.sampled_from(PARSE_FORMATS))
def test_format_parse_never_crashes(msgs, text, format_string):
    with contextlib.suppress(TranslatorError):
        fmt.parse(text, msgs.TestMsg(), format_string, repeated_delimiter=",;")


@SETTINGS
@given(text=any_text, key=st.sampled_from(["a", "o", "x", "foo", "repeat"]))
def test_val_from_string_never_crashes(text, key):
    value = val_from_string(text, key)
    assert value is None or isinstance(value, str)


@SETTINGS
@given(format_string=any_text)
def test_arbitrary_publish_formats_are_config_errors_or_render(msgs, full_test_msg, format_string):
    try:
        fmt.check_serialize_format(msgs.TestMsg.DESCRIPTOR, format_string)
    except TranslatorError:
        return
    assert isinstance(fmt.serialize(full_test_msg, format_string), str)


@SETTINGS
@given(format_string=any_text, text=any_text)
def test_arbitrary_create_formats_are_config_errors_or_parse(msgs, format_string, text):
    try:
        fmt.check_parse_format(msgs.TestMsg.DESCRIPTOR, format_string)
    except TranslatorError:
        return
    with contextlib.suppress(TranslatorError):
        fmt.parse(text, msgs.TestMsg(), format_string)


@pytest.fixture(scope="module")
def all_techniques_translator(loader, Entry):
    e = text_format.Parse(
        f"""protobuf_name: "{TEST_MSG}"
        create {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "KV" }}
        create {{ technique: TECHNIQUE_FORMAT moos_var: "F" format: "{PARSE_FORMATS[4]}" }}
        create {{ technique: TECHNIQUE_FORMAT moos_var: "G" format: "%14%;%1%"
                  algorithm {{ name: "angle_0_360" primary_field: 1 }}
                  algorithm {{ name: "to_upper" primary_field: 14 }} }}
        create {{ technique: TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT moos_var: "PB" }}""",
        Entry(),
    )
    e.create.insert(0, e.create[3])  # the prefixed create first, so the others merge into it
    del e.create[4]
    return Translator([e], loader.message_class)


@SETTINGS
@given(
    kv=any_value,
    f=any_value,
    g=any_value,
    pb=st.one_of(st.just(""), st.just(f"@PB[{TEST_MSG}] int32_default_optional: 1"), any_value),
)
def test_create_is_all_or_nothing(all_techniques_translator, kv, f, g, pb):
    try:
        msg = all_techniques_translator.create(TEST_MSG, {"KV": kv, "F": f, "G": g, "PB": pb})
    except TranslatorError:
        return
    assert msg.DESCRIPTOR.full_name == TEST_MSG
    # Whatever was built can be published in every technique without error.
    for technique in Technique:
        if technique not in (
            Technique.TECHNIQUE_FORMAT,
            Technique.TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS,
        ):
            serialize_protobuf(msg, technique)
    keyvalue.serialize(msg)
