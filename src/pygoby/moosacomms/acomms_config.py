"""pAcommsHandler's configuration and the message set it loads, as a library: for pAcommsHandler
itself and for the tools that show or compose its messages (liaison, iCommander), so that each
reads the same block the same way and no app imports another.

    cfg = read_acomms_config(mission, "pAcommsHandler")  # Goby 1.1/2 forms translated
    messages = AcommsMessageSet.load(cfg, mission.find_file, mission.search_dirs())
    messages.types("SIMPLE_STATUS")                      # a class of load_proto_file,
                                                         # load_shared_library or an XML file
    messages.import_xml("more.xml")                      # iCommander's "Import Message File"

It lives here because it needs both the MOOS side (the mission file, the configuration reader,
the message types of translator apps) and acomms (the Goby 1.1 XML message sets), and `acomms`
never imports `moos`.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

from pygoby.acomms import messages as acomms_pb
from pygoby.dccl import Codec, DcclError
from pygoby.dccl.libraries import BuiltinLibrary, split_libraries
from pygoby.errors import ConfigError
from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.appconfig import read_configuration
from pygoby.moos.moosfile import MissionFile
from pygoby.moos.translator import Translator
from pygoby.moosacomms.transitional import TransitionalMessages
from pygoby.moosacomms.translator_binding import MessageTypes, not_found
from pygoby.protobuf import ProtoLoader
from pygoby.protobuf.goby.apps.moos.protobuf.pAcommsHandler_config_pb2 import (
    pAcommsHandlerConfig,
)
from pygoby.protobuf.goby.moos.protobuf.transitional_pb2 import MessageFile

XML_PATH_FIELD = "message_file.path"  # dccl_cfg/queue_cfg/transitional_cfg all name it so

ErrorMaker = Callable[
    [str, str, str], ConfigError
]  # (reason, field, value): GobyMOOSApp.config_error


def _unlocated(reason: str, field: str, value: str) -> ConfigError:
    return ConfigError(reason, field=field)


def read_acomms_config(
    mission: MissionFile, block: str = "pAcommsHandler", overrides: Sequence[tuple[str, str]] = ()
) -> pAcommsHandlerConfig:
    """The pAcommsHandlerConfig of `mission`'s ProcessConfig `block` (ConfigError file:line)."""
    return read_configuration(pAcommsHandlerConfig, mission, block, overrides)


def acomms_config_or_defaults(mission: MissionFile, block: str) -> pAcommsHandlerConfig:
    """`read_acomms_config`, or pAcommsHandler's defaults when `mission` has no `block` (a log
    tool given a mission with pTranslator only still knows the default variable names)."""
    if mission.goby_block(block) is None:
        return pAcommsHandlerConfig()
    return read_acomms_config(mission, block)


@dataclass
class AcommsMessageSet:
    """The message definitions of one pAcommsHandler configuration: `cfg` (with the queue and
    translator entries of its XML files added), the `loader` every type is in, `types` (name ->
    class), the XML message sets (`transitional`) and the built-ins standing for C++ DCCL codec
    libraries (their messages are in `types`; a codec also needs `apply_libraries`)."""

    cfg: pAcommsHandlerConfig
    loader: ProtoLoader
    types: MessageTypes
    transitional: TransitionalMessages
    dccl_libraries: list[BuiltinLibrary]  # load_shared_library's C++ DCCL codec libraries
    find: Callable[[str], str] = str
    search_dirs: Sequence[str] = field(default_factory=list)  # where `find` looks (for errors)

    @classmethod
    def load(
        cls,
        cfg: pAcommsHandlerConfig,
        find: Callable[[str], str] = str,
        search_dirs: Sequence[str] = (),
        config_error: ErrorMaker | None = None,
    ) -> AcommsMessageSet:
        """Load `cfg`'s message files; `find` resolves relative file names (the mission's
        find_file), `search_dirs` are the folders it looks in (for "not found" errors; default
        the working directory). The XML files' entries are appended to `cfg`, so load a
        configuration once. ConfigError for files that cannot be used, made by
        `config_error(reason, field, value)` (located at the mission line:
        GobyMOOSApp.config_error) when given."""
        error = config_error or _unlocated
        dccl_libraries, modules = split_libraries(
            cfg.load_shared_library, lambda reason, name: error(reason, "load_shared_library", name)
        )
        loader = ProtoLoader()
        search_dirs = list(search_dirs) or [os.getcwd()]
        transitional = TransitionalMessages.expand(
            cfg, loader, _xml_finder(find, search_dirs, error)
        )
        types = MessageTypes(
            [
                *(p for library in dccl_libraries for p in library.proto_files),
                *(find(path) for path in cfg.load_proto_file),
            ],
            [find(module) for module in modules],
            fallback=acomms_pb.goby_message_class,
            loader=loader,
            search_dirs=search_dirs,
            config_error=config_error,
        )
        out = cls(cfg, loader, types, transitional, dccl_libraries, find, search_dirs)
        out.require(
            [entry.protobuf_name for entry in cfg.translator_entry],
            "translator_entry.protobuf_name",
        )
        return out

    def loaded(self) -> list[str]:
        """The message types the files, modules, libraries and XML files define."""
        from_libraries = [name for library in self.dccl_libraries for name in library.messages]
        xml = [name for message_set in self.transitional.sets for name in message_set.names]
        return [*self.types.loaded, *from_libraries, *xml]

    @classmethod
    def of_app(
        cls, app: GobyMOOSApp, block: str, message_files: Sequence[MessageFile] = ()
    ) -> AcommsMessageSet:
        """The message set of the pAcommsHandler block `block` of `app`'s mission, plus the
        app's own XML `message_files` (Goby 1.1's iCommander had them; a file pAcommsHandler
        loads already is skipped). Without the block, `message_files` alone."""
        mission = app.mission
        if mission is None:
            raise ConfigError(f"{app.name} needs the mission file with the {block} ProcessConfig")
        if message_files and mission.goby_block(block) is None:
            cfg = pAcommsHandlerConfig()
        else:
            cfg = read_acomms_config(mission, block)
        out = cls.load(
            cfg,
            app.find_file,
            app.search_dirs(),
            config_error=functools.partial(app.config_error, block=block),
        )
        for message_file in message_files:
            if Path(app.find_file(message_file.path)).resolve() not in out.files():
                out.import_xml(message_file.path, message_file.manipulator, app.config_error)
        return out

    def files(self) -> set[Path]:
        """The XML files loaded (resolved paths)."""
        return {message_set.path.resolve() for message_set in self.transitional.sets}

    def apply_libraries(self, codec: Codec) -> None:
        """Give `codec` what load_shared_library's C++ DCCL codec libraries give a C++ codec
        (pygoby's built-ins: CCL messages and id codec, ...); ConfigError if one cannot."""
        try:
            for library in self.dccl_libraries:
                library.apply(codec)
        except DcclError as err:
            raise ConfigError(f"load_shared_library: {err}") from None

    def require(self, names: Sequence[str], field: str) -> set[str]:
        """`names` (of configuration `field`), each a loaded type, else the located ConfigError
        that lists the loaded types."""
        for name in names:
            self.types.require(name, field, self.loaded())
        return set(names)

    def read_named_values(self, translator: Translator) -> None:
        """Goby 1.1's `name=value` rule for the XML messages' single-field source variables."""
        for name, keys in self.transitional.single_field_sources().items():
            translator.read_named_values(name, keys)

    def import_xml(
        self, path: str, manipulators: Sequence[int] = (), config_error: ErrorMaker | None = None
    ) -> list[str]:
        """Add the messages of one more XML file (iCommander's "Import Message File") to the
        set and to `cfg`; returns their names. ConfigError (file:line) for a file that cannot
        be used or that defines a message already loaded; one not found is located by
        `config_error` when the path comes from a configuration."""
        message_file = self.cfg.transitional_cfg.message_file.add(
            path=path, manipulator=manipulators
        )
        find = _xml_finder(self.find, self.search_dirs, config_error or _unlocated)
        try:
            message_set = self.transitional.add_file(self.cfg, message_file, self.loader, find)
        except ConfigError:
            del self.cfg.transitional_cfg.message_file[-1]
            raise
        return message_set.names


def _xml_finder(
    find: Callable[[str], str], search_dirs: Sequence[str], error: ErrorMaker
) -> Callable[[str], str]:
    """`find` for XML message files, with load_proto_file's error for a file found nowhere."""

    def find_xml(path: str) -> str:
        found = find(path)
        if not Path(found).is_file():
            raise error(not_found(path, search_dirs), XML_PATH_FIELD, path)
        return found

    return find_xml
