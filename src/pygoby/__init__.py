"""pygoby: a pure-Python implementation of the Goby acoustic-communications stack."""

__version__ = "0.1.0"
