"""pAcommsHandler: goby-acomms on a MOOS community (spec goby-moos-apps.md §4).

Translator entries create DCCL messages from MOOS variables and push them into the priority
queue; the MAC opens the slots, the driver asks the queue for frames; messages received over
the link are published through the same entries' publish rules and posted on
ACOMMS_QUEUE_RECEIVE. Every ACOMMS_* variable of the spec's table is published or handled.
The acomms wiring itself is `pygoby.acomms.handler.AcommsHandler`; this module maps the
configuration, the translator and the MOOS variables onto it.

    pAcommsHandler mission.moos [AppName]
    pAcommsHandler --example_config
"""

from __future__ import annotations

import base64
import functools

from google.protobuf.message import Message

from pygoby.acomms import messages as m
from pygoby.acomms.handler import AcommsHandler, HandlerError
from pygoby.acomms.queue import QueueError
from pygoby.dccl import DcclError
from pygoby.frontseat.messages import InterfaceData
from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.appconfig import ConfigError
from pygoby.moos.protocol import MOOSMessage
from pygoby.moos.translator import (
    MoosValues,
    TranslatorError,
    parse_for_moos,
    post_for_moos,
)
from pygoby.moos.translator_binding import MessageTypes, TranslatorBinding
from pygoby.protobuf import ProtoLoader

ROUTE_COMMAND = "goby.acomms.protobuf.RouteCommand"


def _raw_value(raw: bytes) -> str | bytes:
    """Driver traffic as a MOOS string when it is text (NMEA), else as a binary string."""
    try:
        text = raw.decode("ascii")
    except UnicodeDecodeError:
        return raw
    return text if text.isprintable() else raw


class pAcommsHandler(GobyMOOSApp):  # noqa: N801 - the program's name
    config_proto = (
        "goby/apps/moos/protobuf/pAcommsHandler_config.proto",
        "goby.apps.moos.protobuf.pAcommsHandlerConfig",
    )
    default_name = "pAcommsHandler"

    def __init__(self, cfg: Message, **kwargs) -> None:
        super().__init__(cfg, **kwargs)
        names = cfg.moos_var
        self.var = {f.name: names.prefix + getattr(names, f.name)
                    for f in names.DESCRIPTOR.fields if f.name not in ("prefix", "ifrontseat_data_out")}  # fmt: skip
        self.ifs_data_out = names.ifrontseat_data_out
        self.loader = ProtoLoader()
        try:
            self.acomms = AcommsHandler(cfg, self.clock, self.loader)
        except HandlerError as err:
            raise ConfigError(str(err)) from None
        self.queue = self.acomms.queue
        self.publish("MODEM_ID", float(cfg.modem_id))
        self.publish("VEHICLE_ID", float(cfg.modem_id))
        self._message_class = MessageTypes(
            [self._find(path) for path in cfg.load_proto_file],
            [self._find(module) for module in cfg.load_shared_library],
            fallback=m.goby_message_class,
            loader=self.loader,
        )
        self.binding = TranslatorBinding(
            self,
            cfg.translator_entry,
            self._message_class,
            on_created=self._push,
            multiplex_vars=cfg.multiplex_create_moos_var,
            modem_id_lookup_path=self._find(cfg.modem_id_lookup_path)
            if cfg.modem_id_lookup_path
            else "",
        )
        self.translator = self.binding.translator
        self.moos_technique = self.binding.moos_technique
        self._connect_signals()
        try:
            skipped = self.acomms.configure_queue(self._message_class)
        except HandlerError as err:
            raise ConfigError(str(err)) from None
        for name in skipped:
            self.log.debug("queue_cfg: no queue for %s (type not loaded)", name)
        self._subscribe_all()
        self.frontseat_forward = set()
        for name in cfg.dccl_frontseat_forward_name:
            try:
                self._message_class(name)
            except Exception:
                raise ConfigError(
                    f"dccl_frontseat_forward_name {name!r} is not a loaded type"
                ) from None
            self.frontseat_forward.add(name)
        self.liaison = None
        if cfg.HasField("liaison"):
            from pygoby.apps.liaison import Liaison  # imported only when asked for (web stack)

            self.liaison = Liaison.embedded(self)

    def _find(self, path: str) -> str:
        return self.mission.find_file(path) if self.mission is not None else path

    # ------------------------------------------------------------------ wiring
    def _connect_signals(self) -> None:
        """Map the acomms signals to MOOS posts. The slots run inside the driver's and the MAC's
        work, so a failing slot is logged and contained (it must not look like a driver
        failure or break a slot)."""
        acomms, queue, mac = self.acomms, self.acomms.queue, self.acomms.mac
        post = self._post_pb
        connections = [
            (acomms.signal_raw_incoming, functools.partial(self._post_raw, True)),
            (acomms.signal_raw_outgoing, functools.partial(self._post_raw, False)),
            (acomms.signal_modem_receive, functools.partial(post, "driver_receive")),
            (acomms.signal_modem_transmit, functools.partial(post, "driver_transmit")),
            (
                mac.signal_initiate_transmission,
                functools.partial(post, "mac_initiate_transmission"),
            ),
            (mac.signal_slot_start, functools.partial(post, "mac_slot_start")),
            (queue.signal_receive, self._on_queue_receive),
            (queue.signal_ack, self._on_ack),
            (queue.signal_expire, functools.partial(post, "queue_expire")),
            (queue.signal_queue_size_change, functools.partial(post, "queue_size")),
            (queue.signal_data_on_demand, self._on_data_on_demand),
        ]
        for signal, slot in connections:
            signal.connect(self._contained(slot))

    def _contained(self, slot):
        def run(*args) -> None:
            try:
                slot(*args)
            except Exception:
                self.log.exception("pAcommsHandler failed to handle an acomms event")

        return run

    def _subscribe_all(self) -> None:
        handlers = {
            "driver_receive": self._on_external_receive,
            "mac_initiate_transmission": self._on_external_initiate,
            "mac_cycle_update": self._on_mac_update,
            "queue_flush": self._on_flush,
            "config_file_request": self._on_config_request,
            "driver_reset": self._on_driver_reset,
            "driver_cfg_update": self._on_driver_cfg_update,
        }
        for key, handler in handlers.items():
            self.subscribe(self.var[key], handler)
        self.binding.subscribe_all()

    # ------------------------------------------------------------------ running
    def on_start(self) -> None:
        self.binding.start()
        self.acomms.start()  # drivers start at the first loop(); the MAC joins the cycle now

    def on_stop(self) -> None:
        self.acomms.shutdown()

    async def start(self, connect_timeout: float | None = None) -> None:
        await super().start(connect_timeout)
        if self.liaison is not None:
            await self.liaison.start()

    async def stop(self) -> None:
        if self.liaison is not None:
            await self.liaison.stop()
        await super().stop()

    def loop(self) -> None:
        self.binding.tick(self.clock.now())
        try:
            self.acomms.do_work()
        except HandlerError as err:
            self.log.critical("%s; stopping", err)
            self.request_stop()

    # ------------------------------------------------------------------ MOOS -> acomms
    def _push(self, message: Message) -> None:
        try:
            self.queue.push_message(message)
        except (QueueError, DcclError, ValueError) as err:
            self.log.warning("%s not queued: %s", message.DESCRIPTOR.full_name, err)

    def _on_data_on_demand(self, request, message: Message) -> None:
        """ON_DEMAND: a fresh message from the current variables, queued here (so a bad one is
        logged and skipped); `message` is left empty so the queue does not push it again."""
        name = message.DESCRIPTOR.full_name
        try:
            created = self.translator.create(name, MoosValues(self.dynamic_vars))
        except TranslatorError as err:
            self.log.warning("on-demand %s not created: %s", name, err)
            return
        self._push(created)

    def _parse(self, msg: MOOSMessage, cls: type[Message]) -> Message | None:
        out = cls()
        try:
            parse_for_moos(msg.value, out, self.moos_technique)
        except TranslatorError as err:
            self.log.warning("cannot parse %s as %s: %s", msg.key, cls.DESCRIPTOR.full_name, err)
            return None
        return out

    def _from_others(self, msg: MOOSMessage) -> bool:
        return msg.src != self.name

    def _on_external_receive(self, msg: MOOSMessage) -> None:
        if self._from_others(msg) and (transmission := self._parse(msg, m.ModemTransmission)):
            self.acomms.inject_receive(transmission)

    def _on_external_initiate(self, msg: MOOSMessage) -> None:
        if self._from_others(msg) and (transmission := self._parse(msg, m.ModemTransmission)):
            self.acomms.initiate_transmission(transmission)

    def _on_mac_update(self, msg: MOOSMessage) -> None:
        if (update := self._parse(msg, m.MACUpdate)) is not None:
            self.acomms.apply_mac_update(update)

    def _on_flush(self, msg: MOOSMessage) -> None:
        if (flush := self._parse(msg, m.QueueFlush)) is not None:
            self.queue.flush_queue(flush)

    def _on_config_request(self, msg: MOOSMessage) -> None:
        self.publish(
            self.var["config_file"], base64.b64encode(self.cfg.SerializeToString()).decode()
        )

    def _on_driver_reset(self, msg: MOOSMessage) -> None:
        try:
            self.acomms.reset_primary()
        except HandlerError as err:
            self.log.critical("%s; stopping", err)
            self.request_stop()

    def _on_driver_cfg_update(self, msg: MOOSMessage) -> None:
        if (cfg := self._parse(msg, m.DriverConfig)) is not None:
            self.acomms.update_driver_cfg(cfg)

    # ------------------------------------------------------------------ acomms -> MOOS
    def _post_pb(self, key: str, message: Message) -> None:
        self.binding.post([post_for_moos(self.var[key], message, self.moos_technique)])

    def _post_raw(self, incoming: bool, raw) -> None:
        self.publish(
            self.var["driver_raw_in" if incoming else "driver_raw_out"], _raw_value(raw.raw)
        )
        self._post_pb("driver_raw_msg_in" if incoming else "driver_raw_msg_out", raw)

    def _on_ack(self, ack, original: Message) -> None:
        self._post_pb("queue_ack_transmission", ack)
        self._post_pb("queue_ack_original_msg", original)

    def _on_queue_receive(self, message: Message) -> None:
        name = message.DESCRIPTOR.full_name
        self.binding.publish(message)
        if name in self.frontseat_forward:
            try:
                data = self.acomms.codec.encode(message)
            except DcclError as err:
                self.log.warning("cannot forward %s to the frontseat: %s", name, err)
            else:
                self.binding.post([post_for_moos(self.ifs_data_out, InterfaceData(dccl_message=data),
                                          self.moos_technique)])  # fmt: skip
        if name == ROUTE_COMMAND and self.acomms.route_cfg.route.hop:
            self.acomms.replace_route(message.new_route)
        self._post_pb("queue_receive", message)


def main(argv=None) -> int:
    return pAcommsHandler.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
