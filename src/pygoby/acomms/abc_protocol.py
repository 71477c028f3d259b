"""The ABC example modem's text protocol: `KEY,NAME:VALUE,...` lines."""

from __future__ import annotations

from pygoby.acomms.errors import ABCParseError


def parse_abc(line: str) -> tuple[str, dict[str, str]]:
    parts = line.strip().split(",")
    key = parts[0]
    if not key:
        raise ABCParseError(f"empty ABC line {line!r}")
    fields: dict[str, str] = {}
    for part in parts[1:]:
        name, sep, value = part.partition(":")
        if not sep:
            raise ABCParseError(f"ABC element {part!r} has no ':' in {line!r}")
        fields[name] = value
    return key, fields


def format_abc(key: str, **fields: object) -> str:
    return ",".join([key, *(f"{name}:{value}" for name, value in fields.items())]) + "\r\n"
