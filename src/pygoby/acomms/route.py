"""Static routing between subnets of queue managers (experimental upstream).

`bind_router(queue, router)` makes a QueueManager one of the router's subnets: outgoing items
get the next hop as their link destination, and messages received on the link for us but
addressed further on are pushed (with their original bytes) into the queue manager of the
subnet that holds the next hop.
"""

from __future__ import annotations

import logging

from google.protobuf.message import Message

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.queue import QueueManager
from pygoby.acomms.queue.queue import QueuedItem
from pygoby.protobuf.goby.acomms.protobuf import route_pb2
from pygoby.protobuf.goby.acomms.protobuf.route_pb2 import StaticRoute

log = logging.getLogger(__name__)

RouteManagerConfig = route_pb2.RouteManagerConfig
RouteCommand = route_pb2.RouteCommand

NO_ROUTE = -1


class RouteManager:
    def __init__(self, cfg: route_pb2.RouteManagerConfig | None = None) -> None:
        self.cfg = RouteManagerConfig()
        if cfg is not None:
            self.cfg.CopyFrom(cfg)
        self.subnets: list = []  # QueueManagers

    def set_route(self, route: StaticRoute) -> None:
        """Replace the hop list (RouteCommand.new_route)."""
        self.cfg.route.CopyFrom(route)

    def add_subnet_queue(self, queue: QueueManager) -> None:
        if queue not in self.subnets:
            self.subnets.append(queue)

    def find_next_hop(self, us: int, dest: int) -> int:
        hops = list(self.cfg.route.hop)
        if us in hops and dest in hops:
            i, j = hops.index(us), hops.index(dest)
            return us if i == j else hops[i + 1] if j > i else hops[i - 1]
        if self.cfg.HasField("default_gateway"):
            return self.cfg.default_gateway
        return NO_ROUTE

    def handle_out(self, item: QueuedItem, modem_id: int) -> None:
        """Rewrite a queued item's link destination to the next hop (broadcasts untouched)."""
        if item.dest == acomms_pb.BROADCAST_ID:
            return
        hop = self.find_next_hop(modem_id, item.dest)
        if hop != NO_ROUTE:
            item.dest = hop

    def handle_in(self, msg: Message, encoded: bytes, dest: int, modem_id: int) -> None:
        if dest in (modem_id, acomms_pb.BROADCAST_ID):
            return
        hop = self.find_next_hop(modem_id, dest)
        if hop == NO_ROUTE:
            return
        mask = self.cfg.subnet_mask
        for queue in self.subnets:
            if queue.modem_id & mask == hop & mask:
                queue.push_message(msg, encoded=encoded)
                return
        log.debug("no subnet for next hop %d: message for %d not relayed", hop, dest)


def bind_router(queue: QueueManager, router: RouteManager) -> None:
    router.add_subnet_queue(queue)
    queue.signal_out_route.connect(router.handle_out)
    queue.signal_in_route.connect(router.handle_in)
