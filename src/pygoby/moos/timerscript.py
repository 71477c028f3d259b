"""uTimerScript's script, sans I/O: timed MOOS posts, as MOOS-IvP's uTimerScript runs them.

The subset missions use (MOOS-IvP ivp/src/uTimerScript):

* `EVENT = var=NAME, val=VALUE, time=T` (or `time=A:B`, uniformly random in [A, B]; `amt=N`
  repeats the event; `quit` posts EXITED_NORMALLY and ends the app). VALUE is a double when it
  reads as a number, else a string; a double-quoted VALUE is always a string, its quotes are
  removed and `\\"` inside stands for `"` (other backslashes stay, e.g. TextFormat's `\\002`).
  Macros in strings: $(DBTIME), $(UTCTIME)/$(UTC), $(COUNT), $(TCOUNT), $(IDX) (and [..]).
* `RESET_TIME = end|all-posted|none|SECONDS`, `RESET_MAX = N|nolimit`, `PAUSED = true|false`,
  `CONDITION = <logic condition>` (repeatable; the script only runs while all hold),
  `UPON_AWAKE = reset|restart|n/a`, `SCRIPT_NAME`, `SHUFFLE`, `DELAY_START`, `DELAY_RESET`,
  `TIME_WARP`, `STATUS_VAR`, `PAUSE_VAR`, `RESET_VAR`, `FORWARD_VAR`, `VERBOSE`.
* Mail: UTS_PAUSE (true/false/toggle), UTS_RESET (reset/true), UTS_FORWARD (seconds; 0 jumps
  to the next event); the variables of the conditions. Status: UTS_STATUS.

The settings are the block's `Setting`s (MissionFile.process_config); a bad one is a ConfigError
at its line: `mission.moos:12: EVENT: 'var=X, vla=3': unknown field 'vla' (...)`.
"""

from __future__ import annotations

import random
import re
from collections.abc import Iterable
from dataclasses import dataclass
from os import PathLike

from pygoby.errors import ConfigError
from pygoby.moos.logic import LogicCondition, Value
from pygoby.moos.moosfile import Setting


@dataclass
class Event:
    var: str
    value: Value
    time_min: float
    time_max: float
    quoted: bool = False
    quit: bool = False  # `quit`: post EXITED_NORMALLY and end the app
    time: float = -1.0  # scheduled elapsed time
    posted: bool = False


@dataclass
class TimedPost:
    """One post the script makes when an event comes due."""

    var: str
    value: Value


def split_quoted(text: str, separator: str = ",") -> list[str]:
    """MOOS-IvP's parseStringQ: split on `separator` outside double quotes (every `"` toggles)
    and outside braces."""
    parts: list[str] = []
    current: list[str] = []
    quoted, braces = False, 0
    for c in text:
        if c == '"':
            quoted = not quoted
        elif c == "{":
            braces += 1
        elif c == "}" and braces:
            braces -= 1
        if c == separator and not quoted and not braces:
            parts.append("".join(current))
            current = []
        else:
            current.append(c)
    parts.append("".join(current))
    return parts


def parse_value(text: str) -> tuple[Value, bool]:
    """(value, quoted): a number, a quoted string (quotes removed, `\\"` -> `"`), or text."""
    text = text.strip()
    if _is_number(text):
        return float(text), False
    if len(text) >= 2 and text[0] == text[-1] == '"':
        return text[1:-1].replace('\\"', '"'), True
    return text, False


def _is_number(text: str) -> bool:
    return re.fullmatch(r"[+-]?([0-9]+\.?[0-9]*|\.[0-9]+)", text) is not None


def _range(text: str, what: str = "") -> tuple[float, float]:
    """A number or a range A:B; `what` goes in front of the errors (an EVENT's part)."""
    where = f"{what} " if what else ""
    low, sep, high = text.partition(":")
    try:
        a = float(low)
        b = float(high) if sep else a
    except ValueError:
        raise ConfigError(f"{where}{text!r} is not a number or a range A:B") from None
    if a < 0 or b < a:
        raise ConfigError(f"{where}{text!r}: need 0 <= A <= B")
    return a, b


def _boolean(text: str) -> bool:
    lowered = text.strip().lower()
    if lowered in ("true", "1", "yes"):
        return True
    if lowered in ("false", "0", "no"):
        return False
    raise ConfigError(f"must be true or false, not {text!r}")


class TimerScript:
    """Feed `on_mail(var, value)` and call `tick(now)`; both return the posts to make.
    `file` is where `settings` come from, for the errors."""

    def __init__(
        self,
        settings: Iterable[Setting],
        rng: random.Random | None = None,
        file: str | PathLike[str] | None = None,
    ) -> None:
        self.rng = rng or random.Random()
        self.events: list[Event] = []
        self.conditions: list[LogicCondition] = []
        self.reset_time = -1.0  # -1: none, 0: when all posted, >0: at that elapsed time
        self.reset_max: int | None = None  # None: no limit
        self.paused = False
        self.upon_awake = "n/a"
        self.shuffle = True
        self.script_name = "unnamed"
        self.delay_start = (0.0, 0.0)
        self.delay_reset = (0.0, 0.0)
        self.time_warp = (1.0, 1.0)
        self.var_status, self.var_pause = "UTS_STATUS", "UTS_PAUSE"
        self.var_reset, self.var_forward = "UTS_RESET", "UTS_FORWARD"
        self.warnings: list[str] = []
        for setting in settings:
            try:
                self._configure(setting.name.strip().lower(), setting.value.strip())
            except ConfigError as err:
                raise ConfigError(
                    err.reason, file=file, line=setting.line, field=setting.name.strip()
                ) from None
        self.quit = False
        self.values: dict[str, Value] = {}
        self.conditions_ok = not self.conditions
        self.reset_count = 0
        self.posted_total = 0
        self.db_start: float | None = None
        self._start: float | None = None  # None: (re)start the script at the next tick
        self._previous: float | None = None
        self._elapsed = self._skip = self._paused_time = 0.0
        self._posted = 0
        self._delay = self._warp = 0.0

    # -- configuration -------------------------------------------------------------------------
    def _configure(self, name: str, value: str) -> None:
        if name == "event":
            self._add_event(value)
        elif name == "reset_time":
            lowered = value.lower()
            if lowered in ("end", "all-posted"):
                self.reset_time = 0.0
            elif lowered == "none":
                self.reset_time = -1.0
            elif _is_number(value) and float(value) > 0:
                self.reset_time = float(value)
            else:
                raise ConfigError(f"must be end, all-posted, none or seconds, not {value!r}")
        elif name == "reset_max":
            if value.lower() in ("any", "unlimited", "nolimit"):
                self.reset_max = None
            elif value.isdigit():
                self.reset_max = int(value)
            else:
                raise ConfigError(f"must be a count or nolimit, not {value!r}")
        elif name == "paused":
            self.paused = _boolean(value)
        elif name == "condition":
            self.conditions.append(LogicCondition(value))
        elif name == "upon_awake":
            if value.lower() not in ("reset", "restart", "n/a"):
                raise ConfigError(f"must be reset, restart or n/a, not {value!r}")
            self.upon_awake = value.lower()
        elif name == "shuffle":
            self.shuffle = _boolean(value)
        elif name == "script_name":
            self.script_name = value
        elif name in ("delay_start", "delay_reset", "time_warp"):
            setattr(self, name, _range(value))
            if name == "time_warp" and self.time_warp[0] <= 0:
                raise ConfigError("must be positive")
        elif name in (
            "status_var",
            "pause_var",
            "pause_variable",
            "reset_var",
            "reset_variable",
            "forward_var",
            "forward_variable",
        ):
            if not value or any(c.isspace() for c in value):
                raise ConfigError(f"must be a variable name, not {value!r}")
            setattr(self, "var_" + name.split("_", maxsplit=1)[0], value)
        elif name in ("verbose", "appcast", "apptick", "commstick", "maxappticks"):
            pass  # terminal and scheduling settings
        else:
            self.warnings.append(f"unknown uTimerScript parameter {name!r} ignored")

    def _add_event(self, text: str) -> None:
        value: Value | None = None
        var, quoted, times, amount, quit_app = "", False, (0.0, 0.0), 1, False
        for part in split_quoted(text):
            if part.strip().lower() == "quit":
                var, value, quit_app = "EXITED_NORMALLY", "uTimerScript", True
                continue
            key, sep, raw = part.partition("=")
            key = key.strip().lower()
            if not sep:
                raise ConfigError(f"{text!r}: {part.strip()!r} is not key=value")
            if key == "var":
                var = raw.strip()
                if not var or any(c.isspace() for c in var):
                    raise ConfigError(f"{text!r}: var must be a variable name")
            elif key == "val":
                value, quoted = parse_value(raw)
            elif key == "time":
                times = _range(raw.strip(), f"{text!r}: time")
            elif key == "amt":
                if not raw.strip().isdigit() or int(raw) < 1:
                    raise ConfigError(f"{text!r}: amt must be a positive count")
                amount = int(raw)
            else:
                raise ConfigError(f"{text!r}: unknown field {key!r} (var, val, time, amt, quit)")
        if not var:
            raise ConfigError(f"{text!r} has no var=")
        if value is None or value == "":
            raise ConfigError(f"{text!r} has no val=")
        for _ in range(amount):
            self.events.append(Event(var, value, times[0], times[1], quoted, quit_app))

    # -- running -------------------------------------------------------------------------------
    def subscriptions(self) -> list[str]:
        names = {self.var_forward, self.var_pause, self.var_reset}
        for condition in self.conditions:
            names.update(condition.variables)
        return sorted(names)

    def on_mail(self, var: str, value: Value) -> None:
        if var == self.var_forward and isinstance(value, float):
            if value <= 0:
                pending = [e.time - self._elapsed for e in self.events if not e.posted]
                self._skip += min(pending, default=0.0)
            else:
                self._skip += value
        elif var == self.var_reset and str(value).lower() in ("reset", "true"):
            self._reset()
        elif var == self.var_pause and isinstance(value, str):
            lowered = value.lower()
            if lowered in ("true", "false"):
                self.paused = lowered == "true"
            elif lowered == "toggle":
                self.paused = not self.paused
        self.values[var] = value

    def tick(self, now: float) -> list[TimedPost]:
        if self.db_start is None:
            self.db_start = now
        posts: list[TimedPost] = []
        ok = all(c.evaluate(self.values) for c in self.conditions)
        if ok and not self.conditions_ok:  # an awakening
            if self.upon_awake == "reset" and self._elapsed > 0:
                self._reset()
            elif self.upon_awake == "restart":
                self.reset_count = 0
                self._start = None
        self.conditions_ok = ok
        if self._start is None:
            self._schedule(now)
        if (self.paused or not ok) and self._previous is not None:
            self._paused_time += now - self._previous
        self._previous = now
        assert self._start is not None  # (set by the start of the script above)
        self._elapsed = ((now - self._start) + self._skip - self._paused_time) * self._warp
        all_posted = False
        if not self.paused and ok:
            all_posted = self._ready_posts(now, posts)
        if all_posted and self.reset_time == 0:
            self._reset()
        if self.reset_time > 0 and self._elapsed >= self.reset_time:
            self._reset()
        return posts

    def status(self) -> str:
        limit = "any" if self.reset_max is None else str(self.reset_max)
        return (
            f"name={self.script_name}, elapsed_time={self._elapsed:.2f}, posted={self._posted}, "
            f"pending={sum(not e.posted for e in self.events)}, paused={str(self.paused).lower()}, "
            f"conditions_ok={str(self.conditions_ok).lower()}, resets={self.reset_count}/{limit}"
        )

    def _schedule(self, now: float) -> None:
        for event in self.events:
            if self.shuffle or event.time < 0:
                event.time = event.time_min + self.rng.random() * (event.time_max - event.time_min)
            event.posted = False
        delay = self.delay_start if self.reset_count == 0 else self.delay_reset
        self._delay = self.rng.uniform(*delay)
        self._warp = self.rng.uniform(*self.time_warp)
        self._start = now
        self._elapsed = self._skip = self._paused_time = 0.0
        self._previous = None
        self._posted = 0

    def _ready_posts(self, now: float, posts: list[TimedPost]) -> bool:
        for index, event in enumerate(self.events):
            if event.posted or self._elapsed - self._delay < event.time:
                continue
            if self.reset_time > 0 and event.time > self.reset_time:
                continue
            event.posted = True
            self._posted += 1
            self.posted_total += 1
            posts.append(self._post(event, index, now))
        return all(e.posted for e in self.events)

    def _post(self, event: Event, index: int, now: float) -> TimedPost:
        if event.quit:
            self.quit = True
            return TimedPost(event.var, event.value)
        value = event.value
        if not isinstance(value, str):
            return TimedPost(event.var, value)
        uptime = now - (self.db_start or now)
        macros = {
            "DBTIME": f"{uptime:.2f}",
            "UTCTIME": f"{now:.2f}",
            "UTC": f"{now:.2f}",
            "COUNT": str(self._posted),
            "TCOUNT": str(self.posted_total),
            "IDX": f"{index:03d}",
        }
        whole = re.fullmatch(r"\$[(\[](DBTIME|UTCTIME|UTC|COUNT|TCOUNT)[)\]]", value)
        if whole:  # the macro is the whole value: posted as a double
            return TimedPost(event.var, float(macros[whole.group(1)]))
        for name, text in macros.items():
            value = value.replace(f"$({name})", text).replace(f"$[{name}]", text)
        if _is_number(value) and not event.quoted:
            return TimedPost(event.var, float(value))
        return TimedPost(event.var, value)

    def _reset(self) -> None:
        if self.reset_max is not None and self.reset_count >= self.reset_max:
            return
        self.reset_count += 1
        self._start = None
