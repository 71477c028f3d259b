"""A Micro-Modem driver's link straight into an emulated modem in the same process.

`ModemLink` carries sentences, not text: what the driver writes goes to the model's
`handle_sentence`, what the model says (NMEA sentences, and `$CACST` as its values) waits until
the driver reads it. Text is made only where a real line is (serial, pty, TCP). The driver
uses it as a `SentenceLink` (pygoby.acomms.drivers.micromodem.sentence_link) as it is.
"""

from __future__ import annotations

from pygoby.acomms.mmsim.model import MicroModemModel
from pygoby.util.errors import LinkClosedError
from pygoby.util.linebased import LocalLink
from pygoby.util.nmea import NMEASentence


class ModemLink(LocalLink):
    """`waiting` (optional): a set that holds `key` while sentences wait to be read (so that a
    loop over many links need not ask each one)."""

    def __init__(self, model: MicroModemModel, waiting: set | None = None, key=None) -> None:
        super().__init__()
        self.model = model
        self._sentences: list = []
        self._waiting = waiting if waiting is not None else set()
        self._key = key
        model.on_output = self._heard

    def _heard(self, sentence) -> None:
        self._sentences.append(sentence)
        self._waiting.add(self._key)

    @property
    def pending(self) -> bool:
        return bool(self._sentences)

    def write_sentence(self, sentence: NMEASentence) -> None:
        if not self._open:
            raise LinkClosedError("modem link is closed")
        self.model.handle_sentence(sentence)

    def read_sentences(self) -> list:
        sentences, self._sentences = self._sentences, []
        self._waiting.discard(self._key)
        return sentences
