"""The DcclError family: one base class for every DCCL failure."""

from pygoby.errors import PygobyError


class DcclError(PygobyError):
    """Base class of every DCCL error."""


class DcclLoadError(DcclError):
    """A message definition is not valid DCCL (raised when the type is loaded)."""


class DcclEncodeError(DcclError, ValueError):
    """A message cannot be encoded (missing required field, strict-mode violation, ...)."""


class DcclDecodeError(DcclError, ValueError):
    """Bytes cannot be decoded (truncated, unknown ID, wrong type, ...)."""
