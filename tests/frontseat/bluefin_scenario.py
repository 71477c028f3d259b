"""A Bluefin driver and the Huxley simulator joined in memory, tick by tick, on a virtual clock:
deterministic, so the sentence exchange can be recorded and replayed.

Each tick at time t: the lines the simulator produced since the last tick reach the driver
(`>`), the driver works once (`do_work`) and what it writes (`<`) goes to the simulator, whose
replies and own sentences wait for the next tick. The helm drives from the start; from the
first tick in INTERFACE_COMMAND it asks for the course of `LEGS` every second (response
requested), as iFrontSeat passes pHelmIvP's DESIRED_* on.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

from google.protobuf import text_format

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.bluefin.simulator import HuxleyOptions, HuxleySimulator
from pygoby.frontseat.drivers.bluefin import BluefinFrontSeat
from pygoby.util.clock import VirtualClock
from pygoby.util.linebased import MemoryLink

T0 = 1_700_000_000.0  # 2023-11-14 22:13:20 UTC
TICK = 0.1  # s
LAT, LON = 44.0888889, 9.84861111
LEGS = [(0.0, 90.0, 1.5, 10.0), (20.0, 180.0, 2.0, 20.0)]  # (from s, heading, speed, depth)


def config(port: int = 29500, extra: str = "") -> object:
    return text_format.Parse(
        f"""
        name: "bluefin_auv"
        origin {{ lat: {LAT} lon: {LON} }}
        require_helm: true
        [goby.middleware.frontseat.protobuf.bluefin_config] {{
          huxley_tcp_address: "127.0.0.1"
          huxley_tcp_port: {port}
          {extra}
        }}
        """,
        frontseat_pb.Config(),
    )


def course_at(elapsed: float) -> tuple[float, float, float]:
    current = LEGS[0]
    for leg in LEGS:
        if elapsed >= leg[0]:
            current = leg
    return current[1:]


def command(heading: float, speed: float, depth: float, request_id: int) -> object:
    request = frontseat_pb.CommandRequest(response_requested=True, request_id=request_id)
    course = request.desired_course
    course.heading, course.speed, course.depth = heading, speed, depth
    return request


@dataclass
class Step:
    t: float  # s since T0
    to_driver: list[str]
    from_driver: list[str]


class Helm:
    """DRIVE from the start; the leg's course every second once in INTERFACE_COMMAND."""

    def __init__(self, driver: BluefinFrontSeat) -> None:
        self.driver = driver
        self.last: float | None = None
        self.requests = 0
        driver.set_helm_state(frontseat_pb.HELM_DRIVE)

    def act(self, elapsed: float) -> None:
        self.driver.set_helm_state(frontseat_pb.HELM_DRIVE)
        if self.driver.state != frontseat_pb.INTERFACE_COMMAND:
            return
        if self.last is None or elapsed >= self.last + 1.0 - 1e-9:
            self.last = elapsed
            self.driver.send_command_to_frontseat(command(*course_at(elapsed), self.requests))
            self.requests += 1


def driver_on_memory(
    cfg: object | None = None,
) -> tuple[BluefinFrontSeat, MemoryLink, VirtualClock]:
    clock = VirtualClock(T0)
    link = MemoryLink()
    link.open()
    driver = BluefinFrontSeat(cfg if cfg is not None else config(), clock, link=link)
    return driver, link, clock


def run_exchange(
    duration: float, options: HuxleyOptions | None = None, cfg: object | None = None
) -> tuple[list[Step], BluefinFrontSeat, HuxleySimulator]:
    driver, link, clock = driver_on_memory(cfg)
    simulator = HuxleySimulator(options)
    helm = Helm(driver)
    steps: list[Step] = []
    waiting = simulator.connect(T0)
    for n in range(round(duration / TICK) + 1):
        elapsed = round(n * TICK, 3)
        clock.set(T0 + elapsed)
        for line in waiting:
            link.feed(line + "\r\n")
        step = Step(elapsed, waiting, [])
        helm.act(elapsed)
        driver.do_work()
        step.from_driver = [text.removesuffix("\r\n") for text in link.take_written()]
        waiting = []
        for line in step.from_driver:
            waiting += simulator.handle_line(line, clock.now())
        waiting += simulator.tick(clock.now())
        steps.append(step)
    return steps, driver, simulator


def format_exchange(steps: list[Step]) -> str:
    out = []
    for step in steps:
        out += [f"{step.t:.1f} > {line}" for line in step.to_driver]
        out += [f"{step.t:.1f} < {line}" for line in step.from_driver]
    return "\n".join(out) + "\n"


def parse_exchange(text: str) -> Iterator[Step]:
    """The recorded steps back (ticks without traffic are not recorded)."""
    current: Step | None = None
    for line in text.splitlines():
        if not line.strip() or line.startswith("#"):
            continue
        t_text, direction, sentence = line.split(" ", 2)
        t = float(t_text)
        if current is None or current.t != t:
            if current is not None:
                yield current
            current = Step(t, [], [])
        (current.to_driver if direction == ">" else current.from_driver).append(sentence)
    if current is not None:
        yield current
