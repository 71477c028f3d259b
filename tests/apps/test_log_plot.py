"""`pygoby log plot`: the series each figure draws, read from a mission's logs (checked as
data, not pixels), and the PNGs the command writes, with or without the data for them."""

from __future__ import annotations

from pathlib import Path

import pytest
from matplotlib import image

from pygoby.cli import main as pygoby_main
from pygoby.moosacomms.alog_series import AcommsVariables, Track, log_series

ALOG_DATA = Path(__file__).resolve().parents[1] / "data" / "alog"
ALOG, MISSION = ALOG_DATA / "acomms.alog", ALOG_DATA / "acomms.moos"
FIGURES = ("transmissions.png", "link_quality.png", "acks.png", "tracks.png")
PNG_MAGIC = b"\x89PNG\r\n\x1a\n"


def test_series_of_a_missions_log() -> None:
    """acomms.alog (make_acomms_alog.py) of the mission whose pAcommsHandler (modem 1) names
    its variables AC_*."""
    variables = AcommsVariables.of_mission(MISSION, "pAcommsHandler")
    assert (variables.transmit, variables.acked, variables.modem_id) == (
        "AC_MODEM_TRANSMIT",
        "AC_ACK_ORIGINAL",
        1,
    )
    series = log_series([ALOG], variables)
    assert series.start == pytest.approx(1764643673.12)
    assert series.transmissions == {1: [(4.5, "DATA")]}  # the sender is the src
    # receptions are the logging vehicle's: the mission's modem id, then its MODEM_ID post
    assert series.receptions == {1: [(1.0, "DATA"), (4.0, "DATA"), (14.5, "DATA")]}
    # the $CACST on AC_RAW_INCOMING: SNR in 14, out 11, MSE -12 dB
    assert (series.snr_in, series.snr_out, series.mse) == (
        {1: [(5.0, 14.0)]},
        {1: [(5.0, 11.0)]},
        {1: [(5.0, -12.0)]},
    )
    assert series.acked == {"logtest.Status": [10.5, 11.5]}
    assert series.expired == {"logtest.Status": [11.0]}
    # a point whenever X or Y changes once both are known; NAV_X@other is not this vehicle's
    assert series.tracks == {
        "acomms": Track("m", [(12.5, -4.0), (13.5, -4.0), (13.5, -3.0), (14.5, -3.0)])
    }
    # the garbage ModemTransmission and the $CACST that is not one
    assert series.skipped == {"AC_MODEM_RECEIVE": 1, "AC_RAW_INCOMING": 1}


def test_series_of_several_files_share_one_time_axis(tmp_path: Path) -> None:
    """A second vehicle's log opened 100 s later: its times are 100 s later on the axis, its
    own receiving modem comes from its MODEM_ID post, its track is its own."""
    later = tmp_path / "later.alog"
    text = ALOG.read_text().replace("1764643673.12", "1764643773.12")
    later.write_text(text.replace("MODEM_ID             pAcommsHandler  D:1.", "MODEM_ID  x  D:7."))
    series = log_series([ALOG, later], AcommsVariables.of_mission(MISSION, "pAcommsHandler"))
    assert series.transmissions == {1: [(4.5, "DATA"), (104.5, "DATA")]}
    # the second file's receptions before its MODEM_ID post: the mission's modem 1
    times = [t for t, _kind in series.receptions[1]]
    assert times == [1.0, 4.0, 14.5, 101.0, 104.0]
    assert series.receptions[7] == [(114.5, "DATA")]  # after MODEM_ID 7 at 10 s
    assert series.acked["logtest.Status"] == [10.5, 11.5, 110.5, 111.5]
    assert set(series.tracks) == {"acomms", "later"}
    # a file whose banner has no LOGSTART starts with the others
    headless = tmp_path / "headless.alog"
    headless.write_text("".join(line for line in text.splitlines(True) if "LOGSTART" not in line))
    series = log_series([later, headless], AcommsVariables.of_mission(MISSION, "pAcommsHandler"))
    assert series.start == pytest.approx(1764643773.12)
    assert series.transmissions == {1: [(4.5, "DATA"), (4.5, "DATA")]}


def test_plot_writes_the_figures(tmp_path: Path, capsys: pytest.CaptureFixture[str]) -> None:
    out = tmp_path / "figures"
    assert pygoby_main(["log", "plot", str(ALOG), "--mission", str(MISSION), "-o", str(out)]) == 0
    printed = capsys.readouterr().out.splitlines()
    assert printed[:4] == [str(out / name) for name in FIGURES]
    assert printed[4:] == [
        "transmissions: 1 sent, 3 received, modems 1",
        "$CACST statistics: 1",
        "messages: 2 acked, 1 expired",
        "tracks: acomms (4 points)",
        "values that did not parse (skipped): AC_MODEM_RECEIVE 1, AC_RAW_INCOMING 1",
    ]
    for name in FIGURES:
        _assert_png(out / name)


def test_plot_without_the_data_still_writes_every_figure(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    """Without --mission the variables are pAcommsHandler's defaults (ACOMMS_*), so the AC_*
    values of acomms.alog are not acomms data; the figures say "no data"."""
    out = tmp_path / "empty"
    assert pygoby_main(["log", "plot", str(ALOG), "-o", str(out)]) == 0
    assert capsys.readouterr().out.splitlines()[4:] == [
        "transmissions: 0 sent, 0 received, modems -",
        "$CACST statistics: 0",
        "messages: 0 acked, 0 expired",
        "tracks: acomms (4 points)",  # NAV_* do not depend on the mission
    ]
    for name in FIGURES:
        _assert_png(out / name)


def test_plot_with_a_bad_mission_says_where(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    mission = tmp_path / "bad.moos"
    mission.write_text("ProcessConfig = pAcommsHandler\n{\n  modem_id: one\n}\n")
    args = ["log", "plot", str(ALOG), "--mission", str(mission), "-o", str(tmp_path)]
    assert pygoby_main(args) == 1
    err = capsys.readouterr().err
    assert err.startswith(f"pygoby log: {mission}:3: modem_id: ") and "Traceback" not in err
    assert not list(tmp_path.glob("*.png"))


def _assert_png(path: Path) -> None:
    assert path.read_bytes()[:8] == PNG_MAGIC
    height, width, _channels = image.imread(path).shape
    assert width >= 600 and height >= 200
