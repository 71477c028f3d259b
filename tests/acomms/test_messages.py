"""Our acomms .proto files: names, numbers and defaults as the spec lists them, and wire format."""

from pygoby.acomms import messages as acomms_pb


def _numbers(cls) -> dict[str, int]:
    return {f.name: f.number for f in cls.DESCRIPTOR.fields}


def test_modem_transmission_fields_and_defaults():
    assert _numbers(acomms_pb.ModemTransmission) == {
        "src": 1,
        "dest": 2,
        "time": 3,
        "time_source": 5,
        "rate": 6,
        "type": 7,
        "max_num_frames": 11,
        "max_frame_bytes": 12,
        "ack_requested": 13,
        "frame": 14,
        "frame_start": 15,
        "acked_frame": 20,
        "slot_seconds": 30,
        "unique_id": 31,
        "always_initiate": 32,
        "slot_index": 33,
    }
    t = acomms_pb.ModemTransmission()
    assert (t.src, t.dest, t.rate, t.type, t.max_num_frames) == (-1, -1, 0, acomms_pb.DATA, 1)
    assert t.ack_requested is True and t.slot_seconds == 10
    assert t.time_source == acomms_pb.ModemTransmission.GOBY_TIME


def test_udp_example_bytes_match_protobuf_wire_format():
    # spec §8.2 example datagram 1; the field tags are those of goby3's modem_message.proto
    t = acomms_pb.ModemTransmission(
        src=1,
        dest=2,
        rate=0,
        type=acomms_pb.DATA,
        max_frame_bytes=1400,
        ack_requested=True,
        frame_start=7,
    )
    t.frame.append(b"\x01\x02\x03\x04\x05")
    wire = t.SerializeToString()
    assert wire.startswith(b"\x08\x01\x10\x02")  # field 1 varint 1, field 2 varint 2
    assert b"\x60\xf8\x0a" in wire  # field 12 varint 1400
    assert b"\x72\x05\x01\x02\x03\x04\x05" in wire  # field 14 bytes
    assert b"\x78\x07" in wire  # field 15 varint 7
    back = acomms_pb.ModemTransmission.FromString(wire)
    assert back == t


def test_micromodem_extension_round_trip():
    t = acomms_pb.ModemTransmission(type=acomms_pb.DRIVER_SPECIFIC)
    ext = t.Extensions[acomms_pb.MM_TRANSMISSION]
    ext.type = acomms_pb.MICROMODEM_TWO_WAY_PING
    ext.ranging_reply.one_way_travel_time.append(0.5)
    back = acomms_pb.ModemTransmission.FromString(t.SerializeToString())
    assert back.Extensions[acomms_pb.MM_TRANSMISSION].ranging_reply.one_way_travel_time == [0.5]
    assert acomms_pb.MM_TRANSMISSION.number == 1000 and acomms_pb.UDP_CONFIG.number == 1341


def test_queue_entry_defaults():
    e = acomms_pb.QueuedMessageEntry(protobuf_name="x.Y")
    assert (e.ack, e.blackout_time, e.max_queue, e.newest_first, e.ttl, e.value_base) == (
        True,
        0,
        100,
        True,
        1800,
        1.0,
    )
    assert acomms_pb.DriverConfig().line_delimiter == "\r\n"
    assert acomms_pb.DriverConfig().reconnect_interval == 10
