"""Goby 1.1 XML message sets: every tag and algorithm of seed 003 §2.3.8-2.3.10 parsed,
converted (Goby 2 transitional mapping, spec goby-moos-apps.md §4.10) and run through the real
DCCL codec and MOOS translator."""

from __future__ import annotations

import math
import re

import pytest
from google.protobuf import text_format

from pygoby.dccl import Codec
from pygoby.dccl.xml import ALGORITHMS, load_message_set, parse_message_set
from pygoby.moos.translator import AlgorithmRegistry, ModemIdLookup, MoosValues, Translator
from pygoby.protobuf import ProtoLoader
from pygoby.util.geodesy import UTMGeodesy
from tests.goby11.seed_listings import EXAMPLES


def xml(messages: str) -> str:
    return f'<?xml version="1.0" encoding="UTF-8"?>\n<message_set>\n{messages}\n</message_set>\n'


def build(text: str, **translator_args):
    """(message set, codec, classes, translator) for XML text."""
    message_set = parse_message_set(text, "test.xml")
    codec = Codec()
    classes = message_set.load_into(codec)
    translator = Translator(
        message_set.translator_entries(), codec.loader.message_class, **translator_args
    )
    return message_set, codec, classes, translator


def values(**kw) -> MoosValues:
    return MoosValues({k: _mail(v) for k, v in kw.items()})


class _Mail:
    def __init__(self, value) -> None:
        self.value = value
        self.time = 0.0


def _mail(value) -> _Mail:
    return _Mail(float(value) if isinstance(value, int | float) else value)


EVERY_TYPE = xml("""
  <message>
    <name>Every</name>
    <id>5</id>
    <size>64</size>
    <trigger>publish</trigger>
    <trigger_var mandatory_content="kind=every">EVERY_OUT</trigger_var>
    <header>
      <time><name>When</name></time>
      <src_id><name>From</name></src_id>
      <dest_id><name>To</name></dest_id>
    </header>
    <layout>
      <static><name>kind</name><value>every</value></static>
      <int><name>i</name><max>100</max><min>-100</min></int>
      <float><name>f</name><max>10</max><min>0</min><precision>2</precision></float>
      <bool><name>b</name></bool>
      <string><name>s</name><max_length>8</max_length></string>
      <enum><name>e</name><value>one</value><value>two</value></enum>
      <hex><name>h</name><num_bytes>2</num_bytes></hex>
      <int><name>arr</name><max>7</max><min>0</min><array_length>3</array_length></int>
    </layout>
    <on_receipt>
      <publish><publish_var>EVERY_IN</publish_var><all/></publish>
    </on_receipt>
  </message>""")


def test_every_layout_type_round_trips_through_dccl_and_the_translator():
    _message_set, codec, (Every,), translator = build(EVERY_TYPE)
    descriptor = Every.DESCRIPTOR
    assert [(f.name, f.number) for f in descriptor.fields] == [
        ("When", 1),
        ("From", 2),
        ("To", 3),
        ("kind", 4),
        ("i", 5),
        ("f", 6),
        ("b", 7),
        ("s", 8),
        ("e", 9),
        ("h", 10),
        ("arr", 11),
    ]
    assert descriptor.fields_by_name["arr"].is_repeated
    assert [v.name for v in descriptor.enum_types_by_name["EEnum"].values] == ["E_one", "E_two"]
    created = translator.create(
        "Every",
        values(
            EVERY_OUT="kind=every,To=3,From=1,i=-42,f=3.14159,b=true,s=hello,e=two,h=beef,arr={1,2,3}"
        ),
    )
    assert (created.To, created.From, created.i, created.b, created.s) == (3, 1, -42, True, "hello")
    assert created.e == descriptor.fields_by_name["e"].enum_type.values_by_name["E_two"].number
    assert created.h == b"\xbe\xef" and list(created.arr) == [1, 2, 3]
    created.When = 1_300_000_000.0
    decoded = codec.decode(codec.encode(created))
    assert decoded.f == pytest.approx(3.14) and decoded.kind == "every" and decoded.s == "hello"
    (post,) = translator.publish(decoded)
    assert post.var == "EVERY_IN"
    assert (
        post.value.startswith("When=")
        and ",From=1,To=3,kind=every,i=-42,f=3.14,b=true," in post.value
    )
    assert post.value.endswith("s=hello,e=two,h=beef,arr={1,2,3}")


def test_mandatory_content_gates_the_trigger():
    _, _, _, translator = build(EVERY_TYPE)
    entry = translator.entries["Every"]
    assert (entry.trigger.moos_var, entry.trigger.mandatory_content) == ("EVERY_OUT", "kind=every")


def test_bounds_and_precision_are_written_as_goby2_did():
    message_set = parse_message_set(
        xml("""
  <message><name>B</name><id>9</id><size>32</size>
    <layout>
      <float><name>x</name><max>3.14159</max><min>-1.005</min><precision>2</precision></float>
      <int><name>n</name><max>-5</max><min>10</min></int>
    </layout></message>""")
    )
    text = message_set.proto_text()
    assert "(dccl.field).max = 3.14, (dccl.field).min = -1.0" in text  # rounded to precision
    assert (
        "optional int32 n = 5 [(dccl.field).max = 10.0, (dccl.field).min = -5.0]" in text
    )  # swapped
    assert any("swapped" in w for w in message_set.warnings)


def test_header_id_time_trigger_and_queuing():
    message_set, codec, (Status,), translator = build(
        xml("""
  <message>
    <name>Status</name>
    <trigger>time</trigger><trigger_time>15</trigger_time>
    <size>32</size>
    <header><id>300</id></header>
    <layout><float><name>x</name><src_var>NAV_X</src_var><max>100</max><min>0</min>
      <precision>1</precision></float></layout>
    <queuing><ack>true</ack><blackout_time>4</blackout_time><max_queue>3</max_queue>
      <newest_first>false</newest_first><value_base>2.5</value_base><ttl>60</ttl></queuing>
  </message>""")
    )
    assert codec.compiled(Status).id == 300
    entry = translator.entries["Status"]
    assert (entry.trigger.type, entry.trigger.period) == (entry.trigger.TRIGGER_TIME, 15)
    (queue,) = message_set.queue_entries()
    assert (
        queue.ack,
        queue.blackout_time,
        queue.max_queue,
        queue.newest_first,
        queue.value_base,
        queue.ttl,
    ) == (True, 4, 3, False, 2.5, 60)
    assert [(r.type, r.field) for r in queue.role] == [
        (1, "_src_id"),
        (2, "_dest_id"),
        (3, "_time"),
    ]


def test_queuing_defaults_are_goby_1_1s():
    message_set = parse_message_set(
        xml(
            "<message><name>Q</name><id>1</id><size>8</size>"
            "<layout><bool><name>b</name></bool></layout></message>"
        )
    )
    (queue,) = message_set.queue_entries()
    assert (
        queue.ack,
        queue.blackout_time,
        queue.max_queue,
        queue.newest_first,
        queue.value_base,
        queue.ttl,
    ) == (True, 0, 0, True, 1.0, 1800)  # ack: Goby 1.1.2's code, not its manual


def test_deprecated_tags_are_accepted_with_warnings():
    message_set = parse_message_set(
        xml("""
  <message><name>D</name><id>2</id><size>32</size><repeat/>
    <trigger>publish</trigger><trigger_moos_var>D_OUT</trigger_moos_var>
    <incoming_hex_moos_var>IN_D_HEX</incoming_hex_moos_var>
    <outgoing_hex_moos_var>OUT_D_HEX</outgoing_hex_moos_var>
    <destination_var key="Dest">D_DEST</destination_var>
    <layout><int><name>a</name><src_var key="aa">A_VAR</src_var><max>9</max><min>0</min>
      <max_delta>2</max_delta></int></layout>
    <on_receipt><publish><publish_var type="double">D_IN</publish_var>
      <message_var>a</message_var></publish></on_receipt>
    <queuing><priority_base>1</priority_base><priority_time_const>100</priority_time_const></queuing>
  </message>"""),
        "test.xml",
    )
    joined = "\n".join(message_set.warnings)
    for word in (
        "<repeat/>",
        "key=",
        "<max_delta>",
        "priority_base",
        "priority_time_const",
    ):
        assert word in joined, word
    assert all(re.match(r"test\.xml:\d+: ", w) for w in message_set.warnings)
    (msg,) = message_set.messages
    assert msg.hex_vars() == ("IN_D_HEX", "OUT_D_HEX")  # Goby 1.1 configurations post on them
    assert (msg.trigger_var, msg.header["dest_id"].name, msg.header["dest_id"].source_var) == (
        "D_OUT",
        "Dest",
        "D_DEST",
    )


def test_sources_default_to_the_trigger_and_shared_variables_use_key_value_pairs():
    message_set = load_message_set(EXAMPLES / "xml" / "example1.xml")
    goto, status = message_set.translator_entries()
    techniques = {c.moos_var: (c.technique, c.format) for c in goto.create}
    assert (
        techniques["OUTGOING_COMMAND"][0] == goto.TECHNIQUE_COMMA_SEPARATED_KEY_EQUALS_VALUE_PAIRS
    )
    assert techniques["SPECIAL_INSTRUCTIONS"] == (goto.TECHNIQUE_FORMAT, "%8%")
    assert {c.moos_var for c in status.create} == {"NAV_X", "NAV_Y", "VEHICLE_HEALTH"}


def test_seed_example1_scenario_goto_command():
    """Seed 003 §2.3.9's scenario: OUTGOING_COMMAND in, INCOMING_COMMAND and
    SPECIAL_INSTRUCTIONS out on the other side."""
    message_set = load_message_set(EXAMPLES / "xml" / "example1.xml")
    codec = Codec()
    message_set.load_into(codec)
    translator = Translator(message_set.translator_entries(), codec.loader.message_class)
    command = (
        "Destination=3,CommandType=GoTo,goto_x=351,goto_y=294,lights_on=true,"
        "special_instructions=make_toast,goto_speed=2.3"
    )
    created = translator.create(
        "GoToCommand", values(OUTGOING_COMMAND=command, SPECIAL_INSTRUCTIONS="make_toast")
    )
    received = codec.decode(codec.encode(created))
    posts = {p.var: p.value for p in translator.publish(received)}
    assert posts["INCOMING_COMMAND"] == (
        "Destination=3,type=goto,goto_x=351,goto_y=294,"
        "lights_on=true,new_instructions=make_toast,goto_speed=2.3"
    )
    assert posts["SPECIAL_INSTRUCTIONS"] == "special_instructions=make_toast,lights_on=true"


def test_publish_format_placeholders_renumbered_and_arrays_indexed():
    _message_set, _codec, (P,), translator = build(
        xml("""
  <message><name>P</name><id>3</id><size>32</size>
    <layout>
      <int><name>a</name><max>9</max><min>0</min></int>
      <int><name>v</name><max>9</max><min>0</min><array_length>2</array_length></int>
    </layout>
    <on_receipt>
      <publish><publish_var>OUT_%1%</publish_var><format>a=%1%;v0=%2%;v1=%3%</format>
        <message_var>a</message_var><message_var>v</message_var></publish>
      <publish><publish_var>ONE</publish_var><message_var>a</message_var></publish>
      <publish><publish_var>DEFAULT</publish_var><message_var>a</message_var>
        <message_var>v</message_var></publish>
    </on_receipt></message>""")
    )
    first, one, default = translator.entries["P"].publish
    assert (first.moos_var, first.format) == ("OUT_%4%", "a=%4%;v0=%5.0%;v1=%5.1%")
    assert one.format == "%4%"
    assert default.format == "a=%4%,v={%5.0%,%5.1%}"
    posts = {p.var: p.value for p in translator.publish(P(a=7, v=[1, 2]))}
    assert posts == {"OUT_7": "a=7;v0=1;v1=2", "ONE": 7.0, "DEFAULT": "a=7,v={1,2}"}


def test_a_variable_published_twice_is_named_by_its_algorithms():
    message_set = parse_message_set(
        xml("""
  <message><name>T</name><id>4</id><size>32</size>
    <layout><string><name>who</name><max_length>8</max_length></string></layout>
    <on_receipt><publish><publish_var>TWICE</publish_var>
      <message_var>who</message_var><message_var algorithm="to_upper">who</message_var>
    </publish></on_receipt></message>""")
    )
    (entry,) = message_set.translator_entries()
    assert entry.publish[0].format == "who=%4%,to_upper(who)=%100%"


ALGORITHM_SET = xml("""
  <message><name>Alg</name><id>6</id><size>64</size>
    <trigger>publish</trigger><trigger_var>ALG_OUT</trigger_var>
    <header><src_id algorithm="to_lower,name2modem_id"><name>Node</name>
      <moos_var>VEHICLE_NAME</moos_var></src_id></header>
    <layout>
      <string algorithm="to_upper"><name>up</name><max_length>8</max_length></string>
      <string algorithm="to_lower"><name>low</name><max_length>8</max_length></string>
      <float algorithm="angle_0_360"><name>hdg</name><max>360</max><min>0</min><precision>1</precision></float>
      <float algorithm="angle_-180_180"><name>hdg2</name><max>180</max><min>-180</min><precision>1</precision></float>
      <float><name>x</name><max>100000</max><min>-100000</min><precision>0</precision></float>
      <float><name>y</name><max>100000</max><min>-100000</min><precision>0</precision></float>
      <float><name>temp</name><max>40</max><min>-2</min><precision>1</precision></float>
      <float><name>sal</name><max>40</max><min>0</min><precision>1</precision></float>
      <float><name>depth</name><max>1000</max><min>0</min><precision>0</precision></float>
      <float><name>power</name><max>1000</max><min>0</min><precision>1</precision></float>
      <float><name>lat</name><max>90</max><min>-90</min><precision>6</precision></float>
      <float><name>lon</name><max>180</max><min>-180</min><precision>6</precision></float>
    </layout>
    <on_receipt><publish><publish_var>ALG_IN</publish_var>
      <format>%1%|%2%|%3%|%4%|%5%|%6%|%7%|%8%|%9%|%10%|%11%|%12%|%13%|%14%</format>
      <message_var algorithm="modem_id2name">Node</message_var>
      <message_var algorithm="modem_id2type">Node</message_var>
      <message_var algorithm="utm_y2lat:x">y</message_var>
      <message_var algorithm="utm_x2lon:y">x</message_var>
      <message_var algorithm="alg_TSD_to_soundspeed:sal:depth">temp</message_var>
      <message_var algorithm="add:y">x</message_var>
      <message_var algorithm="subtract:y">x</message_var>
      <message_var algorithm="power_to_dB">power</message_var>
      <message_var algorithm="dB_to_power,abs">power</message_var>
      <message_var algorithm="lat2utm_y:lon">lat</message_var>
      <message_var algorithm="lon2utm_x:lat">lon</message_var>
      <message_var>up</message_var><message_var>low</message_var><message_var>hdg</message_var>
    </publish></on_receipt></message>""")


def test_every_algorithm_of_the_manual_runs(tmp_path):
    lookup = ModemIdLookup.from_text("1, topside, ship\n2, mm2, auv\n")
    _, codec, (_Alg,), translator = build(
        ALGORITHM_SET, lat_origin=42.35, lon_origin=-70.95, modem_ids=lookup
    )
    created = translator.create(
        "Alg",
        values(
            ALG_OUT="up=abc,low=DEF,hdg=-90,hdg2=270,x=100,y=300,temp=10,sal=35,depth=100,power=100,"
            "lat=42.36,lon=-70.94",
            VEHICLE_NAME="MM2",
        ),
    )
    assert (created.Node, created.up, created.low) == (2, "ABC", "def")
    assert (created.hdg, created.hdg2) == (270.0, -90.0)
    received = codec.decode(codec.encode(created))
    (post,) = translator.publish(received)
    parts = post.value.split("|")
    assert parts[:2] == ["mm2", "auv"]
    lat, lon = float(parts[2]), float(parts[3])
    assert (lat, lon) == pytest.approx(UTMGeodesy(42.35, -70.95).to_geo(100, 300), abs=1e-9)
    assert float(parts[4]) == pytest.approx(1491.5, abs=2.0)  # Mackenzie at 10 C, 35 PSU, 100 m
    assert (float(parts[5]), float(parts[6])) == (400.0, -200.0)
    assert float(parts[7]) == pytest.approx(20.0) and float(parts[8]) == pytest.approx(10**10)
    x, y = UTMGeodesy(42.35, -70.95).to_local(42.36, -70.94)
    assert float(parts[9]) == pytest.approx(y, abs=0.5) and float(parts[10]) == pytest.approx(
        x, abs=0.5
    )
    assert parts[11:] == ["ABC", "def", "270"]


def test_every_xml_algorithm_exists_in_the_translator():
    registry = AlgorithmRegistry(modem_ids=ModemIdLookup())
    assert set(registry.names()) >= ALGORITHMS


def test_seed_simple_status_converts_and_fits():
    message_set = load_message_set(EXAMPLES / "xml" / "simple_status.xml")
    codec = Codec()
    (Status,) = message_set.load_into(codec)
    assert codec.max_size(Status) == 15 and codec.compiled(Status).id == 20
    (entry,) = message_set.translator_entries()
    report = entry.publish[1]
    assert (report.moos_var, report.format) == (
        "NODE_REPORT",
        "NAME=%100%,TYPE=%101%,UTC_TIME=%1$.0lf,X=%5%,Y=%6%,LAT=%102$lf,"
        "LON=%103$lf,SPD=%7%,HDG=%8%,DEPTH=%9%",
    )
    assert [
        (a.name, a.primary_field, list(a.reference_field), a.output_virtual_field)
        for a in report.algorithm
    ] == [
        ("modem_id2name", 2, [], 100),
        ("modem_id2type", 2, [], 101),
        ("utm_y2lat", 6, [5], 102),
        ("utm_x2lon", 5, [6], 103),
    ]


def test_written_proto_compiles_to_the_same_messages(tmp_path):
    message_set = load_message_set(EXAMPLES / "xml" / "example1.xml")
    path = message_set.write_proto(tmp_path / "out")
    assert path.name == "example1.proto"
    from_file = ProtoLoader()
    from_file.load_file(path)
    in_memory = ProtoLoader()
    message_set.register(in_memory)
    for name in message_set.names:
        a, b = Codec(loader=from_file), Codec(loader=in_memory)
        ca, cb = from_file.message_class(name), in_memory.message_class(name)
        assert a.analyze(ca) == b.analyze(cb)
        msg = text_format.Parse("goto_x: 5" if name == "GoToCommand" else "nav_x: 5", ca())
        assert a.encode(msg) == b.encode(text_format.Parse(text_format.MessageToString(msg), cb()))


def test_lookup_file_of_the_seed_is_read():
    lookup = ModemIdLookup.from_file(EXAMPLES / "MOOS" / "ccl_and_dccl" / "modemidlookup.txt")
    assert (lookup.name(1), lookup.type(2), lookup.modem_id("MM2")) == ("mm1", "auv", 2)
    assert not math.isnan(len(lookup))
