"""The wall clock real links run on (the in-process link brings its own lockstep clock)."""

from __future__ import annotations

import time


class WallClock:
    """Monotonic wall time [s] since construction; ``sleep_until`` sleeps."""

    real_time = True

    def __init__(self) -> None:
        self._origin_s = time.monotonic()

    def now_s(self) -> float:
        return time.monotonic() - self._origin_s

    def sleep_until(self, t_s: float) -> None:
        remaining_s = t_s - self.now_s()
        if remaining_s > 0.0:
            time.sleep(remaining_s)
