"""pTranslator: MOOS variables -> protobuf messages -> MOOS variables.

Every message created by a translator_entry's trigger is published straight back through the
same entry's publish rules. The translation itself is `pygoby.moos.translator`; this module
only wires the configuration to the MOOS application base.
"""

from __future__ import annotations

from collections.abc import Sequence

from google.protobuf.message import Message

from pygoby.moos.app import GobyMOOSApp
from pygoby.moosacomms.translator_binding import MessageTypes, TranslatorBinding
from pygoby.protobuf.goby.apps.moos.protobuf.pTranslator_config_pb2 import pTranslatorConfig


class pTranslator(GobyMOOSApp):  # noqa: N801 - the program's name
    config_class = pTranslatorConfig
    cfg: pTranslatorConfig
    default_name = "pTranslator"

    def __init__(self, cfg: pTranslatorConfig, **kwargs) -> None:
        super().__init__(cfg, **kwargs)
        # load_proto_file entries are compiled and loaded as pAcommsHandler does (goby3's
        # pTranslator looks the path up as a type name and aborts: QUIRKS.md Q-APPS-4)
        types = MessageTypes.of_translator_app(
            cfg.load_proto_file, cfg.load_shared_library, self.search_dirs(), self.config_error
        )
        for entry in cfg.translator_entry:
            types.require(entry.protobuf_name, "translator_entry.protobuf_name")
        self.binding = TranslatorBinding(
            self,
            cfg.translator_entry,
            types,
            on_created=self._loop_back,
            multiplex_vars=cfg.multiplex_create_moos_var,
            modem_id_lookup_path=cfg.modem_id_lookup_path,
        )
        self.translator = self.binding.translator
        self.binding.subscribe_all()

    def on_start(self) -> None:
        self.binding.start()

    def loop(self) -> None:
        self.binding.tick(self.clock.now())

    def _loop_back(self, message: Message) -> None:
        self.binding.publish(message)


def main(argv: Sequence[str] | None = None) -> int:
    return pTranslator.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
