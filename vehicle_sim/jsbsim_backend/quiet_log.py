"""Keeping JSBSim's console chatter out of the user's terminal.

JSBSim 1.3 routes every message (start-up banner, config echo, warnings) through a thread-local
``FGLogger``. ``CollectingLogger`` records them instead of printing; ``logger_installed`` puts it
in place for the duration of a call into JSBSim and then restores whatever was there, so other
JSBSim users in the same thread are unaffected.
"""

from __future__ import annotations

import collections
import contextlib
from collections.abc import Iterator

import jsbsim


class CollectingLogger(jsbsim.FGLogger):
    """An ``FGLogger`` that keeps the last ``max_records`` messages in memory, printing none."""

    def __init__(self, max_records: int = 200) -> None:
        super().__init__()
        self._parts: list[str] = []
        self.records: collections.deque[str] = collections.deque(maxlen=max_records)

    def set_level(self, level: jsbsim.LogLevel) -> None:
        self._parts = []

    def file_location(self, filename: str, line: int) -> None:
        self._parts.append(f"{filename}:{line}: ")

    def message(self, message: str) -> None:
        self._parts.append(message)

    def format(self, format: jsbsim.LogFormat) -> None:
        """Formatting hints (colours) are meaningless for stored text."""

    def flush(self) -> None:
        text = "".join(self._parts).strip()
        if text:
            self.records.append(text)
        self._parts = []


@contextlib.contextmanager
def logger_installed(logger: jsbsim.FGLogger | None) -> Iterator[None]:
    """Route JSBSim's messages in this thread to ``logger`` inside the block (None: unchanged).
    Inside a block that routes them there already it changes nothing (and costs nothing: setting
    a logger takes microseconds, a JSBSim step tens of them)."""
    if logger is None or jsbsim.get_logger() is logger:
        yield
        return
    previous = jsbsim.get_logger()
    jsbsim.set_logger(logger)
    try:
        yield
    finally:
        jsbsim.set_logger(previous)
