"""The root of pygoby's error family.

Every error pygoby raises on purpose is a `PygobyError`. Each package has one root of its own,
defined with the rest of its family in the package's `errors` module and exported by the
package, so a caller catches one class per layer:

    pygoby.dccl.DcclError          pygoby.moos.MoosError (translator errors under it)
    pygoby.acomms.AcommsError      pygoby.netsim.NetsimError
    pygoby.frontseat.FrontSeatError
    pygoby.protobuf.ProtoError     (.proto files and message types)
    pygoby.util.NMEAError, pygoby.util.LinkClosedError   (independent helpers: one per kind)

Every configuration problem, whichever package finds it, is a `ConfigError` (or a subclass that
is also under its package's root, e.g. `ScenarioError`, `TranslatorConfigError`) that says
where (file:line) and which field. Standard mix-ins let callers catch the usual kinds:
`ValueError` for bad values (ConfigError, decode errors), `ConnectionError` for closed links.
"""

from __future__ import annotations

from os import PathLike


class PygobyError(Exception):
    """Base class of every error pygoby raises on purpose."""


class ConfigError(PygobyError, ValueError):
    """A configuration (file, block or command-line option) cannot be used.

    `file`, `line` and `field` say where, when known; `str()` puts them in front of the reason
    as `file:line: field: reason`, the form editors and terminals link to.
    """

    def __init__(
        self,
        reason: str,
        *,
        file: str | PathLike[str] | None = None,
        line: int | None = None,
        field: str | None = None,
    ) -> None:
        self.reason = reason
        self.file = None if file is None else str(file)
        self.line = line
        self.field = field
        super().__init__(self._text())

    def _text(self) -> str:
        where = ""
        if self.file is not None:
            where = self.file if self.line is None else f"{self.file}:{self.line}"
        elif self.line is not None:
            where = f"line {self.line}"
        parts = [p for p in (where, self.field) if p]
        return ": ".join([*parts, self.reason])

    def located(
        self, *, file: str | PathLike[str] | None = None, line: int | None = None
    ) -> ConfigError:
        """This error with a file (and line) filled in where it had none: for the caller that
        knows which file the failing block came from."""
        if self.file is None and file is not None:
            self.file = str(file)
        if self.line is None and line is not None:
            self.line = line
        self.args = (self._text(),)
        return self
