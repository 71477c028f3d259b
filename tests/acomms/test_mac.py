"""MACManager with a VirtualClock: UTC slot alignment, schemes, MACUpdate, Goby 1.1 auto-discovery."""

import pytest

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.mac import (
    MAC_AUTO_DECENTRALIZED,
    MAC_FIXED_DECENTRALIZED,
    MAC_NONE,
    MAC_POLLED,
    MACManager,
)
from pygoby.util.clock import VirtualClock

DAY = 1_700_006_400.0  # 2023-11-15T00:00:00Z (UTC midnight)
U = acomms_pb.MACUpdate


def slot(src, dest=-1, seconds=10, **kw):
    return acomms_pb.ModemTransmission(src=src, dest=dest, slot_seconds=seconds, **kw)


def make(kind, slots, modem_id=1, now=DAY + 43207, **cfg):
    clock = VirtualClock(now)
    mac = MACManager(clock)
    initiated, started = [], []
    mac.signal_initiate_transmission.connect(initiated.append)
    mac.signal_slot_start.connect(started.append)
    mac.startup(acomms_pb.MACConfig(modem_id=modem_id, type=kind, slot=slots, **cfg))
    return clock, mac, initiated, started


def run(clock, mac, until, step=0.1):
    while clock.now() < until:
        clock.advance(step)
        mac.do_work()


def test_joins_mid_cycle_at_next_boundary_as_in_spec_example():
    # spec §6.3: two 10 s slots, 12:00:07 UTC -> first slot run is index 1 at 12:00:10
    clock, mac, initiated, started = make(MAC_FIXED_DECENTRALIZED, [slot(1), slot(2)])
    assert (mac.current, mac.next_slot_time) == (1, DAY + 43210)
    run(clock, mac, DAY + 43210.05)
    assert [(s.slot_index, s.time) for s in started] == [(1, int((DAY + 43210) * 1e6))]
    assert initiated == []  # slot 1 belongs to node 2
    run(clock, mac, DAY + 43220.05)
    assert [s.src for s in initiated] == [1] and initiated[0].time == int((DAY + 43220) * 1e6)


def test_without_start_in_middle_waits_for_cycle_start():
    _clock, mac, _, _ = make(
        MAC_FIXED_DECENTRALIZED, [slot(1), slot(2)], start_cycle_in_middle=False
    )
    assert (mac.current, mac.next_slot_time) == (0, DAY + 43220)


def test_fixed_reference():
    _clock, mac, _, _ = make(
        MAC_FIXED_DECENTRALIZED,
        [slot(1, seconds=7)] * 3,
        now=1000.0,
        ref_time_type=acomms_pb.MACConfig.REFERENCE_FIXED,
        fixed_ref_time=990,
    )
    assert (mac.current, mac.next_slot_time) == (2, 1004.0)


def test_fixed_decentralized_initiation_rules_over_cycles():
    slots = [slot(1), slot(2), slot(3, always_initiate=True)]
    clock, mac, initiated, started = make(MAC_FIXED_DECENTRALIZED, slots, now=DAY + 59.5)
    run(clock, mac, DAY + 120.05)
    assert [s.slot_index for s in started] == [0, 1, 2] * 2 + [0]
    assert [s.src for s in initiated] == [1, 3, 1, 3, 1]
    assert all(s.time % 10_000_000 == 0 for s in started)  # on 10 s UTC boundaries


def test_polled_initiates_every_nonzero_source():
    slots = [slot(1, 0), slot(2, 1), slot(0), slot(3, 1)]
    clock, mac, initiated, _ = make(MAC_POLLED, slots, now=DAY + 39.9)
    run(clock, mac, DAY + 80.05)
    assert [s.src for s in initiated] == [1, 2, 3, 1]


def test_mac_none_never_runs():
    clock, mac, initiated, started = make(MAC_NONE, [slot(1)])
    run(clock, mac, DAY + 43300)
    assert not mac.running and initiated == started == []


def test_skew_skips_slot_and_realigns():
    clock, mac, _initiated, started = make(MAC_FIXED_DECENTRALIZED, [slot(1), slot(2)])
    clock.set(DAY + 43215)  # 5 s late for the 43210 slot
    mac.do_work()
    assert started == [] and (mac.current, mac.next_slot_time) == (0, DAY + 43220)


def test_mac_update_list_operations_and_cycle_state():
    _clock, mac, _, _ = make(MAC_FIXED_DECENTRALIZED, [slot(1), slot(2)])

    def apply(kind, slots=(), **kw):
        return mac.apply_update(U(src=9, dest=1, update_type=kind, slot=list(slots), **kw))

    srcs = lambda: [s.src for s in mac.slots]  # noqa: E731
    apply(U.PUSH_BACK, [slot(3), slot(4)])
    assert srcs() == [1, 2, 3, 4]
    apply(U.PUSH_FRONT, [slot(5), slot(6)])
    assert srcs() == [6, 5, 1, 2, 3, 4]
    apply(U.INSERT, [slot(7)], first_iterator=2)
    assert srcs() == [6, 5, 7, 1, 2, 3, 4]
    apply(U.ERASE, first_iterator=1, second_iterator=3)
    assert srcs() == [6, 1, 2, 3, 4]
    apply(U.ERASE, first_iterator=0)
    apply(U.POP_BACK)
    apply(U.POP_FRONT)
    assert srcs() == [2, 3] and [s.slot_index for s in mac.slots] == [0, 1]
    assert mac.apply_update(U(src=9, dest=2, update_type=U.CLEAR)) is None  # not for us
    assert srcs() == [2, 3]
    apply(U.ASSIGN, [slot(1, seconds=30)])
    assert mac.next_slot_time == DAY + 43230
    assert apply(U.NO_CHANGE, cycle_state=U.STOPPED) is False and not mac.running
    assert apply(U.NO_CHANGE, cycle_state=U.STARTED) is True and mac.running
    apply(U.CLEAR)
    assert not mac.running


# ---------------------------------------------------------------- Goby 1.1 auto-discovery


class Water:
    """Vehicles on a shared VirtualClock; a slot's lone sender is heard by everyone else at
    the end of the slot (two senders collide; nobody hears anything)."""

    def __init__(self, ids, t0, slot_seconds=15, expire_cycles=30):
        self.clock = VirtualClock(t0 - 1)
        self.t0, self.slot_seconds = t0, slot_seconds
        self.macs = {}
        self.sent: dict[int, list] = {}
        for i in ids:
            mac = MACManager(self.clock)
            mac.startup(
                acomms_pb.MACConfig(
                    modem_id=i,
                    type=MAC_AUTO_DECENTRALIZED,
                    slot_seconds=slot_seconds,
                    expire_cycles=expire_cycles,
                )
            )
            mac.signal_initiate_transmission.connect(self.sent.setdefault(i, []).append)
            self.macs[i] = mac
        self.pending: list[int] = []
        self.timeline: list[tuple[int, tuple[int, ...]]] = []

    def step(self, silent=()):
        t = self.t0 + self.slot_seconds * len(self.timeline)
        self.clock.set(t)
        for src in self.pending:
            for i, mac in self.macs.items():
                if i != src:
                    mac.handle_modem_receive(acomms_pb.ModemTransmission(src=src))
        self.clock.set(t + 0.01)
        before = {i: len(s) for i, s in self.sent.items()}
        for mac in self.macs.values():
            mac.do_work()
        senders = tuple(i for i in self.macs if len(self.sent[i]) > before[i] and i not in silent)
        self.pending = list(senders) if len(senders) == 1 else []
        self.timeline.append((t - self.t0, senders))
        return senders


# doc 003 Table 2.1 (who transmits in each 15 s slot); rows 30, 195 and 210 differ, see below
TABLE_2_1 = {
    0: (1, 2),
    15: (),
    30: (2,),
    45: (),
    60: (2,),
    75: (),
    90: (1,),
    105: (),
    120: (),
    135: (1,),
    150: (2,),
    165: (),
    180: (1,),
    195: (),
    210: (2,),
}


def test_auto_discovery_converges_as_in_table_2_1():
    # Two vehicles start together 270 s after midnight (a 30 s and a 45 s cycle boundary).
    water = Water([1, 2], DAY + 270)
    for _ in range(15):
        water.step()
    timeline = dict(water.timeline)
    assert timeline[0] == (1, 2)  # both know only themselves: collision
    assert timeline[60] == (2,)  # vehicle 1 is in its blank: discovers 2
    assert timeline[90] == (1,)  # vehicle 2 is in its blank: discovers 1 ("success: 2 discovers 1")
    assert sorted(water.macs[1].heard) == sorted(water.macs[2].heard) == [1, 2]
    # from the synchronised cycles onward every transmission succeeds (one sender per slot)
    assert all(len(s) <= 1 for t, s in water.timeline if t >= 90)
    # Same rows as the table except 30 (vehicle 1 sends and collides instead of being in its
    # blank), 195 and 210: the table's blank placements cannot all follow the §6.7 rule
    # (they need S2 - S1 = 2 mod 5 with S = sum of ids), so the discovery of 2 by 1 moves
    # from 30 s to 60 s and the blank of the 180 s cycle stays last.
    differing = [t for t, s in water.timeline if TABLE_2_1[t] != tuple(sorted(s))]
    assert differing == [30, 195, 210]
    # converged cycle: [1, 2, blank] or with the blank moved one place up
    for mac in water.macs.values():
        assert sorted(s.src for s in mac.slots) == [0, 1, 2] and mac.cycle_duration == 45


def test_three_vehicles_discover_each_other_and_stop_colliding():
    water = Water([1, 2, 3], DAY + 600)
    for _ in range(200):
        water.step()
    assert all(sorted(mac.heard) == [1, 2, 3] for mac in water.macs.values())
    late = [s for t, s in water.timeline if t >= 1800]
    assert all(len(s) <= 1 for s in late)
    assert sum(len(s) for s in late) > 0.7 * len(late)  # 3 of every 4 slots carry data


def test_auto_discovery_expires_silent_vehicle():
    water = Water([1, 2], DAY + 270, expire_cycles=2)
    for _ in range(15):
        water.step()
    assert sorted(water.macs[1].heard) == [1, 2]
    for _ in range(12):
        water.step(silent=(2,))  # vehicle 2's transmissions are no longer heard
    assert sorted(water.macs[1].heard) == [1]
    assert [s.src for s in water.macs[1].slots if s.src] == [1]


@pytest.mark.parametrize("kind", [MAC_FIXED_DECENTRALIZED, MAC_POLLED])
def test_empty_cycle_stops(kind):
    _clock, mac, _, _ = make(kind, [])
    assert not mac.running
