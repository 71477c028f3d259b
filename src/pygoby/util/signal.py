"""`Signal`: the one callback type of the library (goby's signals, synchronous).

    received: Signal[ModemTransmission] = Signal()   # typed by what its slots are called with
    received.connect(on_receive)        # any number of slots
    received.emit(msg)                  # (or received(msg)): every slot, in connection order
    received.disconnect(on_receive)
    len(received)                       # slots connected (an empty signal is falsy)

A slot's error propagates to the emitter by default: the emitting core decides what a failure
means. Containing errors is explicit, for a whole signal (`Signal(contain_errors=True,
logger=...)`: a subscriber's bug must not stop the emitter, e.g. the frontseat interface's tick)
or for one connection (`connect(slot, contain_errors=True, logger=...)`: e.g. an application's
own slots on library signals). A contained error is logged with its traceback and the other
slots still run.

A signal is generic over its slots' parameters (a ParamSpec): `Signal[ModemTransmission]` calls
`slot(msg)`, `Signal[[ModemTransmission, Message]]` calls `slot(ack, original)`, `Signal[[]]`
calls `slot()`; mypy checks both what is connected and what is emitted.
"""

from __future__ import annotations

import logging
from collections.abc import Callable
from typing import Generic, ParamSpec

log = logging.getLogger(__name__)

P = ParamSpec("P")


class Signal(Generic[P]):
    __slots__ = ("_contain_errors", "_logger", "_slots")

    def __init__(self, *, contain_errors: bool = False, logger: logging.Logger | None = None):
        # each slot with the logger of its contained errors (None: its errors propagate)
        self._slots: list[tuple[Callable[P, object], logging.Logger | None]] = []
        self._contain_errors = contain_errors
        self._logger = logger if logger is not None else log

    def connect(
        self,
        slot: Callable[P, object],
        *,
        contain_errors: bool | None = None,
        logger: logging.Logger | None = None,
    ) -> None:
        """Add `slot`; `contain_errors` (default: the signal's) logs its errors to `logger`
        (default: the signal's) instead of raising them to the emitter."""
        contain = self._contain_errors if contain_errors is None else contain_errors
        self._slots.append((slot, (logger or self._logger) if contain else None))

    def disconnect(self, slot: Callable[P, object]) -> None:
        """Remove the first connection of `slot` (ValueError if it is not connected)."""
        for index, (connected, _) in enumerate(self._slots):
            if connected == slot:
                del self._slots[index]
                return
        raise ValueError(f"{slot!r} is not connected")

    def emit(self, *args: P.args, **kwargs: P.kwargs) -> None:
        # (a copy: a slot may connect or disconnect slots while the signal is emitted)
        for slot, logger in tuple(self._slots):
            if logger is None:
                slot(*args, **kwargs)
                continue
            try:
                slot(*args, **kwargs)
            except Exception:
                logger.exception("%s raised; the other slots still run", _slot_name(slot))

    __call__ = emit

    def __len__(self) -> int:
        return len(self._slots)


def _slot_name(slot: Callable[..., object]) -> str:
    return getattr(slot, "__qualname__", repr(slot))
