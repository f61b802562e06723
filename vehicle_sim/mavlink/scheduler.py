"""Rate scheduler for telemetry streams: which message ids are due at a given time.

Pure: time is passed in. Due times advance by whole periods from a fixed phase, so the long-run
rate equals the nominal rate exactly; after a stall longer than one period the phase restarts
instead of bursting to catch up.
"""

from __future__ import annotations

import math
from collections.abc import Mapping

MIN_INTERVAL_S = 0.004
"""Fastest stream the scheduler accepts (250 Hz)."""


class RateScheduler:
    """Per-link stream intervals (SET_MESSAGE_INTERVAL semantics) and due times.

    Args:
        default_rates_hz: message id -> nominal rate [Hz]; also the set of streamable ids
            that "default interval" (0) restores.
    """

    def __init__(self, default_rates_hz: Mapping[int, float]) -> None:
        self._defaults_s = {mid: 1.0 / hz for mid, hz in default_rates_hz.items() if hz > 0.0}
        self._intervals_s: dict[int, float] = dict(self._defaults_s)
        self._next_s: dict[int, float] = {}

    def interval_s(self, msg_id: int) -> float | None:
        """Current interval [s] of a stream, or None when it is not streamed."""
        return self._intervals_s.get(msg_id)

    def set_interval_us(self, msg_id: int, interval_us: float) -> None:
        """Apply a SET_MESSAGE_INTERVAL: -1 stops the stream, 0 restores its default, >0 sets
        the interval [us] (clamped to MIN_INTERVAL_S). Raises ValueError for other values."""
        if not math.isfinite(interval_us) or (interval_us < 0 and interval_us != -1):
            raise ValueError(f"interval must be -1, 0 or > 0 us, got {interval_us}")
        if interval_us == -1:
            self._intervals_s.pop(msg_id, None)
        elif interval_us == 0:
            if msg_id in self._defaults_s:
                self._intervals_s[msg_id] = self._defaults_s[msg_id]
            else:
                self._intervals_s.pop(msg_id, None)
        else:
            self._intervals_s[msg_id] = max(MIN_INTERVAL_S, interval_us * 1e-6)
        self._next_s.pop(msg_id, None)

    def due(self, now_s: float) -> list[int]:
        """Message ids due at ``now_s`` [s] (each at most once per call), in id order."""
        ready = []
        for msg_id in sorted(self._intervals_s):
            interval = self._intervals_s[msg_id]
            next_s = self._next_s.get(msg_id)
            if next_s is None or now_s >= next_s:
                ready.append(msg_id)
                if next_s is None or now_s - next_s >= interval:
                    self._next_s[msg_id] = now_s + interval
                else:
                    self._next_s[msg_id] = next_s + interval
        return ready

    def restart(self, msg_id: int, now_s: float) -> None:
        """Count a stream as just sent at ``now_s`` (after an out-of-band send)."""
        if msg_id in self._intervals_s:
            self._next_s[msg_id] = now_s + self._intervals_s[msg_id]
