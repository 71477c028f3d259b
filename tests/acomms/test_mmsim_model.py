"""The emulator's modem model, sans-I/O on a virtual clock: commands, NVRAM, timing, ranging,
clock setting, FDP, navigation pings, hardware control, bad input; and the `pygoby mmsim` command."""

import asyncio
import base64
import sys

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.acomms.drivers.micromodem.statistics import CycleStatistics, parse_cst
from pygoby.acomms.mmsim import AcousticPacket, LoopbackChannel, MicroModemModel, ModemPacketKind
from pygoby.acomms.mmsim.channel import ModemReception
from pygoby.acomms.mmsim.model import COMMAND_HANDLERS
from pygoby.acomms.mmsim.timing import DEFAULT_TIMING
from pygoby.util.clock import VirtualClock
from pygoby.util.nmea import NMEASentence
from pygoby.util.timeline import Timeline
from tests.hypothesis_profiles import examples

T0 = 1_700_000_000.0  # 2023-11-14T22:13:20Z


class Water:
    """Emulated modems `range_m` apart on a LoopbackChannel, one Timeline, one VirtualClock;
    `heard[id]` collects (time after T0, sentence) of everything each modem says."""

    def __init__(self, ids=(1, 2), range_m=1500.0, firmware=None, sound_speed=1500.0):
        self.clock = VirtualClock(T0)
        self.timeline = Timeline(self.clock)
        self.channel = LoopbackChannel(self.clock, range_m, sound_speed, self.timeline)
        self.heard: dict[int, list[tuple[float, NMEASentence]]] = {}
        self.modems = {}
        extra = {"firmware": firmware} if firmware else {}
        for modem_id in ids:
            model = MicroModemModel(
                modem_id, self.clock, self.channel, timeline=self.timeline, **extra
            )
            log = self.heard.setdefault(modem_id, [])
            model.on_output = lambda s, log=log: log.append((self.elapsed(), _text(s)))
            self.modems[modem_id] = model

    def elapsed(self) -> float:
        return round(self.clock.now() - T0, 6)  # (float resolution at T0: 2.4e-7 s)

    def say(self, modem_id: int, body: str) -> list[NMEASentence]:
        """Send a host sentence; what the modem answers at once."""
        before = len(self.heard[modem_id])
        self.modems[modem_id].handle_line(NMEASentence.parse(body).message() + "\r\n")
        return [s for _, s in self.heard[modem_id][before:]]

    def run(self, seconds: float) -> None:
        end = self.clock.now() + seconds
        while (t := self.timeline.next_time()) is not None and t <= end:
            self.clock.set(t)
            self.timeline.run_due()
        self.clock.set(end)

    def said(self, modem_id: int, sentence_id: str) -> list[tuple[float, NMEASentence]]:
        return [(t, s) for t, s in self.heard[modem_id] if s.sentence_id == sentence_id]


def _text(sentence) -> NMEASentence:
    """What a host reads (the typed $CACST as its text)."""
    return NMEASentence.parse(sentence.message())


def ids(sentences) -> list[str]:
    return [s.fields[0] for s in sentences]


def serial(body: str) -> float:
    """Seconds a sentence takes on the modem's 19200-baud line (with *HH and CR LF)."""
    return (len(body) + 5) * 10 / 19200


def test_cfg_cfq_accept_only_the_modems_parameters():
    w = Water(ids=(4,))
    assert ids(w.say(4, "$CCCFG,SRC,7")) == ["$CACFG"] and w.modems[4].modem_id == 7
    assert w.say(4, "$CCCFQ,SRC")[0].fields == ("$CACFG", "SRC", "7")
    assert w.say(4, "$CCCFG,dto,5")[0].fields == ("$CACFG", "DTO", "5")  # three letters: any case
    for bad in (
        "$CCCFG,FOO,1",
        "$CCCFG,info.firmware_version,3",
        "$CCCFG,SRC,128",
        "$CCCFG,SRC,x",
        "$CCCFQ,nothing",
    ):
        (err,) = w.say(4, bad)
        assert err.fields[0] == "$CAERR" and err[2] == "NMEA"
    assert "FOO" not in w.modems[4].nvram  # (regression: the table accepted any key)
    info = w.say(4, "$CCCFQ,info")
    assert [s.fields[1:] for s in info] == [("info.firmware_version", "2.0.40000")]
    assert len(w.say(4, "$CCCFQ,TOP")) == len(w.modems[4].nvram)
    assert w.say(4, "$CCCFG,ALL,0")[0].fields == ("$CACFG", "ALL", "0")
    assert w.modems[4].nvram["DTO"] == 2 and w.modems[4].modem_id == 7  # (SRC kept)


def test_unknown_and_bad_commands_get_caerr_and_mm1_lacks_mm2_commands():
    w = Water(ids=(1,), firmware="0.94.0.00")
    assert w.say(1, "$CCXYZ,1")[0][2:4] == ("NMEA", "2")
    for mm2_only in ("$CCTMQ,0", "$CCTMS,2024-01-01T00:00:00Z,0", "$CCALQ,0", "$CCTDP,2,1,0,0,aa"):
        assert w.say(1, mm2_only)[0][2:4] == ("NMEA", "2")
    w.modems[1].handle_line("$CCCFG,SRC,1*00\r\n")  # bad checksum
    assert w.heard[1][-1][1][2] == "NMEA"
    assert Water(ids=(1,)).say(1, "$CCTMQ,0") == []  # an MM2 answers it (later)


def on_air(w, modem_id):
    """(start, end) of each transmission of a modem, from its $CATXP / $CATXF."""
    starts = [t for t, _ in w.said(modem_id, "TXP")]
    ends = [t for t, _ in w.said(modem_id, "TXF")]
    return list(zip(starts, ends, strict=True))


def test_rate0_cycle_init_then_data_with_their_air_times_and_travel_time():
    w = Water()  # 1500 m: one second of travel
    assert ids(w.say(1, "$CCCYC,0,1,2,0,1,1")) == ["$CACYC"]
    ci = round(serial("$CCCYC,0,1,2,0,1,1"), 6)  # the FSK cycle-init leaves once it has come
    w.run(1.5)
    ((drq_t, drq),) = w.said(1, "DRQ")
    assert drq_t == ci + 1.0 and drq.fields[2:] == ("1", "2", "1", "32", "1")  # cycle-init sent
    w.say(1, "$CCTXD,1,2,1,0102030405")
    w.run(20)
    data = round(1.5 + serial("$CCTXD,1,2,1,0102030405"), 6)  # (the DRQ was across by 1.5)
    assert on_air(w, 1) == [(ci, ci + 1.0), (data, pytest.approx(data + 3.2))]  # 80 bit/s
    xst = [s for _, s in w.said(1, "XST")]
    assert [s[3] for s in xst] == [
        f"221320.{int(ci * 1e4):04d}",
        f"221321.{int((data - 1) * 1e4):04d}",
    ]
    heard = [(t, s.fields[0]) for t, s in w.heard[2]]
    assert heard[:3] == [(ci + 1.0, "$CARXP"), (ci + 2.0, "$CACYC"), (ci + 2.0, "$CACST")]
    end = round(data + 4.2, 6)
    assert heard[3:6] == [(data + 1.0, "$CARXP"), (end, "$CARXD"), (end, "$CACST")]
    csts = [parse_cst(s, None) for _, s in w.said(2, "CST")]
    toa = [c.time / 1e6 - T0 for c in csts]
    assert toa == pytest.approx([ci + 1.0, data + 1.0], abs=1e-4)  # times of arrival (0.1 ms)
    assert [c.packet_type for c in csts] == [2, 1]  # FSK mini-packet, FSK
    # the receiver acknowledges (a mini-packet) once the data has been heard
    assert on_air(w, 2) == [(end, end + 1.0)]
    ((ack_t, ack),) = w.said(1, "ACK")
    assert ack_t == end + 2.0 and ack.fields[1:] == ("2", "1", "1", "1")


@pytest.mark.parametrize(
    "rate, frames, size, seconds",
    [
        (1, 1, 64, 0.3 + 2.95 / 3),
        (1, 3, 64, 3.25),
        (3, 2, 256, 3.25),
        (5, 8, 256, 2048 * 8 / 5000),
        (5, 1, 256, 0.3 + (2048 * 8 / 5000 - 0.3) / 8),
    ],
)
def test_psk_air_time_per_rate_and_frame_count(rate, frames, size, seconds):
    w = Water(range_m=0.0)
    cyc = f"$CCCYC,0,1,2,{rate},0,{frames}"
    drqs = w.say(1, cyc)
    assert drqs[-1].fields[5:] == (str(size), "1")  # no cycle-init packet: asked for data at once
    line = serial(cyc)
    for n in range(1, frames + 1):
        txd = f"$CCTXD,1,2,0,{'ab' * size}"
        line += serial(f"$CADRQ,221320,1,2,0,{size},{n}") + serial(txd)
        w.say(1, txd)
    w.run(10)
    ((start, end),) = on_air(w, 1)
    assert start == pytest.approx(line, abs=2e-6)  # once every frame has crossed the serial line
    assert end - start == pytest.approx(seconds)
    assert len(w.said(2, "RXD")) == frames and w.said(2, "RXD")[0][0] == pytest.approx(end)
    assert w.said(2, "CYC")[0][1].fields[1:] == ("0", "1", "2", str(rate), "0", str(frames))


def test_frames_are_clamped_and_truncated_to_the_rate():
    w = Water(range_m=0.0)
    out = w.say(1, "$CCCYC,0,1,2,1,0,9")  # rate 1 carries at most 3 frames of 64 bytes
    assert out[0].fields[1:] == ("0", "1", "2", "1", "0", "3") and out[1][5] == "64"
    w.say(1, "$CCTXD,1,2,0," + "ab" * 100)
    w.say(1, "$CCTXD,1,2,0,01")
    w.say(1, "$CCTXD,1,2,0,02")
    w.run(10)
    assert [len(bytes.fromhex(s[5])) for _, s in w.said(2, "RXD")] == [64, 1, 1]
    assert w.say(1, "$CCCYC,0,1,2,7,0,1")[0][2:4] == ("CYC", "5")  # no rate 7


def test_a_host_that_never_answers_gets_data_timeout():
    w = Water(range_m=0.0)
    w.say(1, "$CCCYC,0,1,2,1,0,2")
    w.say(1, "$CCTXD,1,2,0,aa")  # frame 2 never comes
    w.run(10)
    ((err_t, err),) = w.said(1, "ERR")
    assert err_t == 2.0 and err[2:4] == ("DATA_TIMEOUT", "2")  # NVRAM DTO: 2 s
    assert [s[5] for _, s in w.said(2, "RXD")] == ["aa"]  # what it had goes out


def test_an_empty_txd_ends_the_packet_with_the_frames_already_given():
    """goby3's driver asks for the rate's every frame ($CCCYC ...,5,1,8) and answers the first
    $CADRQ it has no data for with an empty $CCTXD, to stop the requests: the modem asks for no
    more frames, and the packet goes out at once with the frames it has (no DATA_TIMEOUT)."""
    w = Water(range_m=0.0)
    w.say(1, "$CCCYC,0,1,2,5,1,8")
    w.say(1, "$CCTXD,1,2,1," + "ab" * 10)
    assert [s.fields[5:] for _, s in w.said(1, "DRQ")] == [("256", "1"), ("256", "2")]
    echo = w.say(1, "$CCTXD,1,2,1,")
    assert [s.fields[0] for s in echo] == ["$CATXD"] and echo[0][4] == ""
    w.run(20)
    assert len(w.said(1, "DRQ")) == 2 and w.said(1, "ERR") == []
    ((start, end),) = on_air(w, 1)
    assert end - start == pytest.approx(DEFAULT_TIMING.data(5, 1))  # one frame's air time
    assert [s[5] for _, s in w.said(2, "RXD")] == ["ab" * 10]
    assert [s.fields[1:] for _, s in w.said(1, "ACK")] == [("2", "1", "1", "1")]


def test_a_second_transmission_waits_for_the_transducer():
    w = Water(range_m=0.0)
    w.say(1, "$CCCYC,0,1,2,1,0,1")
    w.say(1, "$CCTXD,1,2,0,aa")
    w.say(1, "$CCMUC,1,2,0123")  # while the data is on the water
    w.run(10)
    start = (
        serial("$CCCYC,0,1,2,1,0,1")
        + serial("$CADRQ,221320,1,2,0,64,1")
        + serial("$CCTXD,1,2,0,aa")
    )
    end = start + 0.3 + 2.95 / 3
    assert on_air(w, 1) == [
        (pytest.approx(start, abs=2e-6), pytest.approx(end, abs=2e-6)),
        (pytest.approx(end, abs=2e-6), pytest.approx(end + 1, abs=2e-6)),
    ]
    assert w.said(2, "MUA")[0][1].fields[1:] == ("1", "2", "0123")


@pytest.mark.parametrize("range_m, tat", [(1500.0, 50), (2345.6, 120)])
def test_ping_reply_after_two_way_travel_and_turnaround(range_m, tat):
    w = Water(range_m=range_m, sound_speed=1490.0)
    for modem in w.modems.values():
        modem.nvram["TAT"] = tat
    assert ids(w.say(1, "$CCMPC,1,2")) == ["$CAMPC"]
    w.run(20)
    owtt, start = range_m / 1490.0, serial("$CCMPC,1,2")
    ((mpa_t, mpa),) = w.said(2, "MPA")
    assert mpa_t == pytest.approx(start + owtt + 0.5) and mpa.fields[1:] == ("1", "2")
    ((mpr_t, mpr),) = w.said(1, "MPR")
    assert mpr_t == pytest.approx(start + 2 * owtt + 2 * 0.5 + tat / 1000)
    assert mpr.fields[1:3] == ("2", "1") and float(mpr[3]) == pytest.approx(owtt, abs=1e-4)


def test_time_query_set_and_clock_query():
    w = Water(ids=(1,))
    w.clock.set(T0 + 0.07)
    assert w.say(1, "$CCTMQ,0") == []
    w.run(1)
    ((tmq_t, tmq),) = w.said(1, "TMQ")
    # answered 0.5 s later with the time of the query, its clock and PPS sources (pyacomms
    # reads three fields)
    assert tmq_t == pytest.approx(0.57) and tmq.fields[1:] == (
        "2023-11-14T22:13:20.0Z",
        "RTC",
        "RTC",
    )
    # pyacomms' set_time prints "...ZZ"; the time applies at the modem's next whole second
    w.say(1, "$CCTMS,2024-01-02T03:04:05ZZ,0")
    w.run(1)
    ((tms_t, tms),) = w.said(1, "TMS")
    assert tms_t == 2.0 and tms.fields[1:] == ("0", "2024-01-02T03:04:05.0Z")
    assert w.say(1, "$CCCLQ,0,0")[0].fields[1:] == ("2024", "1", "2", "3", "4", "5")
    w.say(1, "$CCTMQ,0")
    w.run(1)
    assert w.said(1, "TMQ")[-1][1][2] == "USER"  # set by the host now
    w.say(1, "$CCTMS,2024-01-02T03:04:05Z,1")  # at an external PPS: there is none
    w.run(5)
    assert w.said(1, "TMS")[-1][1][1] == "1"  # timed out
    assert w.say(1, "$CCALQ,0")[0].fields[1:] == ("pygoby-mmsim", "11")


def test_a_moos_time_warped_clock_is_accepted():
    """iModemSim's host under MOOSTimeWarp 20 sets the modem to year 3108 (MOOS time = epoch x
    warp); refusing it made every driver start-up retry $CCTMS and give up."""
    w = Water(ids=(1,))
    assert w.say(1, "$CCTMS,3108-05-12T13:20:11Z,0") == []  # (no $CAERR)
    w.run(2)
    ((_, tms),) = w.said(1, "TMS")
    assert tms.fields[1] == "0" and tms.fields[2].startswith("3108-05-12T13:20:1")
    assert w.say(1, "$CCCLQ,0,0")[0].fields[1:4] == ("3108", "5", "12")


@pytest.mark.parametrize(
    "bad",
    [
        "$CCTMS,0001-01-01T00:00:00Z,0",
        "$CCTMS,9999-12-31T23:59:59Z,0",
        "$CCTMS,2024-01-02T03:04:05+02:00,0",
        "$CCCLK,2024,1,2,3,4,99999999999999999999999",
        "$CCCLK,2024,2,30,0,0,0",
        "$CCCLK,1,1,1,0,0,0",
    ],
)
def test_bad_clock_settings_are_refused_and_the_modem_keeps_working(bad):
    """Regressions: a year-1 time wedged the emulator for every client; a huge $CCCLK field
    raised OverflowError."""
    w = Water(ids=(1,))
    (err,) = w.say(1, bad)
    assert err[2:4] == ("NMEA", "3")
    w.run(2)
    assert w.say(1, "$CCCLQ,0,0")[0].fields[1:4] == ("2023", "11", "14")
    assert w.say(1, "$CCMSC,1,1,0")[0].fields[0] == "$CAREV"


def test_clk_sets_the_clock_at_the_next_second():
    w = Water(ids=(1,), firmware="0.94.0.00")
    w.clock.set(T0 + 0.07)
    w.say(1, "$CCCLK,2023,11,14,22,13,21")
    w.run(1)
    ((t, clk),) = w.said(1, "CLK")
    assert t == 1.0 and clk.fields[1:] == ("2023", "11", "14", "22", "13", "21")


def test_flexible_data_packet_as_pyacomms_sends_it():
    w = Water()
    echo = w.say(2, "$CCTDP,1,5,False,False,c0ffee")  # pyacomms prints Python's booleans
    assert echo[0].fields[0] == "$CATDP"
    w.run(10)
    ((rdp_t, rdp),) = w.said(1, "RDP")
    assert rdp.fields[1:] == ("2", "1", "5", "0", "0", "1;3;c0ffee", "")
    ((cst_t, cst),) = w.said(1, "CST")
    assert cst_t == rdp_t and parse_cst(cst, None).packet_type == 5
    w.modems[1].nvram["recv.base64data"] = 1
    w.say(2, "$CCTDP,1,1,0,0," + "ab" * 150)  # two 64-byte frames and some
    w.run(10)
    assert w.said(1, "RDP")[-1][1][6] == "1;150;" + base64.b64encode(b"\xab" * 150).decode()
    for bad in ("$CCTDP,1,0,0,0,aa", "$CCTDP,1,1,0,0," + "ab" * 193, "$CCTDP,1,1,0,0,"):
        assert w.say(2, bad)[0][2:4] == ("TDP", "8")


def test_navigation_pings_echo_and_report_no_transponders_at_the_timeout():
    w = Water(ids=(1,))
    assert w.say(1, "$CCPDT,1,2,0,0,1383,1,1,1,1")[0].fields[0] == "$SNPDT"
    w.run(3)
    ((t, tta),) = w.said(1, "TTA")
    start = serial("$CCPDT,1,2,0,0,1383,1,1,1,1")  # the ping leaves once the command is in
    assert t == pytest.approx(start + 1.383) and tta.fields[1:] == ("", "", "", "", "221320.01")
    assert w.say(1, "$CCPNT,26000,5,5,2716,25000,25500,0,0,1")[0].fields[0] == "$SNPNT"
    pgt = "$CCPGT,1,25000,28,abc,500,25500,28,a,b,c,d,5000,5000,0"  # pyacomms' 14 fields
    assert w.say(1, pgt)[0].fields[0] == "$SNPGT"
    w.run(5)
    assert len(w.said(1, "TTA")) == 3


def test_hardware_control_local_and_remote():
    w = Water()
    assert w.say(1, "$CCMEC,1,1,5,1,1")[0].fields[1:] == ("1", "1", "5", "1", "1")  # set
    assert w.say(1, "$CCMEC,1,1,5,0,0")[0][5] == "1"  # read back (what pyacomms returns)
    w.say(1, "$CCMEC,1,2,3,1,1")
    w.run(10)
    assert w.said(2, "MEA")[0][1].fields[1:] == ("1", "2", "3", "1", "1")
    assert w.said(1, "MER")[0][1].fields[1:] == ("2", "1", "3", "1", "1")


def test_third_party_poll_makes_the_polled_modem_send():
    w = Water(range_m=0.0)
    w.say(1, "$CCCYC,0,2,1,1,1,2")  # 1 polls 2 at rate 1
    w.run(1.5)
    (drq,) = [s for _, s in w.said(2, "DRQ")]
    assert drq.fields[2:] == ("2", "1", "1", "64", "1")
    w.say(2, "$CCTXD,2,1,1,beef")
    w.say(2, "$CCTXD,2,1,1,")  # no more
    w.run(10)
    assert [s[5] for _, s in w.said(1, "RXD")] == ["beef"]


def test_a_rate_0_poll_heard_before_the_host_spoke_goes_on_the_water_at_once():
    """Regression: a modem polled acoustically before its host had sent it anything (two
    iModemSims of a mission both have ModemID 1 until their hosts configure them) started its
    cycle-init at -inf; the $CACST of its reception then raised OverflowError and wedged the
    emulator."""
    w = Water(range_m=0.0)
    w.say(1, "$CCCYC,0,2,1,0,0,1")  # 1 polls 2 at rate 0; 2's host has said nothing
    w.run(5)
    (heard_poll,) = [t for t, _ in w.said(2, "CYC")]
    assert heard_poll == pytest.approx(1.012, abs=1e-3)  # the line, then 1 s of cycle-init
    # 2's own cycle-init goes out as it hears the poll; its host is asked for data as it ends
    assert [t for t, _ in w.said(1, "CYC")][1:] == [pytest.approx(heard_poll + 1.0, abs=1e-6)]
    assert [t for t, _ in w.said(2, "DRQ")] == [pytest.approx(heard_poll + 1.0, abs=1e-6)]
    assert w.say(2, "$CCMSC,1,1,0")[0].sentence_id == "REV"  # and it still answers its host


def test_channel_statistics_reach_cacst():
    model = MicroModemModel(2, VirtualClock(T0), firmware="0.94.0.00")
    packet = AcousticPacket(ModemPacketKind.DATA, 1, 2, rate=1, frames=[b"a", b"b"], duration=1.0)
    model.receive(
        packet,
        ModemReception(
            T0 + 0.25, frame_ok=[True, False], stats={"snr_in": 7.6, "doppler": -0.44, "bogus": 1}
        ),
    )
    lines = [_text(s) for s in model.take_output()]
    assert [s.sentence_id for s in lines] == ["CYC", "RXD", "MSG", "CST"]
    cst = lines[-1]
    assert cst[1] == "1" and cst[21] == "8" and cst[26] == "-0.4"  # BAD_CRC mode, snr_in, doppler
    assert cst[2] == "221320.2500"  # time of arrival (Micro-Modem 1: time of day)


def test_mm2_statistics_carry_their_version_and_date():
    model = MicroModemModel(2, VirtualClock(T0))
    packet = AcousticPacket(ModemPacketKind.DATA, 1, 2, rate=0, frames=[b"a"], duration=3.2)
    model.receive(packet, ModemReception(T0 + 0.25))
    (cst,) = [s for s in model.take_output() if isinstance(s, CycleStatistics)]
    fields = NMEASentence.parse(cst.message()).fields
    assert fields[1:4] == ("6", "0", "20231114221320.2500")


HOST_COMMANDS = [*COMMAND_HANDLERS, "XYZ"]  # every command the model knows, and one it does not
FIELDS = st.one_of(
    st.integers(-(2**70), 2**70).map(str),
    st.sampled_from(
        [
            "",
            "0",
            "1",
            "ALL",
            "SRC",
            "TOP",
            "info",
            "False",
            "ab",
            "0123",
            "ZZ",
            "2024-01-02T03:04:05Z",
            "0001-01-01T00:00:00Z",
            "nan",
            "1e999",
        ]
    ),
    st.text(alphabet="0123456789abcdefABCDEF.-:TZ;", max_size=40),
)


@settings(max_examples=examples(400), deadline=None)
@given(
    st.lists(
        st.one_of(
            st.tuples(st.sampled_from(HOST_COMMANDS), st.lists(FIELDS, max_size=14)),
            st.text(max_size=60),
        ),
        max_size=6,
    )
)
def test_fuzz_host_lines_only_get_answers(lines):
    """Whatever a host sends, the modem answers (or errs) and keeps working: no exception."""
    w = Water()
    for line in lines:
        if isinstance(line, tuple):
            w.modems[1].handle_sentence(NMEASentence(("$CC" + line[0], *line[1])))
        else:
            w.modems[1].handle_line(line)
        w.run(3)
    w.run(30)
    assert w.say(1, "$CCCFQ,SRC")[0].fields[:2] == ("$CACFG", "SRC")


async def test_pygoby_mmsim_command_answers_over_tcp():
    proc = await asyncio.create_subprocess_exec(
        sys.executable,
        "-m",
        "pygoby.cli",
        "mmsim",
        "--port",
        "0",
        "--id",
        "5",
        "--channel-group",
        "239.255.42.98:0",
        stdout=asyncio.subprocess.PIPE,
        stderr=asyncio.subprocess.DEVNULL,
    )
    try:
        async with asyncio.timeout(20):
            line = (await proc.stdout.readline()).decode()
            port = int(line.rsplit(":", 1)[1])
            reader, writer = await asyncio.open_connection("127.0.0.1", port)
            writer.write((NMEASentence.parse("$CCCFQ,SRC").message() + "\r\n").encode())
            reply = (await reader.readline()).decode().strip()
        assert reply == NMEASentence.parse("$CACFG,SRC,5").message()
        writer.close()
    finally:
        proc.terminate()
        await proc.wait()


@pytest.mark.e2e  # (two processes)
async def test_two_mmsim_processes_hear_each_other_over_their_range(tmp_path):
    import random

    group = f"239.255.42.96:{random.randint(40000, 60000)}"
    procs, ports = [], []
    pty_link = tmp_path / "ttyLOOPA1"
    try:
        for modem_id in (1, 2):
            extra = ["--pty", str(pty_link)] if modem_id == 1 else []
            proc = await asyncio.create_subprocess_exec(
                sys.executable,
                "-m",
                "pygoby.cli",
                "mmsim",
                "--port",
                "0",
                "--id",
                str(modem_id),
                "--channel-group",
                group,
                "--range",
                "750",
                *extra,
                stdout=asyncio.subprocess.PIPE,
                stderr=asyncio.subprocess.DEVNULL,
            )
            procs.append(proc)
            line = (await asyncio.wait_for(proc.stdout.readline(), 20)).decode()
            ports.append(int(line.rsplit(":", 1)[1]))
        pty_line = (await asyncio.wait_for(procs[0].stdout.readline(), 20)).decode()
        assert pty_line.split()[-1] == str(pty_link) and pty_link.is_symlink()
        (r1, w1), (r2, w2) = [await asyncio.open_connection("127.0.0.1", p) for p in ports]

        def send(writer, body):
            writer.write((NMEASentence.parse(body).message() + "\r\n").encode())

        async def until(reader, prefix):
            async with asyncio.timeout(10):
                while not (line := (await reader.readline()).decode()).startswith(prefix):
                    pass
            return asyncio.get_running_loop().time(), NMEASentence.parse(line)

        send(w2, "$CCCFQ,SRC")  # a round trip: emulator 2 has registered this client
        await until(r2, "$CACFG")
        send(w1, "$CCCYC,0,1,2,1,0,1")
        _, drq = await until(r1, "$CADRQ")
        assert drq.fields[2:6] == ("1", "2", "0", "64")
        send(w1, "$CCTXD,1,2,0,c0ffee")
        t_txp, _ = await until(r1, "$CATXP")
        t_rxp, _ = await until(r2, "$CARXP")
        t_rxd, rxd = await until(r2, "$CARXD")
        assert rxd.fields[1:] == ("1", "2", "0", "1", "c0ffee")
        assert t_rxp - t_txp == pytest.approx(0.5, abs=0.15)  # 750 m at 1500 m/s
        assert t_rxd - t_rxp == pytest.approx(0.3 + 2.95 / 3, abs=0.15)  # one rate-1 frame
        for w in (w1, w2):
            w.close()
    finally:
        for proc in procs:
            proc.terminate()
            await proc.wait()
    assert not pty_link.exists()  # the link goes with its emulator


def test_timing_table_documents_its_rates():
    assert {r: (t.frames, t.frame_bytes) for r, t in DEFAULT_TIMING.rates.items()} == {
        0: (1, 32),
        1: (3, 64),
        2: (3, 64),
        3: (2, 256),
        4: (2, 256),
        5: (8, 256),
        6: (6, 32),
    }
    assert DEFAULT_TIMING.data(0, 1) == pytest.approx(3.2)
    assert DEFAULT_TIMING.data(6, 6) == pytest.approx(3.25)
