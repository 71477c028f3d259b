"""Micro-Modem driver as a sans-I/O state machine: MemoryLink + VirtualClock, scripted modem."""

import logging

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.driver_base import ModemDriverError
from pygoby.acomms.drivers.micromodem import MMDriver
from pygoby.util.clock import VirtualClock
from pygoby.util.linebased import MemoryLink
from pygoby.util.nmea import NMEASentence
from tests.hypothesis_profiles import examples

T0 = 1_700_000_000.0  # 2023-11-14T22:13:20Z


def cs(body: str) -> str:
    return NMEASentence.parse(body).message()


class Harness:
    def __init__(self, modem_id=1, **mm):
        self.clock = VirtualClock(T0)
        self.link = MemoryLink("\r")
        self.driver = MMDriver(self.clock, self.link)
        self.received, self.results = [], []
        self.driver.signal_receive.connect(self.received.append)
        self.driver.signal_transmit_result.connect(self.results.append)
        self.cfg = acomms_pb.DriverConfig(
            driver_type=acomms_pb.DriverConfig.DESCRIPTOR.fields_by_name["driver_type"]
            .enum_type.values_by_name["DRIVER_WHOI_MICROMODEM"]
            .number,
            modem_id=modem_id,
        )
        self.cfg.Extensions[acomms_pb.MM_CONFIG].query_cfg_on_startup = mm.pop("query", False)
        for k, v in mm.items():
            setattr(self.cfg.Extensions[acomms_pb.MM_CONFIG], k, v)

    def work(self):
        self.driver.do_work()
        return [line.rstrip("\r\n") for line in self.link.take_written()]

    def modem(self, *lines):
        for line in lines:
            self.link.feed(cs(line) + "\r")
        return self.work()

    def start(self):
        d = self.driver
        d.startup(self.cfg)
        mid = self.cfg.modem_id
        assert self.work() == [cs("$CCCFG,CST,1")]
        assert self.modem("$CACFG,CST,1") == [cs(f"$CCCFG,SRC,{mid}")]
        assert self.modem(f"$CACFG,SRC,{mid}") == [cs("$CCCFG,REV,1")]
        assert self.modem("$CACFG,REV,1") == [cs("$CCCFG,RXP,1")]
        assert self.modem("$CACFG,RXP,1") == [cs(f"$CCMSC,{mid},{mid},0")]
        # goby3's first keep-alive, queued behind $CCMSC (the revision is not known yet)
        assert self.modem("$CAREV,000000,AUV,0.94.0.00") == [cs("$CCCFQ,SRC")]
        assert self.modem(f"$CACFG,SRC,{mid}") == []  # waits for 50-100 ms past a second
        self.clock.set(T0 + 0.07)
        assert self.work() == [cs("$CCCLK,2023,11,14,22,13,21")]
        self.clock.set(T0 + 1.0)
        assert self.modem("$CACLK,2023,11,14,22,13,21") == []
        assert d.startup_complete
        return self


def test_startup_sequence_matches_spec_trace():
    h = Harness(modem_id=1).start()
    assert h.driver.revision == (0, 94, 0)
    assert h.driver.nvram == {"CST": 1, "SRC": 1, "REV": 1, "RXP": 1}


def test_startup_queries_all_nvram_until_two_seconds_of_silence():
    h = Harness(query=True)
    h.driver.startup(h.cfg)
    h.work()
    for reply in ["$CACFG,CST,1", "$CACFG,SRC,1", "$CACFG,REV,1", "$CACFG,RXP,1"]:
        h.modem(reply)
    assert h.modem("$CAREV,000000,AUV,2.0.16421") == [cs("$CCCFQ,SRC")]  # first keep-alive
    h.modem("$CACFG,SRC,1")
    h.clock.set(T0 + 0.06)
    assert h.work() == [cs("$CCTMS,2023-11-14T22:13:21Z,0")]  # MM2 clock command
    h.clock.set(T0 + 0.5)
    assert h.modem("$CATMS,0,2023-11-14T22:13:20.5Z") == [cs("$CCCFQ,TOP")]
    h.modem("$CACFG,AGC,0", "$CACFG,AGN,250")
    h.clock.advance(1.5)
    h.modem("$CACFG,BND,3")
    h.clock.advance(1.5)
    assert h.work() == [] and not h.driver.startup_complete
    h.clock.advance(1.0)
    h.work()
    assert h.driver.startup_complete and h.driver.nvram["AGN"] == 250


def test_nvram_cfg_entries_and_reset():
    h = Harness(reset_nvram=True)
    h.cfg.Extensions[acomms_pb.MM_CONFIG].nvram_cfg.extend(
        ["dqf,1", "psk.packet.mod_hdr_version,1"]
    )
    h.driver.startup(h.cfg)
    sent = []
    for _ in range(5):
        line = h.work()
        sent += line
        if line:
            s = NMEASentence.parse(line[0])
            h.link.feed(cs("$CACFG," + ",".join(s.fields[1:])) + "\r")
    assert sent == [
        cs(x)
        for x in [
            "$CCCFG,ALL,0",
            "$CCCFG,CST,1",
            "$CCCFG,DQF,1",
            "$CCCFG,psk.packet.mod_hdr_version,1",
            "$CCCFG,SRC,1",
        ]
    ]


def test_local_data_transmission_rate0_with_ack():
    h = Harness().start()
    requests = []

    def fill(msg):
        requests.append((msg.max_num_frames, msg.max_frame_bytes))
        msg.dest = 2
        msg.frame.append(b"\x01\x02\x03\x04\x05")

    h.driver.signal_data_request.connect(fill)
    h.driver.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=-1, rate=0))
    assert requests == [(1, 32)]
    assert h.work() == ["$CCCYC,0,1,2,0,1,1*5A"]
    assert h.modem("$CACYC,0,1,2,0,1,1") == []
    h.modem("$CAXST,20231114,221320.0000,0,0,0,5000,25000,0,1,2,1,1,1,1,0")
    assert h.results == []  # rate 0: two XSTs (the cycle-init packet and the data)
    assert h.modem("$CADRQ,120000,1,2,1,32,1") == ["$CCTXD,1,2,1,0102030405*7B"]
    h.modem("$CATXD,1,2,1,0102030405", "$CATXP,5", "$CATXF,5")
    h.modem("$CAXST,20231114,221320.0000,0,0,0,5000,25000,0,1,2,1,1,1,1,5")
    assert len(h.results) == 1
    assert len(h.results[0].Extensions[acomms_pb.MM_TRANSMISSION].transmit_stat) == 2
    h.modem("$CAACK,2,1,1,1")
    assert h.received == []  # delivered with the next CST
    h.modem(CST_GOOD)
    assert len(h.received) == 1
    ack = h.received[0]
    assert (ack.type, ack.src, ack.dest, list(ack.acked_frame)) == (acomms_pb.ACK, 2, 1, [0])
    # the statistics' time of arrival is the acknowledgement's time, as for data (goby3)
    stat = ack.Extensions[acomms_pb.MM_TRANSMISSION].receive_stat[0]
    assert (ack.time, ack.time_source) == (stat.time, acomms_pb.ModemTransmission.MODEM_TIME)


def test_no_data_no_cycle():
    h = Harness().start()
    h.driver.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=2, rate=0))
    assert h.work() == []


def test_drq_without_data_gets_empty_txd():
    h = Harness().start()
    h.driver.signal_data_request.connect(lambda msg: msg.frame.extend([b"ab"]))
    h.driver.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=2, rate=1))
    assert h.work() == [cs("$CCCYC,0,1,2,1,1,1")]
    h.modem("$CACYC,0,1,2,1,1,1")
    assert h.modem("$CADRQ,120000,1,2,1,64,1") == [cs("$CCTXD,1,2,1,6162")]
    h.modem("$CATXD,1,2,1,6162")
    assert h.modem("$CADRQ,120000,1,2,1,64,2") == ["$CCTXD,1,2,1,*7A"]


CST_GOOD = (
    "$CACST,0,221320.5000,0,1,20,100,150,0,0,0,0,0,0,1,2,0,1,1,0,100,10,12,30,-10,200,"
    "0.0,50,25000,5000"
)


def test_reception_rate0_two_csts_and_bad_crc():
    h = Harness(modem_id=2).start()
    h.modem("$CARXP,0", "$CACYC,0,1,2,0,1,1")
    h.modem(CST_GOOD)
    assert h.received == []
    h.modem("$CARXD,1,2,1,1,0102030405")
    h.modem(CST_GOOD)
    (rx,) = h.received
    assert (rx.type, rx.src, rx.dest, rx.ack_requested) == (acomms_pb.DATA, 1, 2, True)
    assert list(rx.frame) == [b"\x01\x02\x03\x04\x05"]
    assert rx.time_source == acomms_pb.ModemTransmission.MODEM_TIME
    assert rx.time == int((T0 + 0.5) * 1e6)  # TOA 22:13:20.5 on the current UTC day
    stats = rx.Extensions[acomms_pb.MM_TRANSMISSION].receive_stat
    assert len(stats) == 2 and stats[0].snr_in == 10 and stats[0].carrier_freq == 25000

    h.received.clear()
    h.modem("$CACYC,0,1,2,3,0,2", "$CARXD,1,2,0,1,aa", "$CAMSG,BAD_CRC,2", CST_GOOD)
    (rx,) = h.received
    assert list(rx.frame) == [b"\xaa", b""]
    assert list(rx.Extensions[acomms_pb.MM_TRANSMISSION].frame_with_bad_crc) == [1]


def test_cst_with_an_out_of_range_value_is_ignored(caplog):
    h = Harness(modem_id=2).start()
    fields = CST_GOOD.split(",")
    fields[4] = "8589934592"  # mfd_peak beyond int32
    h.modem("$CARXP,0", "$CACYC,0,1,2,1,0,1", ",".join(fields))  # before any frame
    h.modem("$CARXD,1,2,0,1,0102", ",".join(fields))
    assert h.received == [] and "ignoring malformed $CACST" in caplog.text
    h.modem(CST_GOOD)
    (rx,) = h.received
    assert list(rx.frame) == [b"\x01\x02"]
    assert len(rx.Extensions[acomms_pb.MM_TRANSMISSION].receive_stat) == 1


def test_polled_node_answers_poll_from_its_queue():
    h = Harness(modem_id=2).start()
    h.driver.signal_data_request.connect(lambda msg: msg.frame.append(b"\x10\x20"))
    h.modem("$CACYC,0,2,1,1,1,3")
    assert h.modem("$CADRQ,120000,2,1,1,64,1") == [cs("$CCTXD,2,1,1,1020")]


def test_poller_sends_third_party_cycle():
    h = Harness(modem_id=1).start()
    h.driver.handle_initiate_transmission(acomms_pb.ModemTransmission(src=3, dest=1, rate=1))
    assert h.work() == [cs("$CCCYC,0,3,1,1,1,3")]
    h.driver.handle_initiate_transmission(acomms_pb.ModemTransmission(src=3, dest=-1, rate=1))
    h.modem("$CACYC,0,3,1,1,1,3")
    assert h.work() == []  # Quirk A14: a poll without destination is refused


def test_two_way_ping_and_ping_heard():
    h = Harness().start()
    ping = acomms_pb.ModemTransmission(src=1, dest=2, type=acomms_pb.DRIVER_SPECIFIC)
    ping.Extensions[acomms_pb.MM_TRANSMISSION].type = acomms_pb.MICROMODEM_TWO_WAY_PING
    h.driver.handle_initiate_transmission(ping)
    assert h.work() == ["$CCMPC,1,2*5D"]
    h.modem("$CAMPC,1,2", "$CAMPR,2,1,0.6667")
    (r,) = h.received
    ext = r.Extensions[acomms_pb.MM_TRANSMISSION]
    assert ext.type == acomms_pb.MICROMODEM_TWO_WAY_PING and list(
        ext.ranging_reply.one_way_travel_time
    ) == [pytest.approx(0.6667)]
    h.modem("$CAMPA,3,1")
    assert (
        h.received[1].src == 3
        and not h.received[1]
        .Extensions[acomms_pb.MM_TRANSMISSION]
        .ranging_reply.one_way_travel_time
    )


def test_resend_retries_and_death():
    h = Harness()
    h.driver.startup(h.cfg)
    assert h.work() == [cs("$CCCFG,CST,1")]
    h.clock.advance(5.1)
    assert h.work() == [cs("$CCCFG,CST,1")]  # resent
    h.clock.advance(5.1)
    assert h.work() == [cs("$CCCFG,CST,1")]
    h.clock.advance(5.1)
    assert h.work() == [cs("$CCCFG,SRC,1")]  # dropped after 3 tries, continuing onwards
    h.clock.advance(5.1)
    h.work()
    h.clock.advance(5.1)
    with pytest.raises(ModemDriverError) as info:
        h.work()
    assert info.value.status == acomms_pb.ModemDriverStatus.MODEM_NOT_RESPONDING


def test_malformed_and_bad_checksum_lines_are_logged_and_skipped(caplog):
    h = Harness().start()
    with caplog.at_level(logging.WARNING):
        h.link.feed("$CARXD,1,2,1,1,0102030405*00\r")  # bad checksum
        h.link.feed("garbage\r$CADRQ,notanumber\r$CARXD,1,2,x\r\x00\xff\r")
        h.work()
    assert "checksum" in caplog.text and "malformed" in caplog.text
    assert h.driver.startup_complete and h.received == []


def test_sentences_without_a_handler_are_skipped():
    h = Harness().start()
    for i in range(300):  # sentence ids nobody handles, most of them garbage
        h.modem(f"$CA{i:03d},1", "$CARXP,0", "$CATXF,0")
    assert h.driver.startup_complete and h.received == []
    h.modem("$CACYC,0,3,1,1,0,1", "$CARXD,3,1,0,1,c0ffee")  # handled ones still are
    h.modem(
        "$CACST,0,221330.6675,0,1000,29,16383,134,250,0,0,0,0,0,3,1,0,1,1,0,58,30,25,30,-30,255,0.0,36,25000,5000"
    )
    assert [bytes(f) for f in h.received[0].frame] == [bytes.fromhex("c0ffee")]


def test_caerr_nmea_fails_outstanding_and_keep_alive():
    h = Harness().start()  # the modem's last sentence: $CACLK at T0 + 1
    h.clock.set(T0 + 10.9)
    assert h.work() == []
    h.clock.set(T0 + 11.0)
    assert h.work() == [cs("$CCCFQ,SRC")]  # MM1 keep-alive, 10 s after the modem last spoke
    assert h.modem("$CAERR,000000,NMEA,3,bad") == [cs("$CCCFQ,SRC")]  # resent at once
    h.modem("$CACFG,SRC,1")
    assert h.work() == []


def test_mm2_keep_alive_asks_the_time_after_ten_seconds_without_a_sentence():
    """goby3 restarts the keep-alive period at every sentence from the modem (the interop
    record, tests/data/goby3/pacommshandler_mm.json: none while the modem talks)."""
    h = Harness()
    h.driver.startup(h.cfg)
    h.work()
    for reply in ["$CACFG,CST,1", "$CACFG,SRC,1", "$CACFG,REV,1", "$CACFG,RXP,1"]:
        h.modem(reply)
    assert h.modem("$CAREV,000000,AUV,2.0.16421") == [cs("$CCCFQ,SRC")]
    h.modem("$CACFG,SRC,1")
    h.clock.set(T0 + 0.06)
    h.work()
    h.clock.set(T0 + 0.5)
    assert h.modem("$CATMS,0,2023-11-14T22:13:20.5Z") == []
    assert h.driver.startup_complete
    h.clock.set(T0 + 10.4)
    assert h.work() == []
    h.clock.set(T0 + 10.5)  # 10 s after $CATMS
    assert h.work() == [cs("$CCTMQ,0")]
    h.clock.set(T0 + 11.0)
    h.modem("$CATMQ,2023-11-14T22:13:30.5Z,0")
    h.clock.set(T0 + 18.0)
    assert h.modem("$CARXP,1") == []  # the modem heard something: still alive
    h.clock.set(T0 + 27.9)
    assert h.work() == []
    h.clock.set(T0 + 28.0)
    assert h.work() == [cs("$CCTMQ,0")]


def test_rev_init_resets_clock():
    h = Harness().start()
    h.modem("$CAREV,000000,INIT,0.94.0.00")
    h.clock.advance(2.5)
    h.clock.set(int(h.clock.now()) + 1.06)
    assert h.work()[0].startswith("$CCCLK")


def test_bad_rate_is_refused_and_raw_log_written(tmp_path):
    h = Harness()
    h.cfg.raw_log = str(tmp_path / "raw_%1%.log")
    h.start()
    h.driver.handle_initiate_transmission(acomms_pb.ModemTransmission(src=1, dest=2, rate=9))
    assert h.work() == []  # Quirk A4: rates above 5 are refused
    h.driver.shutdown()
    (log_file,) = tmp_path.glob("raw_*.log")
    assert log_file.name == "raw_20231114T221320.log"
    lines = log_file.read_text().splitlines()
    assert lines[0] == "[tx] $CCCFG,CST,1*37" and "[rx] $CACFG,CST,1" in lines[1]


def special(kind, **fields):
    msg = acomms_pb.ModemTransmission(src=1, dest=2, type=acomms_pb.DRIVER_SPECIFIC)
    ext = msg.Extensions[acomms_pb.MM_TRANSMISSION]
    ext.type = kind
    for name, value in fields.items():
        getattr(ext, name).CopyFrom(value)
    return msg


def test_lbl_pings_and_travel_times():
    h = Harness().start()
    h.driver.handle_initiate_transmission(special(acomms_pb.MICROMODEM_REMUS_LBL_RANGING))
    assert h.work() == [cs("$CCCFG,TAT,50")]  # TAT unknown: set it first
    assert h.modem("$CACFG,TAT,50") == [cs("$CCPDT,1,2,0,0,1383,1,1,1,1")]  # 1000 m*2/1500 + 50 ms
    h.modem("$SNPDT,1,2,0,0,1383,1,1,1,1", "$SNTTA,0.5,1.25,,2,221320.50")
    (r,) = h.received
    ext = r.Extensions[acomms_pb.MM_TRANSMISSION]
    assert ext.type == acomms_pb.MICROMODEM_REMUS_LBL_RANGING and r.src == 1
    assert list(ext.ranging_reply.one_way_travel_time) == [0.5, 1.25, 0.0, 2.0]
    assert (
        r.time == int((T0 + 0.5) * 1e6) and r.time_source == acomms_pb.ModemTransmission.MODEM_TIME
    )
    nb = acomms_pb.MMConfig().narrowband_lbl
    nb.transmit_freq, nb.transmit_ping_ms, nb.receive_ping_ms, nb.turnaround_ms = 26000, 5, 5, 50
    nb.receive_freq.extend([25000, 25500])
    h.driver.handle_initiate_transmission(special(3, narrowband_lbl=nb))
    assert h.work() == [cs("$CCPNT,26000,5,5,2716,25000,25500,0,0,1")]


def test_hardware_control_sweep_and_m_sequence_commands():
    h = Harness().start()
    hw = acomms_pb.MMTransmission().hw_ctl
    hw.line, hw.mode, hw.arg = 5, 1, 1
    h.driver.handle_initiate_transmission(special(6, hw_ctl=hw))
    assert h.work() == [cs("$CCMEC,1,2,5,1,1")]
    h.modem("$CAMEC,1,2,5,1,1", "$CAMER,2,1,5,1,1")
    (r,) = h.received
    assert r.Extensions[acomms_pb.MM_TRANSMISSION].hw_ctl.line == 5 and (r.src, r.dest) == (2, 1)
    sweep = acomms_pb.MMTransmission().fm_sweep
    sweep.start_freq, sweep.stop_freq, sweep.duration_ms = 25000.5, 26000, 100
    h.driver.handle_initiate_transmission(special(9, fm_sweep=sweep))
    assert h.work() == [cs("$CCSWP,250005,260000,999,1000,1,10000")]
    h.modem("$CASWP,250005,260000,999,1000,1,10000")
    seq = acomms_pb.MMTransmission().m_sequence
    seq.seqlen_bits, seq.number_repetitions, seq.carrier_cycles_per_chip, seq.carrier_freq = (
        1023,
        3,
        4,
        25000,
    )
    h.driver.handle_initiate_transmission(special(10, m_sequence=seq))
    assert h.work() == [cs("$CCMSQ,1023,3,4,25000")]


def test_hydroid_gateway_prefixes_strips_and_requests_gps():
    h = Harness(hydroid_gateway_id=1, reset_nvram=True)
    h.driver.startup(h.cfg)
    assert h.work() == ["#G1", "#M1" + cs("$CCCFG,CST,1")]  # never CFG,ALL,0 on a buoy
    h.link.feed("#M1" + cs("$CACFG,CST,1") + "\r")
    assert h.work() == ["#M1" + cs("$CCCFG,SRC,1")]
    h.clock.advance(30)
    assert "#G1" in h.work()


def test_flexible_data_protocol_send_and_receive():
    h = Harness().start()
    h.modem("$CAREV,000000,AUV,2.0.30000")  # MM2 firmware with the odd-length bug
    requests = []

    def fill(msg):
        requests.append(msg.max_frame_bytes)
        msg.frame.append(b"abc")

    h.driver.signal_data_request.connect(fill)
    h.driver.handle_initiate_transmission(special(acomms_pb.MICROMODEM_FLEXIBLE_DATA))
    assert requests == [100] and h.work() == [cs("$CCTDP,2,0,0,0,61626300")]
    h.modem("$CATDP,2,0,0,0,61626300")
    h.modem("$CARDP,2,1,5,0,0,1;2;0102,1;3;aabbcc")
    h.modem("$CARDP,2,1,5,0,0,1;2;0102,0;3;aabbcc")
    good, bad = h.received
    assert list(good.frame) == [b"\x01\x02\xaa\xbb\xcc"] and good.rate == 5
    assert list(bad.frame) == [b""]
    assert list(bad.Extensions[acomms_pb.MM_TRANSMISSION].frame_with_bad_crc) == [0]


def test_application_ack_numbering_and_bitmasks():
    from pygoby.acomms.drivers.micromodem.app_ack import ApplicationAcks

    sender, receiver = ApplicationAcks({1}), ApplicationAcks({2})
    sender.frame_counter = 30
    msg = acomms_pb.ModemTransmission(src=1, dest=2, max_num_frames=3, ack_requested=True)
    size = sender.prepare(msg)
    assert msg.frame_start == 0  # 30 + 3 > 32: numbering starts again
    msg.frame[0] = bytes(msg.frame[0]) + b"x"
    msg.frame.extend([b"y", b""])
    assert sender.finish(msg, size) and sender.frame_counter == 3
    heard = acomms_pb.ModemTransmission()
    heard.CopyFrom(msg)
    heard.Extensions[acomms_pb.MM_TRANSMISSION].frame_with_bad_crc.append(2)
    assert receiver.strip(heard) == [] and list(heard.frame) == [b"x", b"y", b""]
    assert receiver.owed == {1: 0b011}
    reply = acomms_pb.ModemTransmission(src=2, dest=-1, max_num_frames=1)
    size = receiver.prepare(reply)
    assert receiver.finish(reply, size) and reply.dest == 0  # ack-only packet, broadcast
    acks = sender.strip(reply)
    assert [(a.src, a.dest, list(a.acked_frame)) for a in acks] == [(2, 1, [0]), (2, 1, [1])]
    empty = acomms_pb.ModemTransmission(src=2, dest=-1, max_num_frames=1)
    assert not receiver.finish(empty, receiver.prepare(empty))  # nothing owed, no data


def test_sizes_from_the_modem_are_range_checked(caplog):
    """Regressions (hardening issue): `$CACYC,...,40000000` allocated 2.25 GB; a `$CADRQ` with a
    huge byte count built a 200 MB sentence; numbers beyond ssize_t raised OverflowError."""
    import tracemalloc

    h = Harness(modem_id=2, pad_partial_frames=True).start()
    h.driver.signal_data_request.connect(lambda msg: msg.frame.append(b"\x10\x20"))
    tracemalloc.start()
    with caplog.at_level(logging.WARNING):
        h.modem("$CACYC,0,1,2,1,1,4000000")  # frames: at most 8
        h.modem("$CACYC,0,2,1,1,1,3")  # (polled: a frame to answer)
        written = h.modem("$CADRQ,120000,2,1,1,200000000,1")  # bytes: at most 256
        written += h.modem("$CADRQ,120000,2,1,1,99999999999999999999,1")
        h.modem("$CAMPR,1,2,nan", "$CAMPR,1,2,1e999", "$CARXD,1,2,0,1," + "ab" * 257)
        h.modem("$CARDP,1,2,5,0,0,1;3000;" + "ab" * 3000 + ",")
        h.link.feed(cs("$CCCLK,2024,1,2,3,4,5") + "\r")  # (not outstanding: ignored anyway)
    _, peak = tracemalloc.get_traced_memory()
    tracemalloc.stop()
    assert peak < 5_000_000
    assert written == [] and caplog.text.count("malformed") == 7
    assert h.received == []
    # the driver keeps working
    assert h.modem("$CADRQ,120000,2,1,1,64,1") == [cs("$CCTXD,2,1,1,1020" + "00" * 62)]


def test_clock_reply_beyond_any_date_is_malformed_not_a_crash(caplog):
    h = Harness().start()
    h.modem("$CAREV,000000,INIT,0.94.0.00")  # a reboot: the clock is set again
    h.clock.advance(2.5)
    h.clock.set(int(h.clock.now()) + 1.06)
    assert h.work()[0].startswith("$CCCLK")
    with caplog.at_level(logging.WARNING):
        h.modem("$CACLK,99999999999999999999999,11,14,22,13,21")  # OverflowError before
    assert "malformed" in caplog.text


def test_nvram_remembered_from_the_modem_is_bounded():
    h = Harness().start()
    for i in range(3000):
        h.link.feed(cs(f"$CACFG,key{i},{i}") + "\r")
    h.work()
    assert len(h.driver.nvram) <= 1024 and h.driver.nvram["CST"] == 1


def test_update_cfg_sends_the_new_nvram_entries():
    h = Harness().start()
    update = acomms_pb.DriverConfig()
    update.Extensions[acomms_pb.MM_CONFIG].nvram_cfg.extend(
        ["agn,200", "psk.packet.mod_hdr_version,1"]
    )
    h.driver.update_cfg(update)
    assert h.work() == [cs("$CCCFG,AGN,200")]
    assert h.modem("$CACFG,AGN,200") == [cs("$CCCFG,psk.packet.mod_hdr_version,1")]
    assert h.modem("$CACFG,psk.packet.mod_hdr_version,1") == []
    assert list(h.driver.mm_cfg.nvram_cfg) == ["agn,200", "psk.packet.mod_hdr_version,1"]


MODEM_IDS = [
    "REV",
    "ERR",
    "CFG",
    "CLK",
    "TMS",
    "TMQ",
    "CYC",
    "DRQ",
    "XST",
    "ACK",
    "RXD",
    "MSG",
    "CST",
    "MPR",
    "MPA",
    "RDP",
    "MUA",
    "MER",
    "TTA",
    "RXP",
    "TXF",
    "XYZ",
]
FIELD = st.one_of(
    st.integers(-(2**80), 2**80).map(str),
    st.sampled_from(
        [
            "",
            "0",
            "1",
            "6",
            "AUV",
            "INIT",
            "NMEA",
            "BAD_CRC",
            "1;2;0102",
            "nan",
            "221320.5",
            "20231114221320.5",
            "2023-11-14T22:13:20Z",
            "0.94.0.00",
        ]
    ),
    st.text(alphabet="0123456789abcdef.;-:TZ ", max_size=30),
)


@settings(max_examples=examples(300), deadline=None)
@given(st.lists(st.tuples(st.sampled_from(MODEM_IDS), st.lists(FIELD, max_size=32)), max_size=8))
def test_fuzz_modem_lines_never_raise(sentences):
    """Whatever the modem says, the driver logs and carries on (no exception escapes)."""
    h = Harness(modem_id=2).start()
    h.driver.signal_data_request.connect(lambda msg: msg.frame.append(b"x"))
    for sentence_id, fields in sentences:
        h.link.feed(NMEASentence(("$CA" + sentence_id, *fields)).message() + "\r")
        h.work()
    assert h.driver.startup_complete
