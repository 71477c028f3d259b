"""Property tests: round trips within precision; bad bytes raise only DcclError."""

from __future__ import annotations

import contextlib

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pygoby.dccl import Codec, DcclError
from pygoby.dccl.options import message_options
from pygoby.util.clock import VirtualClock
from tests.dccl.strategies import assert_close, message_strategy
from tests.dccl.vectors import message_class
from tests.hypothesis_profiles import examples

NOW = 1_700_000_000.0
ROUND_TRIP = [
    ("example.proto", "example.Example"),
    ("example.proto", "example.Tiny"),
    ("example.proto", "example.LongId"),
    ("versions.proto", "ver.V2"),
    ("versions.proto", "ver.V3"),
    ("versions.proto", "ver.V4"),
    ("edge.proto", "edge.Rep"),
    ("edge.proto", "edge.Nest"),
    ("edge.proto", "edge.OneOf"),
    ("edge.proto", "edge.Enums"),
    ("features.proto", "feat.PresenceAll"),
    ("features.proto", "feat.Oneofs"),
    ("features.proto", "feat.V3Misc"),
]
ALL_TYPES = [
    *ROUND_TRIP,
    ("features.proto", "feat.Numeric"),
    ("features.proto", "feat.Time"),
    ("features.proto", "feat.V2Misc"),
    ("features.proto", "feat.HeadBody"),
    ("edge.proto", "edge.V2Str"),
    ("edge.proto", "edge.Str"),
    ("inhead.proto", "ih.M2"),
]
SETTINGS = settings(
    max_examples=examples(150), deadline=None, suppress_health_check=[HealthCheck.too_slow]
)


def _codec(passphrase: str | None = None) -> Codec:
    return Codec(passphrase=passphrase, clock=VirtualClock(NOW))


@pytest.mark.parametrize(("proto", "name"), ROUND_TRIP, ids=[n for _, n in ROUND_TRIP])
@pytest.mark.parametrize("passphrase", [None, "pass"], ids=["clear", "encrypted"])
def test_round_trip_within_precision(proto: str, name: str, passphrase: str | None) -> None:
    cls = message_class(proto, name)
    codec = _codec(passphrase)
    codec.load(cls)
    version = message_options(cls.DESCRIPTOR).codec_version

    @SETTINGS
    @given(message_strategy(cls.DESCRIPTOR, NOW))
    def check(msg) -> None:
        data = codec.encode(msg)
        assert len(data) <= codec.max_size(cls)
        decoded = codec.decode(data, cls)
        assert_close(msg, decoded, version)
        assert codec.encode(decoded) == data  # decoding then encoding is stable

    check()


@pytest.mark.parametrize(("proto", "name"), ALL_TYPES, ids=[n for _, n in ALL_TYPES])
def test_random_bytes_raise_only_dccl_errors(proto: str, name: str) -> None:
    cls = message_class(proto, name)
    codec = _codec("key")
    clear = _codec()
    for c in (codec, clear):
        c.load(cls)

    @SETTINGS
    @given(st.binary(max_size=80), st.booleans())
    def check(data: bytes, typed: bool) -> None:
        for c in (codec, clear):
            with contextlib.suppress(DcclError):
                c.decode(data, cls if typed else None)

    check()


@pytest.mark.parametrize(("proto", "name"), ROUND_TRIP, ids=[n for _, n in ROUND_TRIP])
def test_truncated_encodings_raise_dccl_errors(proto: str, name: str) -> None:
    cls = message_class(proto, name)
    codec = _codec()
    codec.load(cls)

    @SETTINGS
    @given(message_strategy(cls.DESCRIPTOR, NOW), st.data())
    def check(msg, data) -> None:
        encoded = codec.encode(msg)
        cut = data.draw(st.integers(0, max(0, len(encoded) - 1)))
        try:
            codec.decode(encoded[:cut], cls)
        except DcclError:
            return
        # a prefix may still hold a whole message when the tail was only zero padding
        assert encoded[cut:].strip(b"\0") == b"" or cut == len(encoded)

    check()
