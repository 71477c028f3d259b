"""The emulator's modem model, sans-I/O, and the `pygoby mmsim` command."""

import asyncio
import sys

from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.acomms.mmsim import LoopbackChannel, MicroModemModel
from pygoby.util.clock import VirtualClock
from pygoby.util.nmea import NMEASentence


def say(model, body):
    model.handle_line(NMEASentence.parse(body).message() + "\r\n")
    return [line.strip() for line in model.take_output()]


def test_cfg_cfq_and_unknown_commands():
    model = MicroModemModel(4, VirtualClock(1e9))
    assert say(model, "$CCCFG,SRC,7") == [NMEASentence.parse("$CACFG,SRC,7").message()]
    assert model.modem_id == 7
    assert say(model, "$CCCFQ,SRC") == [NMEASentence.parse("$CACFG,SRC,7").message()]
    assert say(model, "$CCXYZ,1")[0].startswith("$CAERR,")
    model.handle_line("$CCCFG,SRC,1*00\r\n")  # bad checksum -> $CAERR NMEA
    assert ",NMEA," in model.take_output()[0]


def test_rate_limits_frames_and_sizes():
    channel = LoopbackChannel()
    a, b = (
        MicroModemModel(1, VirtualClock(1e9), channel),
        MicroModemModel(2, VirtualClock(1e9), channel),
    )
    out = say(a, "$CCCYC,0,1,2,1,0,9")  # rate 1 carries at most 3 frames of 64 bytes
    assert out[0].startswith("$CACYC,0,1,2,1,0,3*") and ",64,1*" in out[1]
    say(a, "$CCTXD,1,2,0," + "ab" * 100)
    say(a, "$CCTXD,1,2,0,01")
    say(a, "$CCTXD,1,2,0,02")
    rxd = [NMEASentence.parse(x) for x in b.take_output() if x.startswith("$CARXD")]
    assert [len(bytes.fromhex(s[5])) for s in rxd] == [64, 1, 1]


@settings(max_examples=200, deadline=None)
@given(st.text(max_size=60))
def test_fuzz_model_never_raises(text):
    model = MicroModemModel(1, VirtualClock(1e9), LoopbackChannel())
    model.handle_line(text)
    model.handle_line("$CC" + text)


async def test_pygoby_mmsim_command_answers_over_tcp():
    proc = await asyncio.create_subprocess_exec(
        sys.executable, "-m", "pygoby.cli", "mmsim", "--port", "0", "--id", "5",
        "--channel-group", "239.255.42.98:0",
        stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.DEVNULL,
    )  # fmt: skip
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


async def test_two_mmsim_processes_hear_each_other():
    import random

    group = f"239.255.42.96:{random.randint(40000, 60000)}"
    procs, ports = [], []
    try:
        for modem_id in (1, 2):
            proc = await asyncio.create_subprocess_exec(
                sys.executable, "-m", "pygoby.cli", "mmsim", "--port", "0", "--id", str(modem_id),
                "--channel-group", group,
                stdout=asyncio.subprocess.PIPE, stderr=asyncio.subprocess.DEVNULL,
            )  # fmt: skip
            procs.append(proc)
            line = (await asyncio.wait_for(proc.stdout.readline(), 20)).decode()
            ports.append(int(line.rsplit(":", 1)[1]))
        (r1, w1), (r2, w2) = [await asyncio.open_connection("127.0.0.1", p) for p in ports]

        def send(writer, body):
            writer.write((NMEASentence.parse(body).message() + "\r\n").encode())

        async def until(reader, prefix):
            async with asyncio.timeout(10):
                while not (line := (await reader.readline()).decode()).startswith(prefix):
                    pass
            return NMEASentence.parse(line)

        send(w2, "$CCCFQ,SRC")  # a round trip: emulator 2 has registered this client
        await until(r2, "$CACFG")
        send(w1, "$CCCYC,0,1,2,1,0,1")
        drq = await until(r1, "$CADRQ")
        assert drq.fields[2:6] == ("1", "2", "0", "64")
        send(w1, "$CCTXD,1,2,0,c0ffee")
        rxd = await until(r2, "$CARXD")
        assert rxd.fields[1:] == ("1", "2", "0", "1", "c0ffee")
        for w in (w1, w2):
            w.close()
    finally:
        for proc in procs:
            proc.terminate()
            await proc.wait()


def test_channel_statistics_reach_cacst():
    from pygoby.acomms.mmsim import AcousticPacket, PacketKind, Reception

    model = MicroModemModel(2, VirtualClock(1e9))
    packet = AcousticPacket(PacketKind.DATA, 1, 2, rate=1, frames=[b"a", b"b"])
    model.receive(packet, Reception(1e9 + 0.25, frame_ok=[True, False],
                                    stats={"snr_in": 7.6, "doppler": -0.4, "bogus": 1}))  # fmt: skip
    lines = [NMEASentence.parse(x) for x in model.take_output()]
    assert [s.sentence_id for s in lines] == ["RXP", "CYC", "RXD", "MSG", "CST"]
    cst = lines[-1]
    assert cst[1] == "1" and cst[21] == "8" and cst[26] == "-0.4"  # BAD_CRC mode, snr_in, doppler
    assert cst[2].endswith(".2500")  # time of arrival


def test_recurring_cacst_text_is_the_text_made_from_scratch():
    """The emulator keeps the $CACST text after the time of arrival by link and statistics:
    each reception's line must be what format_cst prints for it, every time it recurs, and
    equal statistics must print the same whatever their number type."""
    import datetime as dt

    from pygoby.acomms.drivers.micromodem.statistics import format_cst, parse_cst
    from pygoby.acomms.mmsim import AcousticPacket, PacketKind, Reception

    model = MicroModemModel(2, VirtualClock(1e9))
    packet = AcousticPacket(PacketKind.DATA, 1, 2, rate=1, frames=[b"a", b"b"])

    def cst(arrival, stats, frame_ok=None):
        model.receive(packet, Reception(arrival, frame_ok=frame_ok, stats=stats))
        return [x.strip() for x in model.take_output() if x.startswith("$CACST")]

    as_ints = {"snr_in": 8, "doppler": 0, "spl": 151}
    as_floats = {"snr_in": 8.0, "doppler": 0.0, "spl": 151.0}  # equal numbers
    other = {"snr_in": 7.6, "doppler": -0.4, "spl": 151}
    cases = [(1e9 + 0.25, as_ints), (1e9 + 3.5, as_floats), (1e9 + 7.125, other, [True, False])]
    first = [cst(*case) for case in cases]
    for _ in range(2):  # the links recur
        assert [cst(*case) for case in cases] == first
    day = dt.datetime.fromtimestamp(1e9, dt.UTC).date()
    for [line] in first:
        assert format_cst(parse_cst(NMEASentence.parse(line), day)).message() == line

    def after_time_of_arrival(line: str) -> list[str]:
        return line.split("*")[0].split(",")[3:]

    assert after_time_of_arrival(first[0][0]) == after_time_of_arrival(first[1][0])


def test_recurring_sentence_text_depends_on_the_value_types():
    """The emulator keeps the text of recurring sentences: 1, 1.0 and True must still print
    as themselves (here: NVRAM values answered to $CCCFQ)."""
    model = MicroModemModel(2, VirtualClock(1e9))
    values = [1, 1.0, True, 1, 1.0]
    lines = []
    for value in values:
        model.nvram["X"] = value
        model.handle_line("$CCCFQ,X\r\n")
        lines.extend(model.take_output())
    assert lines == [NMEASentence.build("$CACFG", ["X", v]).message() + "\r\n" for v in values]
    assert [NMEASentence.parse(line)[2] for line in lines[:3]] == ["1", "1.0", "1"]
