"""The Goby 1.1 XML message set as parsed: messages, their variables, publishes and queuing.

Every item remembers the line of the XML element it came from, so later checks (the DCCL load,
the translator) can still say `file:line`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

# Header pieces: XML tag -> (field number in the converted message, default name).
HEADER_PARTS = {"time": (1, "_time"), "src_id": (2, "_src_id"), "dest_id": (3, "_dest_id")}
FIRST_LAYOUT_FIELD = 4
# Header ids are 5-bit numbers in Goby 1.1 (modem ids 0-31).
HEADER_ID_MAX = 31
# Goby 1.1 DCCL ids are 9-bit numbers.
MAX_DCCL_ID = 511
# A Goby 1.1 <format>/<publish_var> placeholder: %k% or %k$<printf spec> (k counts values from 1).
V1_PLACEHOLDER = re.compile(r"%([0-9]+)")


@dataclass
class Var:
    """A `<layout>` variable (static, int, float, bool, string, enum, hex) or a `<header>` piece
    (time, src_id, dest_id)."""

    kind: str
    name: str
    line: int
    source_var: str = ""  # <src_var>/<moos_var>; defaults to the trigger variable
    source_set: bool = False
    algorithms: list[str] = field(default_factory=list)
    max: float | None = None
    min: float | None = None
    precision: int = 0
    max_length: int | None = None
    num_bytes: int | None = None
    array_length: int = 1
    max_delta: float | None = None  # <max_delta>: DCCL1 sends array elements 1.. as deltas
    static_value: str | None = None
    enum_values: list[str] = field(default_factory=list)
    number: int = 0  # field number in the converted protobuf message

    @property
    def is_header(self) -> bool:
        return self.kind in HEADER_PARTS

    @property
    def named(self) -> bool:
        """A header piece the XML gave a <name> (default-named ones are not published by
        <all/> and take no MOOS variable)."""
        return not self.name.startswith("_")


@dataclass
class PublishVar:
    """One `<message_var>` of a `<publish>` (or one added by `<all/>`)."""

    name: str
    algorithms: list[str]
    line: int


@dataclass
class Publish:
    line: int
    moos_var: str = ""  # <publish_var>/<moos_var>; may contain %k% placeholders
    format: str | None = None  # None: the Goby 1.1 default format
    values: list[PublishVar] = field(default_factory=list)
    all: bool = False


@dataclass
class Queuing:
    """`<queuing>` with Goby 1.1's defaults for what the XML leaves out."""

    ack: bool = True  # Goby 1.1.2's code (its manual says false)
    blackout_time: int = 0
    max_queue: int = 0  # 0: no limit
    newest_first: bool = True
    value_base: float = 1.0
    ttl: int = 1800


@dataclass
class XmlMessage:
    file: Path
    line: int
    name: str = ""
    id: int | None = None
    size: int | None = None
    trigger: str = ""  # "", "publish" or "time"
    trigger_var: str = ""
    mandatory_content: str = ""
    trigger_time: int | None = None
    repeat: bool = False  # <repeat/>: DCCL1 packs as many copies as <size> allows
    incoming_hex_var: str = ""  # <incoming_hex_moos_var>; "" for 1.1's IN_<NAME>_HEX_<size>B
    outgoing_hex_var: str = ""  # <outgoing_hex_moos_var>; "" for OUT_<NAME>_HEX_<size>B
    header: dict[str, Var] = field(default_factory=dict)  # by tag: time, src_id, dest_id
    layout: list[Var] = field(default_factory=list)
    publishes: list[Publish] = field(default_factory=list)
    queuing: Queuing = field(default_factory=Queuing)

    def hex_vars(self) -> tuple[str, str]:
        """(incoming, outgoing) MOOS variables of the encoded message, as Goby 1.1 named them."""
        stem = f"{self.name.upper()}_HEX_{self.size}B"
        return (self.incoming_hex_var or f"IN_{stem}", self.outgoing_hex_var or f"OUT_{stem}")

    def header_vars(self) -> list[Var]:
        return [self.header[tag] for tag in HEADER_PARTS]

    def all_vars(self) -> list[Var]:
        return [*self.header_vars(), *self.layout]

    def var(self, name: str) -> Var | None:
        return next((v for v in self.all_vars() if v.name == name), None)

    def single_field_sources(self) -> dict[str, str]:
        """{source variable: variable name} of the source variables that feed one variable
        (the others feed several, read as key=value pairs)."""
        feeds: dict[str, list[str]] = {}
        for var in self.all_vars():
            if var.source_var:
                feeds.setdefault(var.source_var, []).append(var.name)
        return {source: names[0] for source, names in feeds.items() if len(names) == 1}
