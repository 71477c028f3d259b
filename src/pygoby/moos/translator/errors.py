"""Errors raised by the translator (under `pygoby.moos.errors.MoosError`)."""

from pygoby.errors import ConfigError
from pygoby.moos.errors import MoosError


class TranslatorError(MoosError, ValueError):
    """A MOOS value could not be turned into a message (or a message into MOOS values).

    The translation is abandoned as a whole: no partially built message is returned.
    """


class TranslatorConfigError(TranslatorError, ConfigError):
    """A translator entry is unusable (unknown type or algorithm, bad format, ...)."""


class UnconvertibleError(TranslatorError):
    """A string names no value of an enum (the element is skipped, as upstream does)."""
