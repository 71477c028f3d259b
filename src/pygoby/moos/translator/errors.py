"""Errors raised by the translator."""


class TranslatorError(Exception):
    """A MOOS value could not be turned into a message (or a message into MOOS values).

    The translation is abandoned as a whole: no partially built message is returned.
    """


class TranslatorConfigError(TranslatorError):
    """A translator entry is unusable (unknown type or algorithm, bad format, ...)."""
