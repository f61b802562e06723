"""Paper 000's NMPC local planner (eq. 2-4) as one NLP, shared by every solver path.

Multiple shooting with RK4: decision variables w = [vec(X), vec(U)] with X of shape (nx, N+1)
and U of shape (nu, N) (column-major, one column per node). Cost
sum_i ||x_i - x_ref_i||_Q^2 + sum_i ||u_i - u_ref_i||_R^2; constraints x_0 = x_now,
x_{i+1} = f_d(x_i, u_i) (eq. 3), state bounds on x_1..x_N, input bounds on u, and for each
node x_i (i = 1..N) its own N_o nearest obstacles, dis(x_o, x_i) >= d_o (eq. 4).

An obstacle slot is 7 numbers: centre NED [m] (3), axis weights (3; (1, 1, 1) for a sphere,
(1, 1, 0) for a vertical cylinder) and inflated radius r + d_o [m]. The constraint is
sqrt(sum_k w_k (p_k - c_k)^2) - (r + d_o) >= 0. An unused slot has zero weights and radius -1.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Literal

import casadi as ca
import numpy as np

from planners.buffered_function import BufferedFunction
from planners.compiled_function import compiled
from planners.constants_as_inputs import constants_as_input
from planners.nominal_models import NominalModel
from planners.residual import ResidualTerm

OBSTACLE_SLOT_SIZE = 7
UNUSED_SLOT = np.array([0.0, 0.0, 0.0, 0.0, 0.0, 0.0, -1.0])
_POSITION_NAMES = ("pos_n_m", "pos_e_m", "pos_d_m")
_DIST_EPS_M2 = 1e-12
SolverName = Literal["fast", "ipopt"]
SOLVER_NAMES: tuple[str, ...] = ("fast", "ipopt")


@dataclass(frozen=True)
class NmpcConfig:
    """NMPC problem settings.

    Attributes:
        horizon_steps: N, number of shooting intervals.
        dt_s: interval length [s].
        state_weights: diagonal of Q, length nx; None gives 10 for every state but the
            model's untracked ones (0).
        input_weights: diagonal of R, length nu; None gives 1 for every input.
        state_min, state_max: bounds on x_1..x_N, length nx each (use +-inf to leave free);
            None leaves all states free.
        input_max: symmetric input bound, -input_max <= u <= input_max ([Kulathunga23]'s v_max),
            length nu; None leaves inputs free.
        n_obstacles: N_o, obstacle slots per node.
        safe_distance_m: d_o, clearance kept from every obstacle surface [m].
        solver: "fast" (Gauss-Newton SQP, condensed QP) or "ipopt" (reference).
        max_iterations: solver iterations per plan; None uses the solver's default (one SQP
            iteration for "fast": the real-time iteration scheme; 200 for IPOPT). More SQP
            iterations stop early once converged.
        feedforward: the input reference leads the reference velocity by the model's
            velocity lead times the reference acceleration (planners.model_vectors).
        time_budget_s: a plan taking longer is "late" and replaced by the safe command [s].
        clearance_tolerance_m: the simulated plan may come this much closer than d_o to an
            obstacle (linearisation error of an unconverged iterate) before it is rejected.
    """

    horizon_steps: int = 20
    dt_s: float = 0.1
    state_weights: tuple[float, ...] | None = None
    input_weights: tuple[float, ...] | None = None
    state_min: tuple[float, ...] | None = None
    state_max: tuple[float, ...] | None = None
    input_max: tuple[float, ...] | None = (1.5, 1.5, 1.5, 1.0)
    n_obstacles: int = 10
    safe_distance_m: float = 0.5
    solver: SolverName = "fast"
    max_iterations: int | None = None
    feedforward: bool = False
    time_budget_s: float = 0.05
    clearance_tolerance_m: float = 0.05

    def __post_init__(self) -> None:
        if self.solver not in SOLVER_NAMES:
            raise ValueError(
                f"unknown NMPC solver {self.solver!r}; choose one of {', '.join(SOLVER_NAMES)}"
            )
        if self.max_iterations is not None and self.max_iterations < 1:
            raise ValueError(f"max_iterations must be >= 1 or None, got {self.max_iterations}")
        if self.horizon_steps < 1:
            raise ValueError(f"horizon_steps must be >= 1, got {self.horizon_steps}")
        if not self.dt_s > 0:
            raise ValueError(f"dt_s must be > 0 s, got {self.dt_s}")
        if self.n_obstacles < 0:
            raise ValueError(f"n_obstacles must be >= 0, got {self.n_obstacles}")
        if not self.safe_distance_m >= 0:
            raise ValueError(f"safe_distance_m must be >= 0 m, got {self.safe_distance_m}")


def _vector(values: tuple[float, ...] | None, size: int, default: float, what: str) -> np.ndarray:
    if values is None:
        return np.full(size, default)
    arr = np.asarray(values, dtype=float)
    if arr.shape != (size,):
        raise ValueError(f"{what} must have {size} elements for this model, got {len(values)}")
    return arr


def position_of(model: NominalModel, x: ca.SX) -> ca.SX:
    """Position NED [m] (3x1) from a model state; axes the model lacks are 0."""
    parts = [
        x[model.state_names.index(n)] if n in model.state_names else ca.SX(0)
        for n in _POSITION_NAMES
    ]
    return ca.vertcat(*parts)


def obstacle_distance(pos: ca.SX, slot: ca.SX) -> ca.SX:
    """dis(x_o, x) - d_o for one slot (see module docstring); >= 0 means clear."""
    diff = pos - slot[0:3]
    return ca.sqrt(ca.sum1(slot[3:6] * diff**2) + _DIST_EPS_M2) - slot[6]


def slot_clearance_m(pos_ned_m: np.ndarray, slots: np.ndarray) -> np.ndarray:
    """The slots' clearance sqrt(sum_k w_k (p_k - c_k)^2) - r [m] in NumPy: positions
    (..., 3) [m] against slots (..., 7), broadcast over the leading axes (e.g. (n, 1, 3)
    against (n_obs, 7) gives (n, n_obs)); summed axis by axis, with no (..., 3) temporaries."""
    sq = slots[..., 3] * (pos_ned_m[..., 0] - slots[..., 0]) ** 2
    for k in (1, 2):
        sq += slots[..., 3 + k] * (pos_ned_m[..., k] - slots[..., k]) ** 2
    return np.sqrt(sq) - slots[..., 6]


class NmpcFormulation:
    """The NLP of [Kulathunga23] eq. 2-4 for one model, residual and configuration.

    Attributes:
        model, config, residual: as given.
        q_diag (nx,), r_diag (nu,): cost weights.
        x_min, x_max (nx,): state bounds; u_min, u_max (nu,): input bounds.
        step: CasADi Function (x, u) -> x_next, RK4 over dt_s, residual included, a history
            state shifted (NominalModel.interval_step).
        n_w, n_p: sizes of w and of the parameter vector p.
    """

    def __init__(
        self, model: NominalModel, config: NmpcConfig, residual: ResidualTerm | None = None
    ) -> None:
        self.model = model
        self.config = config
        self.residual = residual
        nx, nu, n = model.nx, model.nu, config.horizon_steps
        self.q_diag = _vector(config.state_weights, nx, 10.0, "state_weights")
        if config.state_weights is None:  # a state without a reference costs nothing
            self.q_diag[[model.state_names.index(s) for s in model.untracked_states]] = 0.0
        self.r_diag = _vector(config.input_weights, nu, 1.0, "input_weights")
        self.x_min = _vector(config.state_min, nx, -np.inf, "state_min")
        self.x_max = _vector(config.state_max, nx, np.inf, "state_max")
        u_max = _vector(config.input_max, nu, np.inf, "input_max")
        self.u_min, self.u_max = -u_max, u_max
        self.n_w = nx * (n + 1) + nu * n
        self.n_p = nx + nx * (n + 1) + nu * n + OBSTACLE_SLOT_SIZE * config.n_obstacles * n

        x = ca.SX.sym("x", nx)
        u = ca.SX.sym("u", nu)
        x_next = model.interval_step(x, u, config.dt_s, residual)
        self.step = ca.Function("nmpc_step", [x, u], [ca.cse(x_next)], ["x", "u"], ["x_next"])
        slot = ca.SX.sym("slot", OBSTACLE_SLOT_SIZE)
        self.clearance = ca.Function(
            "clearance", [x, slot], [obstacle_distance(position_of(model, x), slot)]
        )
        # The plan's simulation, node after node. A residual given as an MX Function (dense
        # matrix operations) is evaluated as such, on MX, not expanded to scalars; otherwise
        # the step itself, on SX, unrolled over the horizon (about 6x faster: no MX virtual
        # machine, no call per node, and a residual whose features do not change within the
        # interval is evaluated once, not per RK4 stage), with the step's numbers as an input
        # (planners.constants_as_inputs) so that, without a batched residual (whose step can
        # take longer to compile than a new model may take to be ready), it is compiled to C
        # once per machine and shape (0.05 ms less per plan on the benchmark, measured).
        self._rollout_theta: list[np.ndarray] = []
        if residual is None or residual.fn.is_a("SXFunction"):
            step, theta = constants_as_input(self.step)
            x0, us = ca.SX.sym("x0", nx), ca.SX.sym("u", nu, n)
            th = ca.SX.sym("theta", theta.size)
            name = f"nmpc_rollout_{nx}x{nu}x{n}"
            rollout = ca.Function(name, [x0, us, th], [step.mapaccum(n)(x0, us, th)])
            if residual is None or residual.batch is None:
                rollout = compiled(rollout)
            self._rollout_theta.append(theta)
        else:
            xm, um = ca.MX.sym("x", nx), ca.MX.sym("u", nu)
            x_next_mx = model.interval_step(xm, um, config.dt_s, residual)
            rollout = ca.Function("nmpc_step_mx", [xm, um], [x_next_mx]).mapaccum(n)
        self._rollout = BufferedFunction(rollout)

    # -- packing ---------------------------------------------------------------------------
    def split_parameters(self, p: ca.SX) -> tuple[ca.SX, ca.SX, ca.SX, ca.SX]:
        """p -> (x_now (nx), X_ref (nx, N+1), U_ref (nu, N), slots (7, N_o * N)); slot column
        j * N + i - 1 is node i's j-th obstacle (i = 1..N)."""
        nx, nu, n = self.model.nx, self.model.nu, self.config.horizon_steps
        i = 0
        x_now = p[i : i + nx]
        i += nx
        x_ref = ca.reshape(p[i : i + nx * (n + 1)], nx, n + 1)
        i += nx * (n + 1)
        u_ref = ca.reshape(p[i : i + nu * n], nu, n)
        i += nu * n
        slots = ca.reshape(p[i:], OBSTACLE_SLOT_SIZE, self.config.n_obstacles * n)
        return x_now, x_ref, u_ref, slots

    def pack_parameters(
        self, x_now: np.ndarray, x_ref: np.ndarray, u_ref: np.ndarray, slots: np.ndarray
    ) -> np.ndarray:
        """Parameter vector p from x_now (nx,), x_ref (N+1, nx), u_ref (N, nu) and slots
        (N, N_o, 7): node i's obstacles in row i - 1."""
        by_obstacle = np.transpose(np.asarray(slots, dtype=float), (1, 0, 2))
        return np.concatenate(
            [np.ravel(x_now), np.ravel(x_ref), np.ravel(u_ref), np.ravel(by_obstacle)]
        ).astype(float, copy=False)

    def split_w(self, w: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """w -> (X (N+1, nx), U (N, nu))."""
        nx, n = self.model.nx, self.config.horizon_steps
        return (
            np.reshape(w[: nx * (n + 1)], (n + 1, nx)),
            np.reshape(w[nx * (n + 1) :], (n, self.model.nu)),
        )

    def pack_w(self, states: np.ndarray, inputs: np.ndarray) -> np.ndarray:
        """(X (N+1, nx), U (N, nu)) -> w."""
        return np.concatenate([np.ravel(states), np.ravel(inputs)])

    # -- the NLP ---------------------------------------------------------------------------
    def nlp(self) -> tuple[dict[str, ca.SX], np.ndarray, np.ndarray]:
        """CasADi NLP dict {x, p, f, g} and its constraint bounds (lbg, ubg)."""
        nx, nu, n = self.model.nx, self.model.nu, self.config.horizon_steps
        w = ca.SX.sym("w", self.n_w)
        p = ca.SX.sym("p", self.n_p)
        xs = ca.reshape(w[: nx * (n + 1)], nx, n + 1)
        us = ca.reshape(w[nx * (n + 1) :], nu, n)
        x_now, x_ref, u_ref, slots = self.split_parameters(p)
        ex = xs - x_ref
        eu = us - u_ref
        cost = ca.sum2(ca.sum1(ca.DM(self.q_diag) * ex**2)) + ca.sum2(
            ca.sum1(ca.DM(self.r_diag) * eu**2)
        )
        x_next = self.step.map(n)(xs[:, :n], us)
        g = [xs[:, 0] - x_now, ca.vec(x_next - xs[:, 1:])]
        n_o = self.config.n_obstacles
        if n_o:
            pairs = self.clearance.map(n * n_o)(ca.repmat(xs[:, 1:], 1, n_o), slots)
            g.append(ca.vec(pairs))
        n_eq = nx * (n + 1)
        lbg = np.concatenate([np.zeros(n_eq), np.zeros(n * n_o)])
        ubg = np.concatenate([np.zeros(n_eq), np.full(n * n_o, np.inf)])
        return {"x": w, "p": p, "f": cost, "g": ca.vertcat(*g)}, lbg, ubg

    def w_bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Bounds (lbw, ubw) on w: x_0 free (fixed by x_0 = x_now), x_1..x_N and u bounded."""
        n = self.config.horizon_steps
        free = np.full(self.model.nx, np.inf)
        lbx = np.concatenate([-free, np.tile(self.x_min, n), np.tile(self.u_min, n)])
        ubx = np.concatenate([free, np.tile(self.x_max, n), np.tile(self.u_max, n)])
        return lbx, ubx

    def rollout(self, x_now: np.ndarray, inputs: np.ndarray) -> np.ndarray:
        """Simulate f_d from x_now (nx,) under inputs (N, nu): states (N+1, nx)."""
        x_now = np.asarray(x_now, dtype=float)
        later = self._rollout(x_now, np.asarray(inputs, dtype=float).T, *self._rollout_theta)[0].T
        return np.vstack([x_now, later])
