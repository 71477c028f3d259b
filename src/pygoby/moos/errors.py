"""The MoosError family: what the MOOS layer (wire protocol, client, DB, mission files, apps'
configuration, translator) raises on purpose. `pygoby.moos.translator` adds TranslatorError
under MoosError; configuration problems are `pygoby.errors.ConfigError`s."""

from pygoby.errors import ConfigError, PygobyError


class MoosError(PygobyError):
    """Base class of every MOOS error."""


class MoosProtocolError(MoosError, ValueError):
    """Bytes that do not form a valid MOOS unit (bad length, truncated message, ...)."""


class MoosRefusedError(MoosError):
    """The DB refused the handshake (poison message); carries the DB's reason."""


class AntlerError(MoosError):
    """A mission cannot be started by antler (e.g. its DB port is taken)."""


class MissionFileError(MoosError, ConfigError):
    """A .moos mission file lacks what is asked of it (e.g. the ANTLER block)."""


class BlockSyntaxError(MoosError, ValueError):
    """A mistake TextFormat cannot read past (a scalar without its ':', a block never closed),
    at `line` of the block: reported as it is, before any field of the block is looked at."""

    def __init__(self, line: int, reason: str) -> None:
        super().__init__(f"line {line}: {reason}")
        self.line, self.reason = line, reason
