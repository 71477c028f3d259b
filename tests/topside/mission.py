"""A topside mission for the operator tools' tests: the two pAcommsHandler communities of
tests/apps (embedded MOOSDBs, emulated Micro-Modems on loopback TCP), a modem id lookup file
naming them, and a mission file for vehicle 1's operator tools (liaison / iCommander)."""

from __future__ import annotations

from pathlib import Path

from tests.apps.acomms_mission import TwoCommunities, mission_text

LOOKUP = "0, broadcast, broadcast\n1, vehicle1, ship\n2, vehicle2, auv\n"


def topside_mission(net: TwoCommunities, tmp_path: Path, blocks: str) -> Path:
    """vehicle1's mission with `blocks` (ProcessConfig blocks of the operator tools) added."""
    lookup = tmp_path / "modemidlookup.txt"
    lookup.write_text(LOOKUP)
    text = mission_text(1, net.dbs[0].port, net.sims[0].port, net.extra, net.slots, warp=net.warp)
    path = tmp_path / "topside.moos"
    path.write_text(
        f"LatOrigin = 42.358\nLongOrigin = -71.087\nmodem_id_lookup_path = {lookup}\n"
        f"{text}\n{blocks}\n"
    )
    return path
