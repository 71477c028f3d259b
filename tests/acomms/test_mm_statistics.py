"""$CACST <-> ReceiveStatistics: round trip, short sentences, bad fields, enum clamping."""

import datetime as dt
import logging

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.acomms import messages as m
from pygoby.acomms.drivers.micromodem.statistics import cst_text, format_cst, parse_cst
from pygoby.util.nmea import NMEAFormatError, NMEASentence, with_checksum

DAY = dt.date(2023, 11, 14)
MIDNIGHT_US = int(dt.datetime(2023, 11, 14, tzinfo=dt.UTC).timestamp()) * 1_000_000
CST = "$CACST,0,221330.6675,0,1000,29,16383,134,250,0,0,0,0,0,7,0,0,1,0,0,58,30,25,30,-30,255,0.0,36,25000,5000"
INTS = (
    "mfd_peak", "mfd_power", "mfd_ratio", "spl", "shf_agn", "shf_ainpshift", "shf_ainshift",
    "shf_mfdshift", "shf_p2bshift", "rate", "source", "dest", "number_frames",
    "number_bad_frames", "snr_rss", "snr_in", "snr_out", "snr_symbols", "mse_equalizer",
    "data_quality_factor", "stddev_noise", "carrier_freq", "bandwidth",
)  # fmt: skip


@settings(max_examples=200, deadline=None)
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
    stat = m.ReceiveStatistics(
        version=version, mode=mode, time=MIDNIGHT_US + toa_us, clock_mode=clock_mode,
        psk_error_code=psk_error_code, packet_type=packet_type, doppler=doppler_tenths / 10,
        **dict(zip(INTS, ints, strict=True)),
    )  # fmt: skip
    sentence = format_cst(stat, version)
    as_mapping = {field.name: value for field, value in stat.ListFields()}
    assert format_cst(as_mapping, version) == sentence
    assert with_checksum(cst_text(as_mapping, version)) == sentence.message()
    assert sentence.fields[:2] == (("$CACST", str(version)) if version else ("$CACST", str(mode)))
    assert parse_cst(NMEASentence.parse(sentence.message()), DAY) == stat


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
