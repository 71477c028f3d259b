"""Record C++ DCCL's bytes for REMUS State and Redirect frames (tests/dccl/data/remus_frames.jsonl).

    python tests/dccl/oracle/record_remus.py HARNESS --lib-dir DIR

Same harness and library directory as record.py (built outside this repository; nothing here
builds it). For each frame (edge cases, then random values in range) C++ encodes the CCLMDAT
message carrying it (tests/dccl/remus_cpp.py) and decodes its own bytes back; the tests compare
pygoby.dccl.ccl.remus's bytes and decoded values with both. Redirect frames keep both thrust
bits at m/s (with RPM C++ scales the speed otherwise; see pygoby.dccl.ccl.remus).
"""

from __future__ import annotations

import argparse
import json
import random
import sys
from pathlib import Path

from google.protobuf import text_format

REPO = Path(__file__).resolve().parents[3]
sys.path[:0] = [str(REPO / "src"), str(REPO)]

from pygoby.dccl.ccl import remus  # noqa: E402
from pygoby.dccl.codecs.numeric import f32  # noqa: E402
from tests.dccl.oracle.record import NOW, Oracle, ccl_times  # noqa: E402
from tests.dccl.remus_cpp import CCL_PROTO, DATA, MESSAGE, to_json, to_message  # noqa: E402

MPS = remus.THRUST_MPS_TRANSIT | remus.THRUST_MPS_SURVEY
# depths at the edges of the piecewise steps, speeds beyond the clamp
DEPTHS = [
    0.0,
    0.04,
    0.05,
    99.95,
    100.0,
    100.1,
    199.9,
    200.0,
    999.75,
    1000.0,
    5999.5,
    6000.0,
    7000.0,
    -3.0,
]


def f(rng: random.Random, low: float, high: float) -> float:
    """A float32 value (float fields: the decimal text names exactly this value)."""
    return f32(rng.uniform(low, high))


def random_state(rng: random.Random) -> remus.State:
    return remus.State(
        latitude=rng.uniform(-90, 90),
        longitude=rng.uniform(-180, 180),
        fix_age=rng.randint(0, 1020),
        time=remus.TimeDate.at(rng.randint(946_684_800, 2_050_000_000)),
        heading=f(rng, 0, 360),
        depth=rng.choice([f(rng, 0, 6000), f(rng, 0, 150), rng.choice(DEPTHS)]),
        mission_mode=rng.randrange(8),
        faults=rng.getrandbits(32),
        faults_2=rng.randrange(256),
        mission_leg=rng.randrange(256),
        est_velocity=f(rng, -5.12, 5.08),
        objective_index=rng.randrange(256),
        watts=f(rng, -10, 1100),
        lat_goal=rng.uniform(-90, 90),
        lon_goal=rng.uniform(-180, 180),
        battery_percent=rng.randrange(256),
        gfi_pitch_oil=remus.GFIPitchOil(f(rng, -5, 105), f(rng, -95, 95), f(rng, -5, 105)),
    )


def random_redirect(rng: random.Random) -> remus.Redirect:
    return remus.Redirect(
        latitude=rng.uniform(-90, 90),
        longitude=rng.uniform(-180, 180),
        message_number=rng.randrange(256),
        speed_depth_flags=rng.randrange(256) | MPS,
        transit_depth=rng.choice([f(rng, 0, 6000), rng.choice(DEPTHS)]),
        transit_speed=f(rng, -4.5, 4.5),
        transit_command=rng.randrange(256),
        survey_depth=f(rng, 0, 300),
        survey_speed=f(rng, -4.5, 4.5),
        survey_command=rng.randrange(256),
        num_rows=rng.randrange(256),
        row_length=rng.randrange(65536),
        spacing_0=rng.randrange(256),
        spacing_1=rng.randrange(256),
        row_heading=f(rng, 0, 360),
        start_latitude=rng.uniform(-90, 90),
        start_longitude=rng.uniform(-180, 180),
    )


def edge_frames() -> list[remus.State | remus.Redirect]:
    example = remus.State(
        latitude=42.35,
        longitude=-70.95,
        time=remus.TimeDate.at(NOW),
        heading=45.0,
        depth=111.0,
        est_velocity=f32(1.2),
    )
    out: list[remus.State | remus.Redirect] = [example]
    for lat, lon in [
        (0.0, 0.0),
        (-0.00001, -0.00001),
        (-42.35, -70.95),
        (90.0, 180.0),
        (-90.0, -180.0),
        (-LATLON, LATLON),
    ]:
        out.append(remus.State(latitude=lat, longitude=lon, lat_goal=-lat, lon_goal=-lon))
        out.append(
            remus.Redirect(latitude=lat, longitude=lon, start_latitude=-lat, start_longitude=-lon)
        )
    out += [remus.State(depth=d) for d in DEPTHS]
    out += [
        remus.Redirect(transit_depth=d, survey_depth=d, transit_speed=s, survey_speed=-s)
        for d, s in zip(
            DEPTHS,
            [0.0, 0.0166, 0.0167, 1.5, 4.2, 4.3, 5.0, 100.0, -4.3, 0.5, 2.0, 3.0, 1.0, -1.0],
            strict=True,
        )
    ]
    return out


LATLON = remus.LATLON_STEP  # the smallest non-zero coordinate


def main() -> int:
    parser = argparse.ArgumentParser(
        description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter
    )
    parser.add_argument("harness")
    parser.add_argument("--lib-dir", type=Path, required=True)
    parser.add_argument("--count", type=int, default=60, help="random frames of each type")
    parser.add_argument("--seed", type=int, default=15)
    args = parser.parse_args()
    rng = random.Random(args.seed)
    frames = edge_frames()
    frames += [random_state(rng) for _ in range(args.count)]
    frames += [random_redirect(rng) for _ in range(args.count)]
    oracle = Oracle(args.harness, args.lib_dir.resolve())
    records = []
    for index, frame in enumerate(frames):
        kind = type(frame).__name__
        now = ccl_times()[index % len(ccl_times())]
        oracle.open_codec("builtin", CCL_PROTO)
        oracle.configure(f"now {now}")
        text = text_format.MessageToString(to_message(frame, now), as_one_line=True)
        hex_bytes, error, status = oracle.encode(MESSAGE[kind], text)
        if status != "ok":
            raise RuntimeError(f"C++ could not encode {text}: {error}")
        decoded = oracle.decode(MESSAGE[kind], bytes.fromhex(hex_bytes))
        records.append(
            {
                "type": kind,
                "now": now,
                "values": to_json(frame),
                "cpp_text": text,
                "cpp_hex": hex_bytes,
                "cpp_decoded_bin": decoded["decoded_bin"],
            }
        )
    with DATA.open("w") as out:
        for record in records:
            out.write(json.dumps(record) + "\n")
    print(f"{DATA.relative_to(REPO)}: {len(records)} records", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
