"""What liaison's pages show, from MOOS mail (the models without a browser)."""

from __future__ import annotations

from .liaison_server import Served


def test_the_acomms_page_shows_the_drivers_state(tmp_path):
    s = Served(tmp_path)
    s.web._socket.close()
    s.mail(
        "ACOMMS_DRIVER_STATUS",
        "primary driver WHOI_MICROMODEM::1: failed (1x): STARTUP_FAILED: could not open port "
        "/dev/ttyUSB7; next attempt in 60 s",
    )
    page = s.state.page("acomms", s.clock)
    assert page["drivers"] == [
        "primary driver WHOI_MICROMODEM::1: failed (1x): STARTUP_FAILED: could not open port "
        "/dev/ttyUSB7; next attempt in 60 s"
    ]
    s.mail("ACOMMS_DRIVER_STATUS", "primary driver WHOI_MICROMODEM::1: running")
    assert s.state.page("acomms", s.clock)["drivers"] == [
        "primary driver WHOI_MICROMODEM::1: running"
    ]
