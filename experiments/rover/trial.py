"""Repeat a taught path trial after trial with the LB-NMPC ([Ostafew16] sections 3-4).

Each control step (``dt_s``): localise against the nearest vertex (VT&R stand-in:
experiments.rover.localisation), take the scheduled speed there, build ONE local GP from the
experience bins at (vertex, speed bin), solve the unicycle NMPC for the turn rates (the
disturbance is predicted along each Gauss-Newton iterate; with ``gp_jacobian`` its derivatives
enter the step too), send (speed, turn rate) to the rover and, one step later, record the
observed disturbance. After the pass the experiences go into the bins (the next trials learn
from them) and the speed scheduler (if any) sets the next trial's speeds from the per-vertex
records.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from experiments.rover import learner
from experiments.rover.localisation import LocalisationError
from experiments.rover.scenarios import RoverScenario
from gp.local_gp import LocalGP
from planners.rover.path import LocalisationQuality, project_arc_length
from planners.rover.speed_governor import SpeedGovernor
from planners.rover.speed_scheduler import initial_schedule, next_schedule
from planners.rover.unicycle_nmpc import UnicycleNmpc
from vehicle_sim.rover import RoverSim, rover_preset


@dataclass(frozen=True, eq=False)
class TrialRecord:
    """One trial; per-step arrays (n,) and per-vertex worst records (N,).

    Attributes:
        s_m, e_lat_m, e_head_rad, w_cmd_radps, v_cmd_mps, features: per control step,
            errors of the TRUE pose against the path pose at its projection (what [Ostafew16]
            section 4.2 records when passing a vertex; planners.rover.path).
        e_lat_est_m, e_head_est_rad: per control step, the errors as the robot's localisation
            (the VT&R stand-in) measures them: what [Ostafew16] reports ("quantified by the
            localization of the VT&R algorithm", section 5.1), having no ground truth.
        n_local: experiences in the local GP used at each step.
        step_time_s: wall time of GP + NMPC per step (for bench only).
        step_cpu_s: CPU time of this thread in the same span (for bench only): what the step
            costs, without the time it waited for a core on a loaded machine.
        schedule_mps: the speeds this trial was driven with, per vertex.
        vertex_e_lat_m, vertex_e_head_rad, vertex_w_cmd_radps, vertex_features: per vertex
            (the vertex the robot localised to), the worst |e_L|, |e_H| as the localisation
            measures them, |omega_cmd| and the fewest matched features: what eq. 31 reads
            ([Ostafew16] section 4.2 records e_L, e_H "when passing the ith vertex", from
            VT&R; the robot has no other measure of them).
        travel_time_s: time to reach the end of the path.
        completed: reached the end before the time limit.
        safety_trips: how often the safety governor dropped the speed to v_init in this pass
            (planners.rover.speed_governor; 0 without a scheduler).
    """

    s_m: np.ndarray
    e_lat_m: np.ndarray
    e_head_rad: np.ndarray
    w_cmd_radps: np.ndarray
    v_cmd_mps: np.ndarray
    features: np.ndarray
    n_local: np.ndarray
    step_time_s: np.ndarray
    step_cpu_s: np.ndarray
    schedule_mps: np.ndarray
    vertex_e_lat_m: np.ndarray
    vertex_e_head_rad: np.ndarray
    vertex_w_cmd_radps: np.ndarray
    vertex_features: np.ndarray
    travel_time_s: float
    completed: bool
    e_lat_est_m: np.ndarray
    e_head_est_rad: np.ndarray
    safety_trips: int = 0

    @property
    def max_e_lat_est_m(self) -> float:
        return float(np.max(np.abs(self.e_lat_est_m)))

    @property
    def max_e_head_est_rad(self) -> float:
        return float(np.max(np.abs(self.e_head_est_rad)))

    @property
    def max_e_lat_m(self) -> float:
        return float(np.max(np.abs(self.e_lat_m)))

    @property
    def max_e_head_rad(self) -> float:
        return float(np.max(np.abs(self.e_head_rad)))

    @property
    def rms_e_lat_m(self) -> float:
        return float(np.sqrt(np.mean(self.e_lat_m**2)))

    @property
    def rms_e_head_rad(self) -> float:
        return float(np.sqrt(np.mean(self.e_head_rad**2)))


def run_trial(
    sc: RoverScenario,
    gp: LocalGP,
    schedule_mps: np.ndarray,
    trial_index: int,
    quality: LocalisationQuality = LocalisationQuality(),  # noqa: B008 (frozen)
) -> TrialRecord:
    """Drive the path once; adds this trial's experiences to ``gp`` (if learning)."""
    path, cfg = sc.path, sc.nmpc
    rng = np.random.default_rng([sc.seed, trial_index])
    x0, y0, th0 = path.pose(0)
    start = (x0 + rng.normal(0, 0.02), y0 + rng.normal(0, 0.02), th0 + rng.normal(0, 0.02))
    sim = RoverSim(rover_preset(sc.preset), sc.effects, seed=sc.seed * 1000 + trial_index,
                   pose=start)  # fmt: skip
    sim.arm()
    loc_error = LocalisationError(sc.localisation, sc.dt_s, rng)
    nmpc = UnicycleNmpc(cfg)
    governor = (
        SpeedGovernor(sc.scheduler, sc.governor_trip_factor)
        if sc.scheduler is not None and sc.governor_trip_factor is not None
        else None
    )
    K, dt, N = cfg.horizon, sc.dt_s, len(path)
    curvature = path.curvature_1pm()
    rec = {k: [] for k in ("s", "el", "eh", "w", "v", "f", "n", "t", "cpu", "el_est", "eh_est")}
    worst = {
        "el": np.full(N, np.nan), "eh": np.full(N, np.nan),
        "w": np.full(N, np.nan), "f": np.full(N, np.nan),
    }  # fmt: skip
    hint, w_prev, pose_prev, pending = 0, 0.0, None, None
    experiences: list = []
    t_limit = 4.0 * path.length_m / max(float(np.min(schedule_mps)), 0.1) + 20.0
    completed = False
    while sim.state.t_s < t_limit:
        st = sim.state
        truth = np.array([st.x_m, st.y_m, st.heading_rad])
        est = truth + loc_error.draw()
        if pose_prev is None:
            pose_prev = est.copy()
        fix = path.localise(*est, hint=hint)  # the controller's frame: the nearest vertex
        # what is recorded and scheduled on: errors against the path pose at the projection,
        # [Ostafew16] section 4.2's "when passing the ith vertex" (planners.rover.path)
        est_fix = path.localise_on_path(*est, hint=hint)
        true_fix = path.localise_on_path(*truth, hint=hint)
        hint = fix.vertex
        if pending is not None and sc.learning:  # experience of the previous step
            vtx, v_c, a_prev, pose_k, w_c = pending
            g_obs = learner.observed_disturbance(pose_k, est, v_c, w_c, dt)
            experiences.append((vtx, v_c, a_prev, g_obs))
        if fix.vertex >= N - 2:
            completed = True
            break
        t0, cpu0 = time.perf_counter(), time.thread_time()
        cap = np.inf if governor is None else governor.cap_mps(est_fix.e_lat_m, est_fix.e_head_rad)
        v_now = min(float(schedule_mps[fix.vertex]), cap)
        s_ahead = fix.s_m + v_now * dt * np.arange(K)
        v_h = np.minimum(np.interp(s_ahead, path.s_m, schedule_mps), cap)
        model = (
            learner.LocalDisturbance(gp, fix.vertex, v_now, sc.gp_jacobian) if sc.learning else None
        )

        def reference(poses: np.ndarray, vertex: int = fix.vertex) -> np.ndarray:
            return path.ref_at(project_arc_length(path, poses[:, :2], vertex))

        w = nmpc.solve(
            est,
            v_h,
            reference,
            w_prev,
            pose_prev=pose_prev,
            s0_m=fix.s_m,
            model=model,
            ref0=np.array(path.pose(fix.vertex)),
            omega_ref_radps=v_h * np.interp(s_ahead, path.s_m, curvature)
            if sc.feedforward
            else None,
        )
        step_time, step_cpu = time.perf_counter() - t0, time.thread_time() - cpu0
        n_local = model.n_experiences if model is not None else 0
        w_cmd = float(w[0])
        a_k = learner.experience_query(
            fix.s_m, fix.e_lat_m, fix.e_head_rad, pose_prev, est, v_now, w_cmd, w_prev, dt
        )
        pending = (fix.vertex, v_now, a_k, est.copy(), w_cmd)
        feats = quality.count(sc.lighting[fix.vertex], true_fix.e_lat_m, true_fix.e_head_rad,
                              st.speed_mps)  # fmt: skip
        i = fix.vertex  # the scheduler has what the robot has: its localised errors
        worst["el"][i] = np.nanmax([worst["el"][i], abs(est_fix.e_lat_m)])
        worst["eh"][i] = np.nanmax([worst["eh"][i], abs(est_fix.e_head_rad)])
        worst["w"][i] = np.nanmax([worst["w"][i], abs(w_cmd)])
        worst["f"][i] = np.nanmin([worst["f"][i], feats])
        for key, val in (("s", true_fix.s_m), ("el", true_fix.e_lat_m),
                         ("eh", true_fix.e_head_rad), ("w", w_cmd), ("v", v_now),
                         ("f", feats), ("n", n_local), ("t", step_time), ("cpu", step_cpu),
                         ("el_est", est_fix.e_lat_m), ("eh_est", est_fix.e_head_rad)):  # fmt: skip
            rec[key].append(val)
        sim.set_setpoint(v_now, w_cmd)
        sim.step(dt)
        pose_prev, w_prev = est, w_cmd
    if sc.learning:  # this pass's experiences serve the next trials ([Ostafew16] D^(j))
        learner.store_pass(gp, experiences)
    arr = {k: np.asarray(v, dtype=float) for k, v in rec.items()}
    return TrialRecord(
        arr["s"], arr["el"], arr["eh"], arr["w"], arr["v"], arr["f"], arr["n"].astype(int),
        arr["t"], arr["cpu"], np.asarray(schedule_mps, dtype=float).copy(), worst["el"],
        worst["eh"], worst["w"], worst["f"], float(sim.state.t_s), completed, arr["el_est"],
        arr["eh_est"], 0 if governor is None else governor.trips,
    )  # fmt: skip


def run_trials(
    sc: RoverScenario,
    gp: LocalGP | None = None,
    progress: Callable[[str], None] = lambda message: None,
) -> list[TrialRecord]:
    """All trials of a scenario; the schedule follows eq. 31 when the scenario has a scheduler.
    ``progress`` gets one line per trial driven."""
    gp = learner.make_history_gp() if gp is None else gp
    N = len(sc.path)
    if sc.scheduler is None:
        schedule = np.full(N, sc.fixed_speed_mps)
    else:
        schedule = initial_schedule(N, sc.scheduler)
    out = []
    for j in range(sc.trials):
        r = run_trial(sc, gp, schedule, j)
        out.append(r)
        progress(
            f"trial {j + 1}/{sc.trials}: max |e_L| {r.max_e_lat_m:.3f} m, max |e_H| "
            f"{r.max_e_head_rad:.3f} rad, {r.travel_time_s:.1f} s"
            + ("" if r.completed else ", did not reach the end")
        )
        if sc.scheduler is not None:
            schedule = next_schedule(
                schedule, r.vertex_e_lat_m, r.vertex_e_head_rad, r.vertex_w_cmd_radps,
                r.vertex_features, sc.scheduler,
            )  # fmt: skip
    return out
