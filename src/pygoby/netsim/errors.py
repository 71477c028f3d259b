"""The NetsimError family: what the netsim simulator and netsim_manager raise (or report) on
purpose. Configuration problems (the manager's configuration, a scenario) are
`pygoby.errors.ConfigError`s."""

from __future__ import annotations

from pygoby.errors import ConfigError, PygobyError


class NetsimError(PygobyError):
    """Base class of every netsim error."""


class ScenarioError(NetsimError, ConfigError):
    """The scenario cannot be run (parse error or inconsistent settings)."""


class LineError(NetsimError, ValueError):
    """A NETSIM line that was dropped (reported as a value by the line decoder, never raised
    from it). Carries (a prefix of) the offending line for logging."""

    def __init__(self, reason: str, line: bytes = b"") -> None:
        super().__init__(reason)
        self.line = line[:80]

    def __str__(self) -> str:
        text = super().__str__()
        return f"{text}: {self.line!r}" if self.line else text


class LineTooLongError(LineError):
    """A line exceeded the length limit; it was discarded up to its newline."""


class MissingSeparatorError(LineError):
    """A line with fewer than two ``|``."""


class UnknownNameError(LineError):
    """A well-formed line whose type name is not one this reader handles."""

    def __init__(self, name: bytes, line: bytes = b"") -> None:
        super().__init__(f"unknown message name {name!r}", line)
        self.name = name
