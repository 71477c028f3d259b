"""GobyMOOSApp: the base class of pygoby's Goby MOOS applications (pTranslator, pAcommsHandler,
iFrontSeat, ...): goby3's GobyMOOSApp conventions.

Writing an application
----------------------
::

    from pygoby.moos.app import GobyMOOSApp

    class pExample(GobyMOOSApp):
        # The configuration message: either a class, or (our .proto file, full message name)
        # loaded with pygoby.protobuf.builtin_class. It must have `common` (field 1) of type
        # goby.moos.protobuf.GobyMOOSAppConfig.
        config_proto = ("goby/apps/moos/protobuf/example_config.proto",
                        "goby.apps.moos.protobuf.pExampleConfig")
        default_name = "pExample"          # used when argv[0] is not the program name

        def __init__(self, cfg, **kwargs):
            super().__init__(cfg, **kwargs)
            self.subscribe("NAV_X", self.on_nav_x)            # handler(msg: MOOSMessage)
            self.subscribe("DESIRED_SPEED", blackout=1.0)     # just keep self.dynamic_vars fresh
            self.subscribe_pattern("IFS_*", "*", self.on_ifs)
            self.register_timer(5.0, self.every_five_seconds)

        def on_nav_x(self, msg):                # msg.value: float | str | bytes
            self.publish("NAV_X_SEEN", msg.value)             # float -> D, str -> S, bytes -> B

        def loop(self):                         # every 1/common.app_tick s while connected
            self.publish("EXAMPLE_STATUS", f"gain={self.cfg.gain}")

    if __name__ == "__main__":
        raise SystemExit(pExample.main())      # `pExample mission.moos [AppName]`

The base provides
-----------------
* `cls.main(argv=None) -> int`: the command line (pygoby.moos.appcli) `APP [options] mission.moos [moos_name]`
  (also `-c/--moos_file`, `-a/--moos_name`, `-e/--example_config`, `-V/--version`,
  `--<field> <value>` for any top-level config field). A configuration error prints one
  clear message naming the file line and the field and exits 1 before connecting.
* `cls.from_mission(path, name=None, overrides=(), **kwargs)`: read the configuration and build
  the app (what `main` does; handy in tests).
* Construction: `App(cfg, name=..., mission=MissionFile|None, clock=None, host=None, port=None)`.
  `host`/`port` default to `cfg.common.server_host`/`server_port` (filled from the
  ServerHost/ServerPort globals), else 127.0.0.1:9000; `clock` defaults to MOOS time with
  `common.time_warp_multiplier`.
* Running: `await app.start()` / `await app.stop()`, or `async with app:`, or `await app.run()`
  (until `app.request_stop()`). Mail is handled and `loop()` runs every 1/app_tick seconds
  (warped); while disconnected `loop()` and the timers are not called (as CMOOSApp), unless
  the class sets `iterate_without_comms = True` (its posts are then queued and delivered
  when the DB is back).
* `subscribe(var, handler=None, blackout=0.0)`, `subscribe_pattern(var_pattern, app_pattern,
  handler)`, `publish(var, value, src_aux="", time=None)` (queued while disconnected, sent on
  reconnect), `register_timer(period, callback)` (fires on multiples of `period` since the
  epoch, checked each tick), `dynamic_vars` (newest message per variable), `start_time`,
  `log` (a logging.Logger; terminal at `common.verbosity`, file log per `common.log`,
  see pygoby.moos.applog), `cfg` / `common`, `client` (the MOOSClient), `moos_time()`.
* Protobuf messages on MOOS variables in the app-internal technique (`moos_technique`, from
  `common.moos_parser_technique` / `use_binary_protobuf`; `@PB[type] ...` by default):
  `publish_pb(var, message)`, `parse_pb(msg, cls)` (None, with a warning, when the value does
  not parse) and `subscribe_pb(var, cls, handler, ignore_own=False)` (`handler(message)` for
  each value that parses).
* `find_file(path)`: a relative path from the configuration, looked up next to the mission
  file when it does not exist from the working directory (`search_dirs()` lists both).
* `config_error(reason, field, value="", block=None)`: a ConfigError for a problem found after
  parsing (an unknown type, a missing file), located at the mission line that sets `field` in
  this app's ProcessConfig block (or in `block`, another app's that it reads).
* Hooks: `loop()`, `on_connect()`, `on_disconnect()`, `on_start()`, `on_stop()`,
  `status_lines()` (the state shown by `common.show_gui`'s live view, pygoby.moos.appgui).
* `exit_status`: what `main` returns once the app has stopped (0; an app that stops itself on a
  fatal error calls `fail(reason)`, which sets it to 1 and keeps `reason` in `failure`).
* The MOOSDB refusing the app's name at its first connection (another process has it) is
  such a fatal error; a refusal on a reconnection is not (the DB still holds the old session
  until its client timeout): the client keeps trying (pygoby.moos.client).
* Mail older than the app's start time is stored in `dynamic_vars` but not handed to the
  subscription's handler (`ignore_stale = True`, Goby's rule; snapshots of old values
  therefore do not trigger handlers). Pattern handlers always run.
* On every (re)connect the client re-subscribes, then `common.initializer` entries are posted.
* Every couple of seconds `<NAME>_STATUS` (pygoby.moos.appstatus) is posted.
"""

from __future__ import annotations

import asyncio
import contextlib
import logging
import math
import os
from collections.abc import Callable, Sequence
from operator import attrgetter
from typing import ClassVar

from google.protobuf.message import Message

from pygoby.errors import ConfigError
from pygoby.moos import appcli
from pygoby.moos import protocol as p
from pygoby.moos.appconfig import (
    collecting_notes,
    config_line,
    example_config,
    initializer_posts,
    read_configuration,
)
from pygoby.moos.applog import AppLogHandlers
from pygoby.moos.appstatus import StatusReport
from pygoby.moos.client import MOOSClient
from pygoby.moos.moosfile import MissionFile
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.timewarp import clock_warp, moos_clock
from pygoby.moos.translator import (
    Technique,
    TranslatorError,
    moos_technique_from_config,
    parse_for_moos,
    post_for_moos,
)
from pygoby.protobuf import builtin_class, message_type
from pygoby.protobuf.descriptors import MessageT
from pygoby.protobuf.goby.moos.protobuf.goby_moos_app_pb2 import GobyMOOSAppConfig
from pygoby.util.aiorun import cancel_and_wait
from pygoby.util.clock import Clock
from pygoby.util.errors import MissingExtraError

Handler = Callable[[MOOSMessage], None]

COMMON_PROTO = ("goby/moos/protobuf/goby_moos_app.proto", "goby.moos.protobuf.GobyMOOSAppConfig")
# Mail waiting for the next tick beyond this many messages: the oldest are dropped (an app far
# slower than its mail; CMOOSApp's comms drop their whole inbox beyond 2,048).
MAIL_LIMIT = 100_000
# Routes of pattern subscriptions remembered per (variable, publisher) before starting afresh.
PATTERN_ROUTES_LIMIT = 10_000
_by_time = attrgetter("time")


class _Timer:
    def __init__(self, period: float, callback: Callable[[], None], now: float) -> None:
        self.period = period
        self.callback = callback
        self.next = (math.floor(now / period) + 1) * period

    def due(self, now: float) -> bool:
        if self.next - now > 2 * self.period:  # the clock jumped backwards
            self.next = now + self.period
        if now < self.next:
            return False
        self.next = (math.floor(now / self.period) + 1) * self.period
        return True


def _app_technique(common: GobyMOOSAppConfig) -> Technique:
    try:
        return moos_technique_from_config(common)
    except TranslatorError as err:
        raise ConfigError(str(err)) from None


class GobyMOOSApp:
    """Base class of Goby MOOS applications; see the module docstring for the subclass API."""

    config_class: ClassVar[type[Message] | None] = None
    config_proto: ClassVar[tuple[str, str] | None] = None
    default_name: ClassVar[str] = ""
    ignore_stale: ClassVar[bool] = True
    # loop() and the timers also run while the MOOSDB is away (CMOOSApp's
    # SetIterateWithoutComms): for apps driving hardware or a schedule that must not stop with
    # the DB (pAcommsHandler's modem and MAC, iFrontSeat's frontseat link)
    iterate_without_comms: ClassVar[bool] = False

    # -- configuration -------------------------------------------------------------------------

    @classmethod
    def load_config_class(cls) -> type[Message]:
        config_class = cls.config_class
        if config_class is None:
            if cls.config_proto is None:
                raise TypeError(f"{cls.__name__} must set config_class or config_proto")
            config_class = builtin_class(*cls.config_proto)
        common = config_class.DESCRIPTOR.fields_by_name.get("common")
        if common is None or message_type(common).full_name != COMMON_PROTO[1]:
            raise TypeError(
                f"{config_class.DESCRIPTOR.full_name} needs a `common` field of type {COMMON_PROTO[1]}"
            )
        return config_class

    @classmethod
    def read_config(
        cls, mission: MissionFile | None, name: str, overrides: Sequence[tuple[str, str]] = ()
    ) -> Message:
        return read_configuration(cls.load_config_class(), mission, name, overrides)

    @classmethod
    def from_mission(
        cls,
        path: str | os.PathLike[str],
        name: str | None = None,
        overrides: Sequence[tuple[str, str]] = (),
        **kwargs: object,
    ) -> GobyMOOSApp:
        app_name = name or cls.default_name or cls.__name__
        mission = MissionFile.read(path)
        with collecting_notes() as notes:
            cfg = cls.read_config(mission, app_name, overrides)
        app = cls(cfg, name=app_name, mission=mission, **kwargs)  # type: ignore[arg-type]
        app.config_notes = notes
        return app

    @classmethod
    def example_config(cls, name: str | None = None) -> str:
        return example_config(cls.load_config_class(), name or cls.default_name or cls.__name__)

    @classmethod
    def main(
        cls, argv: Sequence[str] | None = None, prog: str | None = None, command: str | None = None
    ) -> int:
        """Run the app from the command line (pygoby.moos.appcli); returns the exit status."""
        return appcli.run_app(cls, argv, prog, command)

    # -- construction --------------------------------------------------------------------------

    def __init__(
        self,
        cfg: Message,
        *,
        name: str | None = None,
        mission: MissionFile | None = None,
        clock: Clock | None = None,
        host: str | None = None,
        port: int | None = None,
    ) -> None:
        self.cfg = cfg
        self.common = cfg.common  # type: ignore[attr-defined]
        self.name = name or self.default_name or type(self).__name__
        self.mission = mission
        self.moos_technique = _app_technique(self.common)
        warp = float(self.common.time_warp_multiplier or 1)
        self.clock = clock or moos_clock(warp)
        if host is None:
            host = self.common.server_host if self.common.HasField("server_host") else "127.0.0.1"
        if port is None:
            port = (
                self.common.server_port if self.common.HasField("server_port") else p.DEFAULT_PORT
            )
        self._mail: list[MOOSMessage] = []  # received, for the next tick (the list is kept)
        self.client = MOOSClient(
            self.name, host, port, clock=self.clock, on_message=self._mail.append
        )
        self.client.signal_connect.connect(self._connected)
        self.client.signal_disconnect.connect(self._disconnected)
        self.client.signal_refused.connect(self._refused)
        self.log = logging.getLogger(f"pygoby.app.{self.name}")
        self.start_time = self.clock.now()
        self.dynamic_vars: dict[str, MOOSMessage] = {}
        self._handlers: dict[str, list[Handler]] = {}
        self._pattern_handlers: list[tuple[p.Glob, p.Glob, Handler]] = []
        self._pattern_routes: dict[tuple[str, str], list[Handler]] = {}  # (key, src) -> handlers
        self._timers: list[_Timer] = []
        self._published: set[str] = set()
        self._task: asyncio.Task[None] | None = None
        self._stop_requested = asyncio.Event()  # set by request_stop(), even before run()
        self._stopping = False  # a disconnect during stop() is expected, not a lost connection
        self._log_handlers: AppLogHandlers | None = None
        self.terminal_handler: logging.Handler | None = None  # instead of stdout (show_gui)
        self._status = StatusReport()
        self.iterations = 0
        self.exit_status = 0
        # Goby 1.1/2 configuration forms mapped at load (appconfig.collecting_notes), logged once
        self.config_notes: list[str] = []
        self.failure: str | None = None

    # -- API for subclasses --------------------------------------------------------------------

    def subscribe(self, var: str, handler: Handler | None = None, blackout: float = 0.0) -> None:
        """Register for `var` (MOOS Register with interval `blackout`); `handler(msg)` is called
        for each fresh message; without a handler only `dynamic_vars` is kept up to date."""
        if handler is not None:
            self._handlers.setdefault(var, []).append(handler)
        self.client.subscribe(var, blackout)

    def subscribe_pattern(self, var_pattern: str, app_pattern: str, handler: Handler) -> None:
        self._pattern_handlers.append((p.Glob(var_pattern), p.Glob(app_pattern), handler))
        self._pattern_routes.clear()
        self.client.subscribe_wildcard(var_pattern, app_pattern)

    def publish(
        self, var: str, value: p.Value, *, src_aux: str = "", time: float | None = None
    ) -> None:
        self._published.add(var)
        self.client.publish(var, value, src_aux=src_aux, time=time)

    def register_timer(self, period: float, callback: Callable[[], None]) -> None:
        if period <= 0:
            raise ValueError("timer period must be positive")
        self._timers.append(_Timer(period, callback, self.clock.now()))

    def moos_time(self) -> float:
        return self.client.time()

    def loop(self) -> None:
        """Called every 1/app_tick seconds while connected. Override."""

    def on_connect(self) -> None:
        """Called after every (re)connection, after subscriptions and initializers."""

    def on_disconnect(self) -> None:
        """Called when the connection to the MOOSDB is lost."""

    def on_start(self) -> None:
        """Called once by start(), before connecting."""

    def on_stop(self) -> None:
        """Called once by stop()."""

    @property
    def connected(self) -> bool:
        return self.client.connected

    def find_file(self, path: str) -> str:
        """`path` from the configuration, looked up next to the mission file when it is relative
        and does not exist from the working directory (MissionFile.find_file)."""
        return self.mission.find_file(path) if self.mission is not None else path

    def search_dirs(self) -> list[str]:
        """The folders `find_file` looks in, in order (for "not found" errors)."""
        return self.mission.search_dirs() if self.mission is not None else [os.getcwd()]

    def config_error(
        self, reason: str, field: str, value: str = "", block: str | None = None
    ) -> ConfigError:
        """A ConfigError for a problem found after parsing, located at the mission file line
        that sets `field` (to `value`) in this app's block, or in the ProcessConfig `block`
        (another app's that this one reads), when there is one."""
        file = line = None
        if self.mission is not None and self.mission.path is not None:
            file = str(self.mission.path)
            found = self.mission.goby_block(block or self.name)
            line = config_line(found, field, value) if found is not None else None
        return ConfigError(reason, file=file, line=line, field=field)

    # -- protobuf messages on MOOS variables (the app-internal technique) ----------------------

    def publish_pb(self, var: str, message: Message) -> None:
        post = post_for_moos(var, message, self.moos_technique)
        self.publish(post.var, post.value, src_aux=post.source_aux)

    def parse_pb(self, msg: MOOSMessage, cls: type[MessageT]) -> MessageT | None:
        """`msg`'s value as a `cls` message; None, with a warning, when it does not parse."""
        out = cls()
        try:
            parse_for_moos(msg.value, out, self.moos_technique)
        except TranslatorError as err:
            self.log.warning("cannot parse %s as %s: %s", msg.key, cls.DESCRIPTOR.full_name, err)
            return None
        return out

    def subscribe_pb(
        self,
        var: str,
        cls: type[MessageT],
        handler: Callable[[MessageT], None],
        *,
        ignore_own: bool = False,
    ) -> None:
        """`handler(message)` for each post of `var` that parses as `cls` (with `ignore_own`,
        not for this app's own posts)."""

        def on_mail(msg: MOOSMessage) -> None:
            if ignore_own and msg.src == self.name:
                return
            if (message := self.parse_pb(msg, cls)) is not None:
                handler(message)

        self.subscribe(var, on_mail)

    # -- running -------------------------------------------------------------------------------

    async def start(self, connect_timeout: float | None = None) -> None:
        """Start logging, the comms and the tick loop. With `connect_timeout`, wait for the
        first connection (TimeoutError otherwise); without, carry on and keep trying."""
        self._log_handlers = AppLogHandlers.open(
            self.log, self.name, self.common, terminal=self.terminal_handler
        )
        if self.config_notes:
            self.log.info(
                "Goby 1.1/2 configuration forms mapped onto today's:\n  %s",
                "\n  ".join(self.config_notes),
            )
        self._stopping = False
        self.start_time = self.clock.now()
        self.on_start()
        self.client.start()
        self._task = asyncio.create_task(self._tick_loop(), name=f"{self.name}-ticks")
        if connect_timeout is not None:
            await self.client.wait_connected(connect_timeout)

    async def stop(self) -> None:
        self._stopping = True
        if self._task is not None:
            task, self._task = self._task, None
            await cancel_and_wait(task)
            self.on_stop()
        with contextlib.suppress(Exception):
            await self.client.flush(timeout=1.0)
        await self.client.close()
        if self._log_handlers is not None:
            self._log_handlers.close()
            self._log_handlers = None
        self._stop_requested.clear()

    @property
    def stop_requested(self) -> bool:
        """Whether `request_stop()` was called since `start()`."""
        return self._stop_requested.is_set()

    def request_stop(self) -> None:
        """Make `run()` stop the app (also when called before `run()`)."""
        self._stop_requested.set()

    def fail(self, reason: str, exit_status: int = 1) -> None:
        """Stop because of a fatal error: `reason` is logged (critical) and kept in `failure`
        (the command line prints it on stderr), and `main` returns `exit_status`."""
        self.log.critical("%s; stopping", reason)
        self.failure = reason
        self.exit_status = exit_status
        self.request_stop()

    async def run(self) -> None:
        gui, missing = None, None
        if self.common.show_gui:
            try:
                from pygoby.moos.appgui import gui_for  # textual, only when asked for
            except MissingExtraError as exc:
                missing = exc
            else:
                gui = gui_for(self)
                if gui is not None:
                    self.terminal_handler = gui.handler
        await self.start()
        if missing is not None:
            self.log.warning("show_gui: %s; the log stays plain text", missing)
        elif self.common.show_gui and gui is None:
            self.log.info("show_gui: standard output is not a terminal; the log stays plain text")
        try:
            if gui is not None:
                await gui.run_until(self._stop_requested)
            else:
                await self._stop_requested.wait()
        finally:
            await self.stop()

    def status_lines(self) -> list[str]:
        """The app's state in a few lines (show_gui's status panel). Override to add yours."""
        state = "connected" if self.connected else "not connected"
        return [
            f"MOOSDB {self.client.host}:{self.client.port}: {state}",
            f"up {self.clock.now() - self.start_time:.0f} s, {self.iterations} iterations",
        ]

    async def __aenter__(self) -> GobyMOOSApp:
        await self.start(connect_timeout=5.0)
        return self

    async def __aexit__(self, *exc: object) -> None:
        await self.stop()

    # -- connection events ---------------------------------------------------------------------

    def _connected(self) -> None:
        self._post_initializers()
        try:
            self.on_connect()
        except Exception:
            self.log.exception("on_connect failed")

    def _disconnected(self) -> None:
        if self._stopping:
            self.log.info("disconnected from the MOOSDB")
        else:
            self.log.warning("lost the connection to the MOOSDB; reconnecting")
        try:
            self.on_disconnect()
        except Exception:
            self.log.exception("on_disconnect failed")

    def _refused(self, err: Exception) -> None:
        self.fail(
            f"{err}: is another {self.name} running? (give this one another name: "
            f"`APP mission.moos OtherName`)"
        )

    def _post_initializers(self) -> None:
        for var, value in initializer_posts(self.common, self.mission, self.log):
            self.publish(var, value)

    # -- mail ----------------------------------------------------------------------------------

    def _handle_mail(self) -> None:
        mail = self._mail[:]
        self._mail.clear()
        if len(mail) > MAIL_LIMIT:
            self.log.warning(
                "%d messages arrived since the last tick; handling the newest %d",
                len(mail),
                MAIL_LIMIT,
            )
            del mail[:-MAIL_LIMIT]
        mail.sort(key=_by_time)  # CMOOSApp's SortMailByTime
        dynamic_vars = self.dynamic_vars
        handlers_of = self._handlers.get
        stale_before = self.start_time if self.ignore_stale else -math.inf
        patterns = self._pattern_handlers
        for msg in mail:
            if msg.msg_type != p.NOTIFY:
                continue
            key = msg.key
            dynamic_vars[key] = msg
            handlers = handlers_of(key)
            if handlers:
                if msg.time < stale_before:
                    self.log.warning(
                        "ignoring stale message %s (time %.3f before the app started)",
                        key,
                        msg.time,
                    )
                else:
                    for handler in handlers:
                        try:
                            handler(msg)
                        except Exception:
                            self.log.exception("handler for %s failed", key)
            if patterns:
                for handler in self._pattern_route(key, msg.src):
                    try:
                        handler(msg)
                    except Exception:
                        self.log.exception("handler for %s failed", key)

    def _pattern_route(self, key: str, src: str) -> list[Handler]:
        """The pattern handlers for `key` from `src`, matched once per (key, src)."""
        route = self._pattern_routes.get((key, src))
        if route is None:
            if len(self._pattern_routes) >= PATTERN_ROUTES_LIMIT:
                self._pattern_routes.clear()
            route = self._pattern_routes[(key, src)] = [
                handler
                for var_glob, app_glob, handler in self._pattern_handlers
                if var_glob.match(key) and app_glob.match(src)
            ]
        return route

    # -- ticks ---------------------------------------------------------------------------------

    async def _tick_loop(self) -> None:
        loop = asyncio.get_running_loop()
        warp = clock_warp(self.clock)
        app_tick = self.common.app_tick
        period = (1.0 / app_tick / warp) if app_tick > 0 else 0.0
        next_tick = loop.time()
        while True:
            next_tick += period
            await asyncio.sleep(max(next_tick - loop.time(), 0.0))
            if loop.time() - next_tick > 10 * max(period, 0.001):
                next_tick = loop.time()  # fell far behind: do not try to catch up
            self._tick()

    def _tick(self) -> None:
        self._handle_mail()
        if self.client.connected:
            self._post_status()
        elif not self.iterate_without_comms:
            return
        try:
            self.loop()
        except Exception:
            self.log.exception("loop() failed")
        self.iterations += 1
        self._run_timers(self.clock.now())

    def _run_timers(self, now: float) -> None:
        for timer in self._timers:
            if timer.due(now):
                try:
                    timer.callback()
                except Exception:
                    self.log.exception("timer callback failed")

    def _post_status(self) -> None:
        now = self.clock.now()
        if not self._status.due(now):
            return
        status = self._status.line(
            self.name, now - self.start_time, self._published, self.client.subscriptions
        )
        self.client.publish(f"{self.name.upper()}_STATUS", status)
