"""iCommander's terminal UI (textual) over the commander core; the MOOS app is
`pygoby.apps.icommander`."""

from pygoby.topside.icommander.tui import ICommanderTUI

__all__ = ["ICommanderTUI"]
