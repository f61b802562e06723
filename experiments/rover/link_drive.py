"""Repeat a taught path over any companion Link ([Ostafew16] on a PX4-like rover).

The same loop drives the in-process rover (companion.inprocess_rover_link, lockstep) and the
MAVLink rover (vehicle_sim.rover.mavlink_rover through companion.pymavlink_link, wall clock):
read the Link's state, turn NED position and yaw into the path frame (x north, y west, heading
counter-clockwise), localise against the nearest vertex, solve the unicycle NMPC for the turn
rate at the scheduled speed, and stream a NED velocity along the heading plus the yaw rate
(PX4 rover offboard). Optionally learns: pass a LocalGP and the experiences of this drive are
stored after it, as in experiments.rover.trial.

The drive never ends in a crash of the loop with the rover still moving: a lost link, a
non-finite pose or a failed NMPC solve commands a zero velocity and Hold, and is said in
``stopped_for``; Ctrl-C does the same, then is raised on. A pilot (or PX4's failsafe) taking
the rover out of OFFBOARD ends the drive with nothing more sent (``left_offboard_for``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from companion.link import Link, LinkError, VelocityCommand
from experiments.rover import learner
from experiments.rover.link_commands import start_driving, state_pose, stop_rover
from gp.local_gp import LocalGP
from planners.rover.path import TaughtPath, project_arc_length
from planners.rover.unicycle_nmpc import UnicycleNmpc, UnicycleNmpcConfig


@dataclass(frozen=True, eq=False)
class LinkDrive:
    """What one drive over a Link did: per control step (n,) arrays.

    Attributes:
        t_s: link time [s]; s_m: arc length [m]; e_lat_m, e_head_rad: [Ostafew16] errors
        against the path pose at the rover's projection (planners.rover.path; from the Link's
        own state) [m], [rad]; w_cmd_radps: commanded turn rate (path frame) [rad/s].
        vertex_e_lat_m, vertex_e_head_rad, vertex_w_cmd_radps: (N,) per path vertex the worst
        |e_L|, |e_H| and |omega_cmd| while localised to it (NaN where never passed): what the
        speed scheduler reads ([Ostafew16] eq. 31).
        reached_end: the rover reached the last vertices before the deadline.
        left_offboard_for: the mode the vehicle switched to by itself or by someone else (PX4's
        offboard-loss failsafe, a pilot, a ground station), which ended the drive; "" if none.
        stopped_for: why the companion stopped the rover (zero velocity and Hold) before the
        end: a lost link, a non-finite pose, a failed solve; "" if none.
    """

    t_s: np.ndarray
    s_m: np.ndarray
    e_lat_m: np.ndarray
    e_head_rad: np.ndarray
    w_cmd_radps: np.ndarray
    vertex_e_lat_m: np.ndarray
    vertex_e_head_rad: np.ndarray
    vertex_w_cmd_radps: np.ndarray
    reached_end: bool
    left_offboard_for: str = ""
    stopped_for: str = ""

    @property
    def travel_time_s(self) -> float:
        """Time from the first to the last control step [s] (0 without steps)."""
        return float(self.t_s[-1] - self.t_s[0]) if len(self.t_s) else 0.0


def drive_path(
    link: Link,
    path: TaughtPath,
    speed_mps: float | np.ndarray,
    nmpc: UnicycleNmpcConfig = UnicycleNmpcConfig(),  # noqa: B008 (frozen)
    timeout_s: float = 120.0,
    gp: LocalGP | None = None,
    connect: bool = True,
    feedforward: bool = False,
) -> LinkDrive:
    """Arm, switch to OFFBOARD and follow ``path``; then hold.

    ``speed_mps`` is one speed for the whole path or a schedule (N,) per vertex [m/s] (the
    horizon takes the scheduled speeds ahead, as experiments.rover.trial does). ``connect``
    False: the Link is connected already (a later trial on the same Link). ``feedforward``:
    the NMPC's turn-rate penalty is measured from the path's v * curvature ahead, as
    experiments.rover.trial does for a tuning chosen with it (tuning.RoverTuning).

    Once the vehicle has reported OFFBOARD, a report of another mode ends the drive at once,
    with nothing more sent (the companion never fights a pilot or a failsafe): the mode is in
    ``left_offboard_for``.

    Raises:
        LinkError: the Link cannot connect or refuses arming or OFFBOARD (its reason in the
            message); nothing was driven.
    """
    schedule = np.broadcast_to(np.asarray(speed_mps, dtype=float), (len(path),)).copy()
    if not np.all(np.isfinite(schedule)) or not np.all(schedule > 0):
        raise ValueError(f"speeds must be finite and > 0 m/s, got {speed_mps}")
    clock, dt = link.clock, nmpc.dt_s
    if connect:
        link.connect(timeout_s=min(timeout_s, 30.0))
    start_driving(link)
    solver = UnicycleNmpc(nmpc)
    K, N = nmpc.horizon, len(path)
    curvature = path.curvature_1pm()
    window = min(40, N // 2)  # a loop's end must not be found at its start
    t_end = clock.now_s() + timeout_s
    hint, w_prev, pose_prev, pending = 0, 0.0, None, None
    out: dict[str, list[float]] = {k: [] for k in ("t", "s", "el", "eh", "w")}
    worst = {k: np.full(N, np.nan) for k in ("el", "eh", "w")}
    experiences: list = []
    reached, seen_offboard, left_for, stopped_for = False, False, "", ""
    t_next = clock.now_s()
    try:
        while clock.now_s() < t_end:
            st = link.read_state()
            seen_offboard = seen_offboard or st.mode == "OFFBOARD"
            if seen_offboard and st.mode != "OFFBOARD":
                left_for = st.mode
                break
            if not st.is_finite():
                stopped_for = f"the rover's pose is not finite at t={st.t_s:.1f} s"
                break
            pose = state_pose(st)
            pose_prev = pose if pose_prev is None else pose_prev
            fix = path.localise(*pose, hint=hint, window=window)
            on_path = path.localise_on_path(*pose, hint=hint, window=window)
            hint = fix.vertex
            if pending is not None and gp is not None:
                vtx, v_c, a_prev, pose_k, w_c = pending
                g = learner.observed_disturbance(pose_k, pose, v_c, w_c, dt)
                experiences.append((vtx, v_c, a_prev, g))
            if fix.vertex >= N - 2:
                reached = True
                break
            v_now = float(schedule[fix.vertex])
            s_ahead = fix.s_m + v_now * dt * np.arange(K)
            v_h = np.interp(s_ahead, path.s_m, schedule)
            w_ref = v_h * np.interp(s_ahead, path.s_m, curvature) if feedforward else None

            def reference(poses: np.ndarray, vertex: int = fix.vertex) -> np.ndarray:
                return path.ref_at(project_arc_length(path, poses[:, :2], vertex, window))

            try:  # the local GP's factorisation and the NMPC iterations
                model = learner.LocalDisturbance(gp, fix.vertex, v_now) if gp is not None else None
                w = float(
                    solver.solve(pose, v_h, reference, w_prev, pose_prev=pose_prev,
                                 s0_m=fix.s_m, model=model, ref0=np.array(path.pose(fix.vertex)),
                                 omega_ref_radps=w_ref)[0]
                )  # fmt: skip
            except (ArithmeticError, ValueError, RuntimeError, np.linalg.LinAlgError) as exc:
                stopped_for = f"the NMPC solve failed at t={st.t_s:.1f} s: {exc}"
                break
            if not math.isfinite(w):
                stopped_for = f"the NMPC solve gave a non-finite turn rate at t={st.t_s:.1f} s"
                break
            a_k = learner.experience_query(
                fix.s_m, fix.e_lat_m, fix.e_head_rad, pose_prev, pose, v_now, w, w_prev, dt
            )
            pending = (fix.vertex, v_now, a_k, pose.copy(), w)
            yaw = -pose[2]
            link.send_velocity(
                VelocityCommand((v_now * math.cos(yaw), v_now * math.sin(yaw), 0.0), -w)
            )
            i = fix.vertex
            for key, val in (("el", on_path.e_lat_m), ("eh", on_path.e_head_rad), ("w", w)):
                worst[key][i] = np.nanmax([worst[key][i], abs(val)])
            for key, val in (("t", clock.now_s()), ("s", on_path.s_m), ("el", on_path.e_lat_m),
                             ("eh", on_path.e_head_rad), ("w", w)):  # fmt: skip
                out[key].append(val)
            pose_prev, w_prev = pose, w
            t_next += dt
            clock.sleep_until(t_next)
    except LinkError as exc:
        stopped_for = str(exc)
    except KeyboardInterrupt:
        stop_rover(link)
        raise
    if left_for:
        link.stop_streaming()
    elif stopped_for:
        stop_rover(link)
    else:
        link.hold()
    if gp is not None:
        learner.store_pass(gp, experiences)
    arr = {k: np.asarray(v, dtype=float) for k, v in out.items()}
    return LinkDrive(
        arr["t"], arr["s"], arr["el"], arr["eh"], arr["w"], worst["el"], worst["eh"], worst["w"],
        reached, left_for, stopped_for,
    )  # fmt: skip
