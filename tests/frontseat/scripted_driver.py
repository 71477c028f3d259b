"""A frontseat driver for tests whose frontseat command state and data state are set by the
test (`fs_state`, `providing`), which records what it was asked to send, counts its loop()
calls and raises `raise_in_loop` (once) from loop(). Also loadable as a driver plug-in
(`tests.frontseat.scripted_driver`)."""

from __future__ import annotations

from pygoby.frontseat import messages as frontseat_pb
from pygoby.frontseat.interface import InterfaceBase


class ScriptedFrontSeat(InterfaceBase):
    def __init__(self, cfg, clock=None) -> None:
        super().__init__(cfg, clock)
        self.fs_state = frontseat_pb.FRONTSEAT_NOT_CONNECTED
        self.providing = False
        self.loop_calls = 0
        self.raise_in_loop: Exception | None = None
        self.commands: list = []
        self.data: list = []
        self.raws: list = []

    def send_command_to_frontseat(self, command) -> None:
        self.commands.append(command)

    def send_data_to_frontseat(self, data) -> None:
        self.data.append(data)

    def send_raw_to_frontseat(self, raw) -> None:
        self.raws.append(raw)

    def frontseat_state(self) -> int:
        return self.fs_state

    def frontseat_providing_data(self) -> bool:
        return self.providing

    def loop(self) -> None:
        self.loop_calls += 1
        exc, self.raise_in_loop = self.raise_in_loop, None
        if exc is not None:
            raise exc


def frontseat_driver_load(cfg, clock=None) -> ScriptedFrontSeat:
    return ScriptedFrontSeat(cfg, clock)


def not_a_driver(cfg, clock=None):
    """A factory that breaks the contract (returns no driver)."""
    return None
