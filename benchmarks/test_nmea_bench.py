"""Micro-Modem text path, per call (`make bench`): what each emulated reception costs in NMEA and
$CACST work (the netsim simulation runs these ~10 times per reception)."""

from __future__ import annotations

import datetime as dt

import pytest

from pygoby.acomms.drivers.micromodem.statistics import (
    cst_fields,
    cst_text,
    format_cst,
    format_xst,
    parse_cst,
)
from pygoby.util.nmea import NMEASentence, checksum, with_checksum

CST = (
    "$CACST,0,221330.6675,0,1000,29,16383,134,250,0,0,0,0,0,7,0,0,1,0,0,58,30,25,30,-30,255,0.0,"
    "36,25000,5000*4A"
)
DAY = dt.date(2023, 11, 14)
CST_SENTENCE = NMEASentence.parse(CST)
CST_FIELDS = cst_fields(CST_SENTENCE, DAY)


@pytest.mark.benchmark(group="nmea")
def test_build_and_print_cacyc(benchmark):
    benchmark(lambda: NMEASentence.build("$CACYC", (0, 1, 2, 0, 1, 1)).message())


@pytest.mark.benchmark(group="nmea")
def test_parse_cacst_line_first_time(benchmark):
    # NMEASentence.parse remembers recurring lines; _parse is the work for a new one
    benchmark(NMEASentence._parse, CST)


@pytest.mark.benchmark(group="nmea")
def test_checksum_of_cacst(benchmark):
    benchmark(checksum, CST[1:-3])


@pytest.mark.benchmark(group="nmea")
def test_parse_cst(benchmark):
    benchmark(parse_cst, CST_SENTENCE, DAY)


@pytest.mark.benchmark(group="nmea")
def test_cst_fields(benchmark):
    benchmark(cst_fields, CST_SENTENCE, DAY)


@pytest.mark.benchmark(group="nmea")
def test_format_cst_message(benchmark):
    benchmark(lambda: format_cst(CST_FIELDS).message())


@pytest.mark.benchmark(group="nmea")
def test_cst_text_with_checksum(benchmark):
    # what the emulator prints for each $CACST
    benchmark(lambda: with_checksum(cst_text(CST_FIELDS)))


@pytest.mark.benchmark(group="nmea")
def test_format_xst(benchmark):
    benchmark(format_xst, 1_700_000_000.5, 0, 1, 2, False, 1, 32)
