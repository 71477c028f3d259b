"""Replays of goby3 <-> pygoby pAcommsHandler runs: goby3's C++ pAcommsHandler (3.1.5a) as
modem 1, pygoby's as modem 2, exchanging a status (broadcast) and an acknowledged command each
way over the UDP driver, the UDP driver with DCCL encryption, and the Micro-Modem driver
through two `pygoby mmsim` emulators. Each test feeds goby3's recorded bytes or sentences to
pygoby's codec, drivers or modem emulator and compares with what the run recorded, so a wire
format regression shows without goby3 installed. The records and how they were made:
tests/data/goby3/README.md."""

from __future__ import annotations

import asyncio
import contextlib
import json
import socket
import time
from collections import Counter
from pathlib import Path

import pytest
from google.protobuf import text_format
from google.protobuf.message import Message

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.micromodem import MMDriver
from pygoby.acomms.drivers.udp import UDPDriver
from pygoby.acomms.mmsim import LoopbackChannel, MicroModemModel
from pygoby.apps.pacommshandler import pAcommsHandler
from pygoby.dccl import Codec
from pygoby.moos.translator import Translator, parse_for_moos
from pygoby.util.clock import VirtualClock
from pygoby.util.linebased import MemoryLink
from pygoby.util.nmea import NMEASentence
from pygoby.util.timeline import Timeline

from .acomms_mission import Recorder, start_db
from .test_driver_e2e import _free_port

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "tests" / "data" / "goby3"
PROTO = ROOT / "examples" / "two_vehicles" / "two_vehicles.proto"
RECORDS = {
    link: json.loads((DATA / f"pacommshandler_{link}.json").read_text())
    for link in ("udp", "udp_aes", "mm", "mm_rate0")
}
UDP_LINKS = ["udp", "udp_aes"]
MM_LINKS = ["mm", "mm_rate0"]
GOBY3, PYGOBY = "goby3", "pygoby"


def config_of(record: dict, side: str = PYGOBY) -> Message:
    """A side's ProcessConfig block of the run, parsed (the ports do not matter here)."""
    block = record["process_config"][side]
    body = block[block.index("{") + 1 : block.rindex("}")]
    for port in ("{local_port}", "{remote_port}", "{modem_port}"):
        body = body.replace(port, "0")
    cfg = pAcommsHandler.load_config_class()()
    text_format.Merge(body, cfg)
    return cfg


def posts(record: dict, side: str, var: str) -> list:
    return [e["value"] for e in record[side] if e["var"] == var]


def codec_for(record: dict, passphrase: str | None = "record") -> Codec:
    """pygoby's DCCL codec with the mission's types; the record's passphrase unless given."""
    if passphrase == "record":
        passphrase = record["crypto_passphrase"]
    codec = Codec(passphrase=passphrase)
    for name in ("SimpleStatus", "Command"):
        codec.load_proto(PROTO, f"pygoby.examples.{name}")
    return codec


def parsed(cls: type[Message], text: str) -> Message:
    msg = cls()
    parse_for_moos(text, msg)
    return msg


def raw_bytes(text: str) -> bytes:
    """The bytes of an ACOMMS_RAW_* post (a ModemRaw)."""
    return parsed(acomms_pb.ModemRaw, text).raw


def transmissions(record: dict, side: str, var: str) -> list[acomms_pb.ModemTransmission]:
    """The datagrams of a side's ACOMMS_RAW_INCOMING / _OUTGOING, parsed."""
    out = []
    for text in posts(record, side, var):
        msg = acomms_pb.ModemTransmission()
        msg.ParseFromString(raw_bytes(text))
        out.append(msg)
    return out


def queue_received(record: dict, side: str, codec: Codec) -> list[Message]:
    """The messages a side published on ACOMMS_QUEUE_RECEIVE, in pygoby's classes."""
    out = []
    for text in posts(record, side, "ACOMMS_QUEUE_RECEIVE"):
        name = text[len("@PB[") : text.index("]")]
        out.append(parsed(codec.compiled(name).cls, text))
    return out


def decode_frames(codec: Codec, frames) -> list[Message]:
    """Every DCCL message of the frames (several may share one)."""
    out = []
    for frame in frames:
        data = bytes(frame)
        while data:
            msg, used = codec.decode_prefix(data)
            out.append(msg)
            data = data[used:]
    return out


def data_frames(sent: list[acomms_pb.ModemTransmission]) -> list[bytes]:
    return [bytes(f) for t in sent if t.type == acomms_pb.DATA for f in t.frame]


@pytest.mark.parametrize("link", list(RECORDS))
def test_the_record_is_a_full_exchange_both_ways(link):
    """Each side decoded both of the other's messages and had its command acknowledged."""
    record = RECORDS[link]
    for side, peer in ((GOBY3, 2), (PYGOBY, 1)):
        assert posts(record, side, "STATUS_REPORT_IN")[0].startswith(f"src={peer},")
        assert len(posts(record, side, "DESIRED_HEADING")) == 1
        assert len(posts(record, side, "ACOMMS_ACK")) == 1
        assert len(posts(record, side, "ACOMMS_QUEUE_RECEIVE")) == 2


@pytest.mark.parametrize("link", UDP_LINKS)
def test_pygoby_received_goby3s_datagrams_unchanged(link):
    record = RECORDS[link]
    sent = [raw_bytes(t) for t in posts(record, GOBY3, "ACOMMS_RAW_OUTGOING")]
    heard = [raw_bytes(t) for t in posts(record, PYGOBY, "ACOMMS_RAW_INCOMING")]
    assert sent and sent == heard


@pytest.mark.parametrize("link", UDP_LINKS)
def test_goby3s_frames_decode_to_what_pygoby_published_and_encode_back(link):
    record = RECORDS[link]
    codec = codec_for(record)
    frames = data_frames(transmissions(record, GOBY3, "ACOMMS_RAW_OUTGOING"))
    decoded = decode_frames(codec, frames)
    assert decoded == queue_received(record, PYGOBY, codec)
    assert b"".join(frames) == b"".join(codec.encode(m) for m in decoded)


@pytest.mark.parametrize("link", UDP_LINKS)
def test_pygoby_encodes_the_frames_goby3_decoded(link):
    """The messages goby3 published, encoded by pygoby, are the bytes goby3 received."""
    record = RECORDS[link]
    codec = codec_for(record)
    frames = data_frames(transmissions(record, GOBY3, "ACOMMS_RAW_INCOMING"))
    theirs = queue_received(record, GOBY3, codec)
    assert b"".join(frames) == b"".join(codec.encode(m) for m in theirs)
    if record["crypto_passphrase"]:  # the body really is encrypted: in clear it differs
        clear = codec_for(record, passphrase=None)
        assert b"".join(frames) != b"".join(clear.encode(m) for m in theirs)


@pytest.mark.parametrize("link", UDP_LINKS)
def test_goby3_acknowledged_the_frames_pygoby_numbered(link):
    record = RECORDS[link]
    (command,) = [
        t
        for t in transmissions(record, PYGOBY, "ACOMMS_RAW_OUTGOING")
        if t.type == acomms_pb.DATA and t.ack_requested
    ]
    (ack,) = [
        t for t in transmissions(record, GOBY3, "ACOMMS_RAW_OUTGOING") if t.type == acomms_pb.ACK
    ]
    assert (ack.src, ack.dest) == (1, 2)
    first = command.frame_start
    assert list(ack.acked_frame) == list(range(first, first + len(command.frame)))
    assert parsed(acomms_pb.ModemTransmission, posts(record, PYGOBY, "ACOMMS_ACK")[0]) == ack


PEER = {GOBY3: PYGOBY, PYGOBY: GOBY3}


def without_time(t: acomms_pb.ModemTransmission) -> acomms_pb.ModemTransmission:
    t.ClearField("time")
    return t


@pytest.mark.parametrize("side", [PYGOBY, GOBY3])
@pytest.mark.parametrize("link", UDP_LINKS)
def test_pygoby_udp_driver_in_either_place_receives_and_acks_as_recorded(link, side):
    """The other side's datagrams through a real loopback socket into a pygoby UDP driver with
    `side`'s modem id: the same transmissions as that side reported received, and the
    acknowledgements that side sent (their time aside), each reported as a transmission too
    (ACOMMS_MODEM_TRANSMIT, as goby3 does)."""
    record = RECORDS[link]
    modem_id = record[f"{side}_modem_id"]
    peer = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    peer.bind(("127.0.0.1", 0))
    peer.settimeout(5)
    cfg = acomms_pb.DriverConfig(modem_id=modem_id)
    udp = cfg.Extensions[acomms_pb.UDP_CONFIG]
    udp.local.port = _free_port(socket.SOCK_DGRAM)
    udp.remote.add(modem_id=0, ip="127.0.0.1", port=peer.getsockname()[1])
    driver = UDPDriver(VirtualClock(1_700_000_000.0))
    received: list[acomms_pb.ModemTransmission] = []
    driver.signal_receive.connect(received.append)
    reported: list[acomms_pb.ModemTransmission] = []
    driver.signal_transmit_result.connect(reported.append)
    driver.startup(cfg)
    acks = []
    try:
        for text in posts(record, PEER[side], "ACOMMS_RAW_OUTGOING"):
            before = len(received)
            peer.sendto(raw_bytes(text), ("127.0.0.1", udp.local.port))
            deadline = time.monotonic() + 5
            while len(received) == before and time.monotonic() < deadline:
                driver.do_work()
            incoming = received[-1]
            if incoming.type == acomms_pb.DATA and incoming.ack_requested:
                acks.append(acomms_pb.ModemTransmission.FromString(peer.recvfrom(65536)[0]))
    finally:
        driver.shutdown()
        peer.close()
    heard = [
        parsed(acomms_pb.ModemTransmission, v) for v in posts(record, side, "ACOMMS_MODEM_RECEIVE")
    ]
    assert received == heard
    assert reported == acks
    then = [
        t for t in transmissions(record, side, "ACOMMS_RAW_OUTGOING") if t.type == acomms_pb.ACK
    ]
    assert acks and [without_time(t) for t in acks] == [without_time(t) for t in then]
    sent = [
        parsed(acomms_pb.ModemTransmission, v) for v in posts(record, side, "ACOMMS_MODEM_TRANSMIT")
    ]
    assert [t.type for t in sent].count(acomms_pb.ACK) == len(acks)


# ---------------------------------------------------------------------- Micro-Modem


def sentences(record: dict, side: str, var: str) -> list[tuple[float, NMEASentence]]:
    return [(e["t"], NMEASentence.parse(e["value"])) for e in record[side] if e["var"] == var]


# the fields holding a time of arrival or of transmission to 0.1 ms ($CACST, $CAXST): the
# recorded times of the host sentences (to 10 ms, as the MOOS client received them) move them
STAT_TIME_FIELD = {"$CACST": 3, "$CAXST": 3}


def stat_seconds(s: NMEASentence) -> float:
    """The seconds of day of a $CACST / $CAXST time field."""
    text = s[STAT_TIME_FIELD[s.fields[0]]]
    hhmmss = text[-11:]  # (a $CACST v6 field has the date in front)
    return int(hhmmss[:2]) * 3600 + int(hhmmss[2:4]) * 60 + float(hhmmss[4:])


def untimed(s: NMEASentence) -> tuple[str, ...]:
    index = STAT_TIME_FIELD.get(s.fields[0])
    return tuple(f for i, f in enumerate(s.fields) if i != index)


@pytest.mark.parametrize("link", MM_LINKS)
def test_mmsim_tells_both_hosts_what_they_read_in_the_run(link):
    """Both drivers' recorded sentences, from their start-up on and at their recorded times,
    into two of pygoby's Micro-Modem models 750 m apart on one channel (the run's mmsim): each
    model says to its host exactly what that host read in the run (the start-up and clock
    answers, cycles, data requests, echoes, receptions, acknowledgements, statistics), times
    of arrival and of transmission within 10 ms. goby3 cycles for the rate's 8 frames and ends
    each packet with an empty $CCTXD: the modem then asks for no more (QUIRKS.md Q-ACOMMS-16)."""
    record = RECORDS[link]
    zero = record["zero_time"]
    ids = {GOBY3: 1, PYGOBY: 2}
    host_lines = sorted(
        (e["t"], ids[side], order, NMEASentence.parse(e["value"]))
        for side in ids
        for order, e in enumerate(record[side])
        if e["var"] == "ACOMMS_NMEA_OUT"
    )
    clock = VirtualClock(zero + host_lines[0][0])
    timeline = Timeline(clock)
    channel = LoopbackChannel(clock, 750.0, 1500.0, timeline)
    said: dict[int, list[NMEASentence]] = {1: [], 2: []}
    models = {
        modem_id: MicroModemModel(
            modem_id,
            clock,
            channel,
            timeline=timeline,
            on_output=lambda s, out=said[modem_id]: out.append(NMEASentence.parse(s.message())),
        )
        for modem_id in (1, 2)
    }

    def run_until(t: float) -> None:
        while (due := timeline.next_time()) is not None and due <= t:
            clock.set(max(due, clock.now()))
            timeline.run_due()
        clock.set(max(t, clock.now()))

    for t, modem_id, _, sentence in host_lines:
        run_until(zero + t)
        models[modem_id].handle_sentence(sentence)
    run_until(zero + host_lines[-1][0] + 10)
    for side, modem_id in ids.items():
        read = [s for _, s in sentences(record, side, "ACOMMS_NMEA_IN")]
        assert [untimed(s) for s in said[modem_id]] == [untimed(s) for s in read]
        for ours, then in zip(said[modem_id], read, strict=True):
            if ours.fields[0] in STAT_TIME_FIELD:
                assert stat_seconds(ours) == pytest.approx(stat_seconds(then), abs=0.01)
    drqs = [s[6] for s in said[1] if s.fields[0] == "$CADRQ"]
    # two packets of one frame each; at rate 5 each ends with the empty $CCTXD for frame 2
    assert drqs == {"mm": ["1", "2", "1", "2"], "mm_rate0": ["1", "1"]}[link]


@pytest.mark.parametrize("link", MM_LINKS)
def test_goby3s_frames_cross_the_water_and_decode_to_what_pygoby_published(link):
    record = RECORDS[link]
    codec = codec_for(record)
    txd = [
        bytes.fromhex(s[4])
        for _, s in sentences(record, GOBY3, "ACOMMS_NMEA_OUT")
        if s.fields[0] == "$CCTXD" and s[4]
    ]
    rxd = [
        bytes.fromhex(s[5])
        for _, s in sentences(record, PYGOBY, "ACOMMS_NMEA_IN")
        if s.fields[0] == "$CARXD" and s[1] == "1"
    ]
    assert txd and rxd == txd
    decoded = decode_frames(codec, rxd)
    assert decoded == queue_received(record, PYGOBY, codec)
    assert b"".join(rxd) == b"".join(codec.encode(m) for m in decoded)


def without_statistics_only_receptions(received: list[Message]) -> list[Message]:
    """goby3's receptions as pygoby delivers them (QUIRKS.md Q-ACOMMS-17): a reception with no
    source, which goby3 publishes for a rate-0 cycle-init heard after one of its own slots had
    nothing to send, holds the cycle-init's statistics, which belong to the data reception
    that follows."""
    out: list[Message] = []
    pending: list = []
    for msg in received:
        stats = msg.Extensions[acomms_pb.MM_TRANSMISSION].receive_stat
        if not msg.HasField("src"):
            pending += list(stats)
            continue
        if pending:
            merged = list(pending) + list(stats)
            del stats[:]
            stats.extend(merged)
            pending = []
        out.append(msg)
    return out


TICK = 0.01  # s between the replayed driver's do_work calls (the records' time resolution)


def replay_mm_driver(record: dict, side: str) -> tuple[list[str], list[Message]]:
    """Everything `side`'s driver read in the run, from its start-up on, into a pygoby
    Micro-Modem driver of that side's configuration, sans-I/O at the recorded times; its
    transmissions are given the frames of the side's recorded ones. What the driver wrote, and
    the transmissions it reported received."""
    cfg = config_of(record, side)
    driver_cfg = acomms_pb.DriverConfig()
    driver_cfg.CopyFrom(cfg.driver_cfg)
    driver_cfg.modem_id = cfg.modem_id
    nmea = [e for e in record[side] if e["var"] in ("ACOMMS_NMEA_IN", "ACOMMS_NMEA_OUT")]
    clock = VirtualClock(record["zero_time"] + nmea[0]["t"])
    link = MemoryLink("\r")
    driver = MMDriver(clock, link)
    sent = [
        parsed(acomms_pb.ModemTransmission, v)
        for v in posts(record, side, "ACOMMS_MODEM_TRANSMIT")
        if "type: DATA" in v
    ]

    def fill(msg: acomms_pb.ModemTransmission) -> None:
        then = sent.pop(0)
        msg.dest, msg.ack_requested = then.dest, then.ack_requested
        msg.frame.extend(then.frame)

    driver.signal_data_request.connect(fill)
    heard: list[Message] = []
    driver.signal_receive.connect(heard.append)
    driver.startup(driver_cfg)
    written: list[str] = []
    for entry in nmea:  # in the order the side's app posted them
        while clock.now() + TICK < record["zero_time"] + entry["t"]:  # the app's ticks between
            clock.advance(TICK)
            driver.do_work()
            written += [w.rstrip("\r\n") for w in link.take_written()]
        clock.set(max(clock.now(), record["zero_time"] + entry["t"]))
        s = NMEASentence.parse(entry["value"])
        if entry["var"] == "ACOMMS_NMEA_IN":
            link.feed(s.message() + "\r")
        elif s.fields[0] == "$CCCYC" and s[2] == str(cfg.modem_id):  # the MAC opened a slot
            initiate = acomms_pb.ModemTransmission(src=cfg.modem_id, dest=-1, rate=int(s[4]))
            driver.handle_initiate_transmission(initiate)
        driver.do_work()
        written += [w.rstrip("\r\n") for w in link.take_written()]
    return written, heard


@pytest.mark.parametrize("side", [PYGOBY, GOBY3])
@pytest.mark.parametrize("link", MM_LINKS)
def test_pygoby_mm_driver_replayed_writes_and_hears_what_the_driver_did_in_the_run(link, side):
    """pygoby's driver in its own place and in goby3's, replayed from the start-up on
    (`replay_mm_driver`): it writes what that side's driver wrote then (start-up, clock
    setting, cycles, the data and the empty $CCTXD that ends each packet, no keep-alive while
    the modem talks) and hears what it heard (the data and acknowledgement, timed by the
    modem's statistics); the data pygoby sent are its encoding of the messages goby3
    decoded."""
    record = RECORDS[link]
    written, heard = replay_mm_driver(record, side)
    assert written == [s.message() for _, s in sentences(record, side, "ACOMMS_NMEA_OUT")]
    expected = without_statistics_only_receptions(
        [
            parsed(acomms_pb.ModemTransmission, v)
            for v in posts(record, side, "ACOMMS_MODEM_RECEIVE")
        ]
    )
    assert heard == expected
    assert {t.time_source for t in heard} == {acomms_pb.ModemTransmission.MODEM_TIME}
    if side == PYGOBY:
        codec = codec_for(record)
        frames = [bytes.fromhex(NMEASentence.parse(w)[4]) for w in written if "TXD" in w]
        theirs = queue_received(record, GOBY3, codec)
        assert b"".join(frames) == b"".join(codec.encode(m) for m in theirs)


# ---------------------------------------------------------------------- MOOS outputs

TRANSLATED = ("STATUS_REPORT_IN", "COMMAND_IN", "DESIRED_HEADING")


def translator_of(record: dict, codec: Codec) -> Translator:
    """pygoby's translator with the entries of the run's ProcessConfig blocks (the same in both
    communities' missions)."""
    block, goby3_block = record["process_config"][PYGOBY], record["process_config"][GOBY3]
    entries = "  translator_entry {"
    assert block[block.index(entries) :] == goby3_block[goby3_block.index(entries) :]
    entry_list = list(config_of(record).translator_entry)
    return Translator(entry_list, lambda name: codec.compiled(name).cls)


def published(translator: Translator, messages: list[Message]) -> list[tuple[str, object]]:
    return [
        (post.var, post.value)
        for msg in messages
        for post in translator.publish(msg)
        if post.var in TRANSLATED
    ]


def recorded_translations(record: dict, side: str) -> list[tuple[str, object]]:
    return [(e["var"], e["value"]) for e in record[side] if e["var"] in TRANSLATED]


@pytest.mark.parametrize("link", list(RECORDS))
def test_both_sides_published_what_pygobys_translator_makes_of_the_messages(link):
    """Each side's STATUS_REPORT_IN, COMMAND_IN and DESIRED_HEADING, from the messages it
    decoded: pygoby's as recorded, and goby3's the same as pygoby's translator makes."""
    record = RECORDS[link]
    codec = codec_for(record)
    translator = translator_of(record, codec)
    for side in (PYGOBY, GOBY3):
        ours = published(translator, queue_received(record, side, codec))
        assert ours and sorted(ours, key=str) == sorted(
            recorded_translations(record, side), key=str
        )


@pytest.mark.e2e
@pytest.mark.parametrize("link", UDP_LINKS)
async def test_pygoby_pacommshandler_publishes_the_record_from_goby3s_datagrams(link, tmp_path):
    """pygoby's pAcommsHandler from the run's own ProcessConfig block, on a MOOSDB, with goby3's
    recorded datagrams sent to its UDP port from a real socket: it posts what it posted in
    the run for them (the translator's variables, the decoded messages and the received
    transmissions, goby3's acknowledgement among them)."""
    record = RECORDS[link]
    peer = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    peer.bind(("127.0.0.1", 0))
    local = _free_port(socket.SOCK_DGRAM)
    block = (
        record["process_config"][PYGOBY]
        .replace("{local_port}", str(local))
        .replace("{remote_port}", str(peer.getsockname()[1]))
        .replace('load_proto_file: "two_vehicles.proto"', f'load_proto_file: "{PROTO}"')
    )
    # (not ACOMMS_ACK: goby3's acknowledgement names a frame of the run, which this app never
    # sent; the ACK itself is among the received transmissions)
    compared = ("ACOMMS_MODEM_RECEIVE", "ACOMMS_QUEUE_RECEIVE", *TRANSLATED)
    async with contextlib.AsyncExitStack() as stack:
        stack.callback(peer.close)
        db = await start_db(stack, 2, warp=1)
        mission = tmp_path / "vehicle2.moos"
        mission.write_text(f"ServerHost = localhost\nServerPort = {db.port}\n{block}")
        recorder = Recorder("recorder", db.port)
        await recorder.start(list(compared))
        stack.push_async_callback(recorder.close)
        app = pAcommsHandler.from_mission(mission, "pAcommsHandler")
        await stack.enter_async_context(app)
        async with asyncio.timeout(10):
            while not app.acomms.primary.running:
                await asyncio.sleep(0.05)
        for text in posts(record, GOBY3, "ACOMMS_RAW_OUTGOING"):
            peer.sendto(raw_bytes(text), ("127.0.0.1", local))
        expected = {var: posts(record, PYGOBY, var) for var in compared}
        async with asyncio.timeout(10):
            while any(len(recorder.values(v)) < len(expected[v]) for v in compared):
                await asyncio.sleep(0.05)
        await asyncio.sleep(0.2)  # (nothing more may come)
    assert {var: recorder.values(var) for var in compared} == expected


@pytest.mark.parametrize("link", list(RECORDS))
def test_both_sides_post_the_same_variables_as_often(link):
    """The exchange is symmetric, and so are the two pAcommsHandlers' posts: each watched
    variable as often on both sides, and on the Micro-Modem the same sentences each way
    (goby3's keep-alive waits while the modem talks, and so does pygoby's). goby3's one extra
    post: a reception holding only a cycle-init's statistics (QUIRKS.md Q-ACOMMS-17)."""
    record = RECORDS[link]

    def counts(side: str) -> Counter:
        return Counter(e["var"] for e in record[side])

    quirk = Counter(  # goby3's receptions holding only statistics (QUIRKS.md Q-ACOMMS-17)
        e["var"]
        for e in record[GOBY3]
        if e["var"] == "ACOMMS_MODEM_RECEIVE" and " src: " not in e["value"]
    )
    assert counts(GOBY3) - quirk == counts(PYGOBY)
    assert sum(quirk.values()) == (1 if link == "mm_rate0" else 0)
    if link.startswith("mm"):

        def talkers(side: str) -> Counter:
            nmea = ("ACOMMS_NMEA_IN", "ACOMMS_NMEA_OUT")
            return Counter(e["value"].split(",")[0] for e in record[side] if e["var"] in nmea)

        assert talkers(GOBY3) == talkers(PYGOBY)


@pytest.mark.parametrize("link", UDP_LINKS)
def test_both_sides_post_the_same_raw_bytes_goby3_as_text_pygoby_as_binary(link):
    """The datagrams on ACOMMS_NMEA_OUT are the same bytes, goby3's as a MOOS string and
    pygoby's as a MOOS binary string (QUIRKS.md Q-APPS-32)."""
    record = RECORDS[link]
    for side, kind in ((GOBY3, "string"), (PYGOBY, "binary")):
        out = [e for e in record[side] if e["var"] == "ACOMMS_NMEA_OUT"]
        assert {e["type"] for e in out} == {kind}
        as_bytes = [
            bytes.fromhex(e["value"])
            if kind == "binary"
            else e["value"].encode("utf-8", "surrogateescape")
            for e in out
        ]
        assert as_bytes == [raw_bytes(t) for t in posts(record, side, "ACOMMS_RAW_OUTGOING")]
