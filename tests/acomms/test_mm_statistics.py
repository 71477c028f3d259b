"""$CACST <-> ReceiveStatistics: round trip, short sentences, bad fields, enum clamping."""

import datetime as dt
import logging

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.drivers.micromodem.statistics import (
    CycleStatistics,
    add_cst,
    cst_fields,
    cycle_statistics,
    format_cst,
    format_xst,
    parse_cst,
    parse_toa,
    parse_xst,
    toa_text,
)
from pygoby.util.errors import NMEAFormatError
from pygoby.util.nmea import NMEASentence
from tests.hypothesis_profiles import examples

DAY = dt.date(2023, 11, 14)
MIDNIGHT_US = int(dt.datetime(2023, 11, 14, tzinfo=dt.UTC).timestamp()) * 1_000_000
CST = "$CACST,0,221330.6675,0,1000,29,16383,134,250,0,0,0,0,0,7,0,0,1,0,0,58,30,25,30,-30,255,0.0,36,25000,5000"
INTS = (
    "mfd_peak",
    "mfd_power",
    "mfd_ratio",
    "spl",
    "shf_agn",
    "shf_ainpshift",
    "shf_ainshift",
    "shf_mfdshift",
    "shf_p2bshift",
    "rate",
    "source",
    "dest",
    "number_frames",
    "number_bad_frames",
    "snr_rss",
    "snr_in",
    "snr_out",
    "snr_symbols",
    "mse_equalizer",
    "data_quality_factor",
    "stddev_noise",
    "carrier_freq",
    "bandwidth",
)


@settings(max_examples=examples(200), deadline=None)
@given(
    toa_us=st.integers(0, 86_400 * 1_000_000 - 1).map(lambda us: us - us % 100),
    mode=st.integers(0, 2),
    clock_mode=st.integers(0, 3),
    psk_error_code=st.integers(-1, 6),
    packet_type=st.sampled_from([-1, 1, 2, 3, 4, 5]),
    ints=st.lists(st.integers(-(2**31), 2**31 - 1), min_size=len(INTS), max_size=len(INTS)),
    doppler_tenths=st.integers(-30, 30),
    version=st.sampled_from([0, 6, 7]),
)
def test_format_then_parse_gives_the_statistics_back(
    toa_us, mode, clock_mode, psk_error_code, packet_type, ints, doppler_tenths, version
):
    stat = acomms_pb.ReceiveStatistics(
        version=version,
        mode=mode,
        time=MIDNIGHT_US + toa_us,
        clock_mode=clock_mode,
        psk_error_code=psk_error_code,
        packet_type=packet_type,
        doppler=doppler_tenths / 10,
        **dict(zip(INTS, ints, strict=True)),
    )
    sentence = format_cst(stat, version)
    as_mapping = {field.name: value for field, value in stat.ListFields()}
    assert format_cst(as_mapping, version) == sentence
    assert sentence.fields[:2] == (("$CACST", str(version)) if version else ("$CACST", str(mode)))
    assert parse_cst(NMEASentence.parse(sentence.message()), DAY) == stat
    # the values a typed link carries read exactly as their text
    typed = cycle_statistics(stat, version)
    assert typed.message() == sentence.message()
    other_day = dt.date(2001, 2, 3)  # (a version-0 time of day takes the reader's date)
    for bitfield in (False, True):
        assert cst_fields(typed, other_day, bitfield) == cst_fields(sentence, other_day, bitfield)


def test_out_of_range_enum_values_become_invalid():
    fields = CST.split(",")
    fields[1], fields[16], fields[17] = "3", "7", "0"  # mode, psk_error_code, packet_type
    stat = parse_cst(NMEASentence.parse(",".join(fields)), DAY)
    assert (stat.mode, stat.psk_error_code, stat.packet_type) == (-1, -1, -1)
    assert stat.time == MIDNIGHT_US + (22 * 3600 + 13 * 60 + 30) * 1_000_000 + 667_500


def test_short_sentence_keeps_the_fields_it_has(caplog):
    short = ",".join(CST.split(",")[:13])  # ends after shf_p2bshift
    with caplog.at_level(logging.WARNING):
        stat = parse_cst(NMEASentence.parse(short), DAY)
    assert "stopped at rate" in caplog.text
    assert stat.mfd_peak == 1000 and stat.shf_p2bshift == 0
    assert not stat.HasField("rate") and not stat.HasField("doppler")


@pytest.mark.parametrize("index, text", [(4, "x"), (26, "fast"), (29, "1.5")])
def test_a_field_that_is_not_a_number_is_named(index, text):
    fields = CST.split(",")
    fields[index] = text
    with pytest.raises(NMEAFormatError, match=f"field {index} of"):
        parse_cst(NMEASentence.parse(",".join(fields)), DAY)


def test_add_cst_appends_nothing_for_a_bad_sentence():
    rx = acomms_pb.ModemTransmission()
    stats = rx.Extensions[acomms_pb.MM_TRANSMISSION].receive_stat
    add_cst(stats, NMEASentence.parse(CST), DAY)
    with pytest.raises(NMEAFormatError, match="bad time of arrival"):
        add_cst(stats, NMEASentence.parse(CST.replace("221330.6675", "2213x0.6675")), DAY)
    fields = CST.split(",")
    fields[4] = "x"
    with pytest.raises(NMEAFormatError, match="field 4 of"):
        add_cst(stats, NMEASentence.parse(",".join(fields)), DAY)
    fields[4] = str(2**40)  # a number, but out of the int32 field's range
    with pytest.raises(ValueError):
        add_cst(stats, NMEASentence.parse(",".join(fields)), DAY)
    assert len(stats) == 1


def test_add_cst_warns_about_every_short_sentence(caplog):
    rx = acomms_pb.ModemTransmission()
    stats = rx.Extensions[acomms_pb.MM_TRANSMISSION].receive_stat
    short = NMEASentence.parse(",".join(CST.split(",")[:13]))
    with caplog.at_level(logging.WARNING):
        add_cst(stats, short, DAY)
        add_cst(stats, short, DAY)
    assert caplog.text.count("stopped at rate") == 2
    assert stats[1] == parse_cst(short, DAY)


@settings(max_examples=examples(200), deadline=None)
@given(st.integers(0, 2**33 * 10**6 - 1), st.booleans())
def test_toa_text_prints_the_utc_time_of_day_and_parse_toa_reads_it(time_us, with_date):
    toa = dt.datetime.fromtimestamp(time_us // 100 * 100 / 1e6, dt.UTC)
    expected = f"{toa:%H%M%S}.{toa.microsecond // 100:04d}"
    if with_date:
        expected = f"{toa:%Y%m%d}" + expected
    assert toa_text(time_us, with_date) == expected
    day = toa.date() if not with_date else dt.date(1999, 1, 1)  # (a dated time keeps its date)
    assert parse_toa(expected, day) == time_us - time_us % 100


@pytest.mark.parametrize(
    "text",
    [
        "240000.0",
        "236000",
        "225960.5",
        "12345",
        "1234567",
        "12a456",
        "20231314221320.5",
        "00000000221320",
        "20230229000000",
        "2023111422132",
    ],
)
def test_parse_toa_refuses_what_is_not_a_time_of_day(text):
    with pytest.raises(ValueError):
        parse_toa(text, DAY)


def test_parse_xst_fields_enum_ranges_and_short_sentences(caplog):
    xst = parse_xst(
        NMEASentence.parse("$CAXST,20231114,221930.0010,0,0,0,5000,25000,0,7,0,1,1,1,1,17")
    )
    assert (xst.version, xst.date, xst.time) == (0, "20231114", "221930.0010")
    assert (xst.clock_mode, xst.mode, xst.probe_length, xst.bandwidth) == (0, 0, 0, 5000)
    assert (xst.carrier_freq, xst.rate, xst.source, xst.dest) == (25000, 0, 7, 0)
    assert xst.ack_requested is True and xst.number_bytes == 17
    assert (xst.number_frames_expected, xst.number_frames_sent, xst.packet_type) == (1, 1, 1)
    odd = parse_xst(
        NMEASentence.parse("$CAXST,6,20231114,221930.0010,4,5,0,5000,25000,0,7,0,0,1,1,6,0")
    )
    assert odd.version == 6 and odd.date == "20231114"
    assert (odd.clock_mode, odd.mode, odd.packet_type) == (-1, -1, -1)  # out of their ranges
    with caplog.at_level(logging.WARNING):
        short = parse_xst(NMEASentence.parse("$CAXST,20231114,221930.0010,0,2,0,5000"))
    assert "stopped at carrier_freq" in caplog.text
    assert short.mode == 2 and short.bandwidth == 5000 and not short.HasField("carrier_freq")
    with pytest.raises(NMEAFormatError, match="field 5 of"):
        parse_xst(NMEASentence.parse("$CAXST,20231114,221930.0010,0,2,x,5000,25000"))


def test_format_xst_prints_what_parse_xst_reads():
    values = {
        "clock_mode": 1,
        "mode": 0,
        "probe_length": 0,
        "bandwidth": 5000,
        "carrier_freq": 25000,
        "rate": 5,
        "source": 1,
        "dest": 2,
        "ack_requested": True,
        "number_frames_expected": 8,
        "number_frames_sent": 8,
        "packet_type": 3,
        "number_bytes": 2048,
    }
    for version in (0, 6):
        xst = parse_xst(NMEASentence.parse(format_xst(1_700_000_000.25, values, version).message()))
        assert (xst.version, xst.date, xst.time) == (version, "20231114", "221320.2500")
        assert {k: getattr(xst, k) for k in values} == values


def test_cycle_statistics_is_a_sentence_for_the_driver():
    stat = parse_cst(NMEASentence.parse(CST), DAY)
    typed = cycle_statistics(stat, 6)
    assert isinstance(typed, CycleStatistics)
    assert (typed.talker_id, typed.sentence_id) == ("CA", "CST")
    assert typed.fields == NMEASentence.parse(typed.message()).fields
    assert typed.fields[3] == "20231114221330.6675" and typed.time_on(DAY) == stat.time
