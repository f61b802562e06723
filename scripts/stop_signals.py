"""Ctrl-C and SIGTERM reach a command that drives a vehicle, whatever the process inherited.

A parent that ignores SIGINT (a shell's background job, ``nohup``, a supervisor) or blocks it
leaves it ignored or blocked in its children: the companion or rover-path would drive on through
the operator's stop. Inside :func:`stop_signals_answered` SIGINT raises KeyboardInterrupt and
SIGTERM raises :class:`companion.runner.Terminated` (a KeyboardInterrupt), so one ``except``
sends the vehicle its safe stop; what was there before is put back on leaving.
"""

from __future__ import annotations

import signal
from collections.abc import Iterator
from contextlib import contextmanager
from types import FrameType

from companion.runner import Terminated


def _sigterm_as_interrupt(_signum: int, _frame: FrameType | None) -> None:
    raise Terminated


@contextmanager
def stop_signals_answered() -> Iterator[None]:
    """SIGINT and SIGTERM handled and unblocked while inside; restored on leaving."""
    previous_int = signal.signal(signal.SIGINT, signal.default_int_handler)
    previous_term = signal.signal(signal.SIGTERM, _sigterm_as_interrupt)
    blocked = signal.pthread_sigmask(signal.SIG_UNBLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, previous_int)
        signal.signal(signal.SIGTERM, previous_term)
        signal.pthread_sigmask(signal.SIG_SETMASK, blocked)
