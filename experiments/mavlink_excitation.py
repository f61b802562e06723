"""Fly an excitation schedule over a MAVLink link, as a companion computer would.

Arms, takes off to the schedule's altitude, streams its velocity setpoints in OFFBOARD at
``rate_hz`` on the link's (wall) clock, then commands HOLD. The flight log the diagnosis reads
is the vehicle's own (PX4's SD-card log; `vehicle-sim --log`): MAVLink carries no measured
acceleration or thrust. The in-process twin is :func:`diagnosis.fly_schedule.fly_schedule`.
"""

from __future__ import annotations

from collections.abc import Callable

from companion.link import LandedPhase, Link, VelocityCommand
from companion.waiting import command_until_accepted, wait_for
from diagnosis.excitation import ExcitationSchedule

COMMAND_TIMEOUT_S = 30.0  # generous: a busy computer slows the simulator's answers
TAKEOFF_TIMEOUT_S = 60.0
TAKEOFF_REACHED = 0.9  # take-off is done at this fraction of the target altitude
SETTLE_S = 2.0


def fly_schedule_over_link(
    link: Link,
    schedule: ExcitationSchedule,
    rate_hz: float = 20.0,
    progress: Callable[[str], None] = lambda msg: None,
) -> None:
    """Take off, fly ``schedule`` in OFFBOARD at ``rate_hz`` [Hz], then HOLD.

    The link must be connected. Raises ``LinkError`` (one line) when the vehicle refuses or a
    phase times out.
    """
    clock = link.clock
    wait_for(link, lambda s: s.is_finite(), COMMAND_TIMEOUT_S, "telemetry")
    command_until_accepted(link, link.arm, COMMAND_TIMEOUT_S, "arm")
    command_until_accepted(
        link, lambda: link.takeoff(schedule.takeoff_alt_m), COMMAND_TIMEOUT_S, "takeoff"
    )
    target_m = TAKEOFF_REACHED * schedule.takeoff_alt_m
    wait_for(
        link,
        lambda s: s.altitude_m >= target_m and s.landed is LandedPhase.IN_AIR,
        TAKEOFF_TIMEOUT_S,
        f"take-off to {schedule.takeoff_alt_m:g} m",
    )
    clock.sleep_until(clock.now_s() + SETTLE_S)
    link.send_velocity(VelocityCommand((0.0, 0.0, 0.0)))
    clock.sleep_until(clock.now_s() + 0.2)
    command_until_accepted(link, link.start_offboard, COMMAND_TIMEOUT_S, "offboard")
    progress(f"flying {schedule.duration_s:.0f} s of excitation in OFFBOARD at {rate_hz:g} Hz")
    dt_s = 1.0 / rate_hz
    t0_s = clock.now_s()
    for k in range(round(schedule.duration_s * rate_hz)):
        state = link.read_state()
        vel, yaw_rate = schedule.setpoint(clock.now_s() - t0_s, state.altitude_m)
        link.send_velocity(VelocityCommand(vel, yaw_rate))
        clock.sleep_until(t0_s + (k + 1) * dt_s)
    link.send_velocity(VelocityCommand((0.0, 0.0, 0.0)))
    command_until_accepted(link, link.hold, COMMAND_TIMEOUT_S, "hold")
