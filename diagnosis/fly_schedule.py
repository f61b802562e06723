"""Fly an excitation schedule in-process on a simulated vehicle and record its flight log.

Data collection for tests and for planning real flights: takeoff, then one velocity setpoint
per control tick in OFFBOARD, as a companion would stream them. Each row holds the state read
at the tick and the command sent at that tick.
"""

from __future__ import annotations

from collections.abc import Mapping

from diagnosis.excitation import ExcitationSchedule
from flightlog.schema import FlightLog, FlightLogRecorder
from vehicle_sim import FlightMode, SimConfig, Simulator, VelocitySetpoint

TAKEOFF_TIMEOUT_S = 60.0
SETTLE_S = 2.0


class FlightAborted(RuntimeError):
    """The simulated vehicle refused a command or did not reach the excitation flight."""


def fly_schedule(
    config: SimConfig,
    schedule: ExcitationSchedule,
    seed: int = 0,
    rate_hz: float = 20.0,
    params: Mapping[str, float] | None = None,
) -> FlightLog:
    """Take off, fly ``schedule`` in OFFBOARD at ``rate_hz`` [Hz]; the OFFBOARD part as a log.
    ``params``: PX4 parameters set before take-off (e.g. other velocity gains)."""
    sim = Simulator(config, seed=seed)
    for name, value in (params or {}).items():
        sim.set_param(name, value)
    _check(sim.arm(), "arm")
    _check(sim.takeoff(schedule.takeoff_alt_m), "takeoff")
    waited_s = 0.0
    while sim.state.mode is not FlightMode.HOLD:
        if waited_s > TAKEOFF_TIMEOUT_S:
            raise FlightAborted(f"takeoff not complete after {TAKEOFF_TIMEOUT_S} s")
        sim.step(0.5)
        waited_s += 0.5
    sim.step(SETTLE_S)
    dt_s = 1.0 / rate_hz
    sim.set_velocity_setpoint(VelocitySetpoint((0.0, 0.0, 0.0)))
    sim.step(dt_s)
    _check(sim.set_mode(FlightMode.OFFBOARD), "offboard")
    recorder = FlightLogRecorder({**sim.log_metadata(), "rate_hz": rate_hz})
    t0_s = sim.t_s
    for k in range(round(schedule.duration_s * rate_hz)):
        state = sim.state
        vel, yaw_rate = schedule.setpoint(k * dt_s, -float(state.pos_ned_m[2]))
        cmd = VelocitySetpoint(vel, yaw_rate)
        sim.set_velocity_setpoint(cmd)
        row = sim.log_row(cmd)
        row["t_s"] -= t0_s
        recorder.append(row)
        sim.step(dt_s)
    return recorder.to_log()


def _check(result, what: str) -> None:
    if not result.accepted:
        raise FlightAborted(f"{what} refused: {result}")
