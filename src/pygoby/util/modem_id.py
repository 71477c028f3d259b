"""The modem-id lookup file: `modem_id, name, type[, location]` per line, `//` and `#` comments
(goby's ModemIdConvert; shared by the MOOS translator's algorithms and the uField driver)."""

from __future__ import annotations

import logging
import os
import re
from dataclasses import dataclass

log = logging.getLogger(__name__)

_LEADING_INT = re.compile(r"\s*([+-]?[0-9]+)")


def atoi(text: str) -> int:
    """C atoi: the leading integer, else 0."""
    match = _LEADING_INT.match(text)
    return int(match.group(1)) if match else 0


@dataclass(frozen=True)
class ModemIdEntry:
    modem_id: int
    name: str
    type: str
    location: str


class ModemIdLookup:
    """id <-> vehicle name/type table (goby3 ModemIdConvert)."""

    def __init__(self, entries: list[ModemIdEntry] | None = None) -> None:
        self._by_id: dict[int, ModemIdEntry] = {}
        self._by_name: dict[str, int] = {}
        for entry in entries or []:
            self._by_id[entry.modem_id] = entry
            self._by_name[entry.name.lower()] = entry.modem_id

    @classmethod
    def from_text(cls, text: str) -> ModemIdLookup:
        entries = []
        for number, raw in enumerate(text.splitlines(), start=1):
            # Cut comments, then strip whitespace around every field (goby3 only deletes
            # spaces and keeps tabs; fixed: QUIRKS.md Q-APPS-14).
            line = raw.split("#", 1)[0].split("//", 1)[0].strip()
            if not line:
                continue
            columns = [c.strip() for c in line.split(",")]
            if len(columns) < 3:
                log.warning(
                    "modem id lookup line %d is invalid (need id, name, type): %r", number, raw
                )
                continue
            name = columns[1]
            location = columns[3] if len(columns) > 3 and columns[3] else name
            entries.append(ModemIdEntry(atoi(columns[0]), name, columns[2], location))
        return cls(entries)

    @classmethod
    def from_file(cls, path: str | os.PathLike[str]) -> ModemIdLookup:
        """Read a lookup file; an unreadable file gives an empty table (with a warning)."""
        try:
            with open(path, encoding="utf-8", errors="replace") as handle:
                return cls.from_text(handle.read())
        except OSError as exc:
            log.warning("cannot read modem id lookup file %s: %s", path, exc)
            return cls()

    def name(self, modem_id: int) -> str:
        entry = self._by_id.get(modem_id)
        return entry.name if entry else str(modem_id)

    def type(self, modem_id: int) -> str:
        entry = self._by_id.get(modem_id)
        return entry.type if entry else "unknown_type"

    def location(self, modem_id: int) -> str:
        entry = self._by_id.get(modem_id)
        return entry.location if entry else str(modem_id)

    def modem_id(self, name: str) -> int:
        """Case-insensitive name lookup; an unknown name gives atoi(name) (Goby 1.1 rule: the
        leading integer, else 0; goby3 gives an undefined int(NaN): QUIRKS.md Q-APPS-12)."""
        found = self._by_name.get(name.lower())
        return found if found is not None else atoi(name)

    def entries(self) -> list[ModemIdEntry]:
        """Every entry, by modem id."""
        return [self._by_id[modem_id] for modem_id in sorted(self._by_id)]

    def __len__(self) -> int:
        return len(self._by_id)
