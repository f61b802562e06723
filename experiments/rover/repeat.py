"""Repeat a taught path trial after trial over a Link, learning as it goes ([Ostafew16] 3-4).

Each trial is experiments.rover.link_drive.drive_path at the trial's speeds (one fixed speed,
or the speed scheduler's per-vertex schedule, [Ostafew16] eq. 31, from the trial before) with
the experience bins of a LocalGP: trial j drives on the experience of the trials before it
(those of earlier runs too, loaded by the caller) and adds its own after it. A trial starts
where the path starts: the rover must be within ``START_TOLERANCE_M`` and
``START_TOLERANCE_RAD`` of the first vertex's pose (experiments.rover.path_start). A loop ends
there; after an open path the rover is driven back (experiments.rover.drive_back) when
``drive_back`` says how, and otherwise, or when the drive back ends outside those tolerances,
the run stops with a line saying where the rover is. Whatever ends a trial early ends the run:
a pilot or a failsafe taking the rover out of OFFBOARD (nothing more is sent; a failsafe PX4
announced is named with its words), a lost link, a non-finite pose, a failed solve (zero
velocity and Hold), or not reaching the end in time.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np

from companion.handover import failsafe_heard
from companion.link import Link
from experiments.rover.drive_back import DriveBack
from experiments.rover.link_drive import LinkDrive, drive_path
from experiments.rover.path_start import START_TOLERANCE_M, START_TOLERANCE_RAD, start_offset
from gp.local_gp import LocalGP
from planners.rover.path import TaughtPath
from planners.rover.speed_scheduler import SpeedSchedulerConfig, next_schedule
from planners.rover.unicycle_nmpc import UnicycleNmpcConfig

_PLENTY_OF_FEATURES = 1e9  # a companion has no matched-feature count: never the limit


@dataclass(frozen=True, eq=False)
class Trial:
    """One trial: its number over all runs (from 1), the drive, the speeds it was driven with
    per vertex (N,) [m/s], and the experiences stored after it."""

    number: int
    drive: LinkDrive
    schedule_mps: np.ndarray
    experiences: int


@dataclass
class RepeatOutcome:
    """How the run ended.

    Attributes:
        status: "completed" (every trial reached the end), "handed_over" (someone switched
            the rover out of OFFBOARD; nothing more sent), "stopped" (lost link, non-finite
            pose, failed solve, drive back failed: zero velocity and Hold), "incomplete" (a
            trial did not reach the end in time), "not_at_start" (the rover is not at the
            path's start and is not to be driven back, or a drive back ended away from it),
            "refused" (the vehicle is no rover; nothing sent to it).
        detail: one line for the user.
        trials: the trials driven in this run.
        schedule_mps: the speeds the next trial would drive (N,) [m/s].
    """

    status: str
    detail: str
    trials: list[Trial] = field(default_factory=list)
    schedule_mps: np.ndarray | None = None


def repeat_path(
    link: Link,
    path: TaughtPath,
    trials: int,
    gp: LocalGP,
    schedule_mps: np.ndarray,
    scheduler: SpeedSchedulerConfig | None = None,
    first_number: int = 1,
    drive_back: DriveBack | None = None,
    on_trial: Callable[[Trial, np.ndarray], None] = lambda _t, _s: None,
    progress: Callable[[str], None] = lambda _m: None,
    nmpc: UnicycleNmpcConfig = UnicycleNmpcConfig(),  # noqa: B008 (frozen)
    feedforward: bool = False,
    on_drive: Callable[[], None] = lambda: None,
) -> RepeatOutcome:
    """Drive ``trials`` trials from ``schedule_mps`` (N,) [m/s] on the connected ``link``,
    its NMPC tuned by ``nmpc`` and ``feedforward`` (link_drive.drive_path; the rover's are
    experiments.rover.tuning.tuning_for's).

    ``on_trial(trial, next_schedule)`` is called as each trial ends (e.g. to save the
    experience); ``on_drive()`` just before each drive (a trial's, or back to the start) arms
    the rover: from then on Ctrl-C stops the rover with Hold (link_commands.start_driving), and
    each drive ends in Hold or hands the rover over. With ``scheduler`` each trial's records
    set the next trial's speeds.

    Raises:
        LinkError: the rover refused arming or OFFBOARD.
    """
    out = RepeatOutcome("completed", "", [], np.asarray(schedule_mps, dtype=float).copy())
    for k in range(trials):
        number = first_number + k
        dist, dhead = start_offset(link, path)
        if dist > START_TOLERANCE_M or abs(dhead) > START_TOLERANCE_RAD:
            where = f"{dist:.1f} m from the path's start and {dhead:+.2f} rad off its heading"
            if drive_back is None:
                out.status = "not_at_start"
                out.detail = (
                    f"before trial {number} the rover is {where}; drive it there and run again "
                    "(or pass --drive-back to drive back between trials: turn, or reverse along "
                    "the path)"
                )
                return out
            progress(f"trial {number}: driving back to the start, {where}")
            on_drive()
            left_for, stopped_for = drive_back(link, path)
            if left_for or stopped_for:
                out.status = "handed_over" if left_for else "stopped"
                out.detail = (
                    f"the rover left OFFBOARD for {left_for} while driving back; nothing more sent"
                    if left_for
                    else f"driving back stopped: {stopped_for}; the rover was sent Hold"
                )
                return out
            dist, dhead = start_offset(link, path)
            if dist > START_TOLERANCE_M or abs(dhead) > START_TOLERANCE_RAD:
                out.status = "not_at_start"
                out.detail = (
                    f"driving back ended {dist:.1f} m from the path's start and {dhead:+.2f} "
                    f"rad off its heading, before trial {number}; the rover holds there: drive "
                    "it to the start and run again"
                )
                return out
        schedule = out.schedule_mps
        timeout_s = 4.0 * path.length_m / float(np.min(schedule)) + 30.0
        on_drive()
        drive = drive_path(
            link, path, schedule, nmpc, timeout_s=timeout_s, gp=gp, connect=False,
            feedforward=feedforward,
        )  # fmt: skip
        said = failsafe_heard(link, drive.left_offboard_for) if drive.left_offboard_for else ""
        trial = Trial(number, drive, schedule.copy(), len(gp))
        out.trials.append(trial)
        if scheduler is not None:
            out.schedule_mps = next_schedule(
                schedule, drive.vertex_e_lat_m, drive.vertex_e_head_rad, drive.vertex_w_cmd_radps,
                np.full(len(path), _PLENTY_OF_FEATURES), scheduler,
            )  # fmt: skip
        on_trial(trial, out.schedule_mps)
        if drive.left_offboard_for:
            out.status = "handed_over"
            why = f' (a PX4 failsafe: "{said}")' if said else ""
            out.detail = (
                f"the rover left OFFBOARD for {drive.left_offboard_for} during trial {number}"
                f"{why}; the run stopped there and sent nothing more"
            )
            return out
        if drive.stopped_for:
            out.status = "stopped"
            out.detail = f"trial {number} stopped: {drive.stopped_for}; the rover was sent Hold"
            return out
        if not drive.reached_end:
            out.status = "incomplete"
            out.detail = f"trial {number} did not reach the path's end within {timeout_s:.0f} s"
            return out
    out.detail = f"{trials} trial{'s' if trials > 1 else ''} driven"
    return out
