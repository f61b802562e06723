"""Drive the rover back to a pose over a Link: turn in place, drive straight, turn in place.

Between two repeats of an open path the rover has to get back to the path's start. This is
the simplest way a skid-steer or differential rover does it in OFFBOARD: turn towards the
target, drive the straight line to it (the line must be clear: nothing here sees obstacles),
turn to the target heading, Hold. A rover that cannot turn in place (Ackermann) does not get
there and the drive says so at its deadline. Poses are in the path frame (x north, y west,
heading counter-clockwise; experiments.rover.link_drive).
"""

from __future__ import annotations

import math

import numpy as np

from companion.link import ZERO_VELOCITY, Link, LinkError, VelocityCommand
from experiments.rover.link_drive import pose_of, stop_rover

ARRIVED_M = 0.05
ALIGNED_RAD = 0.05
_FACING_RAD = 0.15
_HEADING_GAIN = 1.5  # turn rate per heading error [1/s]
_SPEED_GAIN = 0.8  # speed per remaining distance [1/s]


def _wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


def drive_back(
    link: Link,
    target: tuple[float, float, float],
    speed_mps: float,
    max_turn_radps: float = 0.8,
    timeout_s: float = 120.0,
    dt_s: float = 0.1,
) -> tuple[str, str]:
    """Drive the connected rover to ``target`` (x_m, y_m, heading_rad) and Hold.

    Returns (left_offboard_for, stopped_for), both "" when it got there: the mode someone
    switched the rover to (nothing more is sent then, as experiments.rover.link_drive), or why
    the drive stopped the rover with a zero velocity and Hold (a lost link, a non-finite pose,
    the deadline). Ctrl-C stops the rover (Hold) and is raised on.

    Raises:
        LinkError: arming or OFFBOARD refused (its reason in the message).
    """
    link.send_velocity(ZERO_VELOCITY)
    for what, outcome in (("arm", link.arm), ("offboard", link.start_offboard)):
        result = outcome()
        if not result.accepted:
            raise LinkError(f"rover refused {what}: {result.detail or 'no reason given'}")
    clock = link.clock
    t_end = clock.now_s() + timeout_s
    t_next, seen_offboard, phase = clock.now_s(), False, "face"
    try:
        while True:
            st = link.read_state()
            seen_offboard = seen_offboard or st.mode == "OFFBOARD"
            if seen_offboard and st.mode != "OFFBOARD":
                link.stop_streaming()
                return st.mode, ""
            if not st.is_finite():
                stop_rover(link)
                return "", f"the rover's pose is not finite at t={st.t_s:.1f} s"
            if clock.now_s() > t_end:
                stop_rover(link)
                return "", f"it did not get back to the start within {timeout_s:.0f} s"
            x, y, th = pose_of(link)
            dx, dy = target[0] - x, target[1] - y
            dist = math.hypot(dx, dy)
            bearing_err = _wrap(math.atan2(dy, dx) - th)
            passed = dist < 5 * ARRIVED_M and abs(bearing_err) > math.pi / 2
            if phase != "align" and (dist < ARRIVED_M or passed):  # there, or just past it
                phase = "align"
            if phase == "face" and abs(bearing_err) < _FACING_RAD:
                phase = "drive"
            if phase == "align":
                err = _wrap(target[2] - th)
                if abs(err) < ALIGNED_RAD:
                    break
                v, w = 0.0, err * _HEADING_GAIN
            elif phase == "face":
                v, w = 0.0, bearing_err * _HEADING_GAIN
            else:
                v = min(speed_mps, _SPEED_GAIN * dist) * max(0.0, math.cos(bearing_err))
                w = bearing_err * _HEADING_GAIN
            w = float(np.clip(w, -max_turn_radps, max_turn_radps))
            yaw = -th
            link.send_velocity(VelocityCommand((v * math.cos(yaw), v * math.sin(yaw), 0.0), -w))
            t_next += dt_s
            clock.sleep_until(t_next)
    except LinkError as exc:
        stop_rover(link)
        return "", str(exc)
    except KeyboardInterrupt:
        stop_rover(link)
        raise
    stop_rover(link)
    return "", ""
