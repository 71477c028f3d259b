"""pAcommsHandler: goby-acomms on a MOOS community.

Translator entries create DCCL messages from MOOS variables and push them into the priority
queue; the MAC opens the slots, the driver asks the queue for frames; messages received over
the link are published through the same entries' publish rules and posted on
ACOMMS_QUEUE_RECEIVE. Every ACOMMS_* variable goby3's pAcommsHandler publishes or reads is published
or handled. The modem, the MAC and the queue keep working while the MOOSDB is away (upstream's stop
with it); their posts are delivered when it is back.
The acomms wiring itself is `pygoby.acomms.handler.AcommsHandler`; this module maps the
configuration, the translator and the MOOS variables onto it.

    pAcommsHandler mission.moos [AppName]
    pAcommsHandler --example_config
"""

from __future__ import annotations

import base64
import functools
from collections.abc import Callable, Sequence

from google.protobuf.message import Message

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.driver_base import ModemDriverBase, driver_name
from pygoby.acomms.drivers.ufield import UFldDriver
from pygoby.acomms.handler import AcommsHandler, DriverSlot, HandlerError, make_driver
from pygoby.errors import ConfigError
from pygoby.frontseat.messages import InterfaceData
from pygoby.moos.app import GobyMOOSApp
from pygoby.moos.appconfig import locate, prefixed_var_names
from pygoby.moos.protocol import MOOSMessage, text_or_binary
from pygoby.moosacomms.acomms_config import AcommsMessageSet
from pygoby.moosacomms.goby11 import Goby11Variables
from pygoby.moosacomms.translator_binding import TranslatorBinding, not_loaded
from pygoby.moosacomms.ufield_link import MOOSMailLink
from pygoby.protobuf.goby.apps.moos.protobuf.pAcommsHandler_config_pb2 import pAcommsHandlerConfig
from pygoby.util.clock import Clock
from pygoby.util.signal import Signal

IFS_DATA_OUT = "ifrontseat_data_out"  # a moos_var field without the prefix


def _make_driver(cfg: acomms_pb.DriverConfig, clock: Clock) -> ModemDriverBase | None:
    """The handler's drivers; a uField driver gets its own MOOS connection."""
    driver = make_driver(cfg, clock)
    if isinstance(driver, UFldDriver):
        driver.mail = MOOSMailLink()
    return driver


class pAcommsHandler(GobyMOOSApp):  # noqa: N801 - the program's name
    config_class = pAcommsHandlerConfig
    cfg: pAcommsHandlerConfig
    default_name = "pAcommsHandler"
    # the modem, the MAC and the queue keep going through a MOOSDB outage; what they post
    # meanwhile is delivered when the DB is back
    iterate_without_comms = True

    def __init__(self, cfg: pAcommsHandlerConfig, **kwargs) -> None:
        super().__init__(cfg, **kwargs)
        self.var = prefixed_var_names(cfg.moos_var, skip=(IFS_DATA_OUT,))
        self.ifs_data_out = getattr(cfg.moos_var, IFS_DATA_OUT)
        # load_proto_file, load_shared_library, and the Goby 1.1 XML message files (-> DCCL
        # types, queue and translator entries)
        self.messages = AcommsMessageSet.load(
            cfg, self.find_file, search_dirs=self.search_dirs(), config_error=self.config_error
        )
        self.message_types = self.messages.types
        if cfg.modem_id_lookup_path:  # for the translator and the uField driver
            cfg.modem_id_lookup_path = self.find_file(cfg.modem_id_lookup_path)
        try:
            self.acomms = AcommsHandler(
                cfg, self.clock, self.messages.loader, driver_factory=_make_driver
            )
        except ConfigError as err:  # a field of the block (a driver, a slot's rate)
            raise locate(err, self.mission, self.name) from None
        except HandlerError as err:
            raise ConfigError(str(err)) from None
        self.queue = self.acomms.queue
        dccl1 = None
        if self.messages.transitional.speaks_dccl1(cfg):  # Goby 1.1's bytes and variables
            dccl1 = self.messages.transitional.dccl1_bridge(
                cfg, self.messages.loader, self.clock.now
            )
            self.queue.use_dccl1(dccl1)
        self.publish("MODEM_ID", float(cfg.modem_id))
        self.publish("VEHICLE_ID", float(cfg.modem_id))
        self.messages.apply_libraries(self.acomms.codec)
        self.binding = TranslatorBinding(
            self,
            cfg.translator_entry,
            self.message_types,
            on_created=self._created,
            multiplex_vars=cfg.multiplex_create_moos_var,
            modem_id_lookup_path=cfg.modem_id_lookup_path,
        )
        self.translator = self.binding.translator
        self.messages.read_named_values(self.translator)
        self.goby11 = Goby11Variables(
            self,
            self.acomms,
            cfg.queue_cfg,
            enabled=bool(cfg.queue_cfg.queue or cfg.transitional_cfg.message_file),
            dccl1=dccl1,
            var=self.var,
        )
        self._connect_signals()
        self._configure_queue()
        self._subscribe_all()
        self.frontseat_forward = self.messages.require(
            cfg.dccl_frontseat_forward_name, "dccl_frontseat_forward_name"
        )
        self.liaison = None
        if cfg.HasField("liaison"):
            from pygoby.topside.liaison import Liaison  # imported only when asked for (web stack)

            self.liaison = Liaison.embedded(self, self.messages)

    def _configure_queue(self) -> None:
        try:
            skipped = self.acomms.configure_queue(self.message_types)
        except HandlerError as err:
            raise ConfigError(str(err)) from None
        if skipped:  # goby3 skips them silently: an operator never learns why nothing is sent
            raise self.config_error(
                not_loaded(skipped[0], self.messages.loaded()),
                "queue_cfg.message_entry.protobuf_name",
                skipped[0],
            )

    # ------------------------------------------------------------------ wiring
    def _connect_signals(self) -> None:
        """Map the acomms signals to MOOS posts. The slots run inside the driver's and the MAC's
        work, so a failing slot is logged and contained (it must not look like a driver
        failure or break a slot)."""
        acomms, queue, mac = self.acomms, self.acomms.queue, self.acomms.mac
        connections: list[tuple[Signal[...], Callable[..., object]]] = [
            (acomms.signal_raw_incoming, functools.partial(self._post_raw, True)),
            (acomms.signal_raw_outgoing, functools.partial(self._post_raw, False)),
            (acomms.signal_modem_receive, self._poster("driver_receive")),
            (acomms.signal_modem_transmit, self._poster("driver_transmit")),
            (mac.signal_initiate_transmission, self._poster("mac_initiate_transmission")),
            (mac.signal_slot_start, self._poster("mac_slot_start")),
            (queue.signal_receive, self._on_queue_receive),
            (queue.signal_ack, self._on_ack),
            (queue.signal_data_on_demand, self._on_data_on_demand),
        ]
        if not self.goby11.goby11_forms:  # else Goby11Variables posts Goby 1.1's forms
            connections += [
                (queue.signal_expire, self._poster("queue_expire")),
                (queue.signal_queue_size_change, self._poster("queue_size")),
            ]
        for signal, slot in connections:
            signal.connect(slot, contain_errors=True, logger=self.log)
        acomms.signal_driver_status.connect(
            self._on_driver_status, contain_errors=True, logger=self.log
        )

    def _on_driver_status(self, slot: DriverSlot, text: str) -> None:
        role = "primary" if slot is self.acomms.primary else "listen"
        self.publish(self.var["driver_status"], f"{role} driver {driver_name(slot.cfg)}: {text}")

    def _subscribe_all(self) -> None:
        acomms = self.acomms
        from_others = {
            "driver_receive": acomms.inject_receive,
            "mac_initiate_transmission": acomms.initiate_transmission,
        }
        for key, handler in from_others.items():
            self.subscribe_pb(self.var[key], acomms_pb.ModemTransmission, handler, ignore_own=True)
        self.subscribe(self.var["mac_cycle_update"], self._on_mac_update)
        self.subscribe(self.var["queue_flush"], self._on_flush)
        self.subscribe(self.var["config_file_request"], self._on_config_request)
        self.subscribe(self.var["driver_reset"], self._on_driver_reset)
        self.subscribe_pb(
            self.var["driver_cfg_update"], acomms_pb.DriverConfig, acomms.update_driver_cfg
        )
        self.binding.subscribe_all()
        self.goby11.subscribe_all()

    # ------------------------------------------------------------------ running
    def on_start(self) -> None:
        self.binding.start()
        self.acomms.start()  # drivers start at the first loop(); the MAC joins the cycle now

    def on_stop(self) -> None:
        self.acomms.shutdown()
        self.acomms.close()

    async def start(self, connect_timeout: float | None = None) -> None:
        await super().start(connect_timeout)
        if self.liaison is not None:
            await self.liaison.start()

    async def stop(self) -> None:
        if self.liaison is not None:
            await self.liaison.stop()
        await super().stop()

    def status_lines(self) -> list[str]:
        """show_gui's panel: the drivers, the MAC's current slot, every queue's size."""
        lines = super().status_lines()
        for slot in self.acomms.slots:
            state = slot.describe(self.clock.now())
            role = "primary" if slot is self.acomms.primary else "listen"
            lines.append(f"{role} driver {driver_name(slot.cfg)}: {state}")
        mac = self.acomms.mac
        if mac.running and mac.slots:
            now = mac.slots[(mac.current - 1) % len(mac.slots)]
            # (a slot due since the last tick starts at the next one: "next in 0.0 s")
            next_in = max(0.0, mac.next_slot_time - self.clock.now())
            lines.append(
                f"MAC slot {now.slot_index} ({now.src}->{now.dest}, rate {now.rate}, "
                f"{now.slot_seconds:g} s); next in {next_in:.1f} s"
            )
        else:
            lines.append("MAC: not running")
        lines += [f"queue {q.name} ({q.dccl_id}): {len(q)}" for q in self.queue.queues.values()]
        return lines

    def loop(self) -> None:
        if self.connected:  # time triggers create from MOOS values: not while the DB is away
            self.binding.tick(self.clock.now())
        self._stop_on_failure(self.acomms.do_work)

    def _stop_on_failure(self, work: Callable[[], object]) -> None:
        try:
            work()
        except HandlerError as err:
            self.fail(str(err))

    # ------------------------------------------------------------------ MOOS -> acomms
    def _created(self, message: Message) -> None:
        self.acomms.push(
            self.messages.transitional.complete(message, self.clock.now(), self.cfg.modem_id)
        )

    def _on_mac_update(self, msg: MOOSMessage) -> None:
        """Today's MACUpdate, or Goby 1.1's (ADD/REMOVE/REPLACE with SLOT_* slots)."""
        if not self.goby11.apply_mac_update(msg) and (
            update := self.parse_pb(msg, acomms_pb.MACUpdate)
        ):
            self.acomms.apply_mac_update(update)

    def _on_flush(self, msg: MOOSMessage) -> None:
        """Today's QueueFlush, or Goby 1.1's (by queue key, CCL queues too)."""
        if not (self.goby11.goby11_forms and self.goby11.apply_flush(msg)) and (
            flush := self.parse_pb(msg, acomms_pb.QueueFlush)
        ):
            self.queue.flush_queue(flush)

    def _on_data_on_demand(self, request: acomms_pb.ModemTransmission, message: Message) -> None:
        """ON_DEMAND: a fresh message from the current variables, queued here (so a bad one is
        logged and skipped); `message` is left empty so the queue does not push it again."""
        created = self.binding.create(message.DESCRIPTOR.full_name)
        if created is not None:
            self.acomms.push(created)

    def _on_config_request(self, msg: MOOSMessage) -> None:
        self.publish(
            self.var["config_file"], base64.b64encode(self.cfg.SerializeToString()).decode()
        )

    def _on_driver_reset(self, msg: MOOSMessage) -> None:
        self._stop_on_failure(self.acomms.reset_primary)

    # ------------------------------------------------------------------ acomms -> MOOS
    def _poster(self, key: str):
        return functools.partial(self.publish_pb, self.var[key])

    def _post_raw(self, incoming: bool, raw: acomms_pb.ModemRaw) -> None:
        self.publish(
            self.var["driver_raw_in" if incoming else "driver_raw_out"], text_or_binary(raw.raw)
        )
        self.publish_pb(self.var["driver_raw_msg_in" if incoming else "driver_raw_msg_out"], raw)

    def _on_ack(self, ack: acomms_pb.ModemTransmission, original: Message) -> None:
        if not self.goby11.goby11_forms:  # else Goby 1.1's ModemDataAck (Goby11Variables)
            self.publish_pb(self.var["queue_ack_transmission"], ack)
        self.publish_pb(self.var["queue_ack_original_msg"], original)

    def _on_queue_receive(self, message: Message) -> None:
        self.binding.publish(message)
        name = message.DESCRIPTOR.full_name
        if name in self.frontseat_forward and (data := self.acomms.encode(message)) is not None:
            self.publish_pb(self.ifs_data_out, InterfaceData(dccl_message=data))  # to iFrontSeat
        self.acomms.apply_route_command(message)
        self.publish_pb(self.var["queue_receive"], message)


def main(argv: Sequence[str] | None = None) -> int:
    return pAcommsHandler.main(argv)


if __name__ == "__main__":
    raise SystemExit(main())
