"""Repeat a taught path over any companion Link ([Ostafew16] on a PX4-like rover).

The same loop drives the in-process rover (companion.inprocess_rover_link, lockstep) and the
MAVLink rover (vehicle_sim.rover.mavlink_rover through companion.pymavlink_link, wall clock):
read the Link's state, turn NED position and yaw into the path frame (x north, y west, heading
counter-clockwise), localise against the nearest vertex, solve the unicycle NMPC for the turn
rate at the scheduled speed, and stream a NED velocity along the heading plus the yaw rate
(PX4 rover offboard). Optionally learns: pass a LocalGP and the experiences of this drive are
stored after it, as in experiments.rover.trial.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from companion.link import Link, LinkError, LinkState, VelocityCommand
from experiments.rover import learner
from gp.local_gp import LocalGP
from planners.rover.path import TaughtPath, project_arc_length
from planners.rover.unicycle_nmpc import UnicycleNmpc, UnicycleNmpcConfig


@dataclass(frozen=True, eq=False)
class LinkDrive:
    """What one drive over a Link did: per control step (n,) arrays.

    Attributes:
        t_s: link time [s]; s_m: arc length; e_lat_m, e_head_rad: [Ostafew16] errors against
        the path (from the Link's own state); w_cmd_radps: commanded turn rate (path frame).
        reached_end: the rover reached the last vertices before the deadline.
        left_offboard_for: the mode the vehicle switched to by itself or by someone else (PX4's
        offboard-loss failsafe, a pilot, a ground station), which ended the drive; "" if none.
    """

    t_s: np.ndarray
    s_m: np.ndarray
    e_lat_m: np.ndarray
    e_head_rad: np.ndarray
    w_cmd_radps: np.ndarray
    reached_end: bool
    left_offboard_for: str = ""


def pose_of(link: Link) -> np.ndarray:
    """(x_m, y_m, heading_rad) in the path frame from the Link's NED state."""
    return _pose(link.read_state())


def _pose(st: LinkState) -> np.ndarray:
    return np.array([st.pos_ned_m[0], -st.pos_ned_m[1], -st.yaw_rad])


def drive_path(
    link: Link,
    path: TaughtPath,
    speed_mps: float,
    nmpc: UnicycleNmpcConfig = UnicycleNmpcConfig(),  # noqa: B008 (frozen)
    timeout_s: float = 120.0,
    gp: LocalGP | None = None,
) -> LinkDrive:
    """Connect, arm, switch to OFFBOARD and follow ``path`` at ``speed_mps``; then hold.

    Once the vehicle has reported OFFBOARD, a report of another mode ends the drive at once,
    with nothing more sent (the companion never fights a pilot or a failsafe): the mode is in
    ``left_offboard_for``.

    Raises:
        LinkError: the Link refuses arming or OFFBOARD (its reason in the message).
    """
    if not speed_mps > 0:
        raise ValueError(f"speed_mps must be > 0, got {speed_mps}")
    clock, dt = link.clock, nmpc.dt_s
    link.connect(timeout_s=min(timeout_s, 30.0))
    link.send_velocity(VelocityCommand((0.0, 0.0, 0.0), 0.0))
    for what, outcome in (("arm", link.arm), ("offboard", link.start_offboard)):
        result = outcome()
        if not result.accepted:
            raise LinkError(f"rover refused {what}: {result.detail or 'no reason given'}")
    solver = UnicycleNmpc(nmpc)
    K, N = nmpc.horizon, len(path)
    t_end = clock.now_s() + timeout_s
    hint, w_prev, pose_prev, pending = 0, 0.0, None, None
    out: dict[str, list[float]] = {k: [] for k in ("t", "s", "el", "eh", "w")}
    experiences: list = []
    reached, seen_offboard, left_for = False, False, ""
    t_next = clock.now_s()
    while clock.now_s() < t_end:
        st = link.read_state()
        seen_offboard = seen_offboard or st.mode == "OFFBOARD"
        if seen_offboard and st.mode != "OFFBOARD":
            left_for = st.mode
            break
        pose = _pose(st)
        pose_prev = pose if pose_prev is None else pose_prev
        fix = path.localise(*pose, hint=hint)
        hint = fix.vertex
        if pending is not None and gp is not None:
            vtx, a_prev, pose_k, w_c = pending
            g = learner.observed_disturbance(pose_k, pose, speed_mps, w_c, dt)
            experiences.append((vtx, speed_mps, a_prev, g))
        if fix.vertex >= N - 2:
            reached = True
            break
        v_h = np.full(K, speed_mps)
        model = learner.LocalDisturbance(gp, fix.vertex, speed_mps) if gp is not None else None

        def reference(poses: np.ndarray, vertex: int = fix.vertex) -> np.ndarray:
            return path.ref_at(project_arc_length(path, poses[:, :2], vertex))

        w = float(
            solver.solve(pose, v_h, reference, w_prev, pose_prev=pose_prev, s0_m=fix.s_m,
                         model=model, ref0=np.array(path.pose(fix.vertex)))[0]
        )  # fmt: skip
        a_k = learner.experience_query(
            fix.s_m, fix.e_lat_m, fix.e_head_rad, pose_prev, pose, speed_mps, w, w_prev, dt
        )
        pending = (fix.vertex, a_k, pose.copy(), w)
        yaw = -pose[2]
        link.send_velocity(
            VelocityCommand((speed_mps * math.cos(yaw), speed_mps * math.sin(yaw), 0.0), -w)
        )
        for key, val in (("t", clock.now_s()), ("s", fix.s_m), ("el", fix.e_lat_m),
                         ("eh", fix.e_head_rad), ("w", w)):  # fmt: skip
            out[key].append(val)
        pose_prev, w_prev = pose, w
        t_next += dt
        clock.sleep_until(t_next)
    if left_for:
        link.stop_streaming()
    else:
        link.hold()
    if gp is not None:
        learner.store_pass(gp, experiences)
    arr = {k: np.asarray(v, dtype=float) for k, v in out.items()}
    return LinkDrive(arr["t"], arr["s"], arr["el"], arr["eh"], arr["w"], reached, left_for)
