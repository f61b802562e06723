"""The simulated vehicle a replay re-anchors at measured states.

A hovering OFFBOARD template of the config is copied for each airborne run and each replay
window; the copies are put into measured states with the simulator's public
``Simulator.anchor`` (position, velocity, attitude, rates, rotor thrust and, while the
controller warms up, the velocity-loop integral that reproduces the measured thrust vector,
averaged over the rows of the warm-up: :func:`anchor_matching_thrust`).
"""

from __future__ import annotations

import copy
from functools import lru_cache

from vehicle_sim import AnchorState, FlightMode, SimConfig, Simulator, VelocitySetpoint

TEMPLATE_ALT_M = 5.0
TEMPLATES_KEPT = 16  # configs whose template is kept (a diagnosis replays a few again and again)


class AnchorError(RuntimeError):
    """The template vehicle could not be brought into OFFBOARD flight."""


@lru_cache(maxsize=TEMPLATES_KEPT)
def hovering_template(config: SimConfig) -> Simulator:
    """A vehicle of ``config`` hovering in OFFBOARD, to be copied for each replay window (the
    same for the same config, so it is built once and kept: never step it, copy it)."""
    sim = Simulator(config, seed=0)
    sim.arm()
    sim.takeoff(TEMPLATE_ALT_M)
    for _ in range(120):
        if sim.state.mode is FlightMode.HOLD:
            break
        sim.step(0.5)
    sim.set_velocity_setpoint(VelocitySetpoint((0.0, 0.0, 0.0)))
    sim.step(0.05)
    if not sim.set_mode(FlightMode.OFFBOARD).accepted:
        raise AnchorError(f"replay vehicle {config.preset_name!r} refused OFFBOARD")
    return sim


def fresh_copy(template: Simulator) -> Simulator:
    """An independent copy of ``template``."""
    return copy.deepcopy(template)


def anchor_matching_thrust(sim: Simulator, state: AnchorState, rows_matched: int) -> None:
    """Anchor ``sim`` at ``state``, the ``rows_matched``-th row (from 1) of a warm-up, and set its
    velocity-loop integral to the mean over those rows of the integral each row's measured thrust
    vector implies (``Simulator.anchor``'s ``integral="match_thrust"``), each carried forward to
    now by the loop's own integration (the running mean of the integral carried from the row
    before and the one matched at this row).

    Why the mean: the integral matched at one row inverts that row's attitude, thrust, velocity
    and acceleration, noise included (horizontally about g x the attitude noise plus the
    velocity P gain x the velocity noise: 0.2 m/s^2 for 1 deg and 0.07 m/s), and after the
    warm-up the integral is kept for the whole airborne run. A vehicle re-anchored at every row
    never feels an integral error (its velocity is reset to the measured one), so that one
    row's noise stays a constant acceleration bias in every replay window started from it. Seen
    on a noisy log: a hover window drifted 0.26 m/s from a 0.39 m/s^2 integral, and a command
    delay was fitted 21 % short. The mean of n rows has 1/sqrt(n) of that noise."""
    carried = sim.velocity_integral_mps2
    sim.anchor(state, integral="match_thrust")
    if rows_matched > 1:
        matched = sim.velocity_integral_mps2
        sim.set_velocity_integral(carried + (matched - carried) / rows_matched)
