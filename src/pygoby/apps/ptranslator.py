"""pTranslator: MOOS variables -> protobuf messages -> MOOS variables (spec goby-moos-apps.md 3).

Every message created by a translator_entry's trigger is published straight back through the
same entry's publish rules. The translation itself is `pygoby.moos.translator`; this module
only wires the configuration to the MOOS application base.
"""

from __future__ import annotations

import importlib
import importlib.util
from pathlib import Path

from google.protobuf import descriptor_pool, message_factory
from google.protobuf.message import Message

from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.appconfig import ConfigError
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
    moos_technique_from_config,
)
from pygoby.protobuf import ProtoError, ProtoLoader


def _import_generated_module(name: str) -> None:
    """load_shared_library: a module of generated _pb2 code, by module name or file path."""
    path = Path(name)
    if path.suffix == ".py" and path.is_file():
        spec = importlib.util.spec_from_file_location(path.stem, path)
        if spec is None or spec.loader is None:
            raise ImportError(f"cannot load {name}")
        module = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(module)
    else:
        importlib.import_module(name)


class pTranslator(GobyMOOSApp):  # noqa: N801 - the program's name
    config_proto = (
        "goby/apps/moos/protobuf/pTranslator_config.proto",
        "goby.apps.moos.protobuf.pTranslatorConfig",
    )
    default_name = "pTranslator"

    def __init__(self, cfg: Message, **kwargs) -> None:
        super().__init__(cfg, **kwargs)
        self.loader = ProtoLoader()
        try:
            for module in cfg.load_shared_library:
                _import_generated_module(module)
            for path in cfg.load_proto_file:
                self.loader.load_file(path)
        except (ImportError, ProtoError, OSError, SyntaxError, TypeError) as err:
            raise ConfigError(f"cannot load message definitions: {err}") from None
        modem_ids = (
            ModemIdLookup.from_file(cfg.modem_id_lookup_path) if cfg.modem_id_lookup_path else None
        )
        try:
            self.translator = Translator(
                cfg.translator_entry,
                self._message_class,
                lat_origin=self.common.lat_origin,
                lon_origin=self.common.lon_origin,
                modem_ids=modem_ids,
            )
            self.moos_technique = moos_technique_from_config(self.common)
        except TranslatorError as err:
            raise ConfigError(str(err)) from None
        self.runner: TranslatorRunner | None = None
        self._subscribe_all()

    def _message_class(self, name: str) -> type[Message]:
        try:
            return self.loader.message_class(name)
        except ProtoError:
            # Types from load_shared_library live in protobuf's default pool.
            descriptor = descriptor_pool.Default().FindMessageTypeByName(name)
            return message_factory.GetMessageClass(descriptor)

    def _subscribe_all(self) -> None:
        triggers = set()
        for entry in self.translator.entries.values():
            if entry.HasField("trigger") and entry.trigger.type == entry.trigger.TRIGGER_PUBLISH:
                triggers.add(entry.trigger.moos_var)
        handled = {*triggers, LAT_ORIGIN_VAR, LONG_ORIGIN_VAR}
        for var in sorted(handled):
            self.subscribe(var, self._on_mail_for_runner)
        for var in self.translator.subscriptions():
            if var not in handled:
                self.subscribe(var)  # keeps dynamic_vars fresh for the create rules
        for var in self.cfg.multiplex_create_moos_var:
            self.subscribe(var, self._on_multiplex)

    def on_start(self) -> None:
        self.runner = TranslatorRunner(
            self.translator,
            start_time=self.start_time,
            multiplex_vars=self.cfg.multiplex_create_moos_var,
            variables=MoosValues(self.dynamic_vars),
        )

    def _on_mail_for_runner(self, msg: MOOSMessage) -> None:
        if self.runner is not None:
            self._publish_created(self.runner.on_mail(msg.key, msg.value))

    def _on_multiplex(self, msg: MOOSMessage) -> None:
        if self.runner is None:
            return
        try:
            posts = self.runner.on_multiplex(msg.value, self.moos_technique)
        except TranslatorError as err:
            self.log.warning("multiplexed message on %s not posted: %s", msg.key, err)
            return
        self._post(posts)

    def loop(self) -> None:
        if self.runner is not None:
            self._publish_created(self.runner.tick(self.clock.now()))

    def _publish_created(self, messages: list[Message]) -> None:
        for message in messages:
            try:
                posts = self.translator.publish(message)
            except TranslatorError as err:
                self.log.warning("cannot publish %s: %s", message.DESCRIPTOR.full_name, err)
                continue
            self._post(posts)

    def _post(self, posts: list[Post]) -> None:
        for post in posts:
            self.publish(post.var, post.value, src_aux=post.source_aux)


def main(argv=None) -> int:
    return pTranslator.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
