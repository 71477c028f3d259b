"""`make demo`: pygoby on its embedded defaults, showing what it does.

Encodes a vehicle status report with DCCL (clear and encrypted), decodes it back, and shows the
sizes: the same bytes the C++ DCCL library produces.
"""

from __future__ import annotations

import time
from pathlib import Path

from google.protobuf import text_format

from pygoby.dccl import Codec
from pygoby.dccl.analyze import describe

EXAMPLES = Path(__file__).resolve().parents[2] / "examples"


def dccl_demo() -> None:
    codec = Codec()
    status_cls = codec.load_proto(EXAMPLES / "dccl" / "status.proto", "pygoby.examples.VehicleStatus")
    print(describe(codec.compiled(status_cls)))
    status = status_cls(
        time=float(int(time.time())), src=3, nav_x=1234.4, nav_y=-567.8, nav_depth=42.25,
        nav_heading=271.6, nav_speed=1.46, mode=status_cls.MODE_SURVEY, note="all good",
    )
    plain = codec.encode(status)
    print("\nstatus:    ", text_format.MessageToString(status, as_one_line=True))
    print(f"encoded:    {plain.hex()}  ({len(plain)} bytes;"
          f" protobuf would use {len(status.SerializeToString())})")
    print("decoded:   ", text_format.MessageToString(codec.decode(plain), as_one_line=True))
    secret = Codec(passphrase="demo passphrase")
    encrypted = secret.encode(status)
    print(f"encrypted:  {encrypted.hex()}  (header {encrypted[:2].hex()} stays clear)")
    assert secret.decode(encrypted) == codec.decode(plain)


def main() -> None:
    print("== pygoby demo: DCCL ==\n")
    dccl_demo()
    print("\ndemo finished OK")


if __name__ == "__main__":
    main()
