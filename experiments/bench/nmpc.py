"""NMPC benchmark (`bench --only nmpc`): fast solver path vs IPOPT on one set of problems.

Problems: [Kulathunga23]'s planner (4-DOF kinematic model, N = 20, dt = 0.1 s, 10 obstacle slots
per node, d_o = 0.5 m) with a GP-like residual of the velocity: an SE-kernel mean
sum_i alpha_i k(v, Z_i) with 30 seeded inducing points Z_i and 3 outputs (the form the gp
package exports). A closed loop flown by the fast planner on the residual-augmented plant,
at one plan per 0.1 s, along a seeded 40-60 m B-spline through a seeded forest of vertical
cylinders, some standing on the path (constraints active in about a third of the plans),
records the (state, time) pairs; the IPOPT planner (CasADi defaults) then solves the same
sequence, warm-started the same way. The fast path is the default configuration: one
Gauss-Newton SQP iteration per plan (more on a cold start), CasADi virtual machine. Times are
wall-clock per plan() call, everything included. The fast path's closed loop runs as the
companion runs its planner: one plan per control tick (50 Hz, sleeping in between) in a thread
at the companion's real-time priority (companion.realtime; where the system does not permit it,
the progress line says so and the loop runs at normal priority); IPOPT and acados solve the
same problems back to back at normal priority, then once more paced as the fast path was (one
plan per 50 Hz tick at the same priority): a plan after a 20 ms sleep finds its code gone
cold and pays about the same extra milliseconds whichever solver it runs (0.8-1.0 ms for the
fast path and for IPOPT alike on the 2-core machine of BENCHMARKS.md), so each solver is
compared with the others on the same footing. Figures:
    nmpc_fast_median_ms, nmpc_fast_p99_ms   time per plan() of the fast path [ms]
    nmpc_ipopt_median_ms                    time per plan() of IPOPT [ms]
    nmpc_fast_ok_fraction, nmpc_ipopt_ok_fraction   plans returned with ok=True [-]
    nmpc_cmd_diff_median_mps                median |command difference| fast vs IPOPT [m/s]
    nmpc_augmented_median_ms, nmpc_augmented_p99_ms, nmpc_augmented_ipopt_median_ms
                                            the same three on this GP-augmented problem, under
                                            issue 17's names (the planner the companion flies
                                            with a learned model is this fast path)
    nmpc_augmented_ipopt_paced_median_ms, nmpc_acados_paced_median_ms
                                            IPOPT and acados (NaN when missing) paced like the
                                            fast path: the like-for-like peers of
                                            nmpc_augmented_median_ms [ms]
    nmpc_augmented_cpu_p99_ms               the fast path's own CPU time per plan() (its thread's
                                            CPU clock), p99 [ms]: the wall-clock tail minus
                                            the time the process waited for a core
    nmpc_augmented_preempted_fraction       plans during which the operating system switched
                                            the planner's thread out for another runnable
                                            process (involuntary context switches) [-]
    nmpc_augmented_normal_priority_median_ms, nmpc_augmented_normal_priority_p99_ms
                                            the fast path on the same problems, back to back
                                            at normal priority (how it ran before issue 17) [ms]
    nmpc_augmented_paced_code_warm_median_ms
                                            the fast path paced once more, a twin planner
                                            (same shape, its own buffers) having just solved
                                            the same problem, untimed: how much of the paced
                                            plans' extra time is code and shared objects gone
                                            cold during the 20 ms away [ms]
    nmpc_augmented_ipopt_over_fast_paced, nmpc_augmented_ipopt_over_fast_back_to_back
                                            IPOPT's median over the fast path's, both paced,
                                            and both back to back [-] (issue 17's ">= 10x")
    nmpc_acados_median_ms, nmpc_acados_p99_ms   acados SQP_RTI + HPIPM (the peer, see
                                            experiments.bench.acados_peer) in the same planner,
                                            on the same problems; NaN when acados is missing
    nmpc_acados_solve_median_ms             acados' own solve time (time_tot, C only), without
                                            the per-stage Python set/get of its interface [ms]
    nmpc_acados_build_s                     acados: generate and compile its solver [s]
    nmpc_acados_cmd_diff_median_mps         median |command difference| acados vs IPOPT [m/s]
    nmpc_model_ready_s                      a new residual model file (first_order_lag +
                                            state_input features, m = 30 per output) to the
                                            companion's planner ready to fly (loaded, built,
                                            one warm-up plan) [s]
    nmpc_model_ready_peak_mib               the memory that takes: the rise of the peak
                                            resident set of a fresh process over its own
                                            peak after the imports (the baseline) [MiB]
    nmpc_learned_<regime>_median_ms, _p99_ms, _cpu_p99_ms
                                            the companion's planner (fast path, batched
                                            linearisation) with a learned model of each study
                                            regime's shape (REGIME_SHAPES: first_order_lag +
                                            the regime's features and m), back to back on one
                                            closed loop of 50 Hz plans: wall and CPU time
    nmpc_learned_<regime>_symbolic_median_ms, _symbolic_cpu_p99_ms
                                            the same planner and problems with the symbolic
                                            linearisation (the path before issue 17's session
                                            7, still the reference)
    nmpc_learned_<regime>_cmd_diff_max_mps  max |command difference| batched vs symbolic [m/s]
``quick=True`` flies 3 s instead of 30 s, for a smoke test.
"""

from __future__ import annotations

import dataclasses
import multiprocessing
import resource
import tempfile
import time
from collections.abc import Callable
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import casadi as ca
import numpy as np

from companion.nmpc_planner import CompanionNmpc, NmpcSettings, load_nmpc
from companion.realtime import realtime_section
from companion.runner import COMPANION_RT_PRIORITY
from experiments.bench.acados_peer import AcadosSolver, acados_unavailable, c_stdout_to_stderr
from gp.features import feature_definition
from gp.model_io import ResidualModel, save_model
from gp.posterior import Posterior
from planners.nmpc import NmpcPlanner
from planners.nmpc_formulation import NmpcConfig
from planners.nominal_models import kinematic_4dof
from planners.obstacles import random_forest
from planners.reference import PlannerState
from planners.residual import ResidualTerm
from planners.sqp_solver import GaussNewtonSqp, SqpOptions
from planners.trajectory_generator import generate_trajectories

_N_INDUCING = 30
_RESIDUAL_DT_S = 0.05
_PLAN_DT_S = 0.1
_TICK_S = 0.02  # the companion's control period: one plan per tick [s]


def gp_like_residual(seed: int = 0) -> ca.Function:
    """SE-kernel mean g(v) = k(v, Z) @ alpha, Z (30, 3) [m/s], alpha (30, 3) [m/s^2]."""
    rng = np.random.default_rng(seed)
    inducing = rng.uniform(-1.5, 1.5, (_N_INDUCING, 3))
    alpha = rng.normal(0.0, 0.5, (_N_INDUCING, 3))
    v = ca.SX.sym("v", 3)
    sq_dist = ca.sum2((ca.repmat(v.T, _N_INDUCING, 1) - ca.DM(inducing)) ** 2)
    k = 0.5 * ca.exp(-0.5 * sq_dist / 0.7**2)
    return ca.Function("gp_like_mean", [v], [(k.T @ ca.DM(alpha)).T], ["v"], ["mean"])


def run(progress: Callable[[str], None] = print, quick: bool = False) -> dict[str, float]:
    """Run the NMPC benchmark; returns the figures named in the module docstring."""
    model = kinematic_4dof(_RESIDUAL_DT_S)
    gp = gp_like_residual()
    residual = ResidualTerm.of_velocity(gp, model)
    reference = generate_trajectories(1, seed=11)[0]
    path = reference.sample(np.linspace(0.0, reference.duration_s, 500)).pos_ned_m
    world = random_forest(path, n_trees=80, seed=5, keep_out_m=-0.3, spread_m=5.0)
    base = NmpcConfig(n_obstacles=10, safe_distance_m=0.5)
    progress("nmpc: building the planners")
    fast = NmpcPlanner(model, base, residual, world)
    ipopt = NmpcPlanner(
        model, dataclasses.replace(base, solver="ipopt", time_budget_s=10.0), residual, world
    )

    t_end = 3.0 if quick else 30.0
    progress(f"nmpc: fast planner closed loop, {t_end:.0f} s at {1 / _PLAN_DT_S:.0f} Hz")
    x = reference.x_ref(0.0)
    fast.plan(PlannerState(x[:3], np.zeros(3), x[3]), reference, 0.0)  # first call: setup
    fast.reset()
    problems, fast_res, cpu_ms, preempted = [], [], [], []
    with realtime_section(COMPANION_RT_PRIORITY, "nmpc: fast planner", progress):
        tick_due_s = time.monotonic()
        for k in range(int(round(t_end / _PLAN_DT_S))):
            time.sleep(max(0.0, tick_due_s - time.monotonic()))
            tick_due_s = max(tick_due_s + _TICK_S, time.monotonic())
            t = k * _PLAN_DT_S
            state = PlannerState(x[:3].copy(), np.zeros(3), float(x[3]))
            switches = _involuntary_switches()
            cpu_start = time.thread_time()
            res = fast.plan(state, reference, t)
            cpu_ms.append(1e3 * (time.thread_time() - cpu_start))
            preempted.append(_involuntary_switches() > switches)
            problems.append((state, t))
            fast_res.append(res)
            u = res.command
            vel = u[:3] + _RESIDUAL_DT_S * np.asarray(gp(u[:3])).ravel()
            x = x + _PLAN_DT_S * np.append(vel, u[3])
    fast.reset()
    normal_ms = 1e3 * np.array([fast.plan(s, reference, t).solve_time_s for s, t in problems])
    progress("nmpc: the fast planner paced again, a twin planner solving each problem first")
    twin = NmpcPlanner(model, base, residual, world)
    code_warm_ms = _paced_replay(fast, problems, reference, "nmpc: code warm", progress, twin)

    progress(f"nmpc: IPOPT on the same {len(problems)} problems")
    ipopt_res = [ipopt.plan(state, reference, t) for state, t in problems]
    progress(f"nmpc: IPOPT on the same {len(problems)} problems, paced at 50 Hz")
    ipopt_paced_ms = _paced_replay(ipopt, problems, reference, "nmpc: IPOPT", progress)
    fast_ms = 1e3 * np.array([r.solve_time_s for r in fast_res])
    ipopt_ms = 1e3 * np.array([r.solve_time_s for r in ipopt_res])
    figures = {
        "nmpc_fast_median_ms": float(np.median(fast_ms)),
        "nmpc_fast_p99_ms": float(np.percentile(fast_ms, 99)),
        "nmpc_ipopt_median_ms": float(np.median(ipopt_ms)),
        "nmpc_fast_ok_fraction": float(np.mean([r.ok for r in fast_res])),
        "nmpc_ipopt_ok_fraction": float(np.mean([r.ok for r in ipopt_res])),
        "nmpc_cmd_diff_median_mps": _cmd_diff(fast_res, ipopt_res),
    }
    figures["nmpc_augmented_median_ms"] = figures["nmpc_fast_median_ms"]
    figures["nmpc_augmented_p99_ms"] = figures["nmpc_fast_p99_ms"]
    figures["nmpc_augmented_ipopt_median_ms"] = figures["nmpc_ipopt_median_ms"]
    figures["nmpc_augmented_ipopt_paced_median_ms"] = float(np.median(ipopt_paced_ms))
    figures["nmpc_augmented_cpu_p99_ms"] = float(np.percentile(cpu_ms, 99))
    figures["nmpc_augmented_preempted_fraction"] = float(np.mean(preempted))
    figures["nmpc_augmented_normal_priority_median_ms"] = float(np.median(normal_ms))
    figures["nmpc_augmented_normal_priority_p99_ms"] = float(np.percentile(normal_ms, 99))
    figures["nmpc_augmented_paced_code_warm_median_ms"] = float(np.median(code_warm_ms))
    figures["nmpc_augmented_ipopt_over_fast_paced"] = (
        figures["nmpc_augmented_ipopt_paced_median_ms"] / figures["nmpc_augmented_median_ms"]
    )
    figures["nmpc_augmented_ipopt_over_fast_back_to_back"] = figures[
        "nmpc_augmented_ipopt_median_ms"
    ] / float(np.median(normal_ms))
    figures.update(_acados_figures(model, base, residual, world, problems, ipopt_res, progress))
    progress("nmpc: a new model file to a planner ready to fly")
    figures["nmpc_model_ready_s"] = model_ready_s()
    figures["nmpc_model_ready_peak_mib"] = model_ready_peak_mib()
    for regime, (features_name, m) in REGIME_SHAPES.items():
        progress(f"nmpc: {regime}'s learned model shape ({features_name}, m = {m})")
        figures |= learned_model_figures(regime, features_name, m, 40 if quick else 300)
    return figures


# Each study regime's learned model: (features, m per output) (experiments.study.regimes)
REGIME_SHAPES: dict[str, tuple[str, int]] = {
    "paper000": ("velocity", 30),
    "agile": ("velocity", 30),
    "wind_field": ("position_velocity", 60),
}


def learned_model_figures(regime: str, features_name: str, m: int, n_plans: int) -> dict:
    """The companion's planner with a learned model of this shape, batched vs symbolic
    linearisation, on the same ``n_plans`` problems (a closed loop at 50 Hz along a seeded
    trajectory, the vehicle a first-order lag of 0.5 s), back to back at normal priority."""
    settings = NmpcSettings(speed_limit_mps=4.0, time_budget_s=10.0)
    companion = CompanionNmpc(settings, flying_model(m, 3, features_name))
    f = companion._planner.formulation
    planners = {
        kind: NmpcPlanner(
            f.model,
            f.config,
            f.residual,
            solver_factory=lambda form, k=kind: GaussNewtonSqp(form, SqpOptions(linearisation=k)),
        )
        for kind in ("batched", "symbolic")
    }
    reference = generate_trajectories(1, seed=11)[0]
    pos, vel, problems = reference.x_ref(0.0)[:3], np.zeros(3), []
    for k in range(n_plans):  # the problems: the batched planner's own closed loop
        state = PlannerState(pos.copy(), vel.copy(), 0.0)
        problems.append((state, k * _TICK_S))
        command = planners["batched"].plan(state, reference, k * _TICK_S).command[:3]
        vel = vel + _TICK_S * (command - vel) / 0.5
        pos = pos + _TICK_S * vel
    timing, commands = {}, {}
    for kind, planner in planners.items():
        planner.reset()
        wall, cpu, out = [], [], []
        for state, t in problems:
            cpu_start = time.thread_time()
            result = planner.plan(state, reference, t)
            cpu.append(1e3 * (time.thread_time() - cpu_start))
            wall.append(1e3 * result.solve_time_s)
            out.append(result.command)
        timing[kind], commands[kind] = (np.array(wall), np.array(cpu)), np.array(out)
    prefix = f"nmpc_learned_{regime}"
    (wall, cpu), (sym_wall, sym_cpu) = timing["batched"], timing["symbolic"]
    return {
        f"{prefix}_median_ms": float(np.median(wall)),
        f"{prefix}_p99_ms": float(np.percentile(wall, 99)),
        f"{prefix}_cpu_p99_ms": float(np.percentile(cpu, 99)),
        f"{prefix}_symbolic_median_ms": float(np.median(sym_wall)),
        f"{prefix}_symbolic_cpu_p99_ms": float(np.percentile(sym_cpu, 99)),
        f"{prefix}_cmd_diff_max_mps": float(
            np.max(np.abs(commands["batched"] - commands["symbolic"]))
        ),
    }


def _paced_replay(
    planner: NmpcPlanner,
    problems: list,
    reference,
    what: str,
    progress: Callable[[str], None],
    twin: NmpcPlanner | None = None,
) -> np.ndarray:
    """Wall-clock ms per plan() on ``problems`` (from a reset), one plan per control tick
    (sleeping in between) at the companion's real-time priority, as the fast path's loop.
    With a ``twin`` (a second planner of the same shape) the twin solves each problem first,
    untimed: the code and the shared objects are then in the caches, the timed planner's own
    buffers are not."""
    planner.reset()
    if twin is not None:
        twin.reset()
    wall_ms = []
    with realtime_section(COMPANION_RT_PRIORITY, what, progress):
        tick_due_s = time.monotonic()
        for state, t in problems:
            time.sleep(max(0.0, tick_due_s - time.monotonic()))
            tick_due_s = max(tick_due_s + _TICK_S, time.monotonic())
            if twin is not None:
                twin.plan(state, reference, t)
            wall_ms.append(1e3 * planner.plan(state, reference, t).solve_time_s)
    return np.array(wall_ms)


def _involuntary_switches() -> int:
    """Times this thread was switched out while runnable (Linux RUSAGE_THREAD)."""
    return resource.getrusage(resource.RUSAGE_THREAD).ru_nivcsw


def _cmd_diff(results_a: list, results_b: list) -> float:
    """Median over problems both solved of max |command a - command b| [m/s]."""
    pairs = zip(results_a, results_b, strict=True)
    diff = [np.max(np.abs(a.command - b.command)) for a, b in pairs if a.ok and b.ok]
    return float(np.median(diff)) if diff else float("nan")


def _acados_figures(model, base, residual, world, problems, ipopt_res, progress) -> dict:
    """The acados peer on the same problems (NaN figures and the reason when it is missing)."""
    names = (
        "median_ms",
        "solve_median_ms",
        "p99_ms",
        "build_s",
        "paced_median_ms",
        "cmd_diff_median_mps",
        "ok_fraction",
    )
    why = acados_unavailable()
    if why:
        progress(f"nmpc: acados peer skipped: {why}")
        return {f"nmpc_acados_{n}": float("nan") for n in names}
    progress("nmpc: acados SQP_RTI + HPIPM: generating and compiling its solver")
    start = time.perf_counter()
    solvers: list[AcadosSolver] = []

    def factory(formulation):
        solvers.append(AcadosSolver(formulation))
        return solvers[-1]

    peer = NmpcPlanner(model, base, residual, world, solver_factory=factory)
    build_s = time.perf_counter() - start
    reference = generate_trajectories(1, seed=11)[0]
    x = reference.x_ref(0.0)
    res, solve_ms = [], []
    with c_stdout_to_stderr():  # acados prints its failed QPs on the C stdout
        peer.plan(PlannerState(x[:3], np.zeros(3), x[3]), reference, 0.0)  # first call, as fast
        peer.reset()
        progress(f"nmpc: acados on the same {len(problems)} problems")
        for state, t in problems:
            solvers[0].last_solve_s = float("nan")  # stays NaN if the planner never solves
            res.append(peer.plan(state, reference, t))
            solve_ms.append(1e3 * solvers[0].last_solve_s)
        progress(f"nmpc: acados on the same {len(problems)} problems, paced at 50 Hz")
        paced_ms = _paced_replay(peer, problems, reference, "nmpc: acados", progress)
    ms = 1e3 * np.array([r.solve_time_s for r in res])
    return {
        "nmpc_acados_median_ms": float(np.median(ms)),
        "nmpc_acados_solve_median_ms": float(np.nanmedian(solve_ms)),
        "nmpc_acados_p99_ms": float(np.percentile(ms, 99)),
        "nmpc_acados_build_s": build_s,
        "nmpc_acados_paced_median_ms": float(np.median(paced_ms)),
        "nmpc_acados_cmd_diff_median_mps": _cmd_diff(res, ipopt_res),
        "nmpc_acados_ok_fraction": float(np.mean([r.ok for r in res])),
    }


def flying_model(
    m: int = _N_INDUCING, seed: int = 3, features_name: str = "state_input"
) -> ResidualModel:
    """A seeded residual model of the shape the companion flies: first_order_lag (tau 0.5 s)
    with ``features_name`` features, an SE-ARD posterior of ``m`` points per output (not
    fitted: its numbers only need the shape and scale of a fitted one)."""
    rng = np.random.default_rng(seed)
    features = feature_definition(features_name, "first_order_lag", tau_s=0.5, tau_d_s=0.4)
    d, n_out = features.n_features, len(features.outputs)
    factor = np.tril(rng.normal(0.0, 0.05, (n_out, m, m)))
    posterior = Posterior(
        support=rng.uniform(-1.5, 1.5, (n_out, m, d)),
        lengthscales=rng.uniform(0.7, 2.0, (n_out, d)),
        variance=np.full(n_out, 0.25),
        alpha=rng.normal(0.0, 0.5, (n_out, m)),
        var_factor=factor,
        y_offset=np.zeros(n_out),
    )
    return ResidualModel(features, posterior, np.full(n_out, 0.01), "sgpr")


def model_ready_peak_mib() -> float:
    """The rise [MiB] of a fresh process's peak resident set while :func:`model_ready_s` runs,
    over its peak once the modules are imported (CasADi's own allocations included)."""
    with ProcessPoolExecutor(1, mp_context=multiprocessing.get_context("spawn")) as pool:
        return pool.submit(_peak_rise_mib).result()


def _peak_rise_mib() -> float:
    before_kib = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss  # Linux: KiB
    model_ready_s()
    return (resource.getrusage(resource.RUSAGE_SELF).ru_maxrss - before_kib) / 1024.0


def model_ready_s() -> float:
    """Seconds from a new model file on disk to the companion's planner ready to fly."""
    with tempfile.TemporaryDirectory() as tmp:
        path = save_model(Path(tmp) / "new_model", flying_model())
        start = time.perf_counter()
        load_nmpc(NmpcSettings(speed_limit_mps=2.5), path)
        return time.perf_counter() - start
