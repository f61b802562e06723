"""The simulated vehicle a replay re-anchors at measured states.

A hovering OFFBOARD template of the config is copied for each airborne run and each replay
window; the copies are put into measured states with the simulator's public
``Simulator.anchor`` (position, velocity, attitude, rates, rotor thrust; the velocity-loop
integral a run starts with is fitted by :mod:`.warm_up`).
"""

from __future__ import annotations

import copy
from functools import lru_cache

from vehicle_sim import CheckedSetpoint, FlightMode, SimConfig, Simulator

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
    # checked: copies stream it on from their delay queue (Simulator.stream_setpoints)
    sim.set_velocity_setpoint(CheckedSetpoint((0.0, 0.0, 0.0)))
    sim.step(0.05)
    if not sim.set_mode(FlightMode.OFFBOARD).accepted:
        raise AnchorError(f"replay vehicle {config.preset_name!r} refused OFFBOARD")
    return sim


def fresh_copy(template: Simulator) -> Simulator:
    """An independent copy of ``template``."""
    return copy.deepcopy(template)
