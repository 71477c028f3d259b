"""pLogger: MOOS's logger, writing the .alog (and .slog, .blog, ._moos) files MOOS-IvP's tools read.

    pLogger mission.moos [AppName]

Files land in `PATH/<File>_<D_M_YYYY_____HH_MM_SS>/` (or `PATH/<File>/` with FileTimeStamp =
false); posting LOGGER_RESTART starts a new directory. Writing happens on a thread with a
bounded buffer, so a slow disk never stalls MOOS traffic: lines that do not fit are dropped and
counted (warned about, and shown in the status).
"""

from __future__ import annotations

from pathlib import Path
from typing import TextIO

from pygoby.moos import protocol as p
from pygoby.moos.alog.files import AlogSink, copy_with_banner, make_log_directory
from pygoby.moos.alog.format import AlogFormatter, banner, slog_header, slog_labels, slog_row
from pygoby.moos.alog.logger_config import read_logger_config
from pygoby.moos.classic_app import ClassicMOOSApp
from pygoby.moos.protocol import MOOSMessage


class pLogger(ClassicMOOSApp):  # noqa: N801 - the program's name
    default_name = "pLogger"
    ignore_stale = False  # the DB's current values on registering are logged too, as pLogger does
    example_lines = (
        "File = MyLog               // directory and file stem",
        "PATH = ./logs              // where the directory is made (::GlobalLogPath wins)",
        "FileTimeStamp = true       // append _D_M_YYYY_____HH_MM_SS",
        "AsyncLog = true            // the .alog",
        "SyncLog = true @ 0.2       // the .slog table of Log variables, every 0.2 s",
        "WildCardLogging = true     // log every variable",
        "WildCardOmitPattern = *_STATUS, DB_*",
        "Log = NAV_X @ 0            // (repeatable) VAR @ period [NOSYNC]",
        "LogAuxSrc = true           // sources as src:aux",
        "DoublePrecision = 5",
        "MarkExternalCommunityMessages = false",
        "MarkDataAsBinary = false   // true: binary values inline as B:<hex> instead of a .blog",
        "CompressAlogs = false",
        "MaxAlogSize = 0            // start a new .alog past this size (e.g. 500M); 0: never",
    )

    def __init__(self, cfg, **kwargs) -> None:
        super().__init__(cfg, **kwargs)
        global_path = self.mission.get_value("GlobalLogPath") if self.mission else None
        self.settings = read_logger_config(self.params, self.setting_error, global_path)
        for warning in self.settings.warnings:
            self.log.warning("%s", warning)
        self.sink: AlogSink | None = None
        self.directory: Path | None = None
        self._slog: TextIO | None = None
        self._sync_vars = [r.var for r in self.settings.logs if r.sync]
        self._sync_set = set(self._sync_vars)
        self._log_vars = {r.var for r in self.settings.logs}
        self._fresh: dict[str, float] = {}
        self._last_sync = -1e300
        self._sync_rows = 0
        self._reported_drops = 0
        self._omit = [p.Glob(pattern) for pattern in self.settings.wildcard_omit]
        self._accept = [p.Glob(pattern) for pattern in self.settings.wildcard_patterns]
        self.formatter = AlogFormatter(
            self.start_time,
            self.settings.double_precision,
            self.settings.log_aux_src,
            self.settings.mark_external,
            mark_data_type=self.settings.mark_data_type,
            mark_binary=self.settings.mark_binary,
        )
        if self.settings.wildcard_logging:
            self.subscribe_pattern("*", "*", self._on_wildcard)
        for request in self.settings.logs:
            self.subscribe(request.var, self._on_mail, blackout=request.period)
        self.subscribe("LOGGER_RESTART", self._on_restart)

    # -- files ---------------------------------------------------------------------------------

    def on_start(self) -> None:
        self.formatter.log_start = self.start_time  # start() takes the time afresh
        self._open_session()

    def _on_restart(self, msg: MOOSMessage) -> None:
        """LOGGER_RESTART: close the files and start a new directory (same LOGSTART)."""
        self._close_session()
        self._open_session()
        self.on_connect()

    def _open_session(self) -> None:
        s = self.settings
        self._reported_drops = 0
        root = s.directory_name()
        self.directory = self._make_directory(root)
        if self.directory is None:
            return
        try:
            Path(s.summary_file).write_text(f"LastOpenedLoggingDirectory={self.directory}\n")
        except OSError as err:
            self.log.warning("cannot write %s: %s", s.summary_file, err)
        if self.mission is not None and self.mission.path is not None:
            copy = self.directory / f"{root}._moos"
            try:
                copy_with_banner(self.mission.path, copy, banner(str(copy), self.start_time))
            except OSError as err:
                self.log.warning("no copy of the mission file: %s", err)
        if s.async_log or s.wildcard_logging:
            self.sink = AlogSink(
                self.directory,
                root,
                lambda name: banner(
                    name,
                    self.start_time,
                    mark_data_type=s.mark_data_type,
                    mark_binary=s.mark_binary,
                ),
                compress=s.compress,
                max_bytes=s.max_alog_bytes,
            )
        if s.sync_log:
            slog = self.directory / f"{root}.slog"
            self._slog = open(slog, "w")  # noqa: SIM115 - closed in on_stop
            self._slog.write(slog_header(str(slog), self.start_time, self._sync_vars))
            self._slog.write(slog_labels(self._sync_vars, 0.0))
        self.log.info("logging to %s", self.directory)

    def _make_directory(self, root: str) -> Path | None:
        """PATH/root, else ./root as pLogger falls back; None (and the app fails) if neither."""
        directory = make_log_directory([Path(self.settings.path) / root, Path(root)], self.log)
        if directory is None:
            self.fail(f"no log directory: neither {self.settings.path}/{root} nor ./{root}")
        return directory

    def on_connect(self) -> None:
        self.formatter.own_community = self.client.community
        if self.directory is not None:
            self.publish("LOGGER_DIRECTORY", str(self.directory))

    def on_stop(self) -> None:
        self._handle_mail()  # what arrived since the last tick
        self._close_session()

    def _close_session(self) -> None:
        if self.sink is not None:
            self.sink.close()
            self.sink = None
        if self._slog is not None:
            self._slog.close()
            self._slog = None

    # -- mail ----------------------------------------------------------------------------------

    def _on_wildcard(self, msg: MOOSMessage) -> None:
        key = msg.key
        if any(glob.match(key) for glob in self._omit):
            return
        if self._accept and not any(glob.match(key) for glob in self._accept):
            return
        if key not in self._log_vars:  # a Log = VAR line logs it already
            self._on_mail(msg)

    def _on_mail(self, msg: MOOSMessage) -> None:
        if msg.is_double and msg.key in self._sync_set:
            self._fresh[msg.key] = msg.dval
        if self.sink is None:
            return
        fmt = self.formatter
        if msg.is_binary and not fmt.mark_binary:
            prefix = fmt.prefix(msg.time, msg.key, msg.src, msg.src_aux, msg.community)
            self.sink.put_binary(prefix, msg.sval)
            return
        line = fmt.line(msg.time, msg.key, msg.src, msg.value, msg.src_aux, msg.community)
        self.sink.put_line(line)

    def loop(self) -> None:
        now = self.clock.now()
        if self._slog is not None and now - self._last_sync > self.settings.sync_period:
            self._last_sync = now
            since = now - self.start_time
            self._slog.write(slog_row(since, [self._fresh.get(v) for v in self._sync_vars]))
            self._fresh.clear()
            self._sync_rows += 1
            if self._sync_rows % 30 == 0:
                self._slog.write(slog_labels(self._sync_vars, since))
            self._slog.flush()
        if self.sink is not None and self.sink.dropped != self._reported_drops:
            self.log.warning(
                "%d lines dropped so far: the disk is not keeping up", self.sink.dropped
            )
            self._reported_drops = self.sink.dropped

    def status_lines(self) -> list[str]:
        if self.sink is None:
            return [f"directory: {self.directory}"]
        return [
            f"alog: {self.sink.alog_path}",
            f"lines written: {self.sink.written}, dropped: {self.sink.dropped}",
        ]


def main(argv=None) -> int:
    return pLogger.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
