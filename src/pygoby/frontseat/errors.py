"""The FrontSeatError family: what the frontseat interface, its drivers, the driver loader and
the basic simulator raise on purpose.

(`pygoby.frontseat.messages.FrontSeatError` is the protobuf enum of frontseat error codes, by
its goby3 name; this module's `FrontSeatError` is the exception at the root of the family.)
"""

from __future__ import annotations

from typing import Any

from google.protobuf import text_format

from pygoby.errors import ConfigError, PygobyError
from pygoby.frontseat import messages as frontseat_pb


class FrontSeatError(PygobyError):
    """Base class of every frontseat error."""


class FrontSeatDriverError(FrontSeatError):
    """A driver raises it from loop() to force an error state, from any state; goby3's
    FrontSeatException.

    Carries at most one of a HelmError (-> INTERFACE_HELM_ERROR) or a FrontSeatError code
    (-> INTERFACE_FS_ERROR); one with neither is not a state change and propagates out of
    `do_work()`.
    """

    def __init__(
        self,
        *,
        helm_error: frontseat_pb.HelmError.ValueType | None = None,
        frontseat_error: frontseat_pb.FrontSeatError.ValueType | None = None,
        message: str = "",
    ) -> None:
        if helm_error is not None and frontseat_error is not None:
            raise ValueError(
                "a FrontSeatDriverError carries a helm error or a frontseat error, not both"
            )
        self.helm_error = helm_error
        self.frontseat_error = frontseat_error
        self.message = message
        if helm_error is not None:
            what = _code_name(frontseat_pb.HelmError, helm_error)
        elif frontseat_error is not None:
            what = _code_name(frontseat_pb.FrontSeatError, frontseat_error)
        else:
            what = ""
        super().__init__(": ".join(part for part in (what, message) if part))

    @property
    def is_helm_error(self) -> bool:
        return self.helm_error is not None

    @property
    def is_fs_error(self) -> bool:
        return self.frontseat_error is not None


def _code_name(enum: Any, code: int) -> str:
    return enum.Name(code) if code in enum.values() else str(code)


class FrontSeatFatalError(FrontSeatError, RuntimeError):
    """Raised by do_work() in an error state when `exit_on_error` is set (the app exits 1)."""

    def __init__(self, status: Any) -> None:
        self.status = status
        super().__init__(
            f"error state {frontseat_pb.InterfaceState.Name(status.state)} with exit_on_error: "
            f"true ({text_format.MessageToString(status, as_one_line=True)})"
        )


class DriverLoadError(FrontSeatError):
    """No frontseat driver could be found or made from the given name."""


class SimulatorProtocolError(FrontSeatError, ValueError):
    """A basic-simulator line that is not `KEY,NAME:VALUE,...`, or a message field missing or
    out of range."""


class AbcConfigError(FrontSeatError, ConfigError):
    """The frontseat Config lacks a usable `basic_simulator_config`."""


class BluefinConfigError(FrontSeatError, ConfigError):
    """The frontseat Config lacks a usable `bluefin_config`."""
