"""MACManager: TDMA slot scheduling aligned to UTC.

Schemes: MAC_NONE, MAC_FIXED_DECENTRALIZED, MAC_POLLED (goby3) and MAC_AUTO_DECENTRALIZED (Goby
1.1 passive auto-discovery). Call `do_work()` regularly (>= 5 Hz) with a Clock; at each slot
start the MAC may emit `signal_initiate_transmission(slot)` and always emits
`signal_slot_start(slot)`. For auto-discovery connect the driver's receptions to
`handle_modem_receive`.

Logging (group `goby::acomms::amac::<modem_id>`, pygoby.util.glog): VERBOSE the MAC starting and
stopping, DEBUG1 the cycle after each change, DEBUG2 every slot's timing.
"""

from __future__ import annotations

import math
import time

from pygoby.acomms import messages as acomms_pb
from pygoby.protobuf import enum_type
from pygoby.util.clock import Clock
from pygoby.util.glog import DEBUG1, DEBUG2, VERBOSE, group_logger
from pygoby.util.signal import Signal

SKEW_TOLERANCE = 2.0  # s late before a slot is skipped and the schedule re-anchored
AUTO_ENTROPY = 5
SECONDS_PER_DAY = 86400

MACType = enum_type(acomms_pb.MACConfig.DESCRIPTOR.fields_by_name["type"]).values_by_name
MAC_NONE = MACType["MAC_NONE"].number
MAC_FIXED_DECENTRALIZED = MACType["MAC_FIXED_DECENTRALIZED"].number
MAC_AUTO_DECENTRALIZED = MACType["MAC_AUTO_DECENTRALIZED"].number
MAC_POLLED = MACType["MAC_POLLED"].number
_MAC_TYPE_NAMES = enum_type(acomms_pb.MACConfig.DESCRIPTOR.fields_by_name["type"]).values_by_number
U = acomms_pb.MACUpdate


class MACManager:
    def __init__(self, clock: Clock) -> None:
        self.clock = clock
        self.cfg = acomms_pb.MACConfig()
        self.signal_initiate_transmission: Signal[acomms_pb.ModemTransmission] = Signal()
        self.signal_slot_start: Signal[acomms_pb.ModemTransmission] = Signal()
        self.slots: list = []  # the cycle: ModemTransmissions, in order
        self.running = False
        self.current = 0  # index of the next slot to run
        self.next_slot_time = 0.0
        # auto-discovery: id -> last heard time (own id never expires)
        self.heard: dict[int, float] = {}
        self._cycle_number = 0
        self.glog = group_logger("goby::acomms::amac::0")

    # ------------------------------------------------------------------ control
    def startup(self, cfg: acomms_pb.MACConfig) -> None:
        self.cfg = acomms_pb.MACConfig()
        self.cfg.CopyFrom(cfg)
        self.glog = group_logger(f"goby::acomms::amac::{cfg.modem_id}")
        self.slots = []
        if cfg.type in (MAC_FIXED_DECENTRALIZED, MAC_POLLED):
            for slot in cfg.slot:
                self.slots.append(_copy(slot))
            self._renumber()
        elif cfg.type == MAC_AUTO_DECENTRALIZED:
            self.heard = {cfg.modem_id: self.clock.now()}
        else:
            return
        self.restart()

    def restart(self) -> None:
        if self.running:
            return
        self.running = True
        self.glog.log(VERBOSE, "MAC %s started", _MAC_TYPE_NAMES[self.cfg.type].name)
        self.update()

    def shutdown(self) -> None:
        if self.running:
            self.glog.log(VERBOSE, "MAC stopped")
        self.running = False
        self.current = 0

    @property
    def cycle_duration(self) -> float:
        return sum(s.slot_seconds for s in self.slots)

    def reference_time(self, now: float) -> float:
        if self.cfg.ref_time_type == acomms_pb.MACConfig.REFERENCE_FIXED:
            return float(self.cfg.fixed_ref_time)
        # UTC midnight: a cycle that does not divide 86400 s changes phase at midnight until the
        # next update(), as in goby3 (QUIRKS.md Q-ACOMMS-12)
        return math.floor(now / SECONDS_PER_DAY) * SECONDS_PER_DAY

    def update(self) -> None:
        """Re-anchor the schedule to the reference after any change to the slot list."""
        if self.cfg.type == MAC_AUTO_DECENTRALIZED:
            self._auto_schedule()
            return
        self._renumber()
        if not self.slots:
            self.glog.info("MAC cycle is empty: MAC stopped")
            self.running = False
            return
        now = self.clock.now()
        length = self.cycle_duration
        if length <= 0:
            self.glog.warning("MAC cycle has zero length: MAC stopped")
            self.running = False
            return
        ref = self.reference_time(now)
        n = math.floor((now - ref) / length) + 1
        t0 = ref + n * length
        self.current, self.next_slot_time = 0, t0
        if self.cfg.start_cycle_in_middle and len(self.slots) > 1:
            t, index = t0 - length, 0
            while t < now:
                t += self.slots[index].slot_seconds
                index = (index + 1) % len(self.slots)
            self.current, self.next_slot_time = index, t
        self._log_cycle()

    def _log_cycle(self) -> None:
        if self.glog.isEnabledFor(DEBUG1):
            order = ", ".join(f"{s.src}->{s.dest} {s.slot_seconds:g} s" for s in self.slots)
            self.glog.log(
                DEBUG1,
                "cycle of %d slots, %g s: [%s]; next slot (%d) at %s",
                len(self.slots),
                self.cycle_duration,
                order,
                self.current,
                _clock_text(self.next_slot_time),
            )

    def _renumber(self) -> None:
        for i, slot in enumerate(self.slots):
            slot.slot_index = i

    # ------------------------------------------------------------------ running
    def do_work(self) -> None:
        if not self.running or not self.slots:
            return
        now = self.clock.now()
        if now <= self.next_slot_time:
            return
        if now - self.next_slot_time > SKEW_TOLERANCE:
            self.glog.warning(
                "clock skew: %.3f s late for a slot; re-aligning", now - self.next_slot_time
            )
            self.update()
            return
        if self.cfg.type == MAC_AUTO_DECENTRALIZED and self.current == 0:
            self._auto_place_blank(self.next_slot_time)
        slot = _copy(self.slots[self.current])
        slot.time = acomms_pb.now_us(self.next_slot_time)
        initiates = self._initiates(slot)
        if self.glog.isEnabledFor(DEBUG2):
            self.glog.log(
                DEBUG2,
                "slot %d (%d->%d, rate %d, %g s) starts at %s (%.3f s late)%s",
                slot.slot_index,
                slot.src,
                slot.dest,
                slot.rate,
                slot.slot_seconds,
                _clock_text(self.next_slot_time),
                now - self.next_slot_time,
                ": ours, initiating" if initiates else "",
            )
        if initiates:
            self.signal_initiate_transmission.emit(slot)
        self.signal_slot_start.emit(slot)
        self.next_slot_time += self.slots[self.current].slot_seconds
        self.current = (self.current + 1) % len(self.slots)
        if self.cfg.type == MAC_AUTO_DECENTRALIZED:
            self._auto_expire()

    def _initiates(self, slot: acomms_pb.ModemTransmission) -> bool:
        kind = self.cfg.type
        if kind == MAC_FIXED_DECENTRALIZED:
            return slot.src == self.cfg.modem_id or slot.always_initiate
        if kind == MAC_POLLED:
            return slot.src != 0
        if kind == MAC_AUTO_DECENTRALIZED:
            return slot.src == self.cfg.modem_id
        return False

    # ------------------------------------------------------------------ MACUpdate
    def apply_update(self, update: acomms_pb.MACUpdate) -> bool | None:
        """Apply a MACUpdate addressed to this node.

        Returns None when `cycle_state` is absent, else True for STARTED / False for STOPPED
        (the caller silences or restores a Micro-Modem with `SRC,0` / `SRC,<id>`).
        """
        if update.dest != self.cfg.modem_id:
            return None
        slots = [_copy(s) for s in update.slot]
        kind = update.update_type
        first = update.first_iterator
        if kind == U.ASSIGN:
            self.slots = slots
        elif kind == U.PUSH_BACK:
            self.slots.extend(slots)
        elif kind == U.PUSH_FRONT:
            for slot in slots:
                self.slots.insert(0, slot)
        elif kind in (U.POP_BACK, U.POP_FRONT):
            if not self.slots:
                self.glog.warning("MACUpdate pop on an empty cycle")
            else:
                self.slots.pop(-1 if kind == U.POP_BACK else 0)
        elif kind == U.INSERT:
            self.slots[first:first] = slots
        elif kind == U.ERASE:
            second = update.second_iterator
            del self.slots[first : (first + 1 if second == -1 else second)]
        elif kind == U.CLEAR:
            self.slots = []
        if self.running:
            self.update()
        if not update.HasField("cycle_state"):
            return None
        if update.cycle_state == U.STARTED:
            self.restart()
            return True
        self.shutdown()
        return False

    # ------------------------------------------------------------------ auto-discovery (Goby 1.1)
    def handle_modem_receive(self, transmission: acomms_pb.ModemTransmission) -> None:
        """Learn sources heard on the link (MAC_AUTO_DECENTRALIZED only)."""
        if self.cfg.type != MAC_AUTO_DECENTRALIZED or transmission.src <= 0:
            return
        known = transmission.src in self.heard
        self.heard[transmission.src] = self.clock.now()
        if not known:
            self.glog.info("MAC discovered node %d", transmission.src)
            self._auto_schedule()

    def _auto_slot(self, src: int):
        return acomms_pb.ModemTransmission(
            src=src,
            dest=-1,
            rate=self.cfg.rate,
            type=acomms_pb.DATA,
            slot_seconds=self.cfg.slot_seconds,
        )

    def _auto_schedule(self) -> None:
        """Rebuild the cycle from the known ids and wait for the next aligned cycle start."""
        ids = sorted(self.heard)
        self.slots = [self._auto_slot(i) for i in ids] + [self._auto_slot(0)]
        self._renumber()
        now = self.clock.now()
        length = self.cycle_duration
        ref = self.reference_time(now)
        k = math.floor((now - ref) / length) + 1
        self.current, self.next_slot_time = 0, ref + k * length
        self._log_cycle()

    def _auto_place_blank(self, cycle_start: float) -> None:
        """Blank position = N-1-[(k mod 5) == (S mod 5)] (k: cycles since midnight, S: the sum of
        the heard ids), from the slot count (Goby 1.x stepped a list iterator past its end:
        QUIRKS.md Q-ACOMMS-3)."""
        ids = sorted(self.heard)
        n = len(ids) + 1
        k = round((cycle_start - self.reference_time(cycle_start)) / self.cycle_duration)
        position = n - 1 - int(k % AUTO_ENTROPY == sum(ids) % AUTO_ENTROPY)
        nodes = [self._auto_slot(i) for i in ids]
        self.slots = [*nodes[:position], self._auto_slot(0), *nodes[position:]]
        self._renumber()

    def _auto_expire(self) -> None:
        limit = self.cycle_duration * self.cfg.expire_cycles
        now = self.clock.now()
        stale = [
            i for i, t in self.heard.items() if i not in (self.cfg.modem_id, 0) and now - t > limit
        ]
        if stale:
            for i in stale:
                del self.heard[i]
                self.glog.info("MAC expired node %d", i)
            self._auto_schedule()


def _clock_text(t: float) -> str:
    """A UTC time of day with milliseconds, as slot times are read against the clock."""
    return time.strftime("%H:%M:%S", time.gmtime(t)) + f".{int(t % 1 * 1000):03d}"


def _copy(slot: acomms_pb.ModemTransmission):
    out = acomms_pb.ModemTransmission()
    out.CopyFrom(slot)
    return out
