"""iCommander save files.

    %%% iCommander message save file: Thu Mar  3 22:38:12 2011 %%%
    message::Command
    COMMAND_OUT:=dest=2,command_id=7,heading=90

One `message::<name>` line per open message, then one line of space-separated
`VARIABLE:=name=value,...` items, one per source variable (sorted), fields in message order.
Values are kept as typed, placeholders included.
"""

from __future__ import annotations

import re
import time
from collections.abc import Iterable, Sequence

from pygoby.topside.errors import SaveFileError

HEADER_PREFIX = "%%% iCommander message save file: "
_ITEM = re.compile(r"(?:^|\s)(\S+?):=")


def dump(
    messages: Iterable[tuple[str, Sequence[tuple[str, str, str]]]], when: float | None = None
) -> str:
    """`messages`: (message name, [(source variable, field name, value text), ...]) in field
    order. Empty values are kept (`name=`), as Goby 1 did, so a field cleared on purpose stays
    cleared."""
    stamp = time.asctime(time.localtime(when))
    lines = [f"{HEADER_PREFIX}{stamp} %%%"]
    for name, values in messages:
        lines.append(f"message::{name}")
        by_var: dict[str, list[str]] = {}
        for var, field, text in values:
            by_var.setdefault(var, []).append(f"{field}={text}")
        lines.append(" ".join(f"{var}:={','.join(items)}" for var, items in sorted(by_var.items())))
    return "\n".join(lines) + "\n"


def parse(
    text: str, fields_of: dict[str, Sequence[str]] | None = None
) -> list[tuple[str, dict[str, str]]]:
    """[(message name, {field: value})] from a save file. `fields_of` (message name -> its
    field names) lets a value hold commas: it then runs up to the next `,<field>=`."""
    lines = text.splitlines()
    if not lines or not lines[0].startswith(HEADER_PREFIX):
        raise SaveFileError(
            "not an iCommander message save file (first line must start with "
            f"{HEADER_PREFIX.strip()!r})"
        )
    out: list[tuple[str, dict[str, str]]] = []
    for line in lines[1:]:
        if line.startswith("message::"):
            out.append((line[len("message::") :].strip(), {}))
        elif out and line.strip():
            name, values = out[-1]
            names = (fields_of or {}).get(name)
            starts = list(_ITEM.finditer(line))
            for i, item in enumerate(starts):
                end = starts[i + 1].start() if i + 1 < len(starts) else len(line)
                values.update(_pairs(line[item.end() : end].strip(), names))
    return out


def _pairs(contents: str, names: Sequence[str] | None) -> dict[str, str]:
    if not contents:
        return {}
    if names:
        keys = "|".join(re.escape(n) for n in sorted(names, key=len, reverse=True))
        bounds = list(re.finditer(rf"(?:^|,)({keys})=", contents))
    else:
        bounds = list(re.finditer(r"(?:^|,)([^,=]+)=", contents))
    pairs = {}
    for i, match in enumerate(bounds):
        end = bounds[i + 1].start() if i + 1 < len(bounds) else len(contents)
        pairs[match[1]] = contents[match.end() : end]
    return pairs
