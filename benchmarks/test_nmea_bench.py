"""Micro-Modem sentences, per call (`make bench`): the text path a serial/TCP modem costs (parse,
print) and the typed path an in-process emulator costs ($CACST as its values, read by the
driver)."""

from __future__ import annotations

import datetime as dt

import pytest

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.micromodem.statistics import (
    add_cst,
    cst_fields,
    cycle_statistics,
    format_cst,
    format_xst,
    parse_cst,
)
from pygoby.util.nmea import NMEASentence, checksum

CST = (
    "$CACST,0,221330.6675,0,1000,29,16383,134,250,0,0,0,0,0,7,0,0,1,0,0,58,30,25,30,-30,255,0.0,"
    "36,25000,5000*4A"
)
DAY = dt.date(2023, 11, 14)
CST_SENTENCE = NMEASentence.parse(CST)
CST_FIELDS = cst_fields(CST_SENTENCE, DAY)
CST_TYPED = cycle_statistics(CST_FIELDS, 6)
XST_VALUES = {
    "clock_mode": 1,
    "mode": 0,
    "probe_length": 0,
    "bandwidth": 5000,
    "carrier_freq": 25000,
    "rate": 0,
    "source": 1,
    "dest": 2,
    "ack_requested": 0,
    "number_frames_expected": 1,
    "number_frames_sent": 1,
    "packet_type": 1,
    "number_bytes": 32,
}


@pytest.mark.benchmark(group="nmea")
def test_build_and_print_cacyc(benchmark):
    benchmark(lambda: NMEASentence.build("$CACYC", (0, 1, 2, 0, 1, 1)).message())


@pytest.mark.benchmark(group="nmea")
def test_parse_cacst_line(benchmark):
    benchmark(NMEASentence.parse, CST)


@pytest.mark.benchmark(group="nmea")
def test_checksum_of_cacst(benchmark):
    benchmark(checksum, CST[1:-3])


@pytest.mark.benchmark(group="nmea")
def test_parse_cst_text(benchmark):
    benchmark(parse_cst, CST_SENTENCE, DAY)


@pytest.mark.benchmark(group="nmea")
def test_format_cst_message(benchmark):
    benchmark(lambda: format_cst(CST_FIELDS).message())


@pytest.mark.benchmark(group="nmea")
def test_typed_cst_made_and_added(benchmark):
    # what an in-process emulator and driver do for each $CACST: no text at all
    stats = acomms_pb.ModemTransmission().Extensions[acomms_pb.MM_TRANSMISSION].receive_stat

    def one():
        add_cst(stats, cycle_statistics(CST_FIELDS, 6), DAY, True)
        del stats[:]

    benchmark(one)


@pytest.mark.benchmark(group="nmea")
def test_format_xst(benchmark):
    benchmark(format_xst, 1_700_000_000.5, XST_VALUES, 6)


def test_typed_and_text_cst_read_the_same():
    assert parse_cst(CST_TYPED, DAY) == parse_cst(NMEASentence.parse(CST_TYPED.message()), DAY)
