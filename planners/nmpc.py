"""Paper 000's NMPC local planner behind the :class:`~planners.reference.Planner` contract.

Build it for the kinematic model, with or without a learned residual::

    model = kinematic_4dof(residual_dt_s=0.05)
    planner = NmpcPlanner(model, NmpcConfig(), world=ObstacleWorld([...]))
    planner = NmpcPlanner(model, NmpcConfig(), ResidualTerm.of_velocity(gp_mean_fn, model))
    result = planner.plan(state, reference, t_s)   # never raises

Each call samples the reference on the horizon grid t_s + i dt, warm-starts from the previous
solution (interpolated onto the new grid; the reference on the first call or after a
failure), selects the N_o obstacles nearest to that guess and to the reference, and solves.
A non-finite state, a start inside an obstacle, a failed or late solve, or a plan whose
simulation violates the constraints gives the safe command (zero velocity and yaw rate) with
``ok=False`` and the reason.
"""

from __future__ import annotations

import time
from collections.abc import Callable

import numpy as np

from planners.model_vectors import angle_indices, reference_vectors, state_vector
from planners.nmpc_formulation import (
    UNUSED_SLOT,
    NmpcConfig,
    NmpcFormulation,
    slot_clearance_m,
)
from planners.nmpc_solvers import NlpSolver, make_solver
from planners.nominal_models import NominalModel
from planners.obstacles import ObstacleWorld
from planners.plan_result import PlanResult, safe_result
from planners.reference import PlannerState, Reference
from planners.residual import ResidualTerm

_BOUND_TOL = 1e-6


class NmpcPlanner:
    """NMPC local planner; see the module docstring.

    Arguments: the nominal model, the problem and solver settings, an optional learned
    residual, the obstacle world, ``compile_functions`` (compile the fast path's
    symbolic linearisation to C at first use, cached per machine; see ``SqpOptions.compile``) and
    ``solver_factory`` (formulation -> an ``NlpSolver`` used instead of ``config.solver``, e.g.
    a benchmark peer).

    Attributes:
        formulation: the NLP (model, config, residual).
        world: obstacles to avoid (None: free space); may be replaced between calls.
        late_plan: when the last call came back late, the plan it found (checked like a timely
            one, ``ok=True``, its ``solve_time_s`` the time it took), else None: a caller that
            can judge its age may fly it instead of the safe command.
    """

    def __init__(
        self,
        model: NominalModel,
        config: NmpcConfig | None = None,
        residual: ResidualTerm | None = None,
        world: ObstacleWorld | None = None,
        compile_functions: bool = False,
        solver_factory: Callable[[NmpcFormulation], NlpSolver] | None = None,
    ) -> None:
        self.formulation = NmpcFormulation(model, config or NmpcConfig(), residual)
        self.world = world
        cfg = self.formulation.config
        if solver_factory is not None:  # another solver on the same formulation (a peer)
            self._solver = solver_factory(self.formulation)
        else:
            self._solver = make_solver(
                cfg.solver,
                self.formulation,
                cfg.max_iterations,
                compile_functions,
                cfg.time_budget_s,
            )
        self._angles = angle_indices(model)
        self._pos_index = [
            model.state_names.index(n)
            for n in ("pos_n_m", "pos_e_m", "pos_d_m")
            if n in model.state_names
        ]
        f, tol = self.formulation, cfg.clearance_tolerance_m
        # What _check accepts: inputs (u_lo, u_hi), states after the first (x_lo, x_hi)
        self._check_bounds = (
            f.u_min - _BOUND_TOL,
            f.u_max + _BOUND_TOL,
            f.x_min - tol,
            f.x_max + tol,
        )
        # (a finite plan meets infinite state bounds: checked only when one is finite)
        self._state_bounded = bool(np.isfinite(f.x_min).any() or np.isfinite(f.x_max).any())
        self._node_times = cfg.dt_s * np.arange(cfg.horizon_steps + 1)  # [s] after t_s
        self._warm: tuple[float, np.ndarray, np.ndarray] | None = None
        self.late_plan: PlanResult | None = None

    def reset(self) -> None:
        """Forget the warm start (e.g. after a new reference)."""
        self._warm = None

    def plan(self, state: PlannerState, reference: Reference, t_s: float) -> PlanResult:
        """One NMPC step at time ``t_s`` [s] on the reference's clock; never raises."""
        start = time.perf_counter()
        self.late_plan = None
        try:
            return self._plan(state, reference, float(t_s), start)
        except Exception as err:  # the flight loop must get a command, whatever happened
            self._warm = None
            return self._safe(f"planner error: {type(err).__name__}: {err}", start)

    def _safe(self, reason: str, start: float) -> PlanResult:
        m = self.formulation.model
        return safe_result(m.nu, m.nx, reason, time.perf_counter() - start)

    def _positions(self, states: np.ndarray) -> np.ndarray:
        """NED positions (n, 3) [m] of states (n, nx): a view when they are its first three."""
        if self._pos_index == [0, 1, 2]:
            return states[:, :3]
        pos = np.zeros((states.shape[0], 3))
        pos[:, : len(self._pos_index)] = states[:, self._pos_index]
        return pos

    def _plan(
        self, state: PlannerState, reference: Reference, t_s: float, start: float
    ) -> PlanResult:
        f = self.formulation
        cfg = f.config
        if not (state.is_finite() and np.isfinite(t_s)):
            self._warm = None
            return self._safe("non-finite state or time", start)
        grid = t_s + self._node_times
        x_ref, u_ref = reference_vectors(f.model, reference.sample(grid), f.config.feedforward)
        x_now = state_vector(f.model, state)
        for i in self._angles:  # express angles on the reference's branch
            x_now[i] = x_ref[0, i] + np.angle(np.exp(1j * (x_now[i] - x_ref[0, i])))
        cold_start = self._warm is None
        w0, guess = self._warm_start(grid, x_now, x_ref, u_ref[:-1])
        if self.world is not None and cfg.n_obstacles:
            positions = self._positions(guess)  # row 0: x_now
            # an ObstacleWorld's distance table serves the start check and the slots at once
            table = None
            if isinstance(self.world, ObstacleWorld) and self.world.obstacles:
                table = self.world.surface_distance_m(positions)
            start_clearance = (
                np.min(table[0]) if table is not None else self.world.clearance_m(positions[:1])[0]
            )
            if start_clearance < 0.0:
                self._warm = None
                return self._safe("start inside an obstacle", start)
            # each node's N_o obstacles nearest to where it is expected to be (eq. 4)
            if table is not None:
                slots = self.world.slots_at(table[1:], cfg.n_obstacles, cfg.safe_distance_m)
            else:
                slots = self.world.slots(positions[1:], cfg.n_obstacles, cfg.safe_distance_m)
        else:
            slots = np.tile(UNUSED_SLOT, (cfg.horizon_steps, cfg.n_obstacles, 1))
        p = f.pack_parameters(x_now, x_ref, u_ref[:-1], slots)
        budget = cfg.time_budget_s - (time.perf_counter() - start)
        out = self._solver.solve(w0, p, budget, cold_start)
        if not out.ok:
            self._warm = None
            return self._safe(f"solver failed: {out.reason}", start)
        states, inputs = f.split_w(out.w)
        predicted = f.rollout(x_now, inputs)
        problem = self._check(predicted, inputs, slots)
        if problem:
            self._warm = None
            return self._safe(problem, start)
        self._warm = (t_s, states, inputs)
        elapsed = time.perf_counter() - start
        if elapsed > cfg.time_budget_s:
            self.late_plan = PlanResult(inputs[0], predicted, True, "", elapsed, inputs)
            return safe_result(
                f.model.nu,
                f.model.nx,
                f"late: solve took {elapsed:.4f} s > budget {cfg.time_budget_s} s",
                elapsed,
            )
        return PlanResult(inputs[0], predicted, True, "", elapsed, inputs)

    def _warm_start(
        self, grid: np.ndarray, x_now: np.ndarray, x_ref: np.ndarray, u_ref: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """(w0, its states (N+1, nx)): the previous solution moved onto the new time grid, else
        the reference itself; row 0 is the current state."""
        f = self.formulation
        if self._warm is None:
            states = x_ref.copy()
            inputs = u_ref.copy()
        else:
            t_prev, prev_x, prev_u = self._warm
            at = (grid - t_prev) / f.config.dt_s  # the new grid in the previous one's steps
            states = _resample(prev_x, at)
            inputs = _resample(prev_u, at[:-1])
        states[0] = x_now
        return f.pack_w(states, inputs), states

    def _check(self, predicted: np.ndarray, inputs: np.ndarray, slots: np.ndarray) -> str:
        """Why the simulated plan is unacceptable, or "" if it is fine."""
        if not (np.isfinite(predicted).all() and np.isfinite(inputs).all()):
            return "non-finite plan"
        u_lo, u_hi, x_lo, x_hi = self._check_bounds
        if (inputs < u_lo).any() or (inputs > u_hi).any():
            return "plan violates input bounds"
        later = predicted[1:]
        if self._state_bounded and ((later < x_lo).any() or (later > x_hi).any()):
            return "plan violates state bounds"
        if slots.size:  # node i against its own slots (N, N_o, 7)
            worst = float(np.min(slot_clearance_m(self._positions(later)[:, None, :], slots)))
            if worst < -self.formulation.config.clearance_tolerance_m:
                return f"plan violates obstacle clearance by {-worst:.3f} m"
        return ""


def _resample(rows: np.ndarray, at: np.ndarray) -> np.ndarray:
    """``rows`` (m, c), given at steps 0..m-1 of a uniform grid, linearly interpolated at the
    fractional steps ``at`` (k,) and held constant beyond the ends (np.interp's rule for each
    column, with the weights computed once for all columns): (k, c)."""
    last = rows.shape[0] - 1
    at = np.minimum(np.maximum(at, 0.0), last)  # np.clip's result, a third of its cost
    i = np.minimum(at.astype(int), max(last - 1, 0))
    frac = (at - i)[:, None]
    nxt = np.minimum(i + 1, last)
    return rows[i] + frac * (rows[nxt] - rows[i])
