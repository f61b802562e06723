"""The in-process link paced by the wall clock: the simulator follows real time.

The loop's clock reads wall time (from the simulator's time at construction), so a planner
that takes too long makes the loop miss its deadline exactly as over MAVLink; sleeping waits
for the wall clock and then steps the simulator up to that time. This measures the control
loop's real-time behaviour without sockets.
"""

from __future__ import annotations

import math
import time

from companion.inprocess_link import InProcessLink
from vehicle_sim import Simulator


class WallPacedSimClock:
    """Wall time [s] offset to the simulator's start time; sleeping catches the sim up."""

    real_time = True

    def __init__(self, sim: Simulator) -> None:
        self._sim = sim
        self._origin_wall_s = time.monotonic()
        self._origin_sim_s = float(sim.state.t_s)

    def now_s(self) -> float:
        return self._origin_sim_s + time.monotonic() - self._origin_wall_s

    def sleep_until(self, t_s: float) -> None:
        remaining_s = t_s - self.now_s()
        if remaining_s > 0.0:
            time.sleep(remaining_s)
        dt_s = float(self._sim.physics_dt_s)
        steps = math.floor((self.now_s() - float(self._sim.state.t_s)) / dt_s + 1e-6)
        if steps > 0:
            self._sim.step(steps * dt_s)


class WallPacedInProcessLink(InProcessLink):
    """:class:`InProcessLink` whose clock is :class:`WallPacedSimClock` (real time)."""

    def __init__(self, sim: Simulator) -> None:
        super().__init__(sim, {"pacing": "wall clock"})
        self._paced_clock = WallPacedSimClock(sim)

    @property
    def name(self) -> str:
        return "inprocess-paced"

    @property
    def clock(self) -> WallPacedSimClock:
        return self._paced_clock
