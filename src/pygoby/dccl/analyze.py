"""A readable description of a loaded message type: each field's codec and size, and totals;
and the Python generated for it."""

from __future__ import annotations

from dataclasses import dataclass

from pygoby.dccl.compiled import CompiledType
from pygoby.dccl.plan import ListItem, MessageItem, MessageNode, RepeatedItem, ScalarItem


@dataclass
class FieldRow:
    path: str
    part: str
    codec: str
    min_bits: int
    max_bits: int
    detail: str


def _rows(node: MessageNode, part: str, prefix: str, depth: int) -> list[FieldRow]:
    rows: list[FieldRow] = []
    for oneof in node.oneofs:
        rows.append(
            FieldRow(
                f"{prefix}{oneof.name} (oneof case)",
                part,
                "oneof",
                oneof.bits,
                oneof.bits,
                f"{len(oneof.members)} members",
            )
        )
    for item in node.items:
        path = prefix + item.field.name
        if isinstance(item, ScalarItem):
            codec = item.codec
            rows.append(
                FieldRow(
                    path,
                    part,
                    codec.info.codec_name,
                    item.min_size(),
                    item.max_size(),
                    f"{item.mode.value} {codec.describe()}".strip(),
                )
            )
        elif isinstance(item, MessageItem):
            kind = "presence bit" if item.presence_bit else item.mode.value
            rows.append(
                FieldRow(
                    path,
                    part,
                    f"message v{item.child.codec_version}",
                    item.min_size(),
                    item.max_size(),
                    kind,
                )
            )
            rows += _rows(item.child, part, path + ".", depth + 1)
        elif isinstance(item, RepeatedItem):
            element = item.codec.info.codec_name if item.codec else "message"
            layout = (
                f"{item.max_repeat} slots"
                if item.slots
                else f"{item.prefix_bits}-bit count, {item.min_repeat}..{item.max_repeat}"
            )
            rows.append(
                FieldRow(f"{path}[]", part, element, item.min_size(), item.max_size(), layout)
            )
            if item.child is not None:
                rows += _rows(item.child, part, path + "[].", depth + 1)
        elif isinstance(item, ListItem):
            codec = item.codec
            rows.append(
                FieldRow(
                    f"{path}[]",
                    part,
                    codec.info.codec_name,
                    item.min_size(),
                    item.max_size(),
                    f"whole list, {codec.describe()}",
                )
            )
    return rows


def field_rows(compiled: CompiledType) -> list[FieldRow]:
    rows = []
    if compiled.id_bits:
        rows.append(
            FieldRow(
                "(id)",
                "head",
                "dccl.default.id",
                compiled.id_bits,
                compiled.id_bits,
                f"id {compiled.id}",
            )
        )
    rows += _rows(compiled.head, "head", "", 0)
    rows += _rows(compiled.body, "body", "", 0)
    return rows


def describe(compiled: CompiledType) -> str:
    head_bits = compiled.id_bits + compiled.head.max_size()
    body_min, body_max = compiled.body.min_size(), compiled.body.max_size()
    id_text = "omitted" if compiled.id is None else str(compiled.id)
    lines = [
        f"message {compiled.name}: id {id_text}, codec_version {compiled.version}",
        f"  header: {head_bits} bits -> {compiled.head_bytes} bytes (not encrypted)",
        f"  body:   {body_min}..{body_max} bits -> "
        f"{(body_min + 7) // 8}..{(body_max + 7) // 8} bytes",
        f"  total:  {compiled.min_size()}..{compiled.max_size()} bytes"
        f" (max_bytes {compiled.max_bytes})",
        "",
    ]
    rows = field_rows(compiled)
    widths = [max(len(r.path) for r in rows), max(len(r.codec) for r in rows)] if rows else [5, 5]
    header = f"  {'field':<{widths[0]}}  part  {'codec':<{widths[1]}}  {'bits':>9}  details"
    lines.append(header)
    for r in rows:
        bits = str(r.max_bits) if r.min_bits == r.max_bits else f"{r.min_bits}..{r.max_bits}"
        lines.append(
            f"  {r.path:<{widths[0]}}  {r.part:<4}  {r.codec:<{widths[1]}}  {bits:>9}  {r.detail}"
        )
    return "\n".join(lines)


def generated_source(compiled: CompiledType) -> str:
    """The generated Python of the type's encode/decode functions (head and body parts)."""
    return "\n".join(
        compiled.source[name]
        for name in ("encode_head", "encode_body", "decode_head", "decode_body")
    )
