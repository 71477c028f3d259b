"""NMEA-0183 sentences: parse and print with checksums (sans-I/O, generic, stateless).

A sentence is `$` (or `!`), a talker+type token (`CCCYC`: talker `CC`, type `CYC`), then
comma-separated fields, then optionally `*HH`, the XOR of every character between the start
character and the `*`, as two hex digits. Printing always adds the checksum (upper-case hex);
parsing accepts a sentence without one, but a checksum that is present must match.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

from pygoby.util.errors import NMEAChecksumError, NMEAFormatError


def checksum(body: str) -> int:
    """XOR of the characters of `body` (the text between `$`/`!` and `*`)."""
    value = 0
    for byte in body.encode("ascii"):
        value ^= byte
    return value


def with_checksum(text: str) -> str:
    """Sentence text (`$CCCYC,...`) -> the same with its `*HH` checksum (no line terminator)."""
    return f"{text}*{checksum(text[1:]):02X}"


@dataclass(frozen=True)
class NMEASentence:
    """One sentence: `fields[0]` is the token with its start character (e.g. `$CCCYC`)."""

    fields: tuple[str, ...]

    @classmethod
    def build(cls, token: str, values: Iterable[object] = ()) -> NMEASentence:
        """From a token (`"$CCCYC"`, or `"CCCYC"`, which gets a `$`) and field values
        (booleans print as 1/0, bytes as lower-case hex, anything else as str())."""
        if not token.startswith(("$", "!")):
            token = "$" + token
        # (str and int values are nearly all of them: converted without a call per field;
        # `type(v) is int` is False for bool, which _field_text prints as 1/0)
        fields: list[str] = [
            v if (kind := type(v)) is str else str(v) if kind is int else _field_text(v)  # type: ignore[misc]  # (v is a str when its type is)
            for v in values
        ]
        sentence = cls((token, *fields))
        sentence._validate(",".join(sentence.fields))
        return sentence

    @classmethod
    def parse(cls, line: str) -> NMEASentence:
        """Parse one line (surrounding whitespace ignored). Raises an NMEAError subclass."""
        text = line.strip()
        if not text.startswith(("$", "!")):
            raise NMEAFormatError(f"NMEA sentence must start with '$' or '!': {line!r}")
        if not text.isascii():
            raise NMEAFormatError(f"NMEA sentence must be ASCII: {line!r}")
        star = text.rfind("*")
        if star != -1 and star == len(text) - 3:
            body, given = text[1:star], text[star + 1 :]
            try:
                expected = int(given, 16)
            except ValueError:
                raise NMEAFormatError(f"bad checksum field {given!r} in {line!r}") from None
            actual = checksum(body)
            if actual != expected:
                raise NMEAChecksumError(
                    f"checksum mismatch in {line!r}: given {given}, computed {actual:02X}"
                )
            text = text[:star]
        elif star != -1:
            raise NMEAFormatError(f"'*' is not followed by a two-digit checksum: {line!r}")
        sentence = cls(tuple(text.split(",")))
        sentence._validate(text)
        return sentence

    def _validate(self, text: str) -> None:
        """`text` is the fields joined with commas (one search instead of one per field)."""
        token = self.fields[0]
        if len(token) != 6:
            raise NMEAFormatError(
                f"NMEA token must be 6 characters (start, talker, type): {token!r}"
            )
        if "*" in text or "\r" in text or "\n" in text:
            raise NMEAFormatError(f"NMEA field contains a reserved character: {self.fields!r}")

    @property
    def talker_id(self) -> str:
        return self.fields[0][1:3]

    @property
    def sentence_id(self) -> str:
        """The last three characters of the token (`CYC`), used for dispatch."""
        return self.fields[0][-3:]

    def __len__(self) -> int:
        return len(self.fields)

    def __getitem__(self, index: int) -> str:
        return self.fields[index]

    def as_int(self, index: int, low: int | None = None, high: int | None = None) -> int:
        """Field `index` as an integer, within [low, high] if given; NMEAFormatError if it is
        missing, not a number or out of range."""
        try:
            value = int(self.fields[index])
        except (IndexError, ValueError):
            raise NMEAFormatError(
                f"field {index} of {self.message()!r} is not an integer"
            ) from None
        if (low is not None and value < low) or (high is not None and value > high):
            raise NMEAFormatError(
                f"field {index} of {self.message()!r} is out of range [{low}, {high}]"
            )
        return value

    def as_ints(self, start: int, stop: int) -> list[int]:
        """Fields `start` to `stop - 1` as integers (the error of `as_int` for a bad one)."""
        texts = self.fields[start:stop]
        if len(texts) == stop - start:
            try:
                return list(map(int, texts))
            except ValueError:
                pass
        return [self.as_int(i) for i in range(start, stop)]

    def as_float(self, index: int, low: float | None = None, high: float | None = None) -> float:
        """Field `index` as a number, within [low, high] if given (then never NaN)."""
        try:
            value = float(self.fields[index])
        except (IndexError, ValueError):
            raise NMEAFormatError(f"field {index} of {self.message()!r} is not a number") from None
        if (low is not None and not value >= low) or (high is not None and not value <= high):
            raise NMEAFormatError(
                f"field {index} of {self.message()!r} is out of range [{low}, {high}]"
            )
        return value

    def message_no_cs(self) -> str:
        return ",".join(self.fields)

    def message(self) -> str:
        """The sentence with its checksum, without a line terminator."""
        return with_checksum(",".join(self.fields))


def _field_text(value: object) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, bytes):
        return value.hex()
    return str(value)
