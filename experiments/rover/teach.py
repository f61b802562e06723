"""The teach pass of teach and repeat ([Ostafew16] section 4.1): record the path a rover drives.

Someone drives the rover (a pilot in MANUAL, a mission, or, with ``drive``, the companion
itself in OFFBOARD, open loop: a scripted pattern of straight runs and arcs at one speed, which
is how a simulator or an empty field is taught without a pilot); this records its position
from the Link's telemetry, in the path frame (x north, y west of the local origin), every
``sample_period_s`` once it has moved. Recording starts when the rover is armed (at once if it
is) and ends when it disarms, when it has driven ``max_distance_m``, at ``timeout_s``, at the
end of the scripted pattern, or on Ctrl-C (or SIGTERM, said as such). The positions become a
TaughtPath resampled to the vertex spacing. A pass is refused (TeachError, one line, nothing
to write) when the position is not finite, the rover moved too little, the link was lost or
someone took the rover out of OFFBOARD during a scripted drive.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

from companion.link import Link, LinkError, VelocityCommand
from companion.runner import Terminated
from experiments.rover.link_commands import require_a_rover, start_driving, stop_rover
from planners.rover.path import TaughtPath

MIN_TEACH_M = 1.0
_MIN_STEP_M = 0.02  # a position closer than this to the last recorded one is not kept


class TeachError(RuntimeError):
    """A teach pass that gave no usable path; one line naming why and what to do."""


class HandedOver(TeachError):
    """Someone switched the rover out of OFFBOARD during a scripted teach drive; nothing more
    was sent to it."""


@dataclass(frozen=True)
class TeachPass:
    """A recorded teach pass.

    Attributes:
        path: the taught path, resampled to the vertex spacing.
        ended_for: why recording stopped (disarmed, distance, pattern done, Ctrl-C, SIGTERM,
            timeout).
    """

    path: TaughtPath
    ended_for: str


def _curvature_at(drive: Sequence[tuple[float, float]], s_m: float) -> float | None:
    """Curvature [1/m] of the pattern at distance ``s_m``; None past its end."""
    for length, curvature in drive:
        if s_m < length:
            return curvature
        s_m -= length
    return None


def turns_not_driven(
    drive: Sequence[tuple[float, float]], path: TaughtPath, share: float = 0.8
) -> list[str]:
    """The scripted pattern's arcs the rover did not turn as asked, one line each.

    A rover steers no tighter than its limits (an Ackermann robot's steering angle, a skid-steer
    robot's yaw rate at the drive speed); asked for more, it drives a wider arc, and the taught
    path is that arc, not the pattern. For each arc of ``drive`` ((length_m, curvature_1pm) per
    segment), the taught path's mean curvature over the arc's middle half (heading change over
    distance) is compared with the asked one: below ``share`` of it, the arc is named.
    """
    heading = np.unwrap(path.heading_rad)
    lines, start = [], 0.0
    for number, (length, curvature) in enumerate(drive, 1):
        a, b = start + 0.25 * length, min(start + 0.75 * length, path.length_m)
        start += length
        if curvature == 0.0 or b - a < 2.0 * path.spacing_m:
            continue
        turned = float(np.diff(np.interp([a, b], path.s_m, heading))[0]) / (b - a)
        if turned / curvature < share:
            lines.append(
                f"segment {number} asked for {curvature:+.2f} 1/m and the rover turned "
                f"{turned:+.2f} 1/m there (its steering or yaw-rate limit): the taught path has "
                "the wider turn it drove"
            )
    return lines


def record_teach(
    link: Link,
    spacing_m: float = 0.25,
    max_distance_m: float = math.inf,
    timeout_s: float = math.inf,
    drive: Sequence[tuple[float, float]] | None = None,
    drive_speed_mps: float = 0.5,
    sample_period_s: float = 0.1,
    progress: Callable[[str], None] = lambda _m: None,
) -> TeachPass:
    """Connect, record the teach pass and return its path (see the module docstring).

    ``drive`` is the scripted pattern, (length_m, curvature_1pm) per segment (curvature > 0
    turns left), driven at ``drive_speed_mps``.

    Raises:
        LinkError: no vehicle or no position on connecting, or it refuses arming or OFFBOARD;
            NotARover when the vehicle says it is no rover (nothing sent to it).
        TeachError: the pass gave no usable path (see the module docstring); HandedOver
            when someone took the rover out of OFFBOARD during the scripted drive.
    """
    link.connect(timeout_s=30.0)
    require_a_rover(link)
    clock = link.clock
    t_end = clock.now_s() + timeout_s
    if drive is not None:
        start_driving(link)
        progress(f"driving the teach pattern at {drive_speed_mps:g} m/s")
    points: list[np.ndarray] = []
    driven, last, armed_seen, seen_offboard, ended = 0.0, None, False, False, ""
    t_next = clock.now_s()
    try:
        while not ended:
            st = link.read_state()
            if not st.is_finite():
                raise TeachError(
                    f"the rover's position is not finite (NaN) at t={st.t_s:.1f} s; check its "
                    "position estimate (GPS, EKF) and teach again"
                )
            xy = np.array([st.pos_ned_m[0], -st.pos_ned_m[1]])
            if st.armed and not armed_seen:
                armed_seen = True
                progress("armed: recording the teach pass (Ctrl-C, disarm or the distance ends it)")
            seen_offboard = seen_offboard or st.mode == "OFFBOARD"
            if drive is not None and seen_offboard and st.mode != "OFFBOARD":
                link.stop_streaming()
                raise HandedOver(
                    f"the rover left OFFBOARD for {st.mode} during the teach drive at "
                    f"t={st.t_s:.1f} s; nothing written: run the teach again"
                )
            if armed_seen:
                if last is not None:
                    driven += float(np.hypot(*(xy - last)))
                last = xy
                if not points or np.hypot(*(xy - points[-1])) >= _MIN_STEP_M:
                    points.append(xy)
            if armed_seen and not st.armed:
                ended = "the rover disarmed"
            elif driven >= max_distance_m:
                ended = f"{max_distance_m:g} m driven"
            elif clock.now_s() >= t_end:
                ended = f"{timeout_s:g} s passed"
            elif drive is not None:
                curvature = _curvature_at(drive, driven)
                if curvature is None:
                    ended = "the teach pattern ended"
                else:
                    yaw = st.yaw_rad  # NED, clockwise from north
                    v, w = drive_speed_mps, drive_speed_mps * curvature
                    link.send_velocity(
                        VelocityCommand((v * math.cos(yaw), v * math.sin(yaw), 0.0), -w)
                    )
            if not ended:
                t_next += sample_period_s
                clock.sleep_until(t_next)
    except LinkError as exc:
        if drive is not None:
            stop_rover(link)
        raise TeachError(f"{exc}; nothing written: teach again") from None
    except KeyboardInterrupt as exc:  # Ctrl-C, or SIGTERM as companion.runner.Terminated
        ended = "SIGTERM" if isinstance(exc, Terminated) else "Ctrl-C"
    except HandedOver:
        raise
    except TeachError:
        if drive is not None:
            stop_rover(link)
        raise
    if drive is not None:
        stop_rover(link)
    if driven < max(MIN_TEACH_M, 3 * spacing_m) or len(points) < 3:
        need = f"{MIN_TEACH_M:g} m: drive it along the path"
        if 3 * spacing_m > MIN_TEACH_M:
            need = (
                f"{3 * spacing_m:g} m (3 vertices {spacing_m:g} m apart): drive it further or "
                "pass a smaller --spacing"
            )
        raise TeachError(
            f"the rover drove {driven:.2f} m while recording ({ended}); a path needs at least "
            f"{need} and teach again"
        )
    try:
        path = TaughtPath.from_drive(np.array(points), spacing_m)
    except ValueError as exc:
        raise TeachError(f"the recorded positions give no path: {exc}; teach again") from None
    return TeachPass(path, ended)
