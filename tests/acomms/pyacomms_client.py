"""Run WHOI's pyacomms (PyPI `acomms`) against an emulated modem on a serial pty.

Run as a script in its own process (so `acomms` is the PyPI package, not this test folder):
    python pyacomms_client.py PTY_PATH DEST
Prints one JSON object: the modem id pyacomms learned, and the frames it received.
"""

import json
import sys
import time

from acomms import micromodem


def main() -> None:
    pty_path, dest = sys.argv[1], int(sys.argv[2])
    modem = micromodem.Micromodem(name="crosscheck", log_path="/tmp/pyacomms-logs/")
    modem.connect_serial(pty_path, 19200)
    frames = []
    modem.rxframe_listeners.append(lambda f: frames.append((f.src, f.dest, bytes(f.data).hex())))
    print(json.dumps({"event": "connected", "id": modem.id}), flush=True)
    modem.send_packet_data(dest, bytearray(b"from pyacomms"), 1, False)
    deadline = time.time() + 15
    while not frames and time.time() < deadline:
        time.sleep(0.05)
    print(json.dumps({"event": "frames", "frames": frames}), flush=True)


if __name__ == "__main__":
    main()
