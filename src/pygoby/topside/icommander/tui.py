"""iCommander's screens as a textual app over the commander core: the main
menu, message selection, the editing screen and its action menu, keyboard-driven as in Goby 1.

Editing: Up/Down (or Tab/Shift+Tab) move between fields and the view follows, typing is checked
as it goes (a key that would make the value invalid, e.g. beyond the DCCL maximum, is refused and
the reason shown), Enter opens the action menu. Single-letter specials, only where they make
sense (the footer names those of the field): `t` the current time (time and double fields), `x`/`y`
the local x/y placeholders (a latitude/longitude pair), `m` a modem id (integer fields).

A status line on every screen shows the last acknowledgement or expiry and the `show_variable`
values. Keys are delivered one after the other to the screen that is current once the previous
key's effect (a menu choice opening the next screen) has settled, so fast typing loses none.
"""

from __future__ import annotations

import asyncio
from collections import deque
from collections.abc import Callable
from typing import ClassVar

from pygoby.util.extras import needs_extra

with needs_extra("topside", "iCommander's terminal interface"):
    from textual import events
    from textual.app import App, ComposeResult
    from textual.binding import Binding, BindingType
    from textual.containers import Vertical, VerticalScroll
    from textual.message_pump import MessagePump
    from textual.screen import ModalScreen, Screen
    from textual.widgets import Footer, Input, Label, OptionList, Static
    from textual.widgets.option_list import Option

from pygoby.errors import PygobyError
from pygoby.topside.commander import Commander, Draft, FieldValueError, Notice, Outgoing

TITLE = "iCommander: Vehicle Command Message Sender"
ACTIONS = [
    ("return", "Return to message"),
    ("send", "Send"),
    ("preview", "Preview"),
    ("switch", "Quick switch to another open message"),
    ("time", "Insert special: current time"),
    ("xy", "Insert special: local X,Y to longitude,latitude"),
    ("community", "Insert special: community"),
    ("modem_id", "Insert special: modem id"),
    ("clear", "Clear message"),
    ("menu", "Main Menu"),
]


def box_id(field: str) -> str:
    """The input box of a field (`pose.x` -> `field-pose--x`: widget ids take no dots, field
    names no hyphens)."""
    return "field-" + field.replace(".", "--")


# the letter typed in a field -> the special it inserts (where Commander.specials allows it)
SPECIAL_KEYS = {"t": "time", "x": "xy", "y": "xy", "m": "modem_id"}
SPECIAL_HELP = {"time": "t time", "xy": "x/y local x,y", "modem_id": "m modem id"}


class StatusLine(Static):
    """The last acknowledgement or expiry and the shown variables, on every screen."""

    DEFAULT_CSS = """
    StatusLine { dock: bottom; height: auto; max-height: 3; background: $warning 30%; padding: 0 1; }
    StatusLine.empty { display: none; }
    """

    def __init__(self) -> None:
        super().__init__(id="status", classes="empty")

    def on_mount(self) -> None:
        self.show(getattr(self.app, "status_text", ""))

    def show(self, text: str) -> None:
        self.update(text)
        self.set_class(not text, "empty")


class FieldInput(Input):
    """A field's box: Up/Down and Tab move between fields (an enclosing scroll view must not
    take them to scroll, which left the focus, and so the typing, in a field out of view)."""

    BINDINGS: ClassVar[list[BindingType]] = [
        Binding("down", "app.focus_next", "Next field"),
        Binding("up", "app.focus_previous", "Previous field"),
    ]


class FieldList(VerticalScroll, can_focus=False):
    """The fields; scrolled by the focus moving, never focused itself."""


class Menu(ModalScreen[str | None]):
    """A titled list of choices; Enter picks, Escape cancels."""

    BINDINGS: ClassVar[list[BindingType]] = [Binding("escape", "dismiss_none", "Back")]

    def __init__(self, title: str, choices: list[tuple[str, str]], menu_id: str) -> None:
        super().__init__(id=menu_id)
        self.title_text, self.choices = title, choices

    def compose(self) -> ComposeResult:
        yield StatusLine()
        with Vertical(classes="box"):
            yield Static(self.title_text, classes="title")
            yield OptionList(*(Option(text, id=key) for key, text in self.choices))

    def on_option_list_option_selected(self, event: OptionList.OptionSelected) -> None:
        self.dismiss(event.option.id)

    def action_dismiss_none(self) -> None:
        self.dismiss(None)


class Prompt(ModalScreen[str | None]):
    """One line of input (a file name)."""

    BINDINGS: ClassVar[list[BindingType]] = [Binding("escape", "dismiss_none", "Cancel")]

    def __init__(self, title: str, prompt_id: str) -> None:
        super().__init__(id=prompt_id)
        self.title_text = title

    def compose(self) -> ComposeResult:
        yield StatusLine()
        with Vertical(classes="box"):
            yield Static(self.title_text, classes="title")
            yield Input(placeholder="File name", id="path")

    def on_input_submitted(self, event: Input.Submitted) -> None:
        self.dismiss(event.value.strip() or None)

    def action_dismiss_none(self) -> None:
        self.dismiss(None)


class Report(ModalScreen[str | None]):
    """What was previewed or sent, then a choice of what next."""

    def __init__(self, text: str, choices: list[tuple[str, str]], report_id: str) -> None:
        super().__init__(id=report_id)
        self.text, self.choices = text, choices

    def compose(self) -> ComposeResult:
        yield StatusLine()
        with Vertical(classes="box"):
            yield Static(self.text, id="report-text")
            yield OptionList(*(Option(text, id=key) for key, text in self.choices))

    def on_option_list_option_selected(self, event: OptionList.OptionSelected) -> None:
        self.dismiss(event.option.id)


class EditScreen(Screen):
    """The editing screen: an information box and one line per message variable."""

    def __init__(self, commander: Commander, draft: Draft) -> None:
        super().__init__(id="edit")
        self.commander, self.draft = commander, draft
        self._values: dict[str, str] = {}
        self._quiet = False

    def compose(self) -> ComposeResult:
        kind = self.draft.type
        yield Static(id="info", classes="info")
        yield Static(
            f"Message (Type: {kind.short_name})  {len(kind.fields)} entries total",
            classes="title",
        )
        yield Static(id="keys", classes="keys")
        with FieldList():
            for number, spec in enumerate(kind.fields, start=1):
                label = "static" if spec.kind == "static" else spec.kind
                yield Label(f"{number}. {spec.name} ({label})", classes="field-name")
                box = FieldInput(
                    value=self.draft.value(spec.name),
                    id=box_id(spec.name),
                    disabled=not spec.editable,
                    compact=True,
                )
                self._values[spec.name] = box.value
                yield box
        yield StatusLine()
        yield Footer()

    def on_mount(self) -> None:
        editable = [s for s in self.draft.type.fields if s.editable]
        if editable:
            self.query_one(f"#{box_id(editable[0].name)}", Input).focus()

    def refresh_values(self) -> None:
        self._quiet = True
        for spec in self.draft.type.fields:
            box = self.query_one(f"#{box_id(spec.name)}", Input)
            box.value = self._values[spec.name] = self.draft.value(spec.name)
        self._quiet = False

    def show_info(self, text: str) -> None:
        self.query_one("#info", Static).update(text)

    def _field(self, box: Input) -> str:
        return (box.id or "").removeprefix("field-").replace("--", ".")

    def on_descendant_focus(self, event: events.DescendantFocus) -> None:
        if (
            isinstance(event.widget, Input)
            and event.widget.id
            and event.widget.id.startswith("field-")
        ):
            name = self._field(event.widget)
            kind = self.draft.type
            index = [f.name for f in kind.fields].index(name) + 1
            self.show_info(
                f"Editing message variable {index} of {len(kind.fields)}: {name}\n"
                f"{kind.field(name).describe()}"
            )
            specials = self.commander.specials(kind, name)
            self.query_one("#keys", Static).update(
                "Up/Down/Tab: fields  Enter: options"
                + (
                    f"  specials: {', '.join(SPECIAL_HELP[s] for s in specials if s in SPECIAL_HELP)}"
                    if specials
                    else ""
                )
            )

    def on_input_changed(self, event: Input.Changed) -> None:
        if self._quiet or not (event.input.id or "").startswith("field-"):
            return
        name, box = self._field(event.input), event.input
        before, text = self._values.get(name, ""), event.value
        typed = text[len(before) :] if text.startswith(before) else ""
        special = SPECIAL_KEYS.get(typed)
        if special is not None and special in self.commander.specials(self.draft.type, name):
            self._revert(box, before)
            self.app.run_action_for(self, special, name)  # type: ignore[attr-defined]
            return
        try:
            self.commander.check(self.draft, name, text, partial=True)
        except FieldValueError as err:
            self._revert(box, before)
            self.show_info(f"refused: {err}")
            return
        self._values[name] = text

    def _revert(self, box: Input, value: str) -> None:
        self._quiet = True
        box.value = value
        self._quiet = False

    def commit(self, name: str) -> bool:
        try:
            self.commander.set_value(self.draft, name, self._values.get(name, ""))
        except FieldValueError as err:
            self.show_info(f"refused: {err}")
            return False
        return True

    def on_input_submitted(self, event: Input.Submitted) -> None:
        name = self._field(event.input)
        if self.commit(name):
            self.app.open_actions(name)  # type: ignore[attr-defined]

    def on_descendant_blur(self, event: events.DescendantBlur) -> None:
        if isinstance(event.widget, Input) and (event.widget.id or "").startswith("field-"):
            self.commit(self._field(event.widget))


class ICommanderTUI(App):
    CSS = """
    .box { border: round $accent; padding: 0 1; height: auto; max-height: 90%; width: 90%; margin: 1 4; }
    .title { text-style: bold; padding: 0 0 1 0; }
    .info { border: round $secondary; padding: 0 1; height: auto; min-height: 4; max-height: 6; }
    .keys { color: $text-muted; }
    FieldInput { margin: 0 0 0 4; }
    """
    TITLE = TITLE

    def __init__(
        self,
        commander: Commander,
        show_variables: list[str] | None = None,
        on_exit: Callable[[], None] | None = None,
    ) -> None:
        super().__init__()
        self.commander = commander
        self.show_variables = {name: "" for name in show_variables or [] if name}
        self._on_exit = on_exit
        self.notice_text = ""
        self._typed: deque[events.Key] = deque()
        self._typing: asyncio.Task | None = None

    def compose(self) -> ComposeResult:
        yield StatusLine()

    def on_mount(self) -> None:
        self._main_menu()

    # ------------------------------------------------------------------ keys, one at a time
    async def on_event(self, event: events.Event) -> None:
        if isinstance(event, events.Key) and not event.is_forwarded:
            self._typed.append(event)
            if self._typing is None or self._typing.done():
                self._typing = asyncio.create_task(self._deliver_typed())
            return
        await super().on_event(event)

    async def _deliver_typed(self) -> None:
        """Each key in turn, once what the previous one set off has been handled: a key typed
        right after the Enter that opens a screen goes to that screen (textual forwards keys
        as they come, to whichever widget had the focus, and a menu then lost them)."""
        while self._typed:
            await super().on_event(self._typed.popleft())
            await self._settled()

    async def _settled(self, limit: float = 1.0) -> None:
        """Until the app, the current screen and the focused widget (with its containers) have
        had no message waiting for a few loop turns in a row (a handler that awaits, e.g. a
        screen being mounted, takes some); at most `limit` seconds."""
        loop = asyncio.get_running_loop()
        deadline, quiet = loop.time() + limit, 0
        while quiet < 5 and loop.time() < deadline:
            await asyncio.sleep(0)
            pumps: list[MessagePump] = [self, self.screen]
            if self.focused is not None:
                pumps += list(self.focused.ancestors_with_self)
            busy = any(not pump._message_queue.empty() for pump in pumps)
            quiet = 0 if busy else quiet + 1

    # ------------------------------------------------------------------ the MOOS side
    @property
    def status_text(self) -> str:
        shown = "  ".join(f"{k}: {v}" for k, v in self.show_variables.items() if v)
        return "\n".join(t for t in (self.notice_text, shown) if t)

    def _show_status(self) -> None:
        text = self.status_text
        for screen in self.screen_stack:
            for line in screen.query(StatusLine):
                line.show(text)

    def show_notice(self, notice: Notice) -> None:
        self.notice_text = " ".join(line.strip() for line in notice.banner().splitlines())
        self._show_status()

    def show_variable(self, name: str, value: object) -> None:
        if name in self.show_variables:
            self.show_variables[name] = f"{value:g}" if isinstance(value, float) else str(value)
            self._show_status()

    # ------------------------------------------------------------------ screens
    def _edit_screen(self) -> EditScreen | None:
        screen = self.screen
        return screen if isinstance(screen, EditScreen) else None

    def main_menu(self) -> None:
        """Shown once the screen that chose it has gone (menus call back while closing)."""
        self.call_later(self._main_menu)

    def _main_menu(self) -> None:
        while len(self.screen_stack) > 1:
            self.pop_screen()
        choices = [("return", "Return to active message")] if self.commander.active else []
        choices += [
            ("select", "Select Message"),
            ("load", "Load"),
            ("save", "Save"),
            ("import", "Import Message File"),
            ("exit", "Exit"),
        ]
        title = f"{TITLE}\n{len(self.commander.commands)} messages loaded.\nMain Menu:"
        self.push_screen(Menu(title, choices, "main-menu"), self._main_choice)

    def _main_choice(self, choice: str | None) -> None:
        if choice == "return" and self.commander.active:
            self.edit(self.commander.active.name)
        elif choice == "select":
            kinds = [(t.name, t.short_name) for t in self.commander.commands.types.values()]
            self.push_screen(Menu("Available Messages:", kinds, "select-message"), self._selected)
        elif choice in ("load", "save"):
            title = f"Choose a file to {'open' if choice == 'load' else 'save to'} (Esc to cancel):"
            self.push_screen(Prompt(title, f"{choice}-file"), lambda path: self._file(choice, path))
        elif choice == "import":
            title = "Choose an xml message file to import (Esc to cancel):"
            self.push_screen(Prompt(title, "import-file"), lambda path: self._file("import", path))
        elif choice == "exit":
            self.exit()
            if self._on_exit is not None:
                self._on_exit()
        else:
            self.main_menu()

    def _tell(self, text: str) -> None:
        self.push_screen(Report(text, [("menu", "OK")], "message"), lambda _: self.main_menu())

    def _file(self, what: str, path: str | None) -> None:
        if path is None:
            self.main_menu()
            return
        try:
            if what == "load":
                warnings = self.commander.load(path)
                self._tell(f"File read in:\n{path}" + "".join(f"\n  {w}" for w in warnings))
            elif what == "import":
                names = self.commander.import_xml(path)
                self._tell(f"Imported:\n{path}\n  {', '.join(names)}")
            else:
                self.commander.save(path)
                self._tell(f"Message saved to:\n{path}")
        except (OSError, PygobyError) as err:
            self._tell(f"Invalid {'xml ' if what == 'import' else ''}file:\n{path}\n{err}")

    def _selected(self, name: str | None) -> None:
        if name is None:
            self.main_menu()
        else:
            self.edit(name)

    def edit(self, name: str) -> None:
        self.call_later(self._edit, name)

    def _edit(self, name: str) -> None:
        while len(self.screen_stack) > 1:
            self.pop_screen()
        self.push_screen(EditScreen(self.commander, self.commander.open(name)))

    def open_actions(self, field: str) -> None:
        self.push_screen(
            Menu("Choose an action", ACTIONS, "actions"), lambda choice: self._action(choice, field)
        )

    def run_action_for(self, screen: EditScreen, action: str, field: str) -> None:
        self._action(action, field)

    def _action(self, action: str | None, field: str) -> None:
        screen = self._edit_screen()
        if screen is None or action in (None, "return"):
            return
        commander, draft = self.commander, screen.draft
        try:
            if action == "send":
                record = commander.send(draft)
                self._report(
                    f"Message(s) sent (#{record.record_id})"
                    + (
                        f", autosaved to {commander.autosave_path}"
                        if commander.autosave_path
                        else ""
                    ),
                    commander.preview(draft),
                    [("return", "Return to message"), ("menu", "Main menu")],
                )
            elif action == "preview":
                self._report(
                    "Previewing message (nothing published):",
                    commander.preview(draft),
                    [("return", "Return to message"), ("send", "Send")],
                )
            elif action == "switch":
                opened = [(d.name, d.type.short_name) for d in commander.drafts.values()]
                self.push_screen(
                    Menu("Choose an active message to switch to:", opened, "switch"),
                    lambda name: self.edit(name) if name else None,
                )
            elif action == "time":
                commander.insert_time(draft, field)
            elif action == "xy":
                commander.insert_xy(draft, field)
            elif action == "community":
                commander.insert_community(draft, field)
            elif action == "modem_id":
                ids = [(str(i), f"{i}: {name} ({kind})") for i, name, kind in commander.modem_ids()]
                self.push_screen(
                    Menu("Choose vehicle to insert id for:", ids, "modem-ids"),
                    lambda picked: self._modem_id(field, picked),
                )
            elif action == "clear":
                commander.clear(draft)
            elif action == "menu":
                self.main_menu()
                return
        except PygobyError as err:
            screen.show_info(f"refused: {err}")
        screen.refresh_values()

    def _modem_id(self, field: str, picked: str | None) -> None:
        screen = self._edit_screen()
        if screen is not None and picked is not None:
            try:
                self.commander.insert_modem_id(screen.draft, field, int(picked))
            except PygobyError as err:
                screen.show_info(f"refused: {err}")
            screen.refresh_values()

    def _report(self, heading: str, outgoing: Outgoing, choices: list[tuple[str, str]]) -> None:
        text = "\n".join([heading, *outgoing.lines()])
        if outgoing.warnings:
            text += "\n(Warning) " + "; ".join(outgoing.warnings)
        report_id = "sent" if choices[-1][0] == "menu" else "preview"
        self.push_screen(Report(text, choices, report_id), self._after_report)

    def _after_report(self, choice: str | None) -> None:
        if choice == "send":
            screen = self._edit_screen()
            if screen is not None:
                self._action("send", "")
        elif choice == "menu":
            self.main_menu()
