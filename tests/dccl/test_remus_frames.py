"""REMUS CCL frames (pygoby.dccl.ccl.remus): every frame type round-trips within its resolution,
hand-made frames from the spec's bit layouts (goby-moos-apps.md §7) decode to the documented
values, State and Redirect frames are byte for byte C++ DCCL's (recorded by
tests/dccl/oracle/record_remus.py), bad frames raise CCLFrameError with the reason, and no
input makes a decoder raise anything else."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pygoby.dccl import DcclError
from pygoby.dccl.ccl import remus
from pygoby.dccl.ccl.remus import (
    LATLON_STEP,
    Alert,
    Alert2,
    Alert2Contact,
    AlertContact,
    CCLEncodeError,
    CCLFrameError,
    GFIPitchOil,
    Position,
    Ranger,
    Redirect,
    State,
    TimeDate,
    decode_frame,
)
from pygoby.dccl.codecs.numeric import f32
from tests.dccl.remus_cpp import from_json, message_class, read_records, to_message
from tests.hypothesis_profiles import examples

ALL_TYPES = (State, Redirect, Ranger, Position, Alert, Alert2)
HALF_HEADING = 360 / 255 / 2


def le(value: int, count: int) -> bytes:
    """`value` (two's complement if negative) in `count` little-endian bytes."""
    return (value & ((1 << 8 * count) - 1)).to_bytes(count, "little")


def spec_latlon(degrees: float) -> bytes:
    """The spec's 24-bit coordinate: round_half_away(deg * 0x7FFFFF / 180), two's complement."""
    scaled = degrees * 0x7FFFFF / 180
    return le(int(scaled + (0.5 if scaled > 0 else -0.5)), 3)


def frame(*parts: bytes) -> bytes:
    data = b"".join(parts)
    assert len(data) == 32
    return data


def angle_error(a: float, b: float) -> float:
    return abs((a - b + 180) % 360 - 180)


# ------------------------------------------------------------------ C++ DCCL's bytes
RECORDS = read_records()


def test_the_recorded_file_covers_both_types_and_negative_coordinates():
    kinds = [r["type"] for r in RECORDS]
    assert kinds.count("State") >= 60 and kinds.count("Redirect") >= 60
    assert any(r["values"]["latitude"] < 0 and r["values"]["longitude"] < 0 for r in RECORDS)


@pytest.mark.parametrize("record", RECORDS, ids=lambda r: f"{r['type']}-{r['cpp_hex'][:14]}")
def test_state_and_redirect_bytes_equal_cpp_dccl(record):
    ours = from_json(record["type"], record["values"])
    assert ours.encode().hex() == record["cpp_hex"]


@pytest.mark.parametrize("record", RECORDS, ids=lambda r: f"{r['type']}-{r['cpp_hex'][:14]}")
def test_decoded_values_equal_cpp_dccl(record):
    """What C++ DCCL decodes from its bytes is what we decode (lat/lon exactly: both
    sign-extend, Quirk Q19 fixed)."""
    decoded = type(from_json(record["type"], record["values"])).decode(
        bytes.fromhex(record["cpp_hex"])
    )
    cpp = message_class(record["type"]).FromString(bytes.fromhex(record["cpp_decoded_bin"]))
    assert to_message(decoded, record["now"]) == cpp


# ------------------------------------------------------------------ hand-made frames
TIME_BITS = 20 // 4 | 13 << 4 | 22 << 10 | 14 << 15 | 11 << 20  # 14 Nov, 22:13:20 UTC


def test_hand_made_state():
    gfi_pitch_oil = 3 | 15 << 5 | (-4 << 10 & 0xFC00)  # GFI 3/31, oil 15/31, pitch -4/63 * 180
    data = frame(
        b"\x0e",
        spec_latlon(-42.35),
        spec_latlon(-70.95),
        b"\x02",
        le(TIME_BITS, 3),
        b"\x20",  # heading 32 * 360/255
        le(1055 | 6 << 13, 2),  # depth 100 + (1055 - 1000) * 0.2, mission mode 6
        le(0x04030201, 4),
        b"\x05",
        b"\x06",
        b"\xe2",  # velocity -30 / 25
        b"\x07",
        b"\x0a",  # objective, watts 10 * 4
        spec_latlon(41.5),
        spec_latlon(-70.5),
        b"\x50",
        le(gfi_pitch_oil, 2),
    )
    state = State.decode(data)
    assert state.latitude == pytest.approx(-42.35, abs=LATLON_STEP / 2)  # Q19: no 4.3e-5 bias
    assert state.longitude == pytest.approx(-70.95, abs=LATLON_STEP / 2)
    assert state.fix_age == 8 and state.time == TimeDate(11, 14, 22, 13, 20)
    assert state.heading == 32 * 360 / 255 and state.depth == pytest.approx(111.0)
    assert (state.mission_mode, state.faults, state.faults_2, state.mission_leg) == (
        6,
        0x04030201,
        5,
        6,
    )
    assert state.est_velocity == pytest.approx(-1.2) and state.watts == 40.0
    assert (state.objective_index, state.battery_percent) == (7, 80)
    assert state.lat_goal == pytest.approx(
        41.5, abs=LATLON_STEP
    ) and state.lon_goal == pytest.approx(-70.5, abs=LATLON_STEP)
    assert state.gfi_pitch_oil.gfi == 9.0  # whole percents: int(3 * 100 / 31)
    assert state.gfi_pitch_oil.oil == pytest.approx(
        15 * 100 / 31
    ) and state.gfi_pitch_oil.pitch == pytest.approx(-4 * 180 / 63)
    assert decode_frame(data) == state
    again = state.encode()  # the same bytes but two the reference's rounding moves:
    assert again[20] == 0xE3  # -1.2 * 25 + 0.5 truncated: -29 (C++ DCCL's "positive rounding")
    assert again[30] == 3 - 1 | 15 << 5 & 0xFF  # GFI 9 % * 31 / 100 = 2.79, truncated to 2
    assert again[:20] + again[21:30] + again[31:] == data[:20] + data[21:30] + data[31:]


@pytest.mark.parametrize(
    "raw, depth",
    [
        (0, 0.0),
        (1000, 100.0),
        (1500, 200.0),
        (3100, 1000.0),
        (8100, 6000.0),
        (999, 99.9),
        (1001, 100.2),
        (1501, 200.5),
        (3101, 1001.0),
    ],
)
def test_hand_made_state_depth_pieces(raw, depth):
    data = frame(b"\x0e", bytes(7), le(TIME_BITS, 3), b"\0", le(raw, 2), bytes(18))
    assert State.decode(data).depth == pytest.approx(depth, abs=1e-4)


def test_hand_made_ranger_in_bcd():
    data = bytearray(32)
    data[0] = 16
    data[1:6] = bytes.fromhex("042d210000")  # 042 degrees, sign D, 21.0000 minutes
    data[6:11] = bytes.fromhex("070c570000")  # 070 degrees, sign C (also negative), 57.0000
    data[18] = 0x12  # speed 12 * 0.1
    data[19:21] = bytes.fromhex("0455")  # heading 0455 * 0.1
    data[28], data[23] = 0x01, 0x11  # depth: byte 28 thousands/hundreds, byte 23 tens/ones
    ranger = Ranger.decode(bytes(data))
    assert ranger == Ranger(
        latitude=-42.35, longitude=-70.95, speed=12 * 0.1, heading=45.5, depth=111.0
    )
    north = bytearray(data)
    north[2], north[7] = 0x2F, 0x0A  # any other sign nibble: north / east
    assert (Ranger.decode(bytes(north)).latitude, Ranger.decode(bytes(north)).longitude) == (
        42.35,
        70.95,
    )


def test_hand_made_redirect():
    data = frame(
        b"\x07",
        b"\x05",
        spec_latlon(42.35),
        spec_latlon(-70.95),
        b"\x88",
        le(100, 2),
        b"\x2d",
        b"\x03",  # transit: 10 m, 45 / 30 m/s, command 3
        le(200, 2),
        b"\x1e",
        b"\x04",  # survey: 20 m, 30 / 30 m/s, command 4
        b"\x03",
        le(1000, 2),
        b"\x0a",
        b"\x14",  # rows, row length, spacings
        b"\x40",  # row heading 64 * 360/255
        spec_latlon(42.0),
        spec_latlon(-71.0),
        bytes(3),
    )
    redirect = decode_frame(data)
    assert isinstance(redirect, Redirect)
    assert redirect.latitude == pytest.approx(
        42.35, abs=LATLON_STEP / 2
    ) and redirect.longitude == pytest.approx(-70.95, abs=LATLON_STEP / 2)
    assert (redirect.message_number, redirect.speed_depth_flags) == (5, 0x88)
    assert (redirect.transit_depth, redirect.transit_speed, redirect.transit_command) == (
        10.0,
        1.5,
        3,
    )
    assert (redirect.survey_depth, redirect.survey_speed, redirect.survey_command) == (20.0, 1.0, 4)
    assert (redirect.num_rows, redirect.row_length, redirect.spacing_0, redirect.spacing_1) == (
        3,
        1000,
        10,
        20,
    )
    assert redirect.row_heading == 64 * 360 / 255
    assert redirect.encode() == data


def test_hand_made_position_and_alerts():
    position = frame(
        b"\x08\x02",
        spec_latlon(42.0),
        spec_latlon(-70.0),
        bytes(7),
        b"BUOY 7".ljust(13, b"\0"),
        bytes(4),
    )
    decoded = decode_frame(position)
    assert isinstance(decoded, Position) and (decoded.type_name, decoded.label) == (
        "Gateway Buoy",
        "BUOY 7",
    )
    assert Position.decode(position[:1] + b"\x84" + position[2:]).type_name == "Invalid"

    contacts = le(513, 2) + b"\x03\x04\x05\x06" + le(2, 2) + bytes(4) + bytes(6)
    alert = Alert.decode(
        frame(
            b"\x1f",
            le(0x12345, 4),
            spec_latlon(1.0),
            spec_latlon(-2.0),
            b"\x40",
            contacts,
            bytes(2),
        )
    )
    assert alert.oasis_time == 0x12345 and alert.heading == 64 * 360 / 255
    assert alert.contacts[0] == AlertContact(id=513, age=3, bearing=4, signature1=5, signature2=6)
    assert alert.contacts[1].id == 2 and alert.mode == remus.MDAT_OASIS

    contact = le(7, 2) + b"\x85\x10\x40\x01\x02"  # age 5 with bit 7: heading is absolute
    alert2 = Alert2.decode(
        frame(b"\x1f", le(9, 4), spec_latlon(1.0), spec_latlon(-2.0), contact, bytes(14))
    )
    assert alert2.contacts[0] == Alert2Contact(
        id=7,
        age=5,
        bearing=16,
        heading=64 * 360 / 255,
        absolute_heading=True,
        signature1=1,
        signature2=2,
    )
    assert alert2.contacts[1] == Alert2Contact()


def test_example_values_of_seed_003():
    """mm2's NAV_* of seed 003's example 2 at its datum, encoded as pREMUSCodec does."""
    state = State(
        latitude=42.3511,
        longitude=-70.9485,
        heading=45,
        depth=111,
        est_velocity=1.2,
        time=TimeDate.at(1_700_000_000),
    )
    decoded = State.decode(state.encode())
    assert (decoded.heading, decoded.depth) == (32 * 360 / 255, 111.0)
    assert decoded.est_velocity == pytest.approx(1.2, abs=1e-6)


# ------------------------------------------------------------------ round trips
lat = st.floats(-90, 90)
lon = st.floats(-180, 180)
byte = st.integers(0, 255)
times = st.builds(
    TimeDate,
    st.integers(1, 12),
    st.integers(1, 31),
    st.integers(0, 23),
    st.integers(0, 59),
    st.integers(0, 59),
)


def depth_step(depth: float) -> float:
    return 0.1 if depth < 100 else 0.2 if depth < 200 else 0.5 if depth < 1000 else 1.0


@given(
    st.builds(
        State,
        latitude=lat,
        longitude=lon,
        fix_age=st.integers(0, 1020),
        time=times,
        heading=st.floats(0, 360, exclude_max=True),
        depth=st.floats(0, 5999),
        mission_mode=st.integers(0, 7),
        faults=st.integers(0, 2**32 - 1),
        faults_2=byte,
        mission_leg=byte,
        est_velocity=st.floats(-5.12, 5.08),
        objective_index=byte,
        watts=st.floats(0, 1020),
        lat_goal=lat,
        lon_goal=lon,
        battery_percent=byte,
        gfi_pitch_oil=st.builds(
            GFIPitchOil, st.floats(0, 100), st.floats(-90, 90, exclude_max=True), st.floats(0, 100)
        ),
    )
)
def test_state_round_trip_within_resolution(state):
    back = State.decode(state.encode())
    for name in ("latitude", "longitude", "lat_goal", "lon_goal"):
        assert abs(getattr(back, name) - getattr(state, name)) <= LATLON_STEP / 2 + 1e-12
    assert back.fix_age == state.fix_age // 4 * 4
    assert back.time == state.time._replace(second=state.time.second // 4 * 4)
    assert angle_error(back.heading, state.heading) <= HALF_HEADING + 1e-4
    assert abs(back.depth - state.depth) <= depth_step(state.depth) / 2 + 1e-3
    # C++ DCCL's "positive rounding" (v * 25 + 0.5, truncated toward zero): half a step above
    # zero, up to a step and a half below it
    assert (
        abs(back.est_velocity - state.est_velocity)
        <= (0.02 if state.est_velocity >= 0 else 0.06) + 1e-6
    )
    assert abs(back.watts - state.watts) <= 4 + 1e-3
    for name in (
        "mission_mode",
        "faults",
        "faults_2",
        "mission_leg",
        "objective_index",
        "battery_percent",
    ):
        assert getattr(back, name) == getattr(state, name)
    gpo, sent = back.gfi_pitch_oil, state.gfi_pitch_oil
    assert abs(gpo.gfi - sent.gfi) <= 100 / 31 + 1 and abs(gpo.oil - sent.oil) <= 100 / 31 + 1e-3
    if f32(f32(sent.pitch * 0.35) + 0.5) >= 32:
        # as in C++, a pitch whose 32-bit scaled value rounds up to +32 steps (+90 itself, and
        # anything within float rounding of it) wraps to -32 steps
        assert gpo.pitch == pytest.approx(-32 * 180 / 63, abs=1e-4)
    else:
        assert abs(gpo.pitch - sent.pitch) <= 180 / 63 / 2 + 1e-3


@given(
    st.builds(
        Redirect,
        latitude=lat,
        longitude=lon,
        message_number=byte,
        speed_depth_flags=byte,
        transit_depth=st.floats(0, 5999),
        transit_speed=st.floats(-4.2, 4.2),
        transit_command=byte,
        survey_depth=st.floats(0, 5999),
        survey_speed=st.floats(-4.2, 4.2),
        survey_command=byte,
        num_rows=byte,
        row_length=st.integers(0, 65535),
        spacing_0=byte,
        spacing_1=byte,
        row_heading=st.floats(0, 360, exclude_max=True),
        start_latitude=lat,
        start_longitude=lon,
    )
)
def test_redirect_round_trip_within_resolution(redirect):
    back = Redirect.decode(redirect.encode())
    for name in ("latitude", "longitude", "start_latitude", "start_longitude"):
        assert abs(getattr(back, name) - getattr(redirect, name)) <= LATLON_STEP / 2 + 1e-12
    for name in ("transit_depth", "survey_depth"):
        assert (
            abs(getattr(back, name) - getattr(redirect, name))
            <= depth_step(getattr(redirect, name)) / 2 + 1e-3
        )
    for name in ("transit_speed", "survey_speed"):
        assert abs(getattr(back, name) - getattr(redirect, name)) <= 1 / 60 + 1e-6
    assert angle_error(back.row_heading, redirect.row_heading) <= HALF_HEADING + 1e-4
    for name in (
        "message_number",
        "speed_depth_flags",
        "transit_command",
        "survey_command",
        "num_rows",
        "row_length",
        "spacing_0",
        "spacing_1",
    ):
        assert getattr(back, name) == getattr(redirect, name)


@given(
    st.builds(
        Ranger,
        latitude=lat,
        longitude=lon,
        speed=st.floats(0, 9.9),
        heading=st.floats(0, 359.9),
        depth=st.integers(0, 9999).map(float),
    )
)
def test_ranger_round_trip_within_resolution(ranger):
    back = Ranger.decode(ranger.encode())
    for name in ("latitude", "longitude"):
        assert abs(getattr(back, name) - getattr(ranger, name)) <= 0.0001 / 60 / 2 + 1e-12
    assert (
        abs(back.speed - ranger.speed) <= 0.05 + 1e-9
        and abs(back.heading - ranger.heading) <= 0.05 + 1e-9
    )
    assert back.depth == ranger.depth


labels = st.text(st.characters(min_codepoint=1, max_codepoint=255), max_size=13)


@given(
    st.builds(
        Position,
        latitude=lat,
        longitude=lon,
        type=st.sampled_from([*remus.POSITION_TYPES, 0x80, 0x84]),
        label=labels,
    )
)
def test_position_round_trip(position):
    back = Position.decode(position.encode())
    assert (back.type, back.label) == (position.type, position.label)
    assert abs(back.latitude - position.latitude) <= LATLON_STEP / 2 + 1e-12


contact = st.builds(AlertContact, st.integers(0, 65535), byte, byte, byte, byte)
contact2 = st.builds(
    Alert2Contact,
    st.integers(0, 65535),
    st.integers(0, 127),
    byte,
    st.floats(0, 360, exclude_max=True),
    st.booleans(),
    byte,
    byte,
)


@given(
    st.builds(
        Alert,
        oasis_time=st.integers(0, 2**32 - 1),
        latitude=lat,
        longitude=lon,
        heading=st.floats(0, 360, exclude_max=True),
        contacts=st.lists(contact, min_size=3, max_size=3),
        mode=byte,
    ),
    st.builds(
        Alert2,
        oasis_time=st.integers(0, 2**32 - 1),
        latitude=lat,
        longitude=lon,
        contacts=st.lists(contact2, min_size=3, max_size=3),
        mode=byte,
    ),
)
def test_alert_round_trips(alert, alert2):
    back = Alert.decode(alert.encode())
    assert (back.oasis_time, back.contacts, back.mode) == (
        alert.oasis_time,
        alert.contacts,
        alert.mode,
    )
    assert angle_error(back.heading, alert.heading) <= HALF_HEADING + 1e-4
    back2 = Alert2.decode(alert2.encode())
    assert back2.oasis_time == alert2.oasis_time and back2.mode == alert2.mode
    for got, sent in zip(back2.contacts, alert2.contacts, strict=True):
        assert angle_error(got.heading, sent.heading) <= HALF_HEADING + 1e-4
        assert got == Alert2Contact(**{**vars(sent), "heading": got.heading})


# ------------------------------------------------------------------ bad frames and values
GOOD_STATE = State(latitude=1, longitude=2, time=TimeDate(1, 2, 3, 4, 8)).encode()


def with_bytes(data: bytes, at: int, new: bytes) -> bytes:
    return data[:at] + new + data[at + len(new) :]


@pytest.mark.parametrize(
    "data, cls, reason",
    [
        (b"", None, "empty frame"),
        (b"\x2a" + bytes(31), None, "unknown CCL id 42"),
        (GOOD_STATE[:31], State, "MDAT_STATE: 31-byte frame, needs at least 32"),
        (GOOD_STATE, Redirect, "MDAT_REDIRECT: the frame's id is 14, not 7"),
        (with_bytes(GOOD_STATE, 1, le(0x500000, 3)), State, "MDAT_STATE latitude: 112.5"),
        (with_bytes(GOOD_STATE, 12, le(8101, 2)), State, "raw depth 8101 is beyond 8100"),
        (
            with_bytes(GOOD_STATE, 8, le(13 << 20 | 1 << 15, 3)),
            State,
            "month 13 day 1 00:00:00 is not a date",
        ),
        (
            with_bytes(GOOD_STATE, 8, le(0xF | 1 << 20 | 1 << 15, 3)),
            State,
            "00:00:60 is not a date",
        ),
        (
            b"\x10" + bytes.fromhex("04af210000") + bytes(26),
            Ranger,
            "latitude: nibble 0xA is not a decimal digit",
        ),
        (
            b"\x10" + bytes.fromhex("042f610000") + bytes(26),
            Ranger,
            "61.0000 minutes is not below 60",
        ),
        (b"\x10" + bytes.fromhex("095f000000") + bytes(26), Ranger, "95.000000 is beyond +-90"),
        (b"\x10" + bytes(17) + b"\x1a" + bytes(13), Ranger, "MDAT_RANGER speed: nibble 0xA"),
        (b"\x08\x06" + bytes(30), Position, "unknown position type 6"),
    ],
)
def test_bad_frames_say_why(data, cls, reason):
    with pytest.raises(CCLFrameError, match=reason.replace("+", r"\+").replace("(", r"\(")):
        (cls.decode if cls else decode_frame)(data)


def test_frames_longer_than_32_bytes_and_short_but_complete_ones():
    assert State.decode(GOOD_STATE + b"extra") == State.decode(GOOD_STATE)
    ranger = Ranger(latitude=1, longitude=2, depth=9).encode()
    assert Ranger.decode(ranger[:29]) == Ranger.decode(ranger)  # byte 28 is its last field
    with pytest.raises(CCLFrameError, match="28-byte frame, needs at least 29"):
        Ranger.decode(ranger[:28])


@pytest.mark.parametrize(
    "make, reason",
    [
        (lambda: State(latitude=90.5), "latitude = 90.5 is beyond"),
        (lambda: State(longitude=math.nan), "longitude = nan is not a finite number"),
        (lambda: State(heading="north"), "heading = 'north' is not a number"),
        (lambda: State(est_velocity=6.0), "est_velocity = 6.0 m/s is outside"),
        (lambda: State(fix_age=2000), "fix_age"),
        (lambda: State(time=TimeDate(13, 1, 0, 0, 0)), "month 13"),
        (lambda: State(battery_percent=256), "battery_percent = 256 is not an integer in 0..255"),
        (lambda: Redirect(row_length=70000), "row_length"),
        (lambda: Redirect(num_rows=2.5), "num_rows = 2.5"),
        (lambda: Ranger(depth=10000), "depth = 10000 does not fit 4 digits"),
        (lambda: Ranger(speed=-1), "speed = -1"),
        (lambda: Position(label="fourteen chars"), "label"),
        (lambda: Alert(contacts=[AlertContact()]), "carries 3 contacts, not 1"),
    ],
)
def test_values_a_frame_cannot_carry(make, reason):
    with pytest.raises(CCLEncodeError, match=reason.replace("+", r"\+")):
        make().encode()


def test_errors_are_dccl_errors():
    assert issubclass(CCLFrameError, DcclError) and issubclass(CCLEncodeError, DcclError)


# ------------------------------------------------------------------ fuzz
@settings(max_examples=examples(400))
@given(st.binary(max_size=40), st.sampled_from([None, *ALL_TYPES]))
def test_any_bytes_decode_or_raise_ccl_frame_error(data, cls):
    """No input makes a decoder raise anything but CCLFrameError, and whatever decodes can be
    encoded again."""
    try:
        decoded = decode_frame(data) if cls is None else cls.decode(data)
    except CCLFrameError:
        return
    again = type(decoded).decode(decoded.encode())
    assert type(again) is type(decoded)


@settings(max_examples=examples(300))
@given(st.sampled_from(ALL_TYPES), st.binary(min_size=32, max_size=32))
def test_frames_with_the_right_id_and_random_fields(cls, body):
    data = bytes([cls.ID if cls.ID is not None else body[0]]) + body[1:]
    try:
        decoded = cls.decode(data)
    except CCLFrameError as err:
        assert str(err).startswith(cls.NAME)
        return
    assert type(cls.decode(decoded.encode())) is cls
