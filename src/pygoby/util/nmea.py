"""NMEA-0183 sentences: parse and print with checksums (sans-I/O, generic).

A sentence is `$` (or `!`), a talker+type token (`CCCYC`: talker `CC`, type `CYC`), then
comma-separated fields, then optionally `*HH`, the XOR of every character between the start
character and the `*`, as two hex digits. Printing always adds the checksum (upper-case hex);
parsing accepts a sentence without one, but a checksum that is present must match.
"""

from __future__ import annotations

import functools
from collections.abc import Iterable, Sequence
from dataclasses import dataclass

from pygoby.util.errors import NMEAChecksumError, NMEAFormatError


def checksum(body: str) -> int:
    """XOR of the characters of `body` (the text between `$`/`!` and `*`)."""
    data = body.encode("ascii")
    if len(data) < _FOLD_FROM:
        value = 0
        for byte in data:
            value ^= byte
        return value
    # Long bodies: read the bytes as one integer and fold it in halves (x ^= x >> half) down to
    # one byte, whose value is then the XOR of them all: a few big-integer operations instead
    # of a Python step per character (twice as fast for a 100-character $CACST).
    value = int.from_bytes(data, "little")
    shift = 4 << (len(data) - 1).bit_length()  # half the bits of the next power-of-two size
    while shift >= 8:
        value ^= value >> shift
        shift >>= 1
    return value & 0xFF


_FOLD_FROM = 48  # characters; below this the plain loop is faster


@dataclass(frozen=True)
class NMEASentence:
    """One sentence: `fields[0]` is the token with its start character (e.g. `$CCCYC`)."""

    fields: tuple[str, ...]

    @classmethod
    def build(cls, token: str, values: Iterable[object] = ()) -> NMEASentence:
        """From a token (`"$CCCYC"`, or `"CCCYC"`, which gets a `$`) and field values."""
        if not token.startswith(("$", "!")):
            token = "$" + token
        # str and int values are nearly all of them: converted inline, without a call per field
        # (`type(v) is int` is False for bool, which _field_text prints as 1/0)
        fields = [
            v if (kind := type(v)) is str else str(v) if kind is int else _field_text(v)
            for v in values
        ]
        sentence = cls((token, *fields))
        sentence._validate(",".join(sentence.fields))
        return sentence

    @classmethod
    def parse(cls, line: str) -> NMEASentence:
        """Parse one line (surrounding whitespace ignored). Raises an NMEAError subclass."""
        sentence = _printed.pop(line, None)
        if sentence is not None and type(sentence) is cls:
            return sentence  # printed here (see `printed`): nothing to parse
        return _parse_recurring(cls, line)

    @classmethod
    def of_parts(
        cls, head: tuple[str, ...], tail: tuple[str, ...], tail_text: str, tail_checksum: int
    ) -> NMEASentence:
        """The sentence with fields `head + tail`, for a caller that keeps the text of a
        recurring `tail` (`",".join(tail)`) and its checksum: only the head's part of the text
        and checksum is made (see `message`)."""
        sentence = cls((*head, *tail))
        head_text = ",".join(head) + ","
        sentence.__dict__["_message"] = with_checksum_of_parts(head_text, tail_text, tail_checksum)
        return sentence

    @classmethod
    def _parse(cls, line: str) -> NMEASentence:
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
        """`text` is the fields joined with commas: searching it once is much faster than
        searching every field (commas are not reserved, so the result is the same)."""
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

    def as_int(self, index: int) -> int:
        """Field `index` as an integer; NMEAFormatError if missing or not a number."""
        try:
            return parse_int(self.fields[index])
        except (IndexError, ValueError):
            raise NMEAFormatError(
                f"field {index} of {self.message()!r} is not an integer"
            ) from None

    def as_ints(self, start: int, stop: int) -> list[int]:
        """Fields `start` to `stop - 1` as integers, with the error `as_int` gives for the
        first one that is missing or not a number (one C-level pass when all are known)."""
        texts = self.fields[start:stop]
        if len(texts) == stop - start:
            try:
                return parse_ints(texts)
            except ValueError:
                pass
        return [self.as_int(i) for i in range(start, stop)]

    def as_float(self, index: int) -> float:
        try:
            return float(self.fields[index])
        except (IndexError, ValueError):
            raise NMEAFormatError(f"field {index} of {self.message()!r} is not a number") from None

    def message_no_cs(self) -> str:
        return ",".join(self.fields)

    def message(self) -> str:
        """The sentence with its checksum, without a line terminator."""
        # made once per sentence (immutable; recurring ones are shared): kept beside the fields
        # (in __dict__, so equality, hashing and repr do not see it)
        text = self.__dict__.get("_message")
        if text is None:
            text = self.__dict__["_message"] = with_checksum(",".join(self.fields))
        return text


# Sentences are immutable and many lines recur verbatim (`$CARXP,0`, `$CACYC,...` for each
# source, keep-alive `$CCCFQ,SRC` and its `$CACFG` reply): each is parsed once, then shared.
# Errors are not cached (a bad line raises every time).
@functools.lru_cache(maxsize=1024)
def _parse_recurring(cls: type[NMEASentence], line: str) -> NMEASentence:
    return cls._parse(line)


def printed(sentence: NMEASentence) -> str:
    """`sentence.message()`, for a caller that prints it. Parsing that very text later (the
    other end of an in-process link) gives back `sentence` itself, without any work, when
    parsing would give the same fields: only such texts are remembered (a bounded number)."""
    text = sentence.message()
    fields = sentence.fields
    body = text[:-3]  # (without the *HH message() adds)
    token = fields[0]
    if (
        len(token) == 6
        and token[0] in "$!"
        and text.isascii()
        and body.count(",") == len(fields) - 1
        and "*" not in body
        and "\r" not in body
        and "\n" not in body
    ):
        if len(_printed) >= _PRINTED_LIMIT:
            _printed.clear()
        _printed[text] = sentence
    return text


# Texts printed by this process, with their sentences, until parsed once (see `printed`).
_printed: dict[str, NMEASentence] = {}
_PRINTED_LIMIT = 4096


def with_checksum(text: str) -> str:
    """Sentence text (`$CCCYC,...`) -> the same with its `*HH` checksum (no line terminator)."""
    return f"{text}*{checksum(text[1:]):02X}"


def with_checksum_of_parts(head: str, tail: str, tail_checksum: int) -> str:
    """`with_checksum(head + tail)` for a caller that knows `checksum(tail)` (the checksum is an
    XOR: the parts' checksums combine), e.g. because `tail` recurs."""
    return f"{head}{tail}*{checksum(head[1:]) ^ tail_checksum:02X}"


def parse_int(text: str) -> int:
    """`int(text)`, remembering the texts it has seen: int() of a str is slow (it normalises
    Unicode digits and spaces first) and sentences repeat the same few numbers."""
    value = _INT_TEXTS.get(text)
    if value is None:
        value = int(text)
        if len(_INT_TEXTS) < _INT_TEXTS_LIMIT:
            _INT_TEXTS[text] = value
    return value


def parse_ints(texts: Sequence[str]) -> list[int]:
    """`[int(t) for t in texts]`, through the memory of parse_int."""
    try:
        return list(map(_INT_TEXTS.__getitem__, texts))  # one C-level pass if all are known
    except KeyError:
        return list(map(parse_int, texts))


_INT_TEXTS: dict[str, int] = {}
_INT_TEXTS_LIMIT = 65536  # texts remembered at most


def _field_text(value: object) -> str:
    if isinstance(value, bool):
        return "1" if value else "0"
    if isinstance(value, bytes):
        return value.hex()
    return str(value)
