"""A Goby 1.1 vehicle and a pygoby one on one emulated acoustic channel: the 1.1 side sends
frames recorded from the real Goby 1.1.2 libdccl; pygoby's pAcommsHandler (a Goby 1.1
configuration) receives them through its emulated Micro-Modem and publishes them as the XML
says, and its own SIMPLE_STATUS reaches the 1.1 side in Goby 1.1's bytes."""

from __future__ import annotations

import asyncio
import contextlib
import json
from pathlib import Path

from google.protobuf import text_format

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.mmsim import LoopbackChannel
from pygoby.acomms.mmsim.channel import AcousticPacket, ModemPacketKind, ModemReception
from pygoby.apps.pacommshandler import pAcommsHandler
from pygoby.dccl.dccl1 import Dccl1Codec, stitch, unstitch
from pygoby.dccl.xml import load_message_set
from pygoby.moos.client import MOOSClient
from tests.apps.acomms_mission import (
    WARP,
    Recorder,
    mission_clock,
    modem_and_db,
    two_vehicle_missions,
)
from tests.goby11.missions import micromodem_driver_goby11
from tests.goby11.seed_listings import EXAMPLES

DATA = Path(__file__).parents[1] / "data" / "vectors" / "goby11-dccl1"
SIMPLE_STATUS = DATA / "xml" / "simple_status.xml"
GOBY11_ID = 14  # the recorded vectors below were sent by modem 14


def recorded(case: str) -> dict:
    for line in (DATA / "vectors.jsonl").read_text().splitlines():
        vector = json.loads(line)
        if vector["message"] == "SIMPLE_STATUS" and vector["case"] == case:
            assert vector["src"] == GOBY11_ID and vector["dest"] == 2
            assert vector["passphrase"] is None
            return vector
    raise LookupError(case)


class Goby11Vehicle:
    """The Goby 1.1 side on the acoustic channel: sends the frames it is given, keeps the
    frames it hears."""

    def __init__(self, clock, channel) -> None:
        self.clock, self.channel = clock, channel
        self.heard: list[AcousticPacket] = []
        channel.attach(self)

    @property
    def modem_id(self) -> int:
        return GOBY11_ID

    @property
    def name(self) -> str:
        return "goby11"

    def detect(self, packet: AcousticPacket, arrival: float) -> None:
        pass

    def receive(self, packet: AcousticPacket, reception: ModemReception) -> None:
        self.heard.append(packet)

    def send(self, frame: bytes, dest: int) -> None:
        packet = AcousticPacket(
            ModemPacketKind.DATA, GOBY11_ID, dest, rate=1, frames=[frame], tx_time=self.clock.now()
        )
        packet.duration = 1.0
        self.channel.transmit(self, packet)


def mission(db_port: int, modem_port: int) -> str:
    return f"""ServerHost = localhost
ServerPort = {db_port}
Community = mm2
MOOSTimeWarp = {WARP}
modem_id_lookup_path = {EXAMPLES}/MOOS/ccl_and_dccl/modemidlookup.txt

ProcessConfig = pAcommsHandler
{{
  common
  {{
    verbosity: VERBOSITY_WARN
    log: false
    app_tick: 20
    initializer {{ type: INI_STRING moos_var: "VEHICLE_NAME" sval: "mm2" }}
    initializer {{ type: INI_DOUBLE moos_var: "NAV_X" dval: 120 }}
    initializer {{ type: INI_DOUBLE moos_var: "NAV_Y" dval: -40 }}
    initializer {{ type: INI_DOUBLE moos_var: "NAV_HEADING" dval: 90 }}
    initializer {{ type: INI_DOUBLE moos_var: "NAV_SPEED" dval: 1.2 }}
    initializer {{ type: INI_DOUBLE moos_var: "NAV_DEPTH" dval: 7 }}
  }}
  modem_id: 2
{micromodem_driver_goby11(modem_port)}
  mac_cfg
  {{
    type: MAC_FIXED_DECENTRALIZED
    slot {{ src: 2 dest: {GOBY11_ID} rate: 1 type: SLOT_DATA slot_seconds: 3 }}
  }}
  dccl_cfg {{ message_file {{ path: "{SIMPLE_STATUS}" }} }}
}}
"""


def status_fields(value: str) -> dict[str, str]:
    return dict(item.split("=", 1) for item in value.split(","))


async def test_recorded_goby11_frames_in_and_goby11_bytes_out(tmp_path):
    clock = mission_clock()
    channel = LoopbackChannel(clock, range_m=150)  # 0.1 s away
    goby11 = Goby11Vehicle(clock, channel)
    async with contextlib.AsyncExitStack() as stack:
        sim, db = await modem_and_db(stack, 2, channel, clock)
        path = tmp_path / "mm2.moos"
        path.write_text(mission(db.port, sim.port))
        app = pAcommsHandler.from_mission(path, "pAcommsHandler")
        recorder = Recorder("recorder", db.port, clock)
        await recorder.start(["STATUS_REPORT_IN"])
        stack.push_async_callback(recorder.close)
        await stack.enter_async_context(app)
        await asyncio.sleep(0.5)  # the driver is up

        # a frame of one message, exactly as Goby 1.1.2 wrote it
        first = recorded("random3")
        goby11.send(bytes.fromhex(first["hex"]), 2)
        report = status_fields(
            await recorder.wait_for("STATUS_REPORT_IN", lambda v: "nav_x=-56144" in v)
        )
        expected = first["decoded"]["values"]
        assert (report["Node"], report["nav_y"], report["Speed"], report["Heading"]) == (
            str(GOBY11_ID),
            str(expected["nav_y"]),
            str(expected["Speed"]),
            str(expected["Heading"]),
        )
        # two recorded messages stitched into one frame as Goby 1.1's queue does
        second = recorded("hdr_time_half_even")
        count = len(recorder.values("STATUS_REPORT_IN"))
        goby11.send(
            stitch([(bytes.fromhex(first["hex"]), 2), (bytes.fromhex(second["hex"]), 2)]), 2
        )
        await recorder.wait_for("STATUS_REPORT_IN", lambda v: "nav_x=64281" in v, start=count)
        assert any("nav_x=-56144" in v for v in recorder.values("STATUS_REPORT_IN")[count:])

        # pygoby's answer, heard by the 1.1 side, in Goby 1.1's bytes
        async with asyncio.timeout(30):
            while not any(p.kind is ModemPacketKind.DATA and p.frames for p in goby11.heard):
                await asyncio.sleep(0.05)
    frame = next(p for p in goby11.heard if p.kind is ModemPacketKind.DATA and p.frames).frames[0]
    assert frame[0] == 0x20
    codec = Dccl1Codec()  # a Goby 1.1 node with no passphrase configured
    codec.load(load_message_set(SIMPLE_STATUS))
    decoded = [codec.decode(part.data) for part in unstitch(frame)]
    assert {(d.message, d.header.src) for d in decoded} == {("SIMPLE_STATUS", 2)}
    assert (decoded[0].values["nav_x"], decoded[0].values["Speed"]) == (120, 1.2)
    assert decoded[0].values["Heading"] == 90


EXAMPLE1 = DATA / "xml" / "example1.xml"


EXPIRING = """<?xml version="1.0"?>
<message_set><message><name>Expiring</name><id>5</id><size>8</size>
  <trigger>publish</trigger><trigger_var>EXPIRE_ME</trigger_var>
  <header><dest_id><name>Dest</name></dest_id></header>
  <layout><bool><name>b</name></bool></layout>
  <queuing><ttl>1</ttl></queuing>
</message></message_set>
"""


def command_mission(modem_id: int, db_port: int, modem_port: int, expiring: Path) -> str:
    """The Goby 1.1 manual's example1.xml (GoToCommand: acked, as 1.1.2's <queuing> default),
    SIMPLE_STATUS and a message with a ttl of 1 s on two nodes."""
    return f"""ServerHost = localhost
ServerPort = {db_port}
Community = mm{modem_id}
MOOSTimeWarp = {WARP}
modem_id_lookup_path = {EXAMPLES}/MOOS/ccl_and_dccl/modemidlookup.txt

ProcessConfig = pAcommsHandler
{{
  common {{ verbosity: VERBOSITY_WARN log: false app_tick: 20 }}
  modem_id: {modem_id}
{micromodem_driver_goby11(modem_port)}
  mac_cfg
  {{
    type: MAC_FIXED_DECENTRALIZED
    slot {{ src: 1 dest: 2 rate: 1 type: SLOT_DATA slot_seconds: 3 }}
  }}
  dccl_cfg
  {{
    message_file {{ path: "{EXAMPLE1}" }}
    message_file {{ path: "{SIMPLE_STATUS}" }}
    message_file {{ path: "{expiring}" }}
  }}
}}
"""


def goby11_text(value: str, cls):
    out = cls()
    text_format.Parse(value, out)
    return out


async def test_goby11_moos_interface_of_dccl_messages(tmp_path):
    """ACOMMS_OUTGOING_DATA / OUT_GOTOCOMMAND_HEX_32B on the sender, ACOMMS_INCOMING_DATA /
    IN_GOTOCOMMAND_HEX_32B on the receiver, 1.1's ModemDataAck and QueueSize,
    ACOMMS_FLUSH_QUEUE in 1.1's comma-equals form, a message handed in on the IN_ variable."""
    watched = [
        "ACOMMS_OUTGOING_DATA",
        "OUT_GOTOCOMMAND_HEX_32B",
        "ACOMMS_INCOMING_DATA",
        "IN_GOTOCOMMAND_HEX_32B",
        "INCOMING_COMMAND",
        "ACOMMS_ACK",
        "ACOMMS_QSIZE",
        "ACOMMS_EXPIRE",
    ]
    clock = mission_clock()
    channel = LoopbackChannel(clock, range_m=150)
    expiring = tmp_path / "expiring.xml"
    expiring.write_text(EXPIRING)

    def mission_file(modem_id: int, db_port: int, modem_port: int) -> str:
        return command_mission(modem_id, db_port, modem_port, expiring)

    async with two_vehicle_missions(tmp_path, mission_file, watched, channel, clock) as (
        apps,
        recorders,
    ):
        mm1, _ = apps
        sender, receiver = recorders
        async with MOOSClient("operator", port=mm1.client.port, clock=clock) as operator:
            operator.publish(
                "OUTGOING_COMMAND", "CommandType=GoTo,Destination=2,goto_x=10,goto_speed=1.5"
            )
            await operator.flush()
        outgoing = goby11_text(
            await sender.wait_for("OUT_GOTOCOMMAND_HEX_32B"), acomms_pb.V1ModemDataTransmission
        )
        assert outgoing.data[0] == 0x20 and outgoing.queue_key.id == 1
        assert (
            sender.values("ACOMMS_OUTGOING_DATA")[0] == sender.values("OUT_GOTOCOMMAND_HEX_32B")[0]
        )
        await receiver.wait_for("INCOMING_COMMAND", lambda v: "goto_x=10" in v)
        incoming = goby11_text(
            await receiver.wait_for("IN_GOTOCOMMAND_HEX_32B"), acomms_pb.V1ModemDataTransmission
        )
        assert incoming.data == outgoing.data and incoming.base.src == 1
        ack = goby11_text(await sender.wait_for("ACOMMS_ACK"), acomms_pb.V1ModemDataAck)
        assert (ack.base.src, ack.orig_msg.data) == (2, outgoing.data)
        sizes = [goby11_text(v, acomms_pb.V1QueueSize) for v in sender.values("ACOMMS_QSIZE")]
        assert (acomms_pb.QUEUE_DCCL, 1, 1) in {(s.key.type, s.key.id, s.size) for s in sizes}

        # SIMPLE_STATUS (id 20) queues every 5 s, sent one per slot at most: flush it 1.1's way
        async with MOOSClient("operator", port=mm1.client.port, clock=clock) as operator:
            start = len(sender.values("ACOMMS_QSIZE"))
            await sender.wait_for(
                "ACOMMS_QSIZE", lambda v: "id: 20" in v and "size: 0" not in v, timeout=15
            )
            operator.publish("ACOMMS_FLUSH_QUEUE", "key_type=QUEUE_DCCL,key_id=20")
            await operator.flush()
            await sender.wait_for(
                "ACOMMS_QSIZE", lambda v: "id: 20" in v and "size: 0" in v, start=start
            )

        # for modem 5, which no slot serves: expires after its ttl of 1 s
        async with MOOSClient("operator", port=mm1.client.port, clock=clock) as operator:
            operator.publish("EXPIRE_ME", "Dest=5,b=true")
            await operator.flush()
        expired = goby11_text(await sender.wait_for("ACOMMS_EXPIRE"), acomms_pb.V1ModemDataExpire)
        assert expired.orig_msg.queue_key.id == 5 and expired.orig_msg.data[0] == 0x20
        assert expired.orig_msg.base.dest == 5

        # a received message handed in by another process (as 1.1's tcp_share did)
        count = len(receiver.values("INCOMING_COMMAND"))
        async with MOOSClient("share", port=apps[1].client.port, clock=clock) as share:
            command = mm1.messages.loader.message_class("GoToCommand")
            handed = acomms_pb.V1ModemDataTransmission(
                data=mm1.queue.dccl1.encode(command(goto_x=77, Destination=2, _src_id=1))
            )
            share.publish(
                "IN_GOTOCOMMAND_HEX_32B", text_format.MessageToString(handed, as_one_line=True)
            )
            await share.flush()
        await receiver.wait_for("INCOMING_COMMAND", lambda v: "goto_x=77" in v, start=count)


def test_liaison_names_goby11_frames_and_reads_goby11_queue_sizes():
    from pygoby.moos import protocol
    from pygoby.moosacomms.transitional import TransitionalMessages
    from pygoby.protobuf import ProtoLoader, builtin_class
    from pygoby.topside.liaison.models import AcommsModel

    cfg = builtin_class(
        "goby/apps/moos/protobuf/pAcommsHandler_config.proto",
        "goby.apps.moos.protobuf.pAcommsHandlerConfig",
    )(modem_id=2)
    cfg.transitional_cfg.message_file.add(path=str(SIMPLE_STATUS))
    loader = ProtoLoader()
    TransitionalMessages.expand(cfg, loader)
    model = AcommsModel(cfg, loader.message_class, now=0.0)
    size = acomms_pb.V1QueueSize(size=3)
    size.key.type, size.key.id = acomms_pb.QUEUE_DCCL, 20
    model.handle(
        protocol.notify(
            "ACOMMS_QSIZE", text_format.MessageToString(size, as_one_line=True), time=1.0
        )
    )
    assert model.queues["SIMPLE_STATUS"].size == 3
    frame = bytes.fromhex(recorded("random3")["hex"])
    transmission = acomms_pb.ModemTransmission(frame=[stitch([(frame, 2), (frame, 2)])])
    assert model._messages_in(transmission) == ["SIMPLE_STATUS", "SIMPLE_STATUS"]


def test_goby11_configuration_speaks_dccl1_unless_told_dccl_v2(tmp_path):
    """The default for a Goby 1.1 configuration, and the one setting that keeps Goby 2's bytes."""
    path = tmp_path / "mm2.moos"
    apps = []
    for setting in ("", "transitional_cfg { wire_format: DCCL_V2 }"):
        text = mission(9000, 9001).replace("dccl_cfg {", f"{setting}\n  dccl_cfg {{")
        path.write_text(text)
        apps.append(pAcommsHandler.from_mission(path, "pAcommsHandler"))
    goby11, goby2 = apps
    assert goby11.queue.dccl1 is not None and goby2.queue.dccl1 is None
    status = goby11.messages.loader.message_class("SIMPLE_STATUS")(nav_x=5, Timestamp=0, Node=2)
    goby11.queue.push_message(status)
    goby2.queue.push_message(status)
    (sent11,) = goby11.queue.queues[20].items()
    (sent2,) = goby2.queue.queues[20].items()
    assert sent11.encoded[0] == 0x20 and sent2.encoded[0] == 20 << 1  # DCCL v2's id byte
    assert goby11.queue.dccl1.decode(sent11.encoded).nav_x == 5
    assert goby2.acomms.codec.decode(sent2.encoded).nav_x == 5
