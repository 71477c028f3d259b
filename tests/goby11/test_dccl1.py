"""DCCL1 (Goby 1.1's own DCCL bytes) against messages and multi-message frames recorded from the
real Goby 1.1.2 libdccl, both ways (the manual's examples; our own set of arrays, <max_delta>,
<repeat/>, hex, static, negative precision, renamed header fields); the layout rules spelled out
bit by bit; the CLI; a fuzzed decoder."""

from __future__ import annotations

import io
import json
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.cli import main as pygoby_main
from pygoby.dccl.dccl1 import Dccl1Codec, Dccl1Header, stitch, unix_time, unstitch
from pygoby.dccl.errors import DcclDecodeError, DcclEncodeError
from pygoby.dccl.xml import load_message_set, parse_message_set
from pygoby.errors import ConfigError
from tests.hypothesis_profiles import examples

DATA = Path(__file__).parents[1] / "data" / "vectors" / "goby11-dccl1"
VECTORS = [json.loads(line) for line in (DATA / "vectors.jsonl").read_text().splitlines()]
# our own message set (arrays, <max_delta>, <repeat/>, hex, static, negative precision, renamed
# header fields), recorded from the same Goby 1.1.2 libdccl
LAYOUTS = [json.loads(line) for line in (DATA / "layouts.jsonl").read_text().splitlines()]
# libqueue 1.1 frames of those messages, stitched and split by libqueue's byte rules around the
# same libdccl's header coder
FRAMES = [json.loads(line) for line in (DATA / "frames.jsonl").read_text().splitlines()]
MESSAGE_SETS = {
    name: load_message_set(DATA / "xml" / name) for name in {v["xml"] for v in VECTORS + LAYOUTS}
}


def codec_for(vector: dict) -> Dccl1Codec:
    codec = Dccl1Codec(passphrase=vector["passphrase"], modem_id=vector.get("modem_id", 0))
    codec.load(MESSAGE_SETS[vector["xml"]])
    return codec


def vector_values(vector: dict) -> dict:
    # the recorder marked values handed to libdccl as double/long/bool with a :d/:l/:b suffix
    return {key.split(":")[0]: value for key, value in vector["values"].items()}


@pytest.mark.parametrize("vector", VECTORS + LAYOUTS, ids=lambda v: f"{v['message']}-{v['case']}")
def test_encode_is_goby_112s_bytes(vector: dict) -> None:
    codec = codec_for(vector)
    encode = lambda: codec.encode(  # noqa: E731
        vector["message"],
        vector_values(vector),
        src=vector["src"],
        dest=vector["dest"],
        time=vector["time"],
    )
    if vector["hex"] is None:
        with pytest.raises(DcclEncodeError):
            encode()
    else:
        assert encode().hex() == vector["hex"]


# Goby 1.1.2 adds a delta to an unset key and reads NaN (floats) or the x86 cast of NaN to long
# (ints); pygoby reads such an element as unset
UNSET_KEY_GARBAGE = ("NaN", -(2**63))


def unset_key_garbage_as_none(values: dict) -> dict:
    return {
        name: [None if v in UNSET_KEY_GARBAGE else v for v in value]
        if isinstance(value, list)
        else value
        for name, value in values.items()
    }


@pytest.mark.parametrize(
    "vector",
    [v for v in VECTORS + LAYOUTS if v["hex"]],
    ids=lambda v: f"{v['message']}-{v['case']}",
)
def test_decode_reads_what_goby_112_read(vector: dict) -> None:
    decoded = codec_for(vector).decode(bytes.fromhex(vector["hex"]))
    expected = vector["decoded"]
    assert decoded.message == vector["message"]
    assert decoded.values == unset_key_garbage_as_none(expected["values"])
    head = expected["header"]
    assert (
        decoded.header.id,
        decoded.header.time_of_day,
        decoded.header.src,
        decoded.header.dest,
        decoded.header.multimessage,
        decoded.header.broadcast,
        decoded.header.unused,
    ) == (
        head["_id"],
        head["_time_of_day"],
        head["_src_id"],
        head["_dest_id"],
        head["_multimessage_flag"],
        head["_broadcast_flag"],
        head["_unused"],
    )


def test_the_recorded_set_reaches_encryption_edges_and_lossy_cases() -> None:
    # the vectors above are only worth as much as what they cover
    cases = {v["case"] for v in VECTORS}
    assert {"below", "above", "hdr_time_round_to_86400", "hdr_flags_set"} <= cases
    assert {v["passphrase"] for v in VECTORS} == {None, "my_passphrase!", "twinkletoes%24"}
    assert any(v["roundtrip"] == "lossy" for v in VECTORS)


def test_the_layout_set_reaches_every_layout_rule() -> None:
    messages = {v["message"] for v in LAYOUTS}
    assert messages == {"Arrays", "Deltas", "Repeated", "HexStatic", "Renamed", "Big", "Edges"}
    cases = {(v["message"], v["case"]) for v in LAYOUTS}
    assert {
        ("Deltas", "beyond_max_delta"),
        ("Deltas", "key_unset"),
        ("HexStatic", "short_hex"),
    } <= cases
    assert any(v["hex"] is None for v in LAYOUTS)
    assert {v["passphrase"] for v in LAYOUTS} == {None, "layouts!", "renamed header"}


@pytest.mark.parametrize("frame", FRAMES, ids=lambda f: f["case"])
def test_frames_are_libqueue_112s_bytes_both_ways(frame: dict) -> None:
    # stitch flags a message broadcast when the destination its header carries (5 bits) is 0
    messages = [(bytes.fromhex(m["hex"]), m["dest"] & 0x1F) for m in frame["messages"]]
    assert stitch(messages).hex() == frame["frame"]
    parts = unstitch(bytes.fromhex(frame["frame"]))
    assert [(p.data.hex(), p.broadcast) for p in parts] == [
        (p["hex"], p["broadcast"]) for p in frame["parts"]
    ]
    codec = Dccl1Codec(passphrase=frame["passphrase"])
    codec.load(MESSAGE_SETS[frame["xml"]])
    for part, expected in zip(parts, frame["parts"], strict=True):
        if expected.get("values") is None:
            with pytest.raises(DcclDecodeError):
                codec.decode(part.data)
        else:
            assert codec.decode(part.data).values == unset_key_garbage_as_none(expected["values"])


def xml(body: str) -> str:
    return f'<?xml version="1.0"?>\n<message_set>\n{body}\n</message_set>\n'


def layout_codec(layout: str, size: int = 32, extra: str = "") -> Dccl1Codec:
    text = xml(
        f"<message><name>M</name><id>7</id><size>{size}</size>{extra}"
        f"<trigger>publish</trigger><trigger_var>M_OUT</trigger_var>"
        f"<layout>{layout}</layout></message>"
    )
    codec = Dccl1Codec(passphrase="k")
    codec.load(parse_message_set(text, "m.xml"))
    return codec


def plain_body(codec: Dccl1Codec, data: bytes) -> bytes:
    """The body before encryption (the cipher is CTR: applying it again decrypts)."""
    return codec._cipher.apply(data[:6], data[6:])


def test_array_with_max_delta_sends_deltas_first_and_the_key_last() -> None:
    # int 0..10: key 4 bits; max_delta 2: deltas in 0..4 -> 3 bits. [5, 6, 4]:
    # element 1 -> 6 + 2 - 5 + 1 = 4, element 2 -> 4 + 2 - 5 + 1 = 2, key -> 5 + 1 = 6
    codec = layout_codec(
        "<int><name>a</name><max>10</max><min>0</min><max_delta>2</max_delta>"
        "<array_length>3</array_length></int>"
    )
    data = codec.encode("M", {"a": ["5", "6", "4"]}, src=1, dest=2, time=0)
    assert plain_body(codec, data) == (0b100_010_0110).to_bytes(2, "big")
    assert codec.decode(data).values == {"a": [5, 6, 4]}
    # a delta beyond max_delta is sent as "unset"
    data = codec.encode("M", {"a": ["5", "9", "4"]}, src=1, dest=2, time=0)
    assert codec.decode(data).values == {"a": [5, None, 4]}


def test_array_without_delta_and_repeat_fill_the_size() -> None:
    codec = layout_codec(
        "<bool><name>b</name><array_length>3</array_length></bool>"
        "<enum><name>e</name><value>x</value><value>y</value><value>z</value></enum>"
    )
    data = codec.encode("M", {"b": [True, "false", None], "e": "z"}, time=0)
    # b[1]=false(01) b[2]=unset(00) b[0]=true(10), then e=z (3 of 2 bits): 01 00 10 11
    assert plain_body(codec, data) == bytes([0b01001011])
    assert codec.decode(data).values == {"b": [True, False, None], "e": "z"}
    repeated = layout_codec("<int><name>n</name><max>255</max><min>0</min></int>", 8, "<repeat/>")
    # 8-byte message: 16 body bits; 9 bits per copy -> 1 copy
    assert repeated.message("M").repeat == 1
    repeated = layout_codec("<bool><name>f</name></bool>", 8, "<repeat/>")
    assert repeated.message("M").repeat == 8


def test_hex_is_required_at_its_exact_length() -> None:
    codec = layout_codec("<hex><name>h</name><num_bytes>2</num_bytes></hex>")
    data = codec.encode("M", {"h": "0aFf"}, time=0)
    assert codec.decode(data).values == {"h": "0aff"}
    for bad in ("0aff00", "0a", None):
        with pytest.raises(DcclEncodeError, match="hex value"):
            codec.encode("M", {"h": bad}, time=0)


def test_decoder_strips_trailing_zero_ciphertext_bytes_as_goby_11_does() -> None:
    # find a message whose encrypted body ends in 0x00: 1.1's decoder drops that byte before
    # decrypting, so the last plaintext byte reads as 0 (the sender's value is lost)
    codec = layout_codec("<int><name>n</name><max>60000</max><min>0</min></int>")
    for n in range(60000):
        data = codec.encode("M", {"n": n}, src=1, dest=2, time=0)
        if data[-1] == 0:
            break
    else:
        pytest.fail("no ciphertext ending in 0x00")
    decoded = codec.decode(data).values["n"]
    assert decoded != n
    assert plain_body(codec, data)[-1] != 0  # the sender did send a non-zero last byte


def test_out_of_range_and_unset_numbers_travel_as_zero() -> None:
    codec = layout_codec(
        "<float><name>x</name><max>3</max><min>0</min><precision>1</precision></float>"
    )
    for value in ("3.1", "-0.1", "abc", None):
        assert codec.decode(codec.encode("M", {"x": value}, time=0)).values == {"x": None}
    # the cast after scaling truncates: 2.3 * 100 = 229.99999999999997 -> 229 -> 2.29
    codec = layout_codec(
        "<float><name>x</name><max>3</max><min>0</min><precision>2</precision></float>"
    )
    assert codec.decode(codec.encode("M", {"x": "2.3"}, time=0)).values == {"x": 2.29}


def test_frames_stitch_and_unstitch_as_libqueue_11() -> None:
    codec = Dccl1Codec()
    codec.load(MESSAGE_SETS["simple_status.xml"])
    one = codec.encode("SIMPLE_STATUS", {"nav_x": "1", "Speed": "2"}, src=1, dest=0, time=3)
    two = codec.encode("SIMPLE_STATUS", {"nav_y": "-5"}, src=1, dest=4, time=3)
    frame = stitch([(one, 0), (two, 4)])
    # 0x20, one's header bytes 1-5 (multi-message and broadcast flags), its body length,
    # its body, two's header bytes 1-5 (no flags), two's body
    assert frame == b"\x20" + one[1:5] + bytes([one[5] | 0x0C, len(one) - 6]) + one[6:] + (two[1:])
    parts = unstitch(frame)
    assert [(p.data, p.broadcast) for p in parts] == [(one, True), (two, False)]
    assert codec.decode(parts[1].data).values["nav_y"] == -5
    single = stitch([(one, 0)])
    assert single == one[:5] + bytes([one[5] | 0x04]) + one[6:]
    assert [p.data for p in unstitch(single)] == [one]


def test_received_time_of_day_is_placed_within_12_hours_of_now() -> None:
    noon = 10 * 86400 + 43200
    assert unix_time(43000, noon) == 10 * 86400 + 43000
    # more than 12 h away either way round means yesterday (1.1 never assumes tomorrow)
    assert unix_time(100, noon + 43200 - 50) == 9 * 86400 + 100
    assert unix_time(86000, 10 * 86400 + 10) == 9 * 86400 + 86000  # just after midnight


def test_header_packs_msb_first() -> None:
    header = Dccl1Header(0x20, 511, 86399, 31, 0, True, False, 2)
    assert Dccl1Header.unpack(header.pack()) == header
    assert header.pack()[:2] == b"\x20\xff"


@settings(max_examples=examples(300), deadline=None)
@given(st.binary(max_size=64))
def test_decoder_fuzz_raises_only_decode_errors(data: bytes) -> None:
    codec = Dccl1Codec()
    for message_set in (MESSAGE_SETS["simple_status.xml"], MESSAGE_SETS["example1.xml"]):
        codec.load(message_set)
    for candidate in (data, b"\x20" + data, b"\x20\x0a" + data, b"\x20\x00" + data):
        try:
            for part in unstitch(candidate):
                codec.decode(part.data)
        except DcclDecodeError:
            pass


@pytest.mark.parametrize("huge", [1.79e306, -1.79e306, "1e308"])
def test_a_value_too_large_to_scale_travels_as_out_of_range(huge) -> None:
    """A double that overflows when scaled by 10^precision is out of range (sent as unset),
    as 1.1 sends it, instead of an OverflowError (hypothesis found 1.79e306)."""
    codec = Dccl1Codec()
    codec.load(MESSAGE_SETS["example1.xml"])
    decoded = codec.decode(codec.encode("GoToCommand", {"goto_speed": huge}, src=3, dest=4, time=0))
    assert decoded.values["goto_speed"] is None


@settings(max_examples=examples(200), deadline=None)
@given(
    st.dictionaries(
        st.sampled_from(["goto_x", "goto_y", "lights_on", "new_instructions", "goto_speed"]),
        st.one_of(st.none(), st.booleans(), st.integers(), st.floats(), st.text(max_size=12)),
    )
)
def test_encoder_fuzz_round_trips_through_the_decoder(values: dict) -> None:
    codec = Dccl1Codec()
    codec.load(MESSAGE_SETS["example1.xml"])
    data = codec.encode("GoToCommand", values, src=3, dest=4, time=0)
    decoded = codec.decode(data)
    assert decoded.header.src == 3 and set(decoded.values) >= set(values)


def run_cli(monkeypatch, capsys, *args: str, stdin: str = "") -> tuple[int, list[str]]:
    monkeypatch.setattr("sys.stdin", io.StringIO(stdin))
    status = pygoby_main(["dccl", *args])
    return status, capsys.readouterr().out.splitlines()


def test_cli_encode_decode_and_analyze(monkeypatch, capsys, tmp_path) -> None:
    xmls = [
        "--xml",
        str(DATA / "xml" / "example1.xml"),
        "--xml",
        str(DATA / "xml" / "simple_status.xml"),
    ]
    crypto = next(v for v in VECTORS if v["passphrase"] == "my_passphrase!")
    secret = tmp_path / "secret"
    secret.write_text("my_passphrase!\n")
    request = {k: crypto[k] for k in ("message", "src", "dest", "time")}
    request["values"] = crypto["values"]
    frame = [
        {"message": "GoToCommand", "values": {"goto_x": 7}, "src": 1, "dest": 0, "time": 9},
        {"message": "SIMPLE_STATUS", "values": {"Speed": 1.5}, "src": 1, "dest": 2, "time": 9},
    ]
    stdin = "\n".join([json.dumps(request), json.dumps(frame), "{not json", '{"message": "Nope"}'])
    status, out = run_cli(
        monkeypatch,
        capsys,
        "encode",
        "--goby11",
        *xmls,
        "--passphrase-file",
        str(secret),
        stdin=stdin,
    )
    assert status == 1
    assert out[0] == crypto["hex"]
    assert out[2].startswith("error: not JSON") and out[3].startswith("error: no DCCL1 message")
    status, decoded = run_cli(
        monkeypatch, capsys, "decode", "--goby11", *xmls, "--passphrase-file", str(secret),
        stdin="\n".join([out[0], out[1], "0a0b0c0d0e0f"]),
    )  # fmt: skip
    first = json.loads(decoded[0])
    assert first == [
        {
            "message": crypto["message"],
            "src": crypto["src"],
            "dest": crypto["dest"],
            "time_of_day": crypto["decoded"]["header"]["_time_of_day"],
            "values": crypto["decoded"]["values"],
        }
    ]
    pair = json.loads(decoded[1])
    assert [(m["message"], m["dest"]) for m in pair] == [("GoToCommand", 0), ("SIMPLE_STATUS", 2)]
    assert pair[0]["values"]["goto_x"] == 7 and pair[1]["values"]["Speed"] == 1.5
    assert decoded[2].startswith("error: not a DCCL1 frame")
    status, shown = run_cli(monkeypatch, capsys, "analyze", "--goby11", *xmls[2:])
    assert status == 0 and "SIMPLE_STATUS (DCCL1 id 20)" in shown[0]
    assert any("Timestamp" in line and "17" in line for line in shown)


def test_cli_writes_and_reads_a_recorded_libqueue_frame(monkeypatch, capsys) -> None:
    # the way a user meets frames: a JSON list of messages in, Goby 1.1.2's frame out, and back
    recorded = {(v["message"], v["case"]): v for v in LAYOUTS}
    frame = next(f for f in FRAMES if f["case"] == "broadcast_middle")
    requests = []
    for part in frame["messages"]:
        vector = recorded[(part["message"], part["case"])]
        requests.append({k: vector[k] for k in ("message", "src", "dest", "time")})
        requests[-1]["values"] = vector_values(vector)
    xmls = ["--xml", str(DATA / "xml" / "layouts.xml")]
    status, out = run_cli(
        monkeypatch, capsys, "encode", "--goby11", *xmls, stdin=json.dumps(requests)
    )
    assert (status, out) == (0, [frame["frame"]])
    status, decoded = run_cli(monkeypatch, capsys, "decode", "--goby11", *xmls, stdin=out[0])
    parts = json.loads(decoded[0])
    assert [m["values"] for m in parts] == [p["values"] for p in frame["parts"]]
    # a broadcast message's header carries destination 0 (the 5-bit id)
    assert [m["dest"] for m in parts] == [m["dest"] & 0x1F for m in frame["messages"]]
    assert 0 in [m["dest"] for m in parts]


def test_two_message_sets_with_one_id_are_refused() -> None:
    codec = Dccl1Codec()
    codec.load(MESSAGE_SETS["example1.xml"])
    with pytest.raises(ConfigError, match="chat.xml:3: .*already used"):
        codec.load(load_message_set(DATA / "xml" / "chat.xml"))


BRIDGE_XML = xml(
    "<message><name>D</name><id>3</id><size>32</size><trigger>publish</trigger>"
    "<trigger_var>D_OUT</trigger_var><layout>"
    "<int><name>a</name><max>2000000000</max><min>-2000000000</min>"
    "<max_delta>2000000000</max_delta><array_length>2</array_length></int>"
    "<enum><name>e</name><value>x</value><value>y</value></enum>"
    "<string><name>s</name><max_length>4</max_length></string>"
    "<hex><name>h</name><num_bytes>2</num_bytes></hex></layout></message>"
)


def bridge_for(text: str):
    from pygoby.dccl.dccl1.bridge import Dccl1Bridge
    from pygoby.protobuf import ProtoLoader

    message_set = parse_message_set(text, "d.xml")
    loader = ProtoLoader()
    message_set.register(loader)
    bridge = Dccl1Bridge(Dccl1Codec(), loader.message_class)
    bridge.add(message_set)
    return bridge, loader


def test_bridge_round_trips_the_converted_types() -> None:
    bridge, loader = bridge_for(BRIDGE_XML)
    sent = loader.message_class("D")(a=[5, -3], e=1, s="ab", h=b"\x01\x02", _src_id=4, _time=7)
    received = bridge.decode(bridge.encode(sent), now=100.0)
    assert (list(received.a), received.e, received.s, received.h) == ([5, -3], 1, "ab", b"\x01\x02")
    assert (received._src_id, received._dest_id, received._time) == (4, 0, 7.0)


@settings(max_examples=examples(200), deadline=None)
@given(st.binary(max_size=40))
def test_bridge_fuzz_gives_protobuf_messages_or_decode_errors(data: bytes) -> None:
    """What the queue decodes from a received 0x20 frame: a message of the converted type, or
    DcclDecodeError (an <int> with <max_delta> can decode beyond int32, for instance)."""
    bridge, _ = bridge_for(BRIDGE_XML)
    try:
        msg = bridge.decode(b"\x20\x01\x80" + data)
    except DcclDecodeError:
        return
    assert msg.DESCRIPTOR.full_name == "D"
