"""`common { show_gui: true }`: a live terminal view of a Goby MOOS app (goby3: an NCurses GUI),
made with textual. On the left the app's state (`app.status_lines()`: for pAcommsHandler the
driver, the current MAC slot and every queue's size), below it the log groups seen so far; on
the right the log at `common.verbosity`, all groups or the one selected. `q` (or Ctrl+C) stops
the app.

When standard output is not a terminal (a pipe, a file, antler's prefixes) there is no GUI
(`gui_for(app)` is None) and the log stays plain text. GobyMOOSApp.run does:

    gui = gui_for(app)
    if gui is not None:
        app.terminal_handler = gui.handler      # before app.start()
        await gui.run_until(stop_event)
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import sys
from collections import deque
from typing import TYPE_CHECKING, Any, ClassVar, Protocol

from pygoby.util.extras import needs_extra

with needs_extra("topside", "common.show_gui's live view"):
    from textual.app import App, ComposeResult
    from textual.binding import Binding, BindingType
    from textual.containers import Horizontal, Vertical
    from textual.css.query import NoMatches
    from textual.widgets import Footer, Header, OptionList, RichLog, Static
    from textual.widgets.option_list import Option

from pygoby.util.glog import GobyFormatter, group_name, level_for

if TYPE_CHECKING:
    pass


class ShownApp(Protocol):
    """What the live view needs of an app (pygoby.moos.app.GobyMOOSApp is one): typed here so
    this module does not import the app base that opens it."""

    name: str
    common: Any  # the app's GobyMOOSAppConfig `common` block

    def status_lines(self) -> list[str]: ...

    def request_stop(self) -> None: ...


ALL = "(all groups)"
KEPT_LINES = 5000
REFRESH = 0.25  # s between redraws of the status and the new log lines


class LogBuffer(logging.Handler):
    """The GUI's log handler: formatted lines with their group, the newest KEPT_LINES."""

    def __init__(self, level: int) -> None:
        super().__init__(level)
        self.setFormatter(GobyFormatter())
        self.lines: deque[tuple[str, str]] = deque(maxlen=KEPT_LINES)
        self.groups: dict[str, int] = {}  # group -> lines seen
        self.added = 0  # lines ever added (the view draws the ones it has not drawn)

    def emit(self, record: logging.LogRecord) -> None:
        try:
            text = self.format(record)
        except Exception:
            self.handleError(record)
            return
        group = group_name(record.name) or "(app)"
        self.lines.append((group, text))
        self.groups[group] = self.groups.get(group, 0) + 1
        self.added += 1


class AppGUI(App[None]):
    CSS = """
    #side { width: 44; }
    #status { height: auto; border: round $accent; padding: 0 1; }
    #groups { height: 1fr; border: round $accent; }
    #log { border: round $accent; }
    """
    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("q", "quit_app", "Quit"),
        Binding("ctrl+c", "quit_app", "Quit", show=False),
    ]

    def __init__(self, app: ShownApp) -> None:
        super().__init__()
        self.moos_app = app
        self.handler = LogBuffer(level_for(app.common.verbosity))
        self.selected = ALL
        self._drawn = 0
        self._listed: list[str] = []
        self.title = f"{app.name} ({app.common.community or 'no community'})"

    def compose(self) -> ComposeResult:
        yield Header()
        with Horizontal():
            with Vertical(id="side"):
                yield Static(id="status")
                yield OptionList(Option(ALL, id=ALL), id="groups")
            yield RichLog(id="log", wrap=False, max_lines=KEPT_LINES)
        yield Footer()

    def on_mount(self) -> None:
        self.set_interval(REFRESH, self.refresh_view)
        self.refresh_view()

    def refresh_view(self) -> None:
        try:
            status = self.query_one("#status", Static)
        except NoMatches:  # a tick of the interval while the app shuts down: the widgets are gone
            return
        status.update("\n".join(self.moos_app.status_lines()))
        groups = sorted(self.handler.groups)
        if groups != self._listed:
            self._listed = groups
            options = self.query_one("#groups", OptionList)
            options.clear_options()
            options.add_options([Option(ALL, id=ALL)] + [Option(g, id=g) for g in groups])
        self._draw_new_lines()

    def _draw_new_lines(self) -> None:
        view = self.query_one("#log", RichLog)
        new = self.handler.added - self._drawn
        if new <= 0:
            return
        lines = list(self.handler.lines)[-min(new, len(self.handler.lines)) :]
        for group, text in lines:
            if self.selected in (ALL, group):
                view.write(text)
        self._drawn = self.handler.added

    def on_option_list_option_selected(self, event: OptionList.OptionSelected) -> None:
        self.selected = event.option.id or ALL
        view = self.query_one("#log", RichLog)
        view.clear()
        for group, text in self.handler.lines:
            if self.selected in (ALL, group):
                view.write(text)
        self._drawn = self.handler.added

    def action_quit_app(self) -> None:
        self.moos_app.request_stop()

    async def run_until(self, stop: asyncio.Event) -> None:
        """Show the GUI until `stop` is set (by `q`, a signal or the app itself)."""
        task = asyncio.ensure_future(self.run_async())
        try:
            await stop.wait()
        finally:
            self.exit()
            with contextlib.suppress(Exception):
                await task


def gui_for(app: ShownApp) -> AppGUI | None:
    """The GUI when `common.show_gui` asks for one and stdout is a terminal; else None."""
    if not app.common.show_gui or not sys.stdout.isatty():
        return None
    return AppGUI(app)
