"""Drive the rover back to an open path's start between trials, over a Link, in OFFBOARD.

Two ways, both ending in Hold:

- ``turn`` (:func:`drive_back`): turn towards the target, drive the straight line to it (the
  line must be clear: nothing here sees obstacles), turn to the target heading. For a rover that
  turns in place (skid steer, differential); an Ackermann rover does not, and the drive stops
  after ``STALL_S`` of turning in place without turning, saying to reverse instead.
- ``reverse`` (:func:`reverse_along`): drive backwards along the taught path itself, on ground
  the rover has already driven, steering by pure pursuit [Coulter92] on the path behind it (the
  rover's rear is the pursuer's front). Any rover, Ackermann too: the path was driven forwards,
  so its curvature is within the steering's reach backwards as well.

Poses are in the path frame (x north, y west, heading counter-clockwise;
experiments.rover.link_commands).

[Coulter92] R. C. Coulter, "Implementation of the Pure Pursuit Path Tracking Algorithm",
Carnegie Mellon University, CMU-RI-TR-92-01, 1992.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from companion.link import Link, LinkError, VelocityCommand
from experiments.rover.link_commands import start_driving, state_pose, stop_rover
from planners.rover.path import TaughtPath

ARRIVED_M = 0.05
ALIGNED_RAD = 0.05
_FACING_RAD = 0.15
_HEADING_GAIN = 1.5  # turn rate per heading error [1/s]
_SPEED_GAIN = 0.8  # speed per remaining distance [1/s]
_CREEP_MPS = 0.05  # the slowest a drive closes the last centimetres at
_LOOKAHEAD_MIN_M = 0.6  # pure pursuit's lookahead: at least this,
_LOOKAHEAD_S = 1.5  # or this many seconds of travel [s]
_SEARCH_VERTICES = 20  # how far back along the path the nearest vertex is looked for
STALL_S = 5.0  # turning in place this long [s] ...
STALL_RAD = 0.1  # ... by less than this [rad] is a rover that does not turn in place

Control = Callable[[np.ndarray], "tuple[float, float] | None"]
"""From the pose (x_m, y_m, heading_rad): the forward speed [m/s] (< 0 backwards) and turn
rate [rad/s, counter-clockwise] to command, or None once there."""


class _Stalled(Exception):
    """A drive that cannot go on (the reason is the message); the rover is stopped."""


def _wrap(a: float) -> float:
    return math.atan2(math.sin(a), math.cos(a))


@dataclass(frozen=True)
class DriveBack:
    """How a repeat gets back to an open path's start between trials.

    Attributes:
        how: one of ``WAYS``: "turn" (:func:`drive_back`) or "reverse" (:func:`reverse_along`).
        speed_mps: the drive's speed [m/s], > 0.
    """

    how: str
    speed_mps: float

    WAYS = ("turn", "reverse")

    def __post_init__(self) -> None:
        if self.how not in self.WAYS:
            raise ValueError(f"drive back by {self.how!r}? one of {', '.join(self.WAYS)}")
        if not self.speed_mps > 0:
            raise ValueError(f"drive back at {self.speed_mps} m/s? must be > 0")

    def __call__(self, link: Link, path: TaughtPath) -> tuple[str, str]:
        """Drive the connected rover to ``path``'s start; returns as :func:`drive_back`."""
        if self.how == "reverse":
            return reverse_along(link, path, self.speed_mps)
        return drive_back(link, path.pose(0), self.speed_mps)


def drive_back(
    link: Link,
    target: tuple[float, float, float],
    speed_mps: float,
    max_turn_radps: float = 0.8,
    timeout_s: float = 120.0,
    dt_s: float = 0.1,
) -> tuple[str, str]:
    """Turn in place, drive the straight line to ``target`` (x_m, y_m, heading_rad), turn to
    its heading and Hold.

    Returns (left_offboard_for, stopped_for), both "" when it got there: the mode someone
    switched the rover to (nothing more is sent then, as experiments.rover.link_drive), or why
    the drive stopped the rover with a zero velocity and Hold (a lost link, a non-finite pose,
    the deadline). Ctrl-C stops the rover (Hold) and is raised on.

    Raises:
        LinkError: arming or OFFBOARD refused (its reason in the message).
    """
    control = _TurnDriveTurn(target, speed_mps, max_turn_radps, round(STALL_S / dt_s))
    late = " (a rover that cannot turn in place, an Ackermann one, gets back in reverse)"
    return _drive(link, control, timeout_s, dt_s, late)


def reverse_along(
    link: Link,
    path: TaughtPath,
    speed_mps: float,
    max_turn_radps: float = 0.8,
    timeout_s: float | None = None,
    dt_s: float = 0.1,
) -> tuple[str, str]:
    """Drive backwards along ``path`` from where the rover is on it (its end, or partway) to its
    start, facing the path's direction, and Hold; within ``ARRIVED_M`` of the start along the
    path.

    ``timeout_s`` defaults to three times the path's length at ``speed_mps`` [m/s] plus 30 s.
    Returns and raises as :func:`drive_back`.
    """
    if timeout_s is None:
        timeout_s = 3.0 * path.length_m / speed_mps + 30.0
    return _drive(link, _ReverseAlong(path, speed_mps, max_turn_radps), timeout_s, dt_s)


class _TurnDriveTurn:
    """:func:`drive_back`'s three phases: face the target, drive to it, align with it; raises
    _Stalled when ``stall_calls`` calls in a row turning in place turned less than STALL_RAD."""

    def __init__(
        self,
        target: tuple[float, float, float],
        speed_mps: float,
        max_turn_radps: float,
        stall_calls: int,
    ) -> None:
        self.target, self.speed_mps, self.max_turn_radps = target, speed_mps, max_turn_radps
        self.phase = "face"
        self.stall_calls = stall_calls
        self.turning_from: tuple[float, int] | None = None  # heading [rad], calls since

    def _check_it_turns(self, heading_rad: float, error_rad: float) -> None:
        """Count the calls turning in place while STALL_RAD is less than half the error left."""
        if self.turning_from is None or abs(error_rad) < 2.0 * STALL_RAD:
            self.turning_from = (heading_rad, 0)
            return
        start, calls = self.turning_from
        turned = abs(_wrap(heading_rad - start))
        if turned >= STALL_RAD:
            self.turning_from = (heading_rad, 0)
        elif calls + 1 >= self.stall_calls:
            raise _Stalled(
                f"the rover does not turn in place (it turned {turned:.2f} rad in {STALL_S:g} s "
                "of trying; an Ackermann rover cannot): drive it back with --drive-back reverse"
            )
        else:
            self.turning_from = (start, calls + 1)

    def __call__(self, pose: np.ndarray) -> tuple[float, float] | None:
        x, y, th = pose
        dx, dy = self.target[0] - x, self.target[1] - y
        dist = math.hypot(dx, dy)
        bearing_err = _wrap(math.atan2(dy, dx) - th)
        passed = dist < 5 * ARRIVED_M and abs(bearing_err) > math.pi / 2
        if self.phase != "align" and (dist < ARRIVED_M or passed):  # there, or just past it
            self.phase = "align"
        if self.phase == "face" and abs(bearing_err) < _FACING_RAD:
            self.phase = "drive"
        if self.phase == "align":
            err = _wrap(self.target[2] - th)
            if abs(err) < ALIGNED_RAD:
                return None
            v, w = 0.0, err * _HEADING_GAIN
            self._check_it_turns(th, err)
        elif self.phase == "face":
            v, w = 0.0, bearing_err * _HEADING_GAIN
            self._check_it_turns(th, bearing_err)
        else:
            self.turning_from = None
            v = min(self.speed_mps, _SPEED_GAIN * dist) * max(0.0, math.cos(bearing_err))
            w = bearing_err * _HEADING_GAIN
        return v, float(np.clip(w, -self.max_turn_radps, self.max_turn_radps))


class _ReverseAlong:
    """:func:`reverse_along`'s pure pursuit, backwards: the nearest vertex is first looked for
    along the whole path (among the vertices the rover faces the way of: a rover left partway
    along, beside another part of the path, reverses from where it is), then only moves towards
    the start; the goal point is the lookahead behind the rover's projection on the path (past
    the start, on the line of the start's heading, so the rover arrives aligned with it)."""

    def __init__(self, path: TaughtPath, speed_mps: float, max_turn_radps: float) -> None:
        self.path, self.speed_mps, self.max_turn_radps = path, speed_mps, max_turn_radps
        self.vertex: int | None = None
        self.lookahead_m = max(_LOOKAHEAD_MIN_M, _LOOKAHEAD_S * speed_mps)

    def __call__(self, pose: np.ndarray) -> tuple[float, float] | None:
        x, y, th = pose
        if self.vertex is None:
            d2 = np.sum((self.path.xy_m - (x, y)) ** 2, axis=1)
            facing = np.cos(self.path.heading_rad - th) > 0.0
            self.vertex = int(np.argmin(np.where(facing, d2, np.inf) if facing.any() else d2))
        lo = max(0, self.vertex - _SEARCH_VERTICES)
        d2 = np.sum((self.path.xy_m[lo : self.vertex + 1] - (x, y)) ** 2, axis=1)
        self.vertex = lo + int(np.argmin(d2))
        xv, yv, thv = self.path.pose(self.vertex)
        s_m = self.path.s_m[self.vertex] + (x - xv) * math.cos(thv) + (y - yv) * math.sin(thv)
        if s_m <= ARRIVED_M:
            return None
        goal_s = s_m - self.lookahead_m
        if goal_s >= 0.0:
            gx, gy, _ = self.path.ref_at(np.array([goal_s]))[0]
        else:
            x0, y0, th0 = self.path.pose(0)
            gx, gy = x0 + goal_s * math.cos(th0), y0 + goal_s * math.sin(th0)
        alpha = _wrap(math.atan2(gy - y, gx - x) - (th + math.pi))
        speed = max(min(self.speed_mps, _SPEED_GAIN * s_m), _CREEP_MPS)
        curvature = 2.0 * math.sin(alpha) / max(math.hypot(gx - x, gy - y), 1e-6)
        w = float(np.clip(speed * curvature, -self.max_turn_radps, self.max_turn_radps))
        return -speed, w


def _drive(
    link: Link, control: Control, timeout_s: float, dt_s: float, late: str = ""
) -> tuple[str, str]:
    """Arm, OFFBOARD, and stream ``control``'s commands every ``dt_s`` until it returns None:
    see :func:`drive_back` for what is returned and raised; ``late`` ends the deadline's
    reason."""
    start_driving(link)
    clock = link.clock
    t_end = clock.now_s() + timeout_s
    t_next, seen_offboard = clock.now_s(), False
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
                return "", f"it did not get back to the start within {timeout_s:.0f} s{late}"
            pose = state_pose(st)
            command = control(pose)
            if command is None:
                break
            v, w = command
            yaw = -pose[2]
            link.send_velocity(VelocityCommand((v * math.cos(yaw), v * math.sin(yaw), 0.0), -w))
            t_next += dt_s
            clock.sleep_until(t_next)
    except (LinkError, _Stalled) as exc:
        stop_rover(link)
        return "", str(exc)
    except KeyboardInterrupt:
        stop_rover(link)
        raise
    stop_rover(link)
    return "", ""
