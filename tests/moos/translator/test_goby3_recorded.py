"""Translator entries replayed against what goby3's own C++ pTranslator (3.1.5a) published for
them: FORMAT creates that match only part of their input, publish directives naming no
field, printf directives on algorithm outputs and goby3-examples' ccl_and_dccl mm2 entry.
The recordings and how they were made: tests/data/goby3/README.md."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from google.protobuf import text_format

from pygoby.moos.translator import Translator, entry_class
from pygoby.protobuf import ProtoLoader

TESTS = Path(__file__).resolve().parents[2]
RECORDINGS = TESTS / "data" / "goby3" / "translator_partial_format.jsonl"
PROTO_DIRS = {
    "translator_test.proto": TESTS / "moos" / "translator" / "protos",
    "simple_status.proto": TESTS / "apps" / "data" / "dual_status",
}
RECORDS = [json.loads(line) for line in RECORDINGS.read_text().splitlines() if line.strip()]
CASES = [r for r in RECORDS if not r["goby3_crashed"]]
CRASHES = [r for r in RECORDS if r["goby3_crashed"]]


@pytest.fixture(scope="module")
def loaders() -> dict[str, ProtoLoader]:
    out = {}
    for name, directory in PROTO_DIRS.items():
        loader = ProtoLoader([directory])
        loader.load_file(directory / name)
        out[name] = loader
    return out


def same_value(ours: str | float | bytes, theirs: str | float) -> bool:
    if isinstance(theirs, float) and isinstance(ours, float) and math.isnan(theirs):
        return math.isnan(ours)
    return ours == theirs


def test_every_recorded_case_has_what_goby3_published():
    assert len(CASES) >= 20
    for case in CASES:
        assert case["published"], case["case"]


def test_the_ccl_records_use_the_example_missions_own_entry():
    mission = (TESTS / "apps" / "data" / "ccl_and_dccl" / "mm2.moos").read_text()
    ccl = [c for c in CASES if c["case"].startswith("ccl_and_dccl_mm2")]
    assert len(ccl) == 3
    for case in ccl:
        assert case["entry"] in mission


def entry_of(case):
    # the entry as it stands in the mission: `translator_entry { ... }`
    body = case["entry"].strip().removeprefix("translator_entry").strip()
    return text_format.Parse(body.removeprefix("{").removesuffix("}"), entry_class()())


def translator_for(case, loaders, entry):
    return Translator(
        [entry],
        loaders[case["proto"]].message_class,
        lat_origin=case["lat_origin"],
        lon_origin=case["lon_origin"],
    )


@pytest.mark.parametrize("case", CASES, ids=[c["case"] for c in CASES])
def test_pygoby_publishes_what_goby3_published(case, loaders):
    entry = entry_of(case)
    translator = translator_for(case, loaders, entry)
    variables = {i["var"]: i["value"] for i in case["inputs"]}
    msg = translator.create(entry.protobuf_name, variables)
    ours = {post.var: post for post in translator.publish(msg)}
    theirs = {p["var"]: p for p in case["published"]}
    assert sorted(ours) == sorted(theirs)
    for var, recorded in theirs.items():
        post = ours[var]
        expected = recorded["value"]
        assert isinstance(post.value, float) == (recorded["type"] == "double"), var
        assert same_value(post.value, expected), (var, post.value, expected)
        assert post.source_aux == recorded["src_aux"], var


# What pygoby creates where goby3 died (QUIRKS.md Q-APPS-10): `%116%` appends the names;
# `%116.1%` pads with the enum's first value, as other repeated fields pad with their default,
# and sets index 1 (to the enum's first value when the input has no name of it).
AFTER_GOBY3_CRASH = {
    "format_repeated_enum_index_empty": "enum_default_repeat={ENUM_A,ENUM_A}",
    "format_repeated_enum_index_given": "enum_default_repeat={ENUM_A,ENUM_B}",
    "format_repeated_enum_append": "enum_default_repeat={ENUM_A,ENUM_C}",
}


def test_the_crash_records_are_the_ones_pygoby_departs_from():
    assert sorted(c["case"] for c in CRASHES) == sorted(AFTER_GOBY3_CRASH)
    for case in CRASHES:
        assert case["published"] == []
        assert case["goby3_errors"] == [
            "(Error): uncaught exception: Protocol Buffer reflection usage error:"
        ]


@pytest.mark.parametrize("case", CRASHES, ids=[c["case"] for c in CRASHES])
def test_a_repeated_enum_index_goby3_dies_on_creates_the_message(case, loaders):
    entry = entry_of(case)
    translator = translator_for(case, loaders, entry)
    variables = {i["var"]: i["value"] for i in case["inputs"]}
    posts = translator.publish(translator.create(entry.protobuf_name, variables))
    assert {post.var: post.value for post in posts}["OUT_KV"] == AFTER_GOBY3_CRASH[case["case"]]
