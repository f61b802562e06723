"""Where a trial of a taught path starts: within ``START_TOLERANCE_M`` and
``START_TOLERANCE_RAD`` of the first vertex's pose, and a loop's end is its next trial's start
(experiments.rover.repeat). A module of its own so that the teach pass says whether it taught a
loop without loading the repeat's NMPC and GP.
"""

from __future__ import annotations

import math

import numpy as np

from companion.link import Link
from experiments.rover.link_commands import pose_of
from planners.rover.path import TaughtPath, wrap_angle

START_TOLERANCE_M = 1.0
START_TOLERANCE_RAD = 0.5


def end_gap_m(path: TaughtPath) -> float:
    """Distance from the path's last vertex to its first [m]."""
    return float(np.hypot(*(path.xy_m[-1] - path.xy_m[0])))


def is_loop(path: TaughtPath) -> bool:
    """The path ends where it starts (within the start tolerances): a trial's end is the next
    trial's start."""
    turn = abs(float(wrap_angle(path.heading_rad[-1] - path.heading_rad[0])))
    return end_gap_m(path) <= START_TOLERANCE_M and turn <= START_TOLERANCE_RAD


def start_offset(link: Link, path: TaughtPath) -> tuple[float, float]:
    """How far the rover is from the path's start: distance [m], heading error [rad]."""
    x, y, th = pose_of(link)
    x0, y0, th0 = path.pose(0)
    return float(math.hypot(x - x0, y - y0)), float(wrap_angle(th0 - th))
