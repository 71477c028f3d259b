"""Writes acomms.alog: a handmade log of the acomms.moos mission, its values made by pygoby's own
DCCL encoder and translator serializers (so the decoding tests read what pygoby writes).

    cd tests/data/alog && PYTHONPATH=../../../src python make_acomms_alog.py
"""

from __future__ import annotations

from pygoby.acomms import messages as acomms_pb
from pygoby.dccl import Codec
from pygoby.moos.alog.format import AlogFormatter, banner
from pygoby.moos.translator import Technique, serialize_protobuf
from pygoby.moos.translator.keyvalue import serialize as key_values
from pygoby.moos.translator.textformat import message_text
from pygoby.protobuf import ProtoLoader

LOG_START = 1764643673.12
CST = (  # a version-0 $CACST: 4 good frames heard from modem 2 at SNR in/out 14/11 dB, MSE -12
    "$CACST,0,034800.0000,1,1000,40,200,150,0,0,0,0,0,1,2,1,0,2,4,0,20,14,11,200,-12,180,0.3,"
    "10,25120,5000"
)

loader = ProtoLoader()
loader.load_file("status.proto")
Status = loader.message_class("logtest.Status")
codec = Codec(loader=loader)
codec.load(Status)
first = codec.encode(Status(src=2, depth=5.0, tags=[1, 4]))
second = codec.encode(Status(src=3, depth=12.5))
received = acomms_pb.ModemTransmission(src=2, dest=1, type=acomms_pb.DATA, time=1764643680_000000)
received.frame.append(first + second)  # two messages packed in one frame, as the queue packs
received.frame.append(first[:2])  # a cut message: undecodable
sent = acomms_pb.ModemTransmission(src=1, dest=2, type=acomms_pb.DATA, time=1764643685_000000)
sent.frame.append(second)
published = Status(src=4, depth=7.5, tags=[2])

entries: list[tuple] = [  # (name, source, value[, community])
    ("NAV_X", "uSimVehicle", 12.5),
    (
        "AC_MODEM_RECEIVE",
        "pAcommsHandler",
        'src: 2 dest: 1 type: DATA frame: "\\001\\253" frame: "" '
        "[goby.acomms.micromodem.protobuf.transmission] "
        "{ receive_stat { mode: RECEIVE_GOOD mse_equalizer: -12 } }",
    ),
    ("AC_QSIZE", "pAcommsHandler", "dccl_id: 20 size: 3"),
    ("AC_QUEUE_RECEIVE", "pAcommsHandler", "@PB[logtest.Status] src: 2 depth: 5 tags: 1 tags: 4"),
    ("AC_QUEUE_RECEIVE", "pAcommsHandler", "@PB[logtest.Unknown] src: 2"),
    ("AC_MODEM_RECEIVE", "pAcommsHandler", "this is not protobuf text"),
    ("ACOMMS_QSIZE", "pAcommsHandler", "dccl_id: 20 size: 9"),
    ("AC_MODEM_RECEIVE", "pAcommsHandler", message_text(received)),
    ("AC_MODEM_TRANSMIT", "pAcommsHandler", message_text(sent)),
    ("AC_RAW_INCOMING", "pAcommsHandler", message_text(acomms_pb.ModemRaw(raw=CST.encode()))),
    ("STATUS_OUT", "uCommand", "src=4,depth=7.5,tags=2"),
    ("STATUS_IN", "pAcommsHandler", serialize_protobuf(published, Technique(5))),
    ("PT_DEPTH", "uSimVehicle", "depth=3.25"),
    ("PT_STATUS_TEXT", "pTranslator", message_text(published)),
    ("PT_STATUS_HEX", "pTranslator", serialize_protobuf(published, Technique(6))),
    ("PT_STATUS_BIN", "pTranslator", serialize_protobuf(published, Technique(8))),
    ("PT_STATUS_KV", "pTranslator", key_values(published)),
    ("PT_STATUS_FMT", "pTranslator", "src=4;depth=7.5"),
    ("PT_STATUS_FMT", "pTranslator", "no match here"),
    # for `pygoby log plot`: the modem id, acks and expiries, a track
    ("MODEM_ID", "pAcommsHandler", 1.0),
    ("AC_ACK_ORIGINAL", "pAcommsHandler", serialize_protobuf(published, Technique(5))),
    ("AC_EXPIRE", "pAcommsHandler", serialize_protobuf(published, Technique(5))),
    ("AC_ACK_ORIGINAL", "pAcommsHandler", serialize_protobuf(published, Technique(5))),
    ("NAV_Y", "uSimVehicle", -4.0),
    ("NAV_X", "uSimVehicle", 13.5),
    ("NAV_Y", "uSimVehicle", -3.0),
    ("NAV_X", "uSimVehicle", 14.5),
    ("NAV_X", "uSimVehicle", 99.0, "other"),  # forwarded from another community: not ours
    ("AC_MODEM_RECEIVE", "pAcommsHandler", message_text(received)),
    ("AC_RAW_INCOMING", "pAcommsHandler", 'raw: "$CACST,not,a,statistics,line"'),
]

# pLogger's MarkDataType: without it a string that looks like a number (a hex value can) is
# read back as a double
formatter = AlogFormatter(
    0.0, mark_external=True, own_community="logtest", mark_data_type=True, mark_binary=True
)
with open("acomms.alog", "w") as out:
    out.write(
        banner("acomms.alog", LOG_START, opened_on=LOG_START, mark_data_type=True, mark_binary=True)
    )
    for index, (name, source, value, *community) in enumerate(entries):
        out.write(formatter.line(0.5 * (index + 1), name, source, value, "", *community))
