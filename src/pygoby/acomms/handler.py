"""AcommsHandler: modem drivers, MAC, priority queue and DCCL wired together as pAcommsHandler
wires them, without any MOOS.

    handler = AcommsHandler(cfg, clock, loader)     # cfg: pAcommsHandlerConfig (or any message
                                                    # with the same acomms fields)
    handler.configure_queue(resolve)                # after the message types are loaded
    handler.start()                                 # drivers start at the next do_work, MAC runs
    handler.queue.push_message(msg)                 # outgoing DCCL messages
    handler.do_work()                               # >= 5 Hz, inside a running asyncio loop

`cfg.modem_id` is copied into the queue, the MAC and every driver configuration without its
own id. Every driver (primary and listen) is bound to the queue; only the primary is bound to
the MAC and has its informational signals re-emitted (`signal_raw_incoming`,
`signal_raw_outgoing`, `signal_modem_receive`, `signal_modem_transmit`). A driver exception
from `startup()` or `do_work()` shuts the driver down and applies `driver_failure_approach`.
The queue's and the MAC's own signals are used directly (`handler.queue.signal_receive`, ...).
"""

from __future__ import annotations

import logging
import os
from collections.abc import Callable
from dataclasses import dataclass

from google.protobuf import text_format
from google.protobuf.message import Message

from pygoby.acomms import drivers
from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.bind import bind, unbind
from pygoby.acomms.driver_base import ModemDriverBase, driver_name
from pygoby.acomms.errors import (
    DriverConfigError,
    DriverNotFoundError,
    HandlerError,
    ModemDriverError,
    QueueError,
)
from pygoby.acomms.mac import MACManager
from pygoby.acomms.queue import QueueManager
from pygoby.acomms.queue.persist import QueueStore
from pygoby.acomms.route import RouteCommand, RouteManager, bind_router
from pygoby.dccl import Codec, DcclError
from pygoby.errors import ConfigError
from pygoby.protobuf import ProtoLoader
from pygoby.protobuf.goby.acomms.protobuf.route_pb2 import StaticRoute
from pygoby.util.clock import Clock
from pygoby.util.signal import Signal

log = logging.getLogger(__name__)

Status = acomms_pb.ModemDriverStatus
DRIVER_NONE = acomms_pb.DriverType.DRIVER_NONE
UFIELD = acomms_pb.DriverType.DRIVER_UFIELD_SIM_DRIVER

ROUTE_COMMAND = RouteCommand.DESCRIPTOR.full_name

CONTINUALLY_RESTART_DRIVER = 1
MOVE_LISTEN_DRIVER_TO_PRIMARY = 2
DISABLE_AND_MOVE_LISTEN_DRIVER_TO_PRIMARY = 3


# --------------------------------------------------------------------------------------------
# Drivers


def _check_slot_rates(mac_cfg: acomms_pb.MACConfig, driver: ModemDriverBase) -> None:
    """Every slot's rate is one the driver has: a wrong one would fail every cycle, not once."""
    if driver.RATES is None:
        return
    for index, slot in enumerate(mac_cfg.slot):
        if slot.type == acomms_pb.DATA and slot.rate not in driver.RATES:
            raise ConfigError(
                f"rate {slot.rate} is not a rate of {type(driver).__name__} "
                f"({driver.RATES.start}-{driver.RATES.stop - 1})",
                field=f"mac_cfg.slot[{index}].rate",
            )


def make_driver(cfg: acomms_pb.DriverConfig, clock: Clock) -> ModemDriverBase | None:
    """The driver selected by `cfg` (DriverConfig, through pygoby.acomms.drivers' registry), or
    None for DRIVER_NONE."""
    if cfg.WhichOneof("driver") != "driver_name" and cfg.driver_type == DRIVER_NONE:
        return None
    return drivers.make_driver(cfg, clock)


def make_codec(dccl_cfg: acomms_pb.DCCLConfig, clock: Clock, loader: ProtoLoader | None) -> Codec:
    """The DCCL codec of a handler's `dccl_cfg` (passphrase, ids sent in the clear, id codec);
    also for the tools that decode a handler's frames from its logs."""
    codec = Codec(
        passphrase=dccl_cfg.crypto_passphrase or None,
        clock=clock,
        do_not_encrypt_ids=dccl_cfg.skip_crypto_for_id,
        loader=loader,
    )
    if dccl_cfg.id_codec in ("dccl.default.id", "dccl.ccl.id"):
        codec.set_id_codec(dccl_cfg.id_codec)
    elif dccl_cfg.id_codec:
        log.warning(
            "dccl_cfg.id_codec %r: custom id codecs are not supported; using the default id codec",
            dccl_cfg.id_codec,
        )
    return codec


def wire_driver_cfg(driver_cfg: acomms_pb.DriverConfig, cfg) -> None:
    """pAcommsHandler's special wiring: the uField driver gets the
    top-level `modem_id_lookup_path` and, where its own are unset, the MOOSDB of `common` (so a
    mission on a ServerPort other than 9000 needs no `moos_port`)."""
    if driver_cfg.WhichOneof("driver") == "driver_type" and driver_cfg.driver_type == UFIELD:
        ufld = driver_cfg.Extensions[acomms_pb.UFLD_CONFIG]
        lookup = getattr(cfg, "modem_id_lookup_path", "")
        if lookup and not ufld.HasField("modem_id_lookup_path"):
            ufld.modem_id_lookup_path = lookup
        common = getattr(cfg, "common", None)
        for ours, theirs in (("moos_server", "server_host"), ("moos_port", "server_port")):
            if common is not None and common.HasField(theirs) and not ufld.HasField(ours):  # type: ignore[arg-type]
                setattr(ufld, ours, getattr(common, theirs))


@dataclass(eq=False)
class DriverSlot:
    """One configured driver and its run state (`restart_at` is None while it runs)."""

    driver: ModemDriverBase
    cfg: acomms_pb.DriverConfig
    restart_at: float | None = 0.0
    failures: int = 0
    problem: str = ""  # why it last failed

    @property
    def running(self) -> bool:
        return self.restart_at is None

    def describe(self, now: float) -> str:
        """The state for an operator: running, or why not and when it is tried again."""
        if self.running:
            return "running"
        if not self.problem:
            return "starting"
        assert self.restart_at is not None
        return (
            f"failed ({self.failures}x): {self.problem}; "
            f"next attempt in {max(self.restart_at - now, 0):.0f} s"
        )


# --------------------------------------------------------------------------------------------


class AcommsHandler:
    def __init__(
        self,
        cfg,
        clock: Clock,
        loader: ProtoLoader | None = None,
        driver_factory: Callable[
            [acomms_pb.DriverConfig, Clock], ModemDriverBase | None
        ] = make_driver,
    ) -> None:
        if cfg.modem_id == acomms_pb.BROADCAST_ID:
            raise HandlerError("modem_id 0 is the broadcast address; set a modem_id of 1 or more")
        self.clock = clock
        self.modem_id = cfg.modem_id
        self.failure = type(cfg.driver_failure_approach)()
        self.failure.CopyFrom(cfg.driver_failure_approach)

        # Drivers first (as upstream): a bad driver configuration fails before anything runs.
        self.slots: list[DriverSlot] = []
        self.primary: DriverSlot | None = None
        self.signal_raw_incoming: Signal[acomms_pb.ModemRaw] = (
            Signal()
        )  # (ModemRaw) of the primary driver
        self.signal_raw_outgoing: Signal[acomms_pb.ModemRaw] = Signal()
        self.signal_modem_receive: Signal[acomms_pb.ModemTransmission] = (
            Signal()
        )  # (ModemTransmission) received by the primary
        self.signal_modem_transmit: Signal[acomms_pb.ModemTransmission] = (
            Signal()
        )  # (ModemTransmission) transmit result
        # (DriverSlot, text) when a driver starts or fails: "running" or why it failed and
        # when it is tried again
        self.signal_driver_status: Signal[[DriverSlot, str]] = Signal()
        primary_cfg = acomms_pb.DriverConfig()
        primary_cfg.CopyFrom(cfg.driver_cfg)
        top_level = primary_cfg.WhichOneof("driver") is None and cfg.HasField("driver_type")
        if top_level:
            primary_cfg.driver_type = cfg.driver_type  # Goby 2 style top-level driver_type
        for index, driver_cfg in enumerate([primary_cfg, *cfg.listen_driver_cfg]):
            own = acomms_pb.DriverConfig()
            own.CopyFrom(driver_cfg)
            if not own.HasField("modem_id"):
                own.modem_id = self.modem_id
            wire_driver_cfg(own, cfg)
            try:
                driver = driver_factory(own, clock)
            except ModemDriverError as exc:
                block = "driver_cfg" if index == 0 else f"listen_driver_cfg[{index - 1}]"
                field = block
                if isinstance(exc, DriverNotFoundError):
                    field = "driver_type" if top_level else f"{block}.{own.WhichOneof('driver')}"
                raise DriverConfigError(str(exc), field=field) from None
            if driver is None:
                continue
            slot = DriverSlot(driver, own)
            self.slots.append(slot)
            if index == 0:
                self.primary = slot
            self._forward_informational(slot)

        self.codec = make_codec(cfg.dccl_cfg, clock, loader)

        self.queue_cfg = acomms_pb.QueueManagerConfig()
        self.queue_cfg.CopyFrom(cfg.queue_cfg)
        self.queue_cfg.modem_id = self.modem_id
        self.queue = QueueManager(self.codec, clock)
        for slot in self.slots:
            bind(slot.driver, self.queue)

        self.mac_cfg = acomms_pb.MACConfig()
        self.mac_cfg.CopyFrom(cfg.mac_cfg)
        self.mac_cfg.modem_id = self.modem_id
        self.mac = MACManager(clock)
        if self.primary is not None:
            _check_slot_rates(self.mac_cfg, self.primary.driver)
            self.mac.signal_initiate_transmission.connect(self._initiate_on_primary)
            self.primary.driver.signal_receive.connect(self.mac.handle_modem_receive)

        # Static routing: the queue is the router's one subnet here.
        self.router = RouteManager(cfg.route_cfg)
        bind_router(self.queue, self.router)

    # ------------------------------------------------------------------ start-up
    def configure_queue(self, resolve: Callable[[str], type[Message]]) -> list[str]:
        """Create one queue per `queue_cfg.message_entry` whose type `resolve` knows; the
        others are skipped (as upstream) and their names returned."""
        entries = list(self.queue_cfg.message_entry)
        base = acomms_pb.QueueManagerConfig()
        base.CopyFrom(self.queue_cfg)
        del base.message_entry[:]
        self.queue.set_cfg(base)
        skipped = []
        for entry in entries:
            try:
                cls = resolve(entry.protobuf_name)
            except Exception:
                log.debug("queue_cfg: %s is not a loaded type; no queue", entry.protobuf_name)
                skipped.append(entry.protobuf_name)
                continue
            try:
                self.queue.add_queue(entry, cls)
            except (QueueError, DcclError, ValueError) as exc:
                raise HandlerError(
                    f"queue_cfg message_entry {entry.protobuf_name}: {exc}"
                ) from None
        if self.queue_cfg.persistent_queue_file:
            self._open_persistent_queue(self.queue_cfg.persistent_queue_file)
        return skipped

    def _open_persistent_queue(self, path: str) -> None:
        try:
            store = QueueStore(path)
        except QueueError as exc:
            raise HandlerError(f"queue_cfg persistent_queue_file: {exc}") from None
        restored = self.queue.attach_store(store)
        log.info(
            "persistent queue %s: %d queued message(s) restored", os.path.abspath(path), restored
        )

    def start(self) -> None:
        """Drivers start at the next `do_work`; the MAC starts its cycle now."""
        for slot in self.slots:
            slot.restart_at = 0.0
        self.mac.startup(self.mac_cfg)

    def shutdown(self) -> None:
        self.mac.shutdown()
        for slot in self.slots:
            if slot.running:
                self._shutdown_driver(slot)
            slot.restart_at = 0.0

    def close(self) -> None:
        """After `shutdown`: let go of the persistent queue's file, if any."""
        if self.queue.store is not None:
            self.queue.store.close()

    # ------------------------------------------------------------------ main loop
    # pAcommsHandler's order each tick: restart due drivers, run the drivers, the MAC (not while
    # the primary driver waits to restart), then the queue's expiry.
    def do_work(self) -> None:
        now = self.clock.now()
        for slot in list(self.slots):
            if not slot.running and slot.restart_at is not None and now >= slot.restart_at:
                self._start_driver(slot)
        for slot in list(self.slots):
            if slot.running and slot in self.slots:
                try:
                    slot.driver.do_work()
                except Exception as exc:  # any driver failure, including bugs: never fatal
                    self._driver_failed(
                        slot, _status_of(exc, Status.CONNECTION_TO_MODEM_FAILED), exc
                    )
        if self.primary is None or self.primary.running:
            self.mac.do_work()
        self.queue.do_work()

    # ------------------------------------------------------------------ external requests
    def push(self, message: Message) -> bool:
        """Queue an outgoing message; one the queue or DCCL refuses is logged and dropped
        (False): a bad message must not stop the caller."""
        try:
            self.queue.push_message(message)
        except (QueueError, DcclError, ValueError) as err:
            log.warning("%s not queued: %s", message.DESCRIPTOR.full_name, err)
            return False
        return True

    def encode(self, message: Message) -> bytes | None:
        """`message`'s DCCL bytes (to forward them); None, with a warning, if it cannot go."""
        try:
            return self.codec.encode(message)
        except DcclError as err:
            log.warning("cannot encode %s: %s", message.DESCRIPTOR.full_name, err)
            return None

    def initiate_transmission(self, transmission: acomms_pb.ModemTransmission) -> None:
        """A transmission requested from outside the MAC (e.g. an ad-hoc ping)."""
        if self.primary is None:
            log.warning("no primary driver: transmission request ignored")
            return
        self._initiate_on_primary(transmission)

    def inject_receive(self, transmission: acomms_pb.ModemTransmission) -> None:
        """Treat `transmission` as received by a driver (queue only)."""
        self.queue.handle_modem_receive(transmission)

    def apply_mac_update(self, update: acomms_pb.MACUpdate) -> None:
        """MACUpdate addressed to this node; silences/restores Micro-Modems."""
        state = self.mac.apply_update(update)
        if state is None:
            return
        for slot in self.slots:
            set_silent = getattr(slot.driver, "set_silent", None)
            if set_silent is not None and slot.running:
                set_silent(not state)

    def update_driver_cfg(self, cfg: acomms_pb.DriverConfig) -> None:
        """DriverConfig update for every running driver with the same modem_id."""
        for slot in self.slots:
            if slot.running and slot.cfg.modem_id == cfg.modem_id:
                slot.driver.update_cfg(cfg)

    def reset_primary(self) -> None:
        """Manual reset (ACOMMS_DRIVER_RESET): shut down, then the failure approach."""
        if self.primary is None:
            log.warning("driver reset requested but there is no primary driver")
            return
        self._driver_failed(self.primary, Status.MANUAL_RESET, "manual reset")

    @property
    def route_cfg(self):
        return self.router.cfg

    def replace_route(self, route: StaticRoute) -> None:
        self.router.set_route(route)
        log.info("route replaced: %s", list(route.hop))

    def apply_route_command(self, message: Message) -> None:
        """A RouteCommand received over the link replaces the route when routing is configured
        (pAcommsHandler's rule); any other message is left alone."""
        if message.DESCRIPTOR.full_name == ROUTE_COMMAND and self.route_cfg.route.hop:
            self.replace_route(message.new_route)  # type: ignore[attr-defined]  # (a RouteCommand)

    # ------------------------------------------------------------------ internals
    def _initiate_on_primary(self, transmission: acomms_pb.ModemTransmission) -> None:
        if self.primary is None or not self.primary.running:
            return
        try:
            self.primary.driver.handle_initiate_transmission(transmission)
        except Exception:  # e.g. a slot with a rate the modem lacks: this slot only
            log.exception(
                "%s cannot start the transmission %s",
                _name(self.primary),
                text_format.MessageToString(transmission, as_one_line=True),
            )

    def _forward_informational(self, slot: DriverSlot) -> None:
        driver = slot.driver

        def forward(signal: Signal) -> Callable[[object], None]:
            def emit(msg) -> None:
                if self.primary is slot:
                    signal.emit(msg)

            return emit

        driver.signal_raw_incoming.connect(forward(self.signal_raw_incoming))
        driver.signal_raw_outgoing.connect(forward(self.signal_raw_outgoing))
        driver.signal_receive.connect(forward(self.signal_modem_receive))
        driver.signal_transmit_result.connect(forward(self.signal_modem_transmit))

    def _start_driver(self, slot: DriverSlot) -> None:
        log.info("starting driver %s", _name(slot))
        try:
            slot.driver.startup(slot.cfg)
        except Exception as exc:
            self._driver_failed(slot, _status_of(exc, Status.STARTUP_FAILED), exc, started=False)
            return
        slot.restart_at = None
        if slot.problem:
            log.warning("driver %s running again (after %d failures)", _name(slot), slot.failures)
            slot.problem = ""
        self.signal_driver_status.emit(slot, "running")

    def _shutdown_driver(self, slot: DriverSlot) -> None:
        try:
            slot.driver.shutdown()
        except Exception:
            log.exception("driver %s failed to shut down cleanly", _name(slot))

    def _driver_failed(
        self,
        slot: DriverSlot,
        status: acomms_pb.ModemDriverStatus.Status.ValueType,
        why,
        started: bool = True,
    ) -> None:
        slot.failures += 1
        slot.problem = f"{Status.Status.Name(status)}: {why}"
        if started or slot.running:
            self._shutdown_driver(slot)
        now = self.clock.now()
        technique = self.failure.technique
        if technique == CONTINUALLY_RESTART_DRIVER or slot is not self.primary:
            # restarted every driver_backoff_sec (60 s by default, as goby3): one warning each
            slot.restart_at = now + self.failure.driver_backoff_sec
            log.warning(
                "driver %s failed (%s); trying again in %d s",
                _name(slot),
                slot.problem,
                self.failure.driver_backoff_sec,
            )
            self.signal_driver_status.emit(slot, slot.describe(now))
            return
        log.warning("driver %s failed (%s)", _name(slot), slot.problem)
        if len(self.slots) < 2:
            raise HandlerError(
                f"primary driver {_name(slot)} failed and there is no listen driver to replace it"
            )
        index = self.slots.index(slot)
        new = self.slots[(index + 1) % len(self.slots)]
        new.cfg.modem_id, slot.cfg.modem_id = slot.cfg.modem_id, new.cfg.modem_id
        self._make_primary(new)
        if new.running:
            self._shutdown_driver(new)
        new.restart_at = now + self.failure.new_driver_backoff_sec
        if technique == DISABLE_AND_MOVE_LISTEN_DRIVER_TO_PRIMARY:
            unbind(slot.driver, self.queue)
            self.slots.remove(slot)
            slot.restart_at = None
            log.warning("driver %s disabled", _name(slot))
        else:
            slot.restart_at = now + self.failure.driver_backoff_sec
        log.warning("driver %s is now the primary driver", _name(new))
        self.signal_driver_status.emit(slot, slot.describe(now))

    def _make_primary(self, new: DriverSlot) -> None:
        if self.primary is not None:
            self.primary.driver.signal_receive.disconnect(self.mac.handle_modem_receive)
        self.primary = new
        new.driver.signal_receive.connect(self.mac.handle_modem_receive)


def _status_of(exc: BaseException, default: Status.Status.ValueType) -> Status.Status.ValueType:
    return exc.status if isinstance(exc, ModemDriverError) else default  # type: ignore[return-value]


def _name(slot: DriverSlot) -> str:
    return driver_name(slot.cfg)
