"""pygoby: a pure-Python implementation of the Goby acoustic-communications stack."""

from pygoby.errors import ConfigError, PygobyError

__version__ = "0.1.0"

__all__ = ["ConfigError", "PygobyError", "__version__"]
