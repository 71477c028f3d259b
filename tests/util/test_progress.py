"""RunProgress: a rich bar on a terminal, plain lines at each tenth off one (after a few
seconds), speed in x real time for simulated seconds."""

from __future__ import annotations

import io

from pygoby.util import progress as progress_module
from pygoby.util.progress import RunProgress


class Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


class Clock:
    def __init__(self) -> None:
        self.t = 1000.0

    def __call__(self) -> float:
        return self.t


def test_plain_lines_at_each_tenth_once_the_run_has_lasted(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(progress_module.time, "monotonic", clock)
    out = io.StringIO()
    with RunProgress("simulated", 7200.0, "s", stream=out) as progress:
        clock.t += 1.0
        progress.update(720.0, messages=3)  # 1 s into the run: too early to say anything
        for step in range(2, 11):
            clock.t += 1.0
            progress.update(720.0 * step, messages=3 * step)
            progress.update(720.0 * step + 1, messages=3 * step)  # same tenth: no new line
    lines = out.getvalue().splitlines()
    # the speed counts from the first update (1 s in, 720 s done): 720 simulated s per second
    assert lines[0] == "simulated 2,160/7,200 s (30%): messages 9, 720x real time, ETA 7 s"
    assert lines[-1] == "simulated 7,200/7,200 s (100%): messages 30, 720x real time"
    assert len(lines) == 8


def test_a_total_known_later_and_work_done_before(monkeypatch):
    """As a resumed sweep reports: 40 of 100 runs already stored, then one run a second."""
    clock = Clock()
    monkeypatch.setattr(progress_module.time, "monotonic", clock)
    out = io.StringIO()
    with RunProgress("sweep", unit="runs", stream=out) as progress:
        progress.update(40, total=100)
        for done in range(41, 101):
            clock.t += 1.0
            progress.update(done, total=100)
    lines = out.getvalue().splitlines()
    assert lines[0] == "sweep 43/100 runs (40%): 1.00 runs/s, ETA 57 s"
    assert lines[-1] == "sweep 100/100 runs (100%): 1.00 runs/s"


def test_a_bar_on_a_terminal(monkeypatch):
    clock = Clock()
    monkeypatch.setattr(progress_module.time, "monotonic", clock)
    out = Terminal()
    with RunProgress("simulated", 100.0, "s", stream=out) as progress:
        clock.t += 2.0
        progress.update(50.0, packets=4)
        progress._bar.refresh()
        shown = out.getvalue()
    assert "simulated" in shown and "50/100 s" in shown and "packets 4" in shown
