"""MOOS load generator processes for the MOOSDB benchmark (benchmarks/test_moos_bench.py).

Each publisher or subscriber is its own process speaking raw MOOS V10 over a blocking socket,
so that the generator is never what limits a flood:

* a publisher encodes one packet of `--batch` notifications once and writes it again and again
  (a C++ libMOOS client packs its whole outbox into one packet the same way), as fast as the
  DB takes them (flood) or `--rate` notifications per second, with a `T` packet every second as
  the keep-alive; with `--batch 1` each notification is stamped with the wall clock at sending,
  so that subscribers can measure latency;
* a subscriber counts notifications from packet headers (`n_msgs`, less a leading `T` echo),
  decoding messages only when it measures latency.

Protocol: a process prints `ready` once connected (subscribers: once registered), a publisher
waits for a line on stdin before it starts, and every process prints one JSON line with its
figures before it exits. Times are `time.monotonic()`, which all processes on a host share.

    python benchmarks/moos_load.py sub --port 9000 --name s0 --var X --expect 100000
    python benchmarks/moos_load.py pub --port 9000 --name p0 --var X --count 100000
"""

from __future__ import annotations

import argparse
import json
import socket
import sys
import time

from pygoby.moos import protocol as p

_HEADER_SIZE = p.PACKET_HEADER_SIZE


def _connect(port: int, name: str) -> socket.socket:
    sock = socket.create_connection(("127.0.0.1", port))
    sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
    sock.sendall(p.PROTOCOL_STRING + p.encode_packet([p.handshake_message(name, time.time())]))
    reader = _PacketReader(sock)
    welcome = p.decode_packet(reader.next_packet())[0]
    if welcome.msg_type != p.WELCOME:
        raise SystemExit(f"{name}: refused: {welcome.string}")
    return sock


class _PacketReader:
    """The packets of a blocking socket, one at a time."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        self.framer = p.PacketFramer()
        self.queued: list[bytes] = []

    def next_packet(self) -> bytes:
        while not self.queued:
            data = self.sock.recv(1 << 16)
            if not data:
                raise SystemExit("the MOOSDB closed the connection")
            buf, spans = self.framer.feed(data)
            self.queued = [buf[start:end] for start, end in spans]
        return self.queued.pop(0)


def _timing_packet() -> bytes:
    return p.encode_packet([p.timing_message(time.time())])


def publish(args: argparse.Namespace) -> None:
    sock = _connect(args.port, args.name)
    payload = "x" * args.size
    print("ready", flush=True)
    sys.stdin.readline()
    start = time.monotonic()
    last_timing = -1.0
    sent = 0
    batch = [
        p.notify(args.var, payload, time=time.time(), src=args.name, msg_id=i)
        for i in range(args.batch)
    ]
    packet = p.encode_packet(batch)  # encoded once, sent again and again (flood, paced batches)
    period = 0.0 if args.rate is None else args.batch / args.rate
    next_send = start
    while sent < args.count:
        now = time.monotonic()
        if now < next_send:
            time.sleep(next_send - now)
        next_send += period
        if time.monotonic() - last_timing >= 1.0:
            sock.sendall(_timing_packet())
            last_timing = time.monotonic()
        n = min(args.batch, args.count - sent)
        if args.batch == 1:  # stamped at sending, for latency
            packet = p.encode_packet(
                [p.notify(args.var, payload, time=time.time(), src=args.name, msg_id=sent)]
            )
        elif n < args.batch:
            packet = p.encode_packet(batch[:n])
        sock.sendall(packet)
        sent += n
        _drain(sock)
    end = time.monotonic()
    # everything sent reaches the DB before our FIN; the DB then closes its side
    sock.shutdown(socket.SHUT_WR)
    sock.settimeout(10)
    while sock.recv(1 << 16):
        pass
    sock.close()
    print(json.dumps({"sent": sent, "start": start, "end": end}), flush=True)


def _drain(sock: socket.socket) -> None:
    """Discard what the DB sent us (timing echoes) without blocking."""
    while True:
        try:
            if not sock.recv(1 << 16, socket.MSG_DONTWAIT):
                raise SystemExit("the MOOSDB closed the connection")
        except BlockingIOError:
            return


def subscribe(args: argparse.Namespace) -> None:
    sock = _connect(args.port, args.name)
    register = p.MOOSMessage(p.REGISTER, p.DOUBLE, args.var, time.time(), 0.0, src=args.name)
    # the Q's reply comes after the registration is in place: then we are ready
    request = p.MOOSMessage(
        p.SERVER_REQUEST,
        p.STRING,
        "VAR_SUMMARY",
        time.time(),
        src=args.name,
        id=p.SERVER_REQUEST_ID,
    )
    sock.sendall(p.encode_packet([p.timing_message(time.time()), register, request]))
    reader = _PacketReader(sock)
    while not any(m.id == p.SERVER_REQUEST_ID for m in p.decode_packet(reader.next_packet())):
        pass
    print("ready", flush=True)
    sock.settimeout(0.25)
    received = 0
    first = last = 0.0
    latencies: list[float] = []
    last_timing = time.monotonic()
    deadline = time.monotonic() + args.timeout
    timing_type = ord(p.TIMING)
    while received < args.expect and time.monotonic() < deadline:
        now = time.monotonic()
        if now - last_timing >= 1.0:
            sock.sendall(_timing_packet())
            last_timing = now
        try:
            data = sock.recv(1 << 20)
        except TimeoutError:
            continue
        if not data:
            break
        arrived = time.monotonic()
        buf, spans = reader.framer.feed(data)
        for start, end in spans:
            n = int.from_bytes(buf[start + 4 : start + 8], "little")
            if n and buf[start + _HEADER_SIZE + 8] == timing_type:
                n -= 1
            if not n:
                continue
            if not received:
                first = arrived
            received += n
            last = arrived
            if args.latency:
                wall = time.time()
                latencies.extend(
                    wall - m.time
                    for m in p.decode_packet(buf, start, end)
                    if m.msg_type == p.NOTIFY
                )
    sock.close()
    print(
        json.dumps({"received": received, "first": first, "last": last, "latencies": latencies}),
        flush=True,
    )


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = parser.add_subparsers(dest="role", required=True)
    pub = sub.add_parser("pub")
    pub.add_argument("--count", type=int, required=True)
    pub.add_argument("--batch", type=int, default=50, help="notifications per packet")
    pub.add_argument("--rate", type=float, help="notifications per second (default: flood)")
    pub.add_argument("--size", type=int, default=64, help="string value length, bytes")
    sbs = sub.add_parser("sub")
    sbs.add_argument("--expect", type=int, required=True)
    sbs.add_argument("--latency", action="store_true", help="decode messages for latency")
    sbs.add_argument("--timeout", type=float, default=60.0)
    for role in (pub, sbs):
        role.add_argument("--port", type=int, required=True)
        role.add_argument("--name", required=True)
        role.add_argument("--var", required=True)
    args = parser.parse_args()
    (publish if args.role == "pub" else subscribe)(args)


if __name__ == "__main__":
    main()
