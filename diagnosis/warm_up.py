"""The autopilot's velocity integral at the start of a replay's airborne run, by output error.

A replay's follower carries the velocity loop's integral from the run's first row, integrating
the measured velocity errors as the measured vehicle's loop did; what it cannot know is the
integral the vehicle already had there (it hovered against a payload, a wind, or had started
accelerating). That start integral c (3,) is fitted to the run's first ``LEAD_IN_S`` (the
warm-up, never part of a replay window): copies of the vehicle fly free from the first row on
the logged setpoints with c = 0 and with each axis of c perturbed, and the c that best explains
the measured velocities is solved for by linear least squares, together with the first row's
velocity error dv0 (3,) (its noise would otherwise be read as an integral: a constant
acceleration error and a decaying start error leave different traces).

This replaced reading the integral off each warm-up row's thrust vector by inverting the
velocity loop, which takes the attitude as the one the loop commands: while the commanded
acceleration changes, the attitude lags it (second order, through the rate loop), and no lag
term fitted it well enough. On the project's own line and square missions flown by the NMPC
in process and diagnosed against the very config that flew them, the integral came out
0.03 m/s^2 off for the whole run, the follower's rate integral wound up on it, and the held-out
replay error was 0.067 and 0.093 m/s, 700-900x the noise floor: "unexplained", and on the square
a command delay named that was not there. By output error: 0.0003 m/s on both. It also needs no
thrust, which MAVLink telemetry does not carry.
"""

from __future__ import annotations

import copy
from collections.abc import Sequence
from dataclasses import replace

import numpy as np

from diagnosis.window_nuisance import finite_differences
from vehicle_sim import AnchorState, Simulator, VelocitySetpoint

LEAD_IN_S = 1.0


def start_integral(
    start: Simulator,
    first: AnchorState,
    t_s: np.ndarray,
    setpoints: Sequence[VelocitySetpoint],
    meas_vel_ned_mps: np.ndarray,
) -> np.ndarray:
    """(3,) NED [m/s^2] the velocity-loop integral at the warm-up's first row.

    The vehicle's response is linear enough in both unknowns over a second that one finite
    difference per unknown (7 free flights of the warm-up) and one least-squares solve do.

    Args:
        start: the vehicle anchored at ``first`` (the warm-up's first row) with that row's
            setpoint given; left unchanged (copies fly).
        first: the first row's measured state.
        t_s: (m + 1,) times of the m warm-up rows and of the row after them [s].
        setpoints: the m warm-up rows' logged setpoints.
        meas_vel_ned_mps: (m, 3) measured velocity NED [m/s] of the m rows after the first,
            which the copies' velocity after each row's interval is compared with.
    """

    def fly(integral: np.ndarray, dv0: np.ndarray) -> np.ndarray:
        free = copy.deepcopy(start)
        free.set_velocity_integral(integral)
        if dv0.any():
            free.anchor(replace(first, vel_ned_mps=np.add(first.vel_ned_mps, dv0)))
        legs = free.stream_setpoints([None, *setpoints[1:]], np.diff(t_s[: len(setpoints) + 1]))
        return legs.vel_ned_mps

    nominal, responses = finite_differences(fly)
    jac = responses.reshape(-1, 6)
    solution, *_ = np.linalg.lstsq(jac, (meas_vel_ned_mps - nominal).reshape(-1), rcond=None)
    return solution[:3]
