"""What a replay cannot know at its windows' anchors, removed from their error by least squares.

A window flies free from a measured state. Two things there are not the config's to answer for:

- the velocity-loop integral the follower carried to the anchor. It is fitted at the airborne
  run's start (:mod:`.warm_up`) and then integrated row by row like the vehicle's own, so an
  error in that start stays, the same, for the whole run: on a clean NMPC flight's log thinned
  to 25-50 Hz the setpoint step that opened OFFBOARD fell between two kept rows, and the start
  came out 0.04-0.09 m/s^2 off. One offset (3,) per run, shared by all its windows.
- the measured velocity's own error at each anchor row (sensor noise: a stiffer velocity loop
  forgets it sooner, so left in, it favours stiffer gains). One (3,) per window.

Both leave a known trace: the config's own response to an integral offset and to a start
velocity error, flown once per config from hover (:func:`responses`). The run's windows are
taken after the least-squares combination of them. A per-window integral would also take up
a third of a command delay's error around a setpoint step (its rise and fall look alike); one
per run cannot follow the steps, and a start-velocity error takes up 1-3 % of it.

Measured on a clean NMPC flight's onboard log with realistic sensor noise
(`vehicle_sim.sensor_noise`), diagnosed against the config that flew it: without the removal
`flight_control` was named on 8 seeds of 14 (gains 1.1-1.6x: a vertical velocity P gain of 6-7
for the true 4); BENCHMARKS.md has the counts.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from functools import lru_cache

import numpy as np

from diagnosis import sim_anchor
from vehicle_sim import AnchorState, CheckedSetpoint, SimConfig

HORIZON_S = 2.5  # a 2 s window's last compared row: within 2 s of its anchor plus a row gap
GRID_S = 0.02  # the responses' time step (interpolated linearly between; rows 20-40 ms apart)
_HORIZON_STEPS = int(round(HORIZON_S / GRID_S))
_STEP_MPS2 = 0.1  # integral perturbation of the finite differences [m/s^2]
_STEP_MPS = 0.1  # start-velocity perturbation of the finite differences [m/s]
_HOVER = CheckedSetpoint((0.0, 0.0, 0.0))


@lru_cache(maxsize=sim_anchor.TEMPLATES_KEPT)
def responses(config: SimConfig, steps: int = _HORIZON_STEPS) -> np.ndarray:
    """(steps + 1, 3, 6) the velocity NED [m/s] at times ``GRID_S * i`` after the start per
    unit of each nuisance: the velocity-loop integral offset NED [m/s^2] (columns 0-2) and the
    start velocity error NED [m/s] (3-5); by finite differences about hover, the setpoint
    streamed. A longer flight's first rows are a shorter one's (the flights are the same)."""
    template = sim_anchor.hovering_template(config)
    hover = template.state

    def fly(integral: np.ndarray, dv0: np.ndarray) -> np.ndarray:
        sim = sim_anchor.fresh_copy(template)
        if dv0.any():
            sim.anchor(
                AnchorState(hover.pos_ned_m, hover.vel_ned_mps + dv0, hover.q_wxyz,
                            hover.rates_frd_radps)
            )  # fmt: skip
        sim.set_velocity_integral(sim.velocity_integral_mps2 + integral)
        start = sim.vel_ned_mps
        # the setpoint streamed, as a log's are: no OFFBOARD loss
        return np.vstack(
            [start, sim.stream_setpoints([_HOVER] * steps, [GRID_S] * steps).vel_ned_mps]
        )

    return finite_differences(fly)[1]


def finite_differences(
    fly: Callable[[np.ndarray, np.ndarray], np.ndarray],
) -> tuple[np.ndarray, np.ndarray]:
    """``fly(integral, dv0)`` (velocity NED [m/s], (m, 3), of a flight from an integral offset
    [m/s^2] and a start-velocity error [m/s], both (3,)) unperturbed, and (m, 3, 6) its change
    per unit of each (integral offset in columns 0-2, start velocity 3-5), by one-sided finite
    differences: seven flights."""
    zero = np.zeros(3)
    nominal = fly(zero, zero)
    columns = [(fly(_STEP_MPS2 * e, zero) - nominal) / _STEP_MPS2 for e in np.eye(3)]
    columns += [(fly(zero, _STEP_MPS * e) - nominal) / _STEP_MPS for e in np.eye(3)]
    return nominal, np.stack(columns, axis=-1)


class RunNuisance:
    """One airborne run's windows, added as they are flown: the nuisance (one integral offset
    for the run, one start-velocity error per window) that best explains what they miss of
    the measured velocity, and what is left. The least squared error left by the windows so
    far never exceeds what all of them leave (more rows only add to a sum minimised over the
    same offset), so a search may stop replaying a config on it (diagnosis.replay.replay_sse).
    """

    def __init__(self, config: SimConfig) -> None:
        self._config = config
        self._curves = responses(config)
        self._parts: list[tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]] = []
        self._normal, self._rhs, self._sq = np.zeros((3, 3)), np.zeros(3), 0.0

    def add(self, tau_s: np.ndarray, sim_vel_ned_mps: np.ndarray, meas: np.ndarray) -> None:
        """A window's compared rows: times since its anchor ``tau_s`` (m,) [s], simulated and
        measured velocity NED (m, 3) [m/s]. Rows past ``HORIZON_S`` (a window longer than 2 s)
        get responses flown as far, in whole multiples of it (never extrapolated)."""
        last_s = float(np.max(tau_s, initial=0.0))
        if last_s > (len(self._curves) - 1) * GRID_S:
            spans = math.ceil(last_s / HORIZON_S)
            self._curves = responses(self._config, spans * _HORIZON_STEPS)
        grid = np.arange(len(self._curves)) * GRID_S
        k = np.clip(np.searchsorted(grid, tau_s) - 1, 0, len(grid) - 2)
        w = ((tau_s - grid[k]) / GRID_S)[:, None, None]
        jac = ((1.0 - w) * self._curves[k] + w * self._curves[k + 1]).reshape(-1, 6)
        integral, start = jac[:, :3], jac[:, 3:]
        error = (meas - sim_vel_ned_mps).reshape(-1)
        q, _ = np.linalg.qr(start)  # the window's own start error is projected out first
        integral_left = integral - q @ (q.T @ integral)
        error_left = error - q @ (q.T @ error)
        self._normal += integral_left.T @ integral_left
        self._rhs += integral_left.T @ error_left
        self._sq += float(error_left @ error_left)
        self._parts.append((integral, q, error, sim_vel_ned_mps))

    def _offset(self) -> np.ndarray:
        return np.linalg.lstsq(self._normal, self._rhs, rcond=None)[0]

    def sse(self) -> float:
        """Sum over the windows' rows of the squared 3-D velocity error left [m^2/s^2]."""
        return max(self._sq - float(self._rhs @ self._offset()), 0.0)

    def fitted(self) -> list[np.ndarray]:
        """Each window's simulated velocity plus the nuisance's part, (m_w, 3) [m/s]."""
        offset = self._offset()
        out = []
        for integral, q, error, sim in self._parts:
            explained = integral @ offset
            explained += q @ (q.T @ (error - explained))
            out.append(sim + explained.reshape(-1, 3))
        return out
