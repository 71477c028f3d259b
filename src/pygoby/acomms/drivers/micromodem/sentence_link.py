"""What MMDriver reads and writes: NMEA sentences, whatever carries them.

`SentenceLink` is the one interface the driver uses. A link that carries sentences itself (an
emulated modem in the same process, pygoby.acomms.mmsim.ModemLink) is one; `DirectSentences`
adds the driver's traffic reports to it. A text line (serial, TCP, pty, a test's MemoryLink) is
one through `TextSentences`, which parses the lines the driver reads and prints the sentences it
writes. Traffic goes to the driver's raw log and raw signals: for a text line every line as it
is on the wire; for a direct link (no wire) each sentence's text, only when someone listens.
"""

from __future__ import annotations

import logging
from collections.abc import Iterable, Iterator
from typing import Protocol, runtime_checkable

from pygoby.acomms import messages as acomms_pb
from pygoby.acomms.driver_base import ModemDriverBase
from pygoby.acomms.errors import ModemDriverError
from pygoby.util.errors import LinkClosedError, NMEAError
from pygoby.util.nmea import NMEASentence

log = logging.getLogger("pygoby.acomms.drivers.micromodem.driver")  # reported as the driver


@runtime_checkable
class SentenceLink(Protocol):
    def read_sentences(self) -> Iterable[NMEASentence]: ...

    def write_sentence(self, sentence: NMEASentence) -> None: ...


def sentence_link(driver: ModemDriverBase, buoy: int) -> SentenceLink:
    """The driver's link as sentences: direct when the link carries sentences, else as text
    (`buoy`: a Hydroid gateway buoy id, whose lines are prefixed `#M<buoy>`)."""
    link = driver.link
    if isinstance(link, SentenceLink):
        return DirectSentences(driver, link)
    return TextSentences(driver, buoy)


class DirectSentences:
    def __init__(self, driver: ModemDriverBase, link: SentenceLink) -> None:
        self.driver = driver
        self.link = link

    def _reported(self) -> bool:
        driver = self.driver
        return bool(driver.signal_raw_incoming) or driver._raw_log is not None

    def read_sentences(self) -> Iterable[NMEASentence]:
        sentences = self.link.read_sentences()
        if not sentences or not self._reported():
            return sentences
        return self._reporting(sentences)

    def _reporting(self, sentences: Iterable[NMEASentence]) -> Iterator[NMEASentence]:
        for sentence in sentences:
            self.driver._log_raw("[rx] ", sentence.message())
            self.driver.emit_raw(True, sentence.message())
            yield sentence

    def write_sentence(self, sentence: NMEASentence) -> None:
        try:
            self.link.write_sentence(sentence)
        except LinkClosedError as exc:
            raise ModemDriverError(
                str(exc), acomms_pb.ModemDriverStatus.CONNECTION_TO_MODEM_FAILED
            ) from exc
        driver = self.driver
        if driver.signal_raw_outgoing or driver._raw_log is not None:
            driver._log_raw("[tx] ", sentence.message())
            driver.emit_raw(False, sentence.message())


class TextSentences:
    def __init__(self, driver: ModemDriverBase, buoy: int) -> None:
        self.driver = driver
        self.buoy = buoy

    def read_sentences(self) -> Iterator[NMEASentence]:
        """The valid sentences of the lines read (the raw log has every line); each line is
        reported, and parsed, when the driver takes the sentence before it."""
        return self._parse(self.driver.modem_read())

    def _parse(self, lines: list[str]) -> Iterator[NMEASentence]:
        for line in lines:
            if self.buoy:
                line = line[3:]
            text = line.strip()
            if not text:
                continue
            self.driver.emit_raw(True, text)
            try:
                yield NMEASentence.parse(line)
            except NMEAError as exc:
                log.warning("ignoring invalid line from the modem: %s", exc)

    def write_sentence(self, sentence: NMEASentence) -> None:
        text = sentence.message()
        buoy = self.buoy
        self.driver.modem_write((f"#M{buoy}" if buoy else "") + text + "\r\n")
        self.driver.emit_raw(False, text)
