"""`make demo` (python -m pygoby.demo) runs the two-vehicle mission and exits 0."""

from __future__ import annotations

import re
import subprocess
import sys


def test_demo_exits_zero_with_traffic_both_ways():
    done = subprocess.run(
        [sys.executable, "-m", "pygoby.demo"], capture_output=True, text=True, timeout=60
    )
    assert done.returncode == 0, done.stdout[-2000:] + done.stderr[-2000:]
    out = done.stdout
    assert "demo finished OK" in out
    assert "command 1 acknowledged" in out and "unicorn: command received" in out
    assert re.search(r"slot 0 \(topside\)", out) and re.search(r"slot 1 \(unicorn\)", out)
    delivered = int(re.search(r"(\d+) messages delivered end to end", out).group(1))
    assert delivered >= 20  # 400 s of 20 s TDMA cycles: a status each way per cycle + commands
    assert "Traceback" not in done.stderr
