"""The translator's parse side fed arbitrary bytes as MOOS strings (issue 16 item 10).

A MOOS string is raw bytes (decoded with surrogate escapes): whatever they are, a create either
builds a message or raises TranslatorError, and one entry's bad value never costs another entry
its message, neither on a time tick nor on mail.
"""

from __future__ import annotations

import contextlib

import pytest
from google.protobuf import text_format
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pygoby.moos.protocol import decode_text
from pygoby.moos.translator import Technique, Translator, TranslatorError, TranslatorRunner
from tests.hypothesis_profiles import examples

SETTINGS = settings(
    max_examples=examples(300),
    deadline=None,
    suppress_health_check=[HealthCheck.function_scoped_fixture],
)
TEST_MSG = "pygoby.test.translator.TestMsg"
BNR = "pygoby.test.translator.BasicNodeReport"
PREFIXES = [
    b"",
    b"string_default_optional=",
    b"string_default_repeat={",
    b"Name=",
    b'@PB[pygoby.test.translator.TestMsg] string_default_optional: "',
    b'string_default_optional: "',
    b"msg_default_optional { val: 1 } ",
    b"enum_default_optional=",
    b"int32_default_optional=" + b"9" * 5000 + b",",  # beyond Python's int() digit limit
    b"9" * 5000 + b";",
]
moos_bytes = st.builds(lambda p, b: p + b, st.sampled_from(PREFIXES), st.binary(max_size=60))
# a MOOS string value as the client library hands it over, or the raw bytes themselves
moos_value = moos_bytes.flatmap(lambda raw: st.sampled_from([decode_text(raw), raw]))

BAD_CREATES = {
    Technique.TECHNIQUE_FORMAT: 'format: "%3%;%14%;%1%;%114%;%16%"',
    Technique.TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS: "",
    Technique.TECHNIQUE_PROTOBUF_TEXT_FORMAT: "",
    Technique.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT: "",
    Technique.TECHNIQUE_PROTOBUF_NATIVE_ENCODED: "",
    Technique.TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_ENCODED: "",
    Technique.TECHNIQUE_PROTOBUF_NATIVE_HEX: "",
    Technique.TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_HEX: "",
}


def two_timed_entries(Entry, loader, technique: Technique) -> Translator:
    """TestMsg from BAD (any technique) and BasicNodeReport from GOOD, both every second."""
    bad = text_format.Parse(
        f'protobuf_name: "{TEST_MSG}" trigger {{ type: TRIGGER_TIME period: 1 }} '
        f'create {{ technique: {technique.name} moos_var: "BAD" {BAD_CREATES[technique]} }} '
        f'publish {{ technique: TECHNIQUE_FORMAT moos_var: "BAD_OUT" format: "%14%" }}',
        Entry(),
    )
    good = text_format.Parse(
        f'protobuf_name: "{BNR}" trigger {{ type: TRIGGER_TIME period: 1 }} '
        'create { technique: TECHNIQUE_FORMAT moos_var: "GOOD" format: "%1%" }',
        Entry(),
    )
    return Translator([bad, good], loader.message_class)


@pytest.mark.parametrize("technique", list(BAD_CREATES), ids=lambda t: t.name)
def test_one_entry_bad_bytes_never_cost_the_other_its_message(Entry, loader, technique):
    translator = two_timed_entries(Entry, loader, technique)

    @SETTINGS
    @given(value=moos_value)
    def check(value):
        runner = TranslatorRunner(translator, start_time=0.0)
        runner.on_mail("GOOD", "alpha")
        runner.on_mail("BAD", value)
        created = runner.tick(1.0)  # raises nothing
        names = [msg.DESCRIPTOR.full_name for msg in created]
        assert BNR in names and created[names.index(BNR)].Name == "alpha"
        for msg in created:  # whatever was built is valid and can be published
            msg.SerializePartialToString()  # required fields may stay unset, as upstream
            translator.publish(msg)

    check()


@SETTINGS
@given(value=moos_value, trigger=st.sampled_from(["BAD", "GOOD"]))
def test_mail_triggered_creates_raise_only_translator_errors(Entry, loader, value, trigger):
    entry = text_format.Parse(
        f'protobuf_name: "{TEST_MSG}" trigger {{ moos_var: "{trigger}" mandatory_content: "a" }} '
        'create { technique: TECHNIQUE_FORMAT moos_var: "BAD" format: "%14%" }',
        Entry(),
    )
    runner = TranslatorRunner(Translator([entry], loader.message_class), start_time=0.0)
    runner.on_mail("GOOD", "a")
    for msg in runner.on_mail("BAD", value):
        msg.SerializePartialToString()  # required fields may stay unset, as upstream


@SETTINGS
@given(value=moos_value)
def test_multiplexed_bytes_raise_only_translator_errors(Entry, loader, value):
    entry = text_format.Parse(
        f'protobuf_name: "{TEST_MSG}" '
        'publish { technique: TECHNIQUE_FORMAT moos_var: "OUT" format: "%14%" }',
        Entry(),
    )
    runner = TranslatorRunner(Translator([entry], loader.message_class), start_time=0.0)
    for technique in Technique:
        with contextlib.suppress(TranslatorError):
            runner.on_multiplex(value, technique)
