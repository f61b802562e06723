"""Build the simulator's compiled loops into numba's cache once, before many processes need them.

    python -m vehicle_sim.prebuild

The two loops (:mod:`vehicle_sim.builtin_plant`) are compiled at their first call and kept on
disk (:mod:`vehicle_sim.compile_notice`); a process that finds them there loads them in a
fraction of a second. On a fresh clone nothing is there yet, and ``make test``'s four pytest
workers, and the MAVLink endpoints their first tests start, each compiled both at once (about
17 s of CPU each). ``make test`` runs this first, so one process builds them and every later
one loads them. It flies the built-in quadrotor briefly through both loops: the closed loop of
:meth:`Simulator.step` and the setpoint stream of :meth:`Simulator.stream_setpoints`, with the
argument types of a replay.
"""

from __future__ import annotations

from vehicle_sim import builtin_plant
from vehicle_sim.config import load_sim_config
from vehicle_sim.simulator import Simulator
from vehicle_sim.vehicle_types import CheckedSetpoint, FlightMode


def prebuild() -> None:
    """Fly both compiled loops once (compiling them if numba's cache has not got them)."""
    sim = Simulator(load_sim_config("iris"))
    hover = CheckedSetpoint((0.0, 0.0, 0.0))
    if not (sim.arm().accepted and sim.takeoff(2.0).accepted):
        raise RuntimeError("the built-in quadrotor refused to arm and take off on the ground")
    for _ in range(4):  # the closed loop, streaming setpoints as OFFBOARD requires first
        sim.set_velocity_setpoint(hover)
        sim.step(0.05)
    if not sim.set_mode(FlightMode.OFFBOARD).accepted:
        raise RuntimeError("the built-in quadrotor refused OFFBOARD with setpoints streaming")
    sim.stream_setpoints([hover] * 4, [0.05] * 4)
    if not builtin_plant.run_scheduled.signatures:
        raise RuntimeError("the setpoint stream flew leg by leg: its compiled loop was not built")


if __name__ == "__main__":
    prebuild()
