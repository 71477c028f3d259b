"""The example files printed in the Goby 1.1 manual, without the listing's line numbers: what
examples/goby1.1/ ships, apart from the documented fixes and additions (README, "Coming from
Goby 1.1").

The manual is not part of this repository: the project keeps its text (seed document 003) in a
folder beside the repository (`../shared/seeds/`, or `$PYGOBY_SHARED/seeds/`). Tests that compare
with it skip when it is absent (a plain clone); EXAMPLES and LISTINGS work without it."""

from __future__ import annotations

import os
import re
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SHARED = Path(os.environ.get("PYGOBY_SHARED", REPO.parent / "shared"))
SEED = SHARED / "seeds" / "003_ee40e5deddca8942.txt"
EXAMPLES = REPO / "examples" / "goby1.1"

# shipped file -> (caption printed before the listing, number of lines)
LISTINGS = {
    "xml/example1.xml": ("Let’s call this file `example1.xml`", 95),
    "MOOS/basic_ccl/mm1.moos": (
        "*MOOS file for Node 1: goby/share/cfg/MOOS/basic\\_ccl/mm1.moos*",
        98,
    ),
    "MOOS/basic_ccl/mm2.moos": (
        "*MOOS file for Node 2: goby/share/cfg/MOOS/basic\\_ccl/mm2.moos*",
        88,
    ),
    "MOOS/ccl_and_dccl/mm1.moos": (
        "*MOOS file for Node 1: goby/share/cfg/MOOS/ccl\\_and\\_dccl/mm1.moos*",
        111,
    ),
    "MOOS/ccl_and_dccl/mm2.moos": (
        "MOOS file for Node 2: *goby/share/cfg/MOOS/ccl\\_and\\_dccl/mm2.moos*",
        112,
    ),
    "xml/simple_status.xml": (
        "*XML definition of Simple Status: goby/xml/simple\\_status.xml*",
        89,
    ),
    "MOOS/ccl_and_dccl/modemidlookup.txt": (
        "*Modem Lookup Table: goby/share/cfg/MOOS/ccl\\_and\\_dccl/modemidlookup.txt*",
        2,
    ),
}


def plogger_addition(community: str) -> list[str]:
    """The lines pygoby adds to each of the manual's missions (README): pLogger in the ANTLER
    block and its ProcessConfig, so that a run leaves the community's .alog."""
    return [
        "    // pygoby's addition (not in the manual): the community's log (pLogger below)",
        "    Run = pLogger @ NewConsole = false",
        "// pygoby's addition (not in the manual): the community's log in",
        f"// logs/{community}_<date>/{community}_<date>.alog (`pygoby log summary FILE`, "
        "`pygoby log plot FILE`)",
        "ProcessConfig = pLogger",
        "{",
        "    AppTick = 4",
        "    CommsTick = 4",
        f"    File = {community}",
        "    PATH = ./logs",
        "    WildCardLogging = true",
        "    WildCardOmitPattern = DB_VARSUMMARY, DB_RWSUMMARY  // values of many lines",
        "    LogAuxSrc = true",
        "}",
    ]


def listing(caption: str, count: int) -> list[str]:
    """Lines 1..count of the listing after `caption`. The print right-aligns the line numbers of
    some listings to two digits ("1  text", "10 text") and not others ("1 text"); text between
    the numbered lines (page breaks, a stray sentence) is skipped."""
    if not SEED.is_file():
        pytest.skip(f"the Goby 1.1 manual's text (seed 003) is absent: {SEED} (set PYGOBY_SHARED)")
    lines = SEED.read_text(encoding="utf-8").splitlines()
    start = next(i for i, line in enumerate(lines) if caption in line)
    out: list[str] = []
    width = None
    for raw in lines[start + 1 :]:
        if len(out) == count:
            break
        match = re.match(r"(\d+)( |$)", raw)
        if not match or int(match.group(1)) != len(out) + 1:
            continue
        if width is None:
            width = 2 if raw.startswith("1  ") else 1
        rest = raw[len(match.group(1)) :]
        pad = max(width - len(match.group(1)), 0)
        out.append(rest[1 + pad :] if rest[1 : 1 + pad].strip() == "" else rest[1:])
    assert len(out) == count, f"{caption}: found {len(out)} of {count} lines"
    return out


def printed(name: str) -> str:
    caption, count = LISTINGS[name]
    return "\n".join(listing(caption, count)) + "\n"
