import logging
import math

import pytest
from google.protobuf import text_format

from pygoby.moos.translator import (
    ModemIdLookup,
    MoosValues,
    Post,
    Technique,
    Translator,
    TranslatorConfigError,
    TranslatorError,
    TranslatorRunner,
    post_for_moos,
    serialize_protobuf,
)
from pygoby.util.clock import VirtualClock

from .test_algorithms import LOOKUP

BNR = "pygoby.test.translator.BasicNodeReport"
TEST_MSG = "pygoby.test.translator.TestMsg"
REPEAT = [1, -1, 2, -2, 3, -3, 4, -4, 5, -5, 6, -6]


def entry(Entry, text):
    return text_format.Parse(text, Entry())


def one_in_one_out(Entry, loader, technique, name=TEST_MSG):
    e = Entry(protobuf_name=name)
    e.create.add(technique=technique, moos_var="TEST_MSG_1")
    e.publish.add(technique=technique, moos_var="TEST_MSG_1")
    return Translator([e], loader.message_class)


@pytest.mark.parametrize("technique", [1, 2, 3, 5, 6, 7, 8])
def test_one_in_one_out_round_trip(Entry, loader, full_test_msg, technique):
    translator = one_in_one_out(Entry, loader, technique)
    posts = translator.publish(full_test_msg)
    assert [p.var for p in posts] == ["TEST_MSG_1"]
    assert posts[0].source_aux == f"{TEST_MSG}:{Technique(technique).name}"
    if technique in (2, 8):
        assert isinstance(posts[0].value, bytes)
    out = translator.create(TEST_MSG, {p.var: p.value for p in posts})
    assert out.SerializeToString() == full_test_msg.SerializeToString()


def test_upstream_node_report_scenario(Entry, loader, msgs):
    node_format = "NAME=%1%,X=%202%,Y=%3%,HEADING=%201%,REPEAT={%10%}"
    e = entry(
        Entry,
        f"""protobuf_name: "{BNR}"
        create {{ technique: TECHNIQUE_FORMAT moos_var: "NAV_X" format: "%202%" }}
        create {{ technique: TECHNIQUE_FORMAT moos_var: "VEHICLE_NAME" format: "%1%"
                  algorithm {{ name: "to_lower" primary_field: 1 }} }}
        create {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "NAV_HEADING"
                  algorithm {{ name: "angle_0_360" primary_field: 201 }} }}
        create {{ technique: TECHNIQUE_FORMAT moos_var: "NAV_Y" format: "%3%" }}
        publish {{ technique: TECHNIQUE_FORMAT moos_var: "NODE_REPORT_FORMAT"
          format: "{node_format};LAT=%100%;LON=%101%;X+Y=%104%,X-Y=%105%"
          algorithm {{ name: "utm_x2lon" output_virtual_field: 101 primary_field: 202 reference_field: 3 }}
          algorithm {{ name: "utm_y2lat" output_virtual_field: 100 primary_field: 3 reference_field: 202 }}
          algorithm {{ name: "name2modem_id" output_virtual_field: 102 primary_field: 1 }}
          algorithm {{ name: "name2modem_id" output_virtual_field: 103 primary_field: 1 }}
          algorithm {{ name: "modem_id2type" output_virtual_field: 103 primary_field: 1 }}
          algorithm {{ name: "to_upper" output_virtual_field: 103 primary_field: 1 }}
          algorithm {{ name: "add" output_virtual_field: 104 primary_field: 202 reference_field: 3 }}
          algorithm {{ name: "subtract" output_virtual_field: 105 primary_field: 202 reference_field: 3 }}
        }}""",
    )
    key_value = e.publish.add()
    key_value.CopyFrom(e.publish[0])
    key_value.ClearField("format")
    key_value.technique = Technique.TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS
    key_value.moos_var = "NODE_REPORT_KEY_VALUE"
    translator = Translator(
        [e],
        loader.message_class,
        lat_origin=42.35,
        lon_origin=-70.95,
        modem_ids=ModemIdLookup.from_text(LOOKUP),
    )
    variables = {
        "NAV_X": 550.0,
        "NAV_Y": 1023.5,
        "NAV_HEADING": "heading=-120",
        "VEHICLE_NAME": "UNICORN",
    }
    out = translator.create(BNR, variables)
    expected = msgs.BasicNodeReport(Name="unicorn", x=550, y=1023.5, heading=240)
    assert out.SerializeToString() == expected.SerializeToString()

    # pyproj: (x, y) = (550, 1023.5) from origin (42.35, -70.95), zone 19, rounded to 12/11 decimals
    lat_text, lon_text = "42.359325790417", "-70.94360998891"
    posts = translator.publish(out)
    assert posts == [
        Post(
            "NODE_REPORT_FORMAT",
            f"NAME=unicorn,X=550,Y=1023.5,HEADING=240,REPEAT={{}};LAT={lat_text};LON={lon_text};"
            "X+Y=1573.5,X-Y=-473.5",
            f"{BNR}:TECHNIQUE_FORMAT",
        ),
        Post(
            "NODE_REPORT_KEY_VALUE",
            f"Name=unicorn,x=550,y=1023.5,heading=240,utm_y2lat(y)={lat_text},utm_x2lon(x)={lon_text},"
            "name2modem_id(Name)=3,name2modem_id+modem_id2type+to_upper(Name)=AUV,add(x)=1573.5,"
            "subtract(x)=-473.5",
            f"{BNR}:TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS",
        ),
    ]


def test_posts_sorted_by_variable_then_declaration(Entry, loader, msgs):
    e = entry(
        Entry,
        f"""protobuf_name: "{BNR}"
        publish {{ technique: TECHNIQUE_FORMAT moos_var: "Z_VAR" format: "%1%" }}
        publish {{ technique: TECHNIQUE_FORMAT moos_var: "A_VAR" format: "second %1%" }}
        publish {{ technique: TECHNIQUE_FORMAT moos_var: "A_VAR" format: "third" }}
        publish {{ technique: TECHNIQUE_FORMAT moos_var: "NAV_%1%" format: "%202%" }}
        publish {{ technique: TECHNIQUE_PROTOBUF_NATIVE_ENCODED moos_var: "B_BIN" }}
        publish {{ technique: TECHNIQUE_FORMAT moos_var: "B_TXT" format: "%1%" }}
        publish {{ technique: TECHNIQUE_PROTOBUF_NATIVE_HEX moos_var: "B_HEX" }}
        """,
    )
    translator = Translator([e], loader.message_class)
    report = msgs.BasicNodeReport(Name="7", x=1.5)
    aux = f"{BNR}:TECHNIQUE_FORMAT"
    assert translator.publish(report) == [
        Post("A_VAR", "second 7", aux),
        Post("A_VAR", "third", aux),
        Post("B_BIN", report.SerializeToString(), f"{BNR}:TECHNIQUE_PROTOBUF_NATIVE_ENCODED"),
        Post("B_HEX", "0a0137d10c000000000000f83f", f"{BNR}:TECHNIQUE_PROTOBUF_NATIVE_HEX"),
        Post("B_TXT", 7.0),  # decided per publish: not binary after a binary publish (Q6 fixed)
        Post("NAV_7", 1.5),
        Post("Z_VAR", 7.0),
    ]


def test_hex_of_digits_stays_a_string(Entry, loader, msgs):
    # goby3 posts any output that reads as a number as a MOOS double, hex included: "0802"
    # would arrive as 802 and no longer decode (the leading zero is gone). Hex stays a string.
    translator = one_in_one_out(Entry, loader, Technique.TECHNIQUE_PROTOBUF_NATIVE_HEX, BNR)
    (post,) = translator.publish(msgs.BasicNodeReport(repeat=[8]))
    assert post == Post("TEST_MSG_1", "5008", f"{BNR}:TECHNIQUE_PROTOBUF_NATIVE_HEX")
    deploy = "pygoby.test.translator.Deploy"
    translator = one_in_one_out(Entry, loader, Technique.TECHNIQUE_PROTOBUF_NATIVE_HEX, deploy)
    (post,) = translator.publish(msgs.Deploy(deploy_mode=2))
    assert post == Post("TEST_MSG_1", "0802", f"{deploy}:TECHNIQUE_PROTOBUF_NATIVE_HEX")


def test_numeric_text_format_output_is_never_a_double(Entry, loader, msgs):
    translator = one_in_one_out(Entry, loader, Technique.TECHNIQUE_PROTOBUF_TEXT_FORMAT, BNR)
    assert translator.publish(msgs.BasicNodeReport()) == [
        Post("TEST_MSG_1", "", f"{BNR}:TECHNIQUE_PROTOBUF_TEXT_FORMAT")
    ]


def test_protobuf_create_replaces_and_csv_format_merge(Entry, loader, msgs):
    e = entry(
        Entry,
        f"""protobuf_name: "{BNR}"
        create {{ technique: TECHNIQUE_FORMAT moos_var: "A" format: "%202%" }}
        create {{ technique: TECHNIQUE_PROTOBUF_TEXT_FORMAT moos_var: "B" }}
        create {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "C" }}
        create {{ technique: TECHNIQUE_FORMAT moos_var: "D" format: "%3%" }}
        """,
    )
    translator = Translator([e], loader.message_class)
    out = translator.create(BNR, {"A": 1.0, "B": "speed: 2 y: 9", "C": "heading=3", "D": "0.1"})
    assert out == msgs.BasicNodeReport(speed=2, heading=3, y=0.1)


def test_double_source_uses_17_digits(Entry, loader):
    e = entry(
        Entry,
        f'protobuf_name: "{BNR}" create {{ technique: TECHNIQUE_FORMAT moos_var: "V" format: "%1%" }}',
    )
    assert (
        Translator([e], loader.message_class).create(BNR, {"V": 0.1}).Name == "0.10000000000000001"
    )


def test_missing_variable_reads_as_empty(Entry, loader):
    e = entry(
        Entry,
        f'protobuf_name: "{BNR}" create {{ technique: TECHNIQUE_FORMAT moos_var: "V" format: "%202%" }}',
    )
    assert math.isnan(Translator([e], loader.message_class).create(BNR, {}).x)


def test_bad_input_creates_nothing(Entry, loader):
    e = entry(
        Entry,
        f"""protobuf_name: "{BNR}"
        create {{ technique: TECHNIQUE_FORMAT moos_var: "A" format: "X=%202%" }}
        create {{ technique: TECHNIQUE_PROTOBUF_TEXT_FORMAT moos_var: "B" }}""",
    )
    translator = Translator([e], loader.message_class)
    with pytest.raises(TranslatorError, match=f"{BNR} from B: cannot parse"):
        translator.create(BNR, {"A": "X=1", "B": "x: {"})


def test_a_partly_matching_format_input_still_creates_the_message(Entry, loader):
    # goby3 fills what the format could parse and creates the message (a vehicle whose DEPTH
    # was never posted still sends its status); the mismatch is reported to the caller.
    e = entry(
        Entry,
        f"""protobuf_name: "{BNR}"
        create {{ technique: TECHNIQUE_FORMAT moos_var: "A" format: "name=%1%" }}
        create {{ technique: TECHNIQUE_FORMAT moos_var: "DEPTH" format: "depth:=%6%" }}""",
    )
    mismatches = []
    msg = Translator([e], loader.message_class).create(BNR, {"A": "name=unicorn"}, mismatches)
    assert msg.Name == "unicorn"
    assert math.isnan(msg.depth)
    (mismatch,) = mismatches
    assert str(mismatch) == (
        f"{BNR} from DEPTH: input '' does not match format 'depth:=%6%': no 'd' (format "
        "character 0) in the input after character 0"
    )


def test_strict_format_keeps_the_refusal(Entry, loader):
    e = entry(
        Entry,
        f"""protobuf_name: "{BNR}" strict_format: true
        create {{ technique: TECHNIQUE_FORMAT moos_var: "A" format: "X=%202%" }}""",
    )
    translator = Translator([e], loader.message_class)
    assert translator.create(BNR, {"A": "x=1"}).x == 1
    with pytest.raises(
        TranslatorError,
        match=f"{BNR} from A: input 'Y=1' does not match format 'X=%202%': no 'x' .*"
        r"\(strict_format: nothing created\)",
    ):
        translator.create(BNR, {"A": "Y=1"})


def test_publish_without_entry_is_an_error(Entry, loader, msgs):
    translator = Translator([], loader.message_class)
    with pytest.raises(TranslatorError, match=f"No TranslatorEntry for Protobuf type: {BNR}"):
        translator.publish(msgs.BasicNodeReport())


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ('protobuf_name: "no.Such"', "is not a loaded message type"),
        (
            f'protobuf_name: "{BNR}" create {{ technique: TECHNIQUE_FORMAT moos_var: "A" format: "%1%" '
            'algorithm { name: "add" primary_field: 1 } }',
            "cannot be used in a create rule",
        ),
        (
            f'protobuf_name: "{BNR}" create {{ technique: TECHNIQUE_FORMAT moos_var: "A" format: "%77%" }}',
            "Bad field: 77",
        ),
        (
            f'protobuf_name: "{BNR}" create {{ technique: TECHNIQUE_FORMAT moos_var: "A" }}',
            "needs a format",
        ),
        (
            f'protobuf_name: "{BNR}" publish {{ technique: TECHNIQUE_FORMAT moos_var: "A" format: "%1$y" }}',
            "bad directive",
        ),
        (
            f'protobuf_name: "{BNR}" publish {{ technique: TECHNIQUE_FORMAT moos_var: "A" format: "%1%" '
            'algorithm { name: "add" output_virtual_field: 50 primary_field: 1 reference_field: 10 } }',
            "reference field 10",
        ),
        (f'protobuf_name: "{BNR}" trigger {{ type: TRIGGER_TIME }}', "period > 0"),
        (f'protobuf_name: "{BNR}" trigger {{ type: TRIGGER_PUBLISH }}', "needs trigger.moos_var"),
    ],
)
def test_config_errors(Entry, loader, text, message):
    with pytest.raises(TranslatorConfigError, match=message):
        Translator([entry(Entry, text)], loader.message_class)


def test_duplicate_entry(Entry, loader):
    e = entry(Entry, f'protobuf_name: "{BNR}"')
    with pytest.raises(TranslatorConfigError, match=f"Duplicate translator entry for {BNR}"):
        Translator([e, e], loader.message_class)


def trigger_translator(Entry, loader):
    return Translator(
        [
            entry(
                Entry,
                f"""protobuf_name: "{BNR}"
                trigger {{ moos_var: "CMD" mandatory_content: "report" }}
                create {{ technique: TECHNIQUE_FORMAT moos_var: "CMD" format: "report %1%" }}
                create {{ technique: TECHNIQUE_FORMAT moos_var: "NAV_X" format: "%202%" }}
                publish {{ technique: TECHNIQUE_FORMAT moos_var: "OUT" format: "%1%:%202%" }}""",
            ),
            entry(
                Entry,
                f"""protobuf_name: "{TEST_MSG}"
                trigger {{ type: TRIGGER_TIME period: 2 }}
                create {{ technique: TECHNIQUE_FORMAT moos_var: "NAV_X" format: "%1%" }}""",
            ),
        ],
        loader.message_class,
    )


def test_publish_trigger_with_mandatory_content(Entry, loader):
    translator = trigger_translator(Entry, loader)
    assert translator.subscriptions() == ["CMD", "NAV_X"]
    assert translator.triggered_by("CMD", "report alpha") == [BNR]
    assert translator.triggered_by("CMD", "status") == []
    assert translator.triggered_by("CMD", 1.0) == []
    assert translator.triggered_by("CMD", b"\x00report") == [BNR]
    assert translator.triggered_by("NAV_X", "report") == []


def test_runner_triggers_and_stale_mail(Entry, loader):
    runner = TranslatorRunner(trigger_translator(Entry, loader), start_time=100.0)
    assert runner.on_mail("NAV_X", 5.0) == []
    assert runner.on_mail("CMD", "report alpha", stale=True) == []
    (created,) = runner.on_mail("CMD", "report bravo")
    assert (created.Name, created.x) == ("bravo", 5.0)
    assert runner.translator.publish(created) == [Post("OUT", "bravo:5", f"{BNR}:TECHNIQUE_FORMAT")]


def test_runner_time_trigger_schedule(Entry, loader):
    runner = TranslatorRunner(trigger_translator(Entry, loader), start_time=100.0)
    runner.on_mail("NAV_X", 2.5)
    assert runner.tick(101.9) == []
    (created,) = runner.tick(102.0)
    assert created.double_default_optional == 2.5
    assert runner.tick(103.5) == []
    assert len(runner.tick(104.2)) == 1  # deadline 104 -> next 106
    assert runner.tick(105.9) == []
    assert len(runner.tick(110.0)) == 1  # 4 s late: schedule restarts from now
    assert runner.tick(111.9) == []
    assert len(runner.tick(112.0)) == 1


def test_runner_warns_about_a_partial_match_once_a_minute_per_rule(Entry, loader, caplog):
    clock = VirtualClock(1000.0)
    runner = TranslatorRunner(trigger_translator(Entry, loader), start_time=0.0, clock=clock)
    with caplog.at_level(logging.WARNING):
        (created,) = runner.on_mail("CMD", "report")  # no space after 'report'
        assert created.Name == ""  # "report" was consumed by the literals that matched
        clock.advance(59)
        assert len(runner.on_mail("CMD", "report")) == 1
        clock.advance(1)
        assert len(runner.on_mail("CMD", "report")) == 1
    warnings = [r.getMessage() for r in caplog.records]
    assert len(warnings) == 2
    assert warnings[0].startswith(
        f"{BNR} from CMD: input 'report' does not match format 'report %1%': no ' ' (format "
        "character 6) in the input after character 6; created from the part that matched"
    )


def test_runner_bad_input_logged_and_skipped(Entry, loader, caplog):
    e = entry(
        Entry,
        f"""protobuf_name: "{BNR}" trigger {{ moos_var: "B" }}
        create {{ technique: TECHNIQUE_PROTOBUF_TEXT_FORMAT moos_var: "B" }}""",
    )
    runner = TranslatorRunner(Translator([e], loader.message_class), start_time=0.0)
    with caplog.at_level(logging.WARNING):
        assert runner.on_mail("B", "x: {") == []
    assert f"not creating {BNR}: {BNR} from B: cannot parse" in caplog.text


def test_runner_updates_datum_from_origin_mail(Entry, loader):
    runner = TranslatorRunner(trigger_translator(Entry, loader), start_time=0.0)
    assert {"LAT_ORIGIN", "LONG_ORIGIN"} <= set(runner.subscriptions())
    runner.on_mail("LAT_ORIGIN", 42.35)
    runner.tick(0.1)
    assert runner.translator.registry.geodesy.zone == 31  # needs both
    runner.on_mail("LONG_ORIGIN", -70.95)
    runner.on_mail("LAT_ORIGIN", math.nan)
    runner.tick(0.2)
    geodesy = runner.translator.registry.geodesy
    assert (geodesy.zone, geodesy.lat_origin, geodesy.lon_origin) == (19, 42.35, -70.95)


def test_multiplex_inverse_publish(Entry, loader, msgs):
    runner = TranslatorRunner(
        trigger_translator(Entry, loader), start_time=0.0, multiplex_vars=["MUX"]
    )
    report = msgs.BasicNodeReport(Name="alpha", x=3)
    value = serialize_protobuf(report, Technique.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT)
    posts = runner.on_multiplex(value, Technique.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT)
    aux = f"{BNR}:TECHNIQUE_FORMAT"
    assert posts == [Post("CMD", "report alpha", aux), Post("NAV_X", 3.0)]
    for post in posts:
        runner.on_mail(post.var, post.value)
    assert runner.variables["CMD"] == "report alpha"
    assert (
        runner.on_multiplex(
            "@PB[nope.Type] x: 1", Technique.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT
        )
        == []
    )


def test_inverse_publish_adds_empty_trigger_post(Entry, loader, msgs):
    e = entry(
        Entry,
        f"""protobuf_name: "{BNR}" trigger {{ moos_var: "GO" }}
        create {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "KV" }}""",
    )
    posts = Translator([e], loader.message_class).inverse_publish(
        msgs.BasicNodeReport(x=1, Name="a")
    )
    assert posts == [
        Post("GO", ""),
        Post("KV", "Name=a,x=1", f"{BNR}:TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS"),
    ]


def test_runner_reads_an_external_variable_table(Entry, loader):
    table = {"NAV_X": 4.0, "CMD": "report x"}  # the application stores mail before handling it
    runner = TranslatorRunner(trigger_translator(Entry, loader), start_time=0.0, variables=table)
    (created,) = runner.on_mail("CMD", "report x")
    assert (created.Name, created.x) == ("x", 4.0)
    runner.on_mail("NAV_X", 9.0)
    assert table["NAV_X"] == 4.0  # the runner never writes the application's table


def test_post_for_moos(msgs):
    report = msgs.BasicNodeReport(x=1)
    assert post_for_moos("R", report, Technique.TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT) == Post(
        "R", f"@PB[{BNR}] x: 1 ", f"{BNR}:TECHNIQUE_PREFIXED_PROTOBUF_TEXT_FORMAT"
    )
    assert post_for_moos(
        "R", report, Technique.TECHNIQUE_PREFIXED_PROTOBUF_NATIVE_ENCODED
    ).value == (f"@PB[{BNR}] ".encode() + report.SerializeToString())


def test_moos_values_view():
    from pygoby.moos import protocol

    table = {
        "A": protocol.MOOSMessage(key="A", data_type=protocol.DOUBLE, dval=1.5),
        "B": protocol.MOOSMessage(key="B", data_type=protocol.STRING, sval=b"x"),
    }
    view = MoosValues(table)
    assert dict(view) == {"A": 1.5, "B": "x"}
    assert view.get("C") is None


def test_invalid_utf8_for_a_string_field_creates_nothing(Entry, loader):
    e = entry(
        Entry,
        f"""protobuf_name: "{TEST_MSG}"
        create {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "KV" }}""",
    )
    translator = Translator([e], loader.message_class)
    with pytest.raises(
        TranslatorError, match="string field string_default_optional is not valid UTF-8"
    ):
        translator.create(
            TEST_MSG, {"KV": b"int32_default_optional=1,string_default_optional=\xff"}
        )


def test_read_back_reads_each_rule_naming_the_variable(Entry, loader, msgs):
    """`read_back` (the log tools): a create variable through its rule with its algorithms, a
    publish variable as published; a publish naming an algorithm's virtual field, or whose
    variable name is a format, is not read back; a value no rule reads is an error."""
    e = entry(
        Entry,
        f"""protobuf_name: "{BNR}"
        create {{ technique: TECHNIQUE_FORMAT moos_var: "NAV_X" format: "%202%" }}
        create {{ technique: TECHNIQUE_FORMAT moos_var: "VEHICLE_NAME" format: "%1%"
                  algorithm {{ name: "to_lower" primary_field: 1 }} }}
        create {{ technique: TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS moos_var: "NAV_HEADING"
                  algorithm {{ name: "angle_0_360" primary_field: 201 }} }}
        publish {{ technique: TECHNIQUE_FORMAT moos_var: "REPORT" format: "NAME=%1%;X=%202%" }}
        publish {{ technique: TECHNIQUE_FORMAT moos_var: "REPORT_LAT" format: "%100%"
          algorithm {{ name: "utm_y2lat" output_virtual_field: 100 primary_field: 3 reference_field: 202 }} }}
        publish {{ technique: TECHNIQUE_FORMAT moos_var: "REPORT_%1%" format: "%202%" }}
        publish {{ technique: TECHNIQUE_PROTOBUF_NATIVE_HEX moos_var: "REPORT_HEX" }}""",
    )
    translator = Translator([e], loader.message_class)
    assert translator.read_back_variables() == {
        "NAV_X",
        "VEHICLE_NAME",
        "NAV_HEADING",
        "REPORT",
        "REPORT_HEX",
    }
    assert translator.read_back("NAV_X", 550.0) == [msgs.BasicNodeReport(x=550)]  # a double
    assert translator.read_back("VEHICLE_NAME", "UNICORN") == [msgs.BasicNodeReport(Name="unicorn")]
    assert translator.read_back("NAV_HEADING", "heading=-120") == [
        msgs.BasicNodeReport(heading=240)
    ]
    assert translator.read_back("REPORT", "NAME=Unicorn;X=12.5") == [
        msgs.BasicNodeReport(Name="Unicorn", x=12.5)  # as published: no create algorithms
    ]
    report = msgs.BasicNodeReport(Name="a", y=3.5, repeat=[1, 2])
    (hex_value,) = [p.value for p in translator.publish(report) if p.var == "REPORT_HEX"]
    assert translator.read_back("REPORT_HEX", hex_value) == [report]
    assert translator.read_back("OTHER", "x") == []
    with pytest.raises(TranslatorError, match="REPORT: no rule reads the value"):
        translator.read_back("REPORT", "nothing like the format")
    with pytest.raises(TranslatorError, match="REPORT_HEX"):
        translator.read_back("REPORT_HEX", "not hex")
