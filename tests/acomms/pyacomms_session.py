"""WHOI's pyacomms (PyPI `acomms`) driving two emulated Micro-Modems on serial ptys.

Run as a script in its own process (so `acomms` is the PyPI package, not this test folder):
    python pyacomms_session.py PTY_A PTY_B LOG_DIR
Each step prints one JSON line {"step": ..., ...} with what pyacomms returned; the test
(test_pyacomms_crosscheck.py) asserts on them.
"""

import datetime as dt
import json
import sys
import threading
import time
from queue import Empty, Queue

from acomms import micromodem


def report(step: str, **values) -> None:
    print(json.dumps({"step": step, **values}, default=str), flush=True)


def receive_packet(modem, fsk: bool, results: list) -> threading.Thread:
    """pyacomms' own receive loop ($CARXP, then the statistics, then the frames), in a thread."""

    def run() -> None:
        data = modem.wait_for_data_packet(fsk=fsk, timeout=20)
        results.append(None if data is None else bytes(data).hex())

    thread = threading.Thread(target=run, daemon=True)
    thread.start()
    return thread


def main() -> None:
    pty_a, pty_b, log_dir = sys.argv[1:4]
    a = micromodem.Micromodem(name="alpha", log_path=log_dir)
    b = micromodem.Micromodem(name="bravo", log_path=log_dir)
    a.connect_serial(pty_a, 19200)
    b.connect_serial(pty_b, 19200)
    time.sleep(0.3)
    report("connected", ids=[a.id, b.id])

    # configuration: write, read back, a parameter the modem does not have, a group, API level
    report(
        "config",
        set=sorted(a.set_config("AGN", 200) or []),
        get=a.get_config("AGN"),
        unknown=a.set_config("FOO", 1),
        info=a.get_config("info", response_timeout=1),
        api_level=a.query_nmea_api_level(),
    )

    # time: set (pyacomms prints "...ZZ"), then query
    target = dt.datetime(2030, 1, 2, 3, 4, 5)
    answer = a.set_time(target)
    report(
        "set_time",
        time=answer.time if answer else None,
        timed_out=answer.timed_out if answer else None,
    )
    time.sleep(1.2)
    info = a.get_time_info(timeout=2)
    report("get_time", time=info[0] if info else None, sources=list(info[1:]) if info else None)

    # two-way ping
    a.send_ping(b.id)
    report("ping", owtt=a.wait_for_ping_reply(b.id, timeout=15))

    # data packets at rates 0, 1 and 5, each whole (every frame the rate carries)
    for rate, size in ((0, 32), (1, 192), (5, 2048)):
        sent = bytes((rate * 7 + i) % 256 for i in range(size))
        got: list = []
        thread = receive_packet(b, fsk=rate == 0, results=got)
        time.sleep(0.3)
        a.send_packet_data(b.id, bytearray(sent), rate, False)
        thread.join(30)
        report("packet", rate=rate, sent=sent.hex(), received=got[0] if got else None)

    # mini-packet (13 bits)
    a.send_minipacket(b.id, "0abc")
    report("mini", received=b.wait_for_minipacket(timeout=15))

    # flexible data packet (Micro-Modem 2), received whole with its statistics
    fdp = Queue()
    b.incoming_fdp_queues.append(fdp)
    payload = bytes(range(40))
    a.send_tdp(dest_id=b.id, databytes=bytearray(payload), rate_num=1)
    try:
        packet = fdp.get(timeout=15)
        report(
            "fdp",
            received=bytes(packet.databytes).hex(),
            good=packet.packet_is_good,
            stats=packet.cyclestats is not None,
            sent=payload.hex(),
        )
    except Empty:
        report("fdp", received=None, sent=payload.hex())
    a.disconnect()
    b.disconnect()


if __name__ == "__main__":
    main()
