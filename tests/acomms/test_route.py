"""Static routing: next hop, link destination rewrite, relay through a middle node."""

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.route import RouteManager, RouteManagerConfig, bind_router
from pygoby.util.clock import VirtualClock

from .queue_helpers import entry, manager


def router(hops, **kw):
    cfg = RouteManagerConfig(**kw)
    cfg.route.hop.extend(hops)
    return RouteManager(cfg)


def test_find_next_hop():
    r = router([1, 2, 3, 4])
    assert [r.find_next_hop(2, d) for d in (4, 1, 2)] == [3, 1, 2]
    assert r.find_next_hop(2, 9) == -1
    assert router([1, 2], default_gateway=7).find_next_hop(5, 9) == 7


def test_relay_through_middle_node():
    clock = VirtualClock(1_700_000_000.0)
    nodes = {i: manager(clock, modem_id=i, entries=[entry("Status")]) for i in (1, 2, 3)}
    for qm, _ in nodes.values():
        bind_router(qm, router([1, 2, 3]))
    Status = nodes[1][1][0]
    got3, got2 = [], []
    nodes[3][0].signal_receive.connect(got3.append)
    nodes[2][0].signal_receive.connect(got2.append)
    nodes[1][0].push_message(Status(src=1, dest=3, value=99))
    clock.advance(1)
    hop1 = acomms_pb.ModemTransmission(src=-1, dest=-1, max_num_frames=1)
    nodes[1][0].handle_modem_data_request(hop1)
    assert hop1.dest == 2  # link destination rewritten to the next hop
    hop1.type = acomms_pb.DATA
    nodes[2][0].handle_modem_receive(hop1)
    assert got2 == [] and nodes[2][0].size(20) == 1  # queued for relay, not delivered
    clock.advance(1)
    hop2 = acomms_pb.ModemTransmission(src=-1, dest=-1, max_num_frames=1)
    nodes[2][0].handle_modem_data_request(hop2)
    assert hop2.dest == 3 and bytes(hop2.frame[0]) == bytes(hop1.frame[0])  # bytes untouched
    hop2.type = acomms_pb.DATA
    nodes[3][0].handle_modem_receive(hop2)
    assert [x.value for x in got3] == [99]
