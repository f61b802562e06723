"""The simulated vehicle a replay re-anchors at measured states.

A hovering OFFBOARD template of the config is copied for each airborne run and each replay
window; the copies are put into measured states with the simulator's public
``Simulator.anchor`` (position, velocity, attitude, rates, rotor thrust and, while the
controller warms up, the velocity-loop integral that reproduces the measured thrust vector:
:func:`matched_minus_carried`, fitted over the warm-up by :mod:`.warm_up`).
"""

from __future__ import annotations

import copy
from functools import lru_cache

import numpy as np

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


def matched_minus_carried(sim: Simulator, state: AnchorState) -> np.ndarray:
    """(3,) [m/s^2] the velocity-loop integral the measured thrust vector of ``state`` implies
    (``Simulator.anchor``'s ``integral="match_thrust"``) minus the one ``sim`` carries; ``sim``
    is left anchored at ``state`` with its carried integral (:mod:`.warm_up` fits these)."""
    carried = np.array(sim.velocity_integral_mps2, dtype=float)
    sim.anchor(state, integral="match_thrust")
    matched = np.array(sim.velocity_integral_mps2, dtype=float)
    sim.set_velocity_integral(carried)
    return matched - carried
