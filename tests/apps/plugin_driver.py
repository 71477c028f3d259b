"""A pAcommsHandler driver plugin for tests (loaded through $PACOMMSHANDLER_PLUGINS): it
"transmits" by asking the queue for data and reporting the filled transmission as sent.

Its behaviour is steered through class attributes: `fail_startups` (how many startups fail
before one succeeds) and, per instance, `fail_next_work` (the next do_work raises)."""

from __future__ import annotations

from typing import ClassVar

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.driver_base import ModemDriverBase, ModemDriverError


class ScriptedDriver(ModemDriverBase):
    fail_startups = 0
    instances: ClassVar[list[ScriptedDriver]] = []

    def __init__(self, clock=None) -> None:
        super().__init__(clock)
        self.started = 0
        self.stopped = 0
        self.fail_next_work = False
        self.initiated: list = []
        self.cfg_updates: list = []
        ScriptedDriver.instances.append(self)

    def startup(self, cfg) -> None:
        self.cfg = cfg
        if ScriptedDriver.fail_startups > 0:
            ScriptedDriver.fail_startups -= 1
            raise ModemDriverError("modem absent", acomms_pb.ModemDriverStatus.STARTUP_FAILED)
        self.started += 1

    def shutdown(self) -> None:
        self.stopped += 1

    def do_work(self) -> None:
        if self.fail_next_work:
            self.fail_next_work = False
            raise ModemDriverError("modem silent", acomms_pb.ModemDriverStatus.MODEM_NOT_RESPONDING)

    def handle_initiate_transmission(self, transmission) -> None:
        self.initiated.append(transmission)
        self.signal_data_request.emit(transmission)
        self.signal_transmit_result.emit(transmission)

    def update_cfg(self, cfg) -> None:
        self.cfg_updates.append(cfg)


def goby_driver_name() -> str:
    return "SCRIPTED"


def goby_make_driver(clock=None) -> ScriptedDriver:
    return ScriptedDriver(clock)
