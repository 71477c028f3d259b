"""The errors of the shared utilities. util is a set of independent helpers, not a layer a
caller catches as a whole, so each kind has its own root directly under `PygobyError`:
`NMEAError` for text that is not a valid NMEA-0183 sentence, `LinkClosedError` for writing to a
line link that is not open, `MissingExtraError` for a feature whose optional package is not
installed."""

from pygoby.errors import PygobyError


class NMEAError(PygobyError, ValueError):
    """A line is not a valid NMEA sentence."""


class NMEAFormatError(NMEAError):
    """Missing start character, bad token, non-ASCII text or a malformed checksum field."""


class NMEAChecksumError(NMEAError):
    """The `*HH` checksum does not match the sentence."""


class LinkClosedError(PygobyError, ConnectionError):
    """Writing to a link that is not open."""


class PtyError(PygobyError, OSError):
    """A pseudo-terminal link cannot be made (a running process owns it, or the path is not
    one we may replace)."""


class PluginError(PygobyError):
    """No plug-in could be found or loaded under the given name (pygoby.util.plugins)."""


class MissingExtraError(PygobyError, ImportError):
    """A feature's package is not installed; the text names the pip extra that installs it
    (pygoby.util.extras)."""
