"""The TopsideError family: what the operator tools (the commander core, iCommander, liaison)
raise on purpose."""

from pygoby.errors import PygobyError


class TopsideError(PygobyError):
    """Base class of every topside error."""


class CommanderError(TopsideError):
    """The commander cannot do what was asked (unknown message, no multiplex variable, ...)."""


class FieldValueError(TopsideError, ValueError):
    """A value the field cannot take; the message names the field and the limit."""


class SpecialError(TopsideError, ValueError):
    """A placeholder that cannot be replaced (an x without its y, metres that are no number)."""


class SaveFileError(TopsideError, ValueError):
    """Not an iCommander save file."""


class ScopeFilterError(TopsideError, ValueError):
    """A Scope filter liaison does not take (too long)."""


class TooManyStreamsError(TopsideError):
    """Every live-update stream liaison allows is open (max_streams)."""


class LogFileError(TopsideError):
    """A file liaison cannot replay (missing, unreadable, not a MOOS .alog)."""


class LogControlError(TopsideError, ValueError):
    """A log replay request liaison does not take (a speed it does not offer, no number)."""
