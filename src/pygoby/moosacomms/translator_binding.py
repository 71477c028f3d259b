"""What every Goby MOOS app with translator_entry blocks shares (pTranslator, pAcommsHandler).

* `MessageTypes`: the app's message definitions: `load_shared_library` modules of generated code
  (protobuf's default pool) or built-in upstream libraries (C++ DCCL codec libraries are the
  app's to load into its Codec, pygoby.dccl.libraries), and `load_proto_file` files (compiled
  at start-up), looked up by name.
* `TranslatorBinding`: a `Translator` wired to a `GobyMOOSApp`: it subscribes the triggers, the
  datum variables and the multiplex variables, runs the `TranslatorRunner`, hands each created
  message to the app's callback, and posts publications.
"""

from __future__ import annotations

import contextlib
import logging
import os
from collections.abc import Callable, Iterable, Sequence
from pathlib import Path

from google.protobuf import descriptor_pool, text_format
from google.protobuf.message import Message

from pygoby.dccl.libraries import split_libraries
from pygoby.errors import ConfigError
from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.appconfig import locate
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.translator import (
    LAT_ORIGIN_VAR,
    LONG_ORIGIN_VAR,
    ModemIdLookup,
    MoosValues,
    Post,
    Translator,
    TranslatorError,
    TranslatorRunner,
)
from pygoby.protobuf import ProtoError, ProtoLoader, class_of
from pygoby.protobuf.goby.moos.protobuf.translator_pb2 import TranslatorEntry
from pygoby.util.glog import DEBUG1, VERBOSE, group_logger
from pygoby.util.libraries import DCCL_CODECS, MESSAGES, builtin_for, is_shared_library, unavailable
from pygoby.util.modules import import_module_or_file

log = logging.getLogger(__name__)
glog = group_logger("goby::moos::translator")  # created messages and their publications


class MessageTypes:
    """Message classes by full name: .proto files first, then generated modules, then fallbacks
    (e.g. pygoby's own messages).

    `proto_files` (load_proto_file) are looked up in `search_dirs` (default: the working
    directory), then as import names on the .proto import path. `shared_libraries`
    (load_shared_library) are Python modules or .py files of generated code, or upstream `.so`
    names: those pygoby has built in (pygoby.util.libraries) are accepted (a DCCL codec library
    is the app's to apply to its Codec), any other is a ConfigError saying to use load_proto_file. `config_error(field, value)` makes the located
    ConfigError for a bad entry (GobyMOOSApp.config_error: reason, field, value); `loaded` lists the message types the
    files and modules define (for errors naming what is loaded).
    """

    def __init__(
        self,
        proto_files: Iterable[str] = (),
        shared_libraries: Iterable[str] = (),
        fallback: Callable[[str], type[Message]] | None = None,
        loader: ProtoLoader | None = None,
        search_dirs: Sequence[str] = (),
        config_error: Callable[[str, str, str], ConfigError] | None = None,
    ) -> None:
        self.loader = loader if loader is not None else ProtoLoader()
        self._fallback = fallback
        self._search_dirs = list(search_dirs) or [os.getcwd()]
        self._error = config_error or (
            lambda reason, field, value: ConfigError(reason, field=field)
        )
        self.loaded: list[str] = []
        for name in shared_libraries:
            self._load_library(name)
        for path in proto_files:
            self._load_proto(path)

    @classmethod
    def of_translator_app(
        cls,
        load_proto_file: Iterable[str],
        load_shared_library: Iterable[str],
        search_dirs: Sequence[str] = (),
        config_error: Callable[[str, str, str], ConfigError] | None = None,
    ) -> MessageTypes:
        """The types of a pTranslator configuration: its C++ DCCL codec libraries stand for
        pygoby's built-ins (their .proto files are loaded), the other libraries are modules."""
        error = config_error or (lambda reason, field, value: ConfigError(reason, field=field))
        libraries, others = split_libraries(
            load_shared_library, lambda reason, name: error(reason, "load_shared_library", name)
        )
        return cls(
            [*(p for library in libraries for p in library.proto_files), *load_proto_file],
            others,
            search_dirs=search_dirs,
            config_error=config_error,
        )

    def _load_proto(self, path: str) -> None:
        found = _find(path, self._search_dirs)
        if found is None and not self.loader.on_import_path(path):
            searched = [*self._search_dirs, *self.loader.import_path()]
            raise self._error(not_found(path, searched), "load_proto_file", path)
        try:
            descriptor = self.loader.load_file(found or path)
        except (ProtoError, OSError) as err:
            raise self._error(f'cannot load "{path}": {err}', "load_proto_file", path) from None
        log.info("loaded %s", found or path)
        self.loaded += [d.full_name for d in descriptor.message_types_by_name.values()]

    def _load_library(self, name: str) -> None:
        field = "load_shared_library"
        if is_shared_library(name):
            builtin = builtin_for(name)
            if builtin is not None and builtin.kind == MESSAGES:
                log.info("load_shared_library %s: its messages are built into pygoby", name)
            elif builtin is not None and builtin.kind == DCCL_CODECS:
                pass  # loaded into the app's Codec through pygoby.dccl.libraries
            else:
                raise self._error(f'"{name}": {unavailable(name)}', field, name)
            return
        module_path = _find(name, self._search_dirs) if name.endswith(".py") else name
        try:
            module = import_module_or_file(module_path or name)
        except (ImportError, OSError, SyntaxError, TypeError) as err:
            raise self._error(f'cannot load "{name}": {err}', field, name) from None
        file_descriptor = getattr(module, "DESCRIPTOR", None)
        types = getattr(file_descriptor, "message_types_by_name", {})
        self.loaded += [d.full_name for d in types.values()]

    def __call__(self, name: str) -> type[Message]:
        with contextlib.suppress(ProtoError):
            return self.loader.message_class(name)
        with contextlib.suppress(KeyError):
            descriptor = descriptor_pool.Default().FindMessageTypeByName(name)
            return class_of(descriptor)
        if self._fallback is not None:
            return self._fallback(name)
        raise ProtoError(f"unknown message type {name!r}")

    def require(self, name: str, field: str, loaded: Sequence[str] | None = None) -> type[Message]:
        """The class of `name`, set in configuration `field`; else the located ConfigError that
        lists the loaded types (`loaded`, default the ones these files and modules define)."""
        try:
            return self(name)
        except ProtoError:
            listed = self.loaded if loaded is None else loaded
            raise self._error(not_loaded(name, listed), field, name) from None


def not_loaded(name: str, loaded: Sequence[str]) -> str:
    """The reason of a configuration error for a message type no file defines (typically a
    misspelling), with the types that are there to compare."""
    return (
        f'"{name}" is not a loaded message type; the types load_proto_file and '
        f"load_shared_library loaded are: {', '.join(loaded) or 'none'}"
    )


def not_found(path: str, searched: Sequence[str]) -> str:
    """The reason of a configuration error for a file found nowhere: the name as given and the
    folders (in order) it was looked for in, so that a user sees which relative base applies."""
    return f'"{path}" not found; searched: {", ".join(searched)}'


def _find(path: str, search_dirs: Sequence[str]) -> str | None:
    """`path` if absolute and a file, else the first `dir/path` that is a file."""
    given = Path(path)
    if given.is_absolute():
        return path if given.is_file() else None
    for directory in search_dirs:
        candidate = Path(directory) / given
        if candidate.is_file():
            return str(candidate)
    return None


class TranslatorBinding:
    """Runs an app's translator_entry blocks on the app's MOOS mail."""

    def __init__(
        self,
        app: GobyMOOSApp,
        entries: Iterable[TranslatorEntry],
        resolve: Callable[[str], type[Message]],
        on_created: Callable[[Message], None],
        multiplex_vars: Iterable[str] = (),
        modem_id_lookup_path: str = "",
    ) -> None:
        self.app = app
        self.on_created = on_created
        self.multiplex_vars = list(multiplex_vars)
        modem_ids = ModemIdLookup.from_file(modem_id_lookup_path) if modem_id_lookup_path else None
        self.translator = Translator(
            (),
            resolve,
            lat_origin=app.common.lat_origin,
            lon_origin=app.common.lon_origin,
            modem_ids=modem_ids,
        )
        for index, entry in enumerate(entries):
            try:
                notes = self.translator.add_entry(entry)
            except TranslatorError as err:
                error = ConfigError(str(err), field=f"translator_entry[{index}]")
                raise locate(error, app.mission, app.name) from None
            for note in notes:  # runs as in goby3, but probably not what was meant: say once
                where = ConfigError(note.message, field=f"translator_entry[{index}].{note.field}")
                app.log.warning("%s", locate(where, app.mission, app.name))
        self.moos_technique = app.moos_technique
        self.runner: TranslatorRunner | None = None

    def subscribe_all(self) -> None:
        triggers = set()
        for entry in self.translator.entries.values():
            if entry.HasField("trigger") and entry.trigger.type == entry.trigger.TRIGGER_PUBLISH:
                triggers.add(entry.trigger.moos_var)
        handled = {*triggers, LAT_ORIGIN_VAR, LONG_ORIGIN_VAR}
        for var in sorted(handled):
            self.app.subscribe(var, self._on_mail)
        for var in self.translator.subscriptions():
            if var not in handled:
                self.app.subscribe(var)  # keeps dynamic_vars fresh for the create rules
        for var in self.multiplex_vars:
            self.app.subscribe(var, self._on_multiplex)

    def start(self) -> None:
        """Call from the app's on_start: the runner ignores mail older than the app's start."""
        self.runner = TranslatorRunner(
            self.translator,
            start_time=self.app.start_time,
            multiplex_vars=self.multiplex_vars,
            variables=MoosValues(self.app.dynamic_vars),
            clock=self.app.clock,
        )

    def tick(self, now: float) -> None:
        """Call from the app's loop: time triggers and pending datum changes."""
        if self.runner is not None:
            self._created(self.runner.tick(now))

    def create(self, name: str) -> Message | None:
        """`name` made now from the app's newest values (e.g. for an ON_DEMAND queue); None,
        with a warning, when a rule fails or before `start`."""
        return self.runner.create(name) if self.runner is not None else None

    def publish(self, message: Message) -> None:
        """Post a message through its entry's publish rules (warns instead of posting part)."""
        try:
            posts = self.translator.publish(message)
        except TranslatorError as err:
            self.app.log.warning("cannot publish %s: %s", message.DESCRIPTOR.full_name, err)
            return
        self.post(posts)

    def post(self, posts: Iterable[Post]) -> None:
        posts = list(posts)
        if posts and glog.isEnabledFor(VERBOSE):
            glog.log(VERBOSE, "published %s", ", ".join(post.var for post in posts))
        for post in posts:
            if glog.isEnabledFor(DEBUG1):
                glog.log(DEBUG1, "  %s = %r", post.var, post.value)
            self.app.publish(post.var, post.value, src_aux=post.source_aux)

    def _created(self, messages: list[Message]) -> None:
        for message in messages:
            if glog.isEnabledFor(VERBOSE):
                glog.log(VERBOSE, "created %s", message.DESCRIPTOR.full_name)
            if glog.isEnabledFor(DEBUG1):
                glog.log(DEBUG1, "  %s", text_format.MessageToString(message, as_one_line=True))
            self.on_created(message)

    def _on_mail(self, msg: MOOSMessage) -> None:
        if self.runner is not None:
            self._created(self.runner.on_mail(msg.key, msg.value))

    def _on_multiplex(self, msg: MOOSMessage) -> None:
        if self.runner is None:
            return
        try:
            posts = self.runner.on_multiplex(msg.value, self.moos_technique)
        except TranslatorError as err:
            self.app.log.warning("multiplexed message on %s not posted: %s", msg.key, err)
            return
        self.post(posts)
