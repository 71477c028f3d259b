"""`pygoby dccl encode|decode|analyze --goby11 --xml F...`: DCCL1 (Goby 1.1's bytes) from the
command line.

encode reads one JSON object per line, {"message", "values", "src", "dest", "time"} (or a JSON
list of them: one multi-message frame) and prints the hex; decode reads hex frames and prints a
JSON list of the messages in each; a bad line prints `error: reason`.
"""

from __future__ import annotations

import json
from collections.abc import Iterable

from pygoby.dccl.dccl1.codec import HEADER_LAYOUT, Dccl1Codec, Dccl1Header, Dccl1Message
from pygoby.dccl.dccl1.frames import is_dccl1_frame, stitch, unstitch
from pygoby.dccl.errors import DcclDecodeError, DcclEncodeError


def _request(codec: Dccl1Codec, item: object) -> tuple[bytes, int]:
    if not isinstance(item, dict):
        raise DcclEncodeError("each message must be a JSON object")
    unknown = set(item) - {"message", "values", "src", "dest", "time"}
    if unknown:
        raise DcclEncodeError(f"unknown key(s) {sorted(unknown)}")
    name = item.get("message")
    if not isinstance(name, str | int) or isinstance(name, bool):
        raise DcclEncodeError('"message" must be a message name (or DCCL id)')
    values = item.get("values", {})
    if not isinstance(values, dict):
        raise DcclEncodeError('"values" must be a JSON object')
    for key, value in values.items():
        elements = value if isinstance(value, list) else [value]
        if any(isinstance(e, dict | list) for e in elements):
            raise DcclEncodeError(f"{key}: values are strings, numbers, booleans or lists")
    header = {k: item.get(k) for k in ("src", "dest", "time")}
    for key, value in header.items():
        if value is not None and (isinstance(value, bool) or not isinstance(value, int | float)):
            raise DcclEncodeError(f'"{key}" must be a number')
    data = codec.encode(name, values, **header)
    return data, Dccl1Header.unpack(data).dest


def encode_line(codec: Dccl1Codec, line: str) -> str:
    try:
        request = json.loads(line)
    except json.JSONDecodeError as err:
        raise DcclEncodeError(f"not JSON: {err}") from None
    if isinstance(request, list):
        return stitch([_request(codec, item) for item in request]).hex()
    return _request(codec, request)[0].hex()


def decode_line(codec: Dccl1Codec, line: str) -> str:
    try:
        frame = bytes.fromhex(line)
    except ValueError:
        raise DcclDecodeError(f"not a hex string: {line!r}") from None
    if frame and not is_dccl1_frame(frame):
        raise DcclDecodeError(
            f"not a DCCL1 frame: first byte 0x{frame[0]:02x} is a CCL message type"
        )
    out = []
    for part in unstitch(frame):
        decoded = codec.decode(part.data)
        out.append(
            {
                "message": decoded.message,
                "src": decoded.header.src,
                "dest": decoded.header.dest,
                "time_of_day": decoded.header.time_of_day,
                "values": decoded.values,
            }
        )
    return json.dumps(out)


def describe(message: Dccl1Message) -> str:
    """The DCCL1 bit layout of a message: header parts, then each layout variable."""
    xml = message.xml
    lines = [
        f"{message.name} (DCCL1 id {message.id}): requested {xml.size} bytes, uses "
        f"{6 + message.body_bytes} bytes ({48 + message.body_bits} bits: 48 header + "
        f"{message.body_bits} body)"
    ]
    if xml.repeat:
        lines.append(f"  <repeat/>: {message.repeat} copies")
    lines.append(f"  {'field':<24} {'type':<8} {'bits':>6}  detail")
    for (default, width), name in zip(HEADER_LAYOUT, message.header_names, strict=True):
        renamed = f" (header {default})" if name != default else ""
        lines.append(f"  {name:<24} {'header':<8} {width:>6}  {renamed.strip()}")
    for f in message.fields:
        var = f.var
        detail = ""
        if f.is_number:
            low, high = f.bounds
            detail = f"[{low:g}, {high:g}] precision {f.precision}"
            if f.uses_delta:
                detail += f", max_delta {var.max_delta:g} ({f.delta_bits()} bits per delta)"
        elif f.kind == "enum":
            detail = "values " + ",".join(var.enum_values)
        elif f.kind == "static":
            detail = f"value {var.static_value!r} (not sent)"
        elif f.kind in ("string", "hex"):
            detail = f"{f.key_bits() // 8} bytes"
        if f.array_length > 1:
            detail += f"; array of {f.array_length} (elements 1.. first, element 0 last)"
        lines.append(f"  {f.name:<24} {f.kind:<8} {f.total_bits():>6}  {detail}")
    return "\n".join(lines)


def run(action: str, codec: Dccl1Codec, names: list[str] | None, lines: Iterable[str]) -> int:
    if action == "analyze":
        chosen = [m for m in codec.messages if names is None or m.name in names]
        print("\n\n".join(describe(m) for m in chosen))
        return 0
    convert = encode_line if action == "encode" else decode_line
    status = 0
    for raw in lines:
        line = raw.strip()
        if not line:
            continue
        try:
            print(convert(codec, line), flush=True)
        except (DcclEncodeError, DcclDecodeError) as exc:
            print(f"error: {exc}", flush=True)
            status = 1
    return status
