"""The NMPC as the companion flies it: [Kulathunga23]'s planner, nominal or with a learned residual.

The planner model is a nominal model from :mod:`planners.nominal_models`: [Kulathunga23]'s 4-DOF
kinematic model (velocity and yaw-rate commands; the default), the first-order velocity lag
(an a-priori model in the sense of [Ostafew16]) or PX4's velocity PI loop, whose integrator the
companion keeps itself: 0 at the first plan (the settled hover before the reference: the
model's integrator is relative to the value that holds it), then I += Ki (u - v) dt between
plans, with the planner's last command and the measured velocity (mean over the interval).
When no learned residual flies (no model file, or one whose GP was refused) the PI model plans
offset-free ([Pannocchia03]): the integrator at the plan's start is taken to cancel a constant
disturbance d (a loop at rest on its disturbance, I + d = 0; with the model's drag terms at
their default 0: with drag_*_per_s > 0 the rest is I + d = drag v, not used here), so d = -I(0)
is held over the horizon, which is the model started from I(0) = 0; otherwise the model reads
the integrator that holds a steady wind as an acceleration the vehicle does not have (measured:
1.2-2.0x worse tracking than the kinematic model through the wind field). When a learned
residual flies the integrator enters as kept: the residual was fitted against it
(gp.velocity_integrator) and carries the disturbance.
Augmented, a residual model file from ``fit-gp`` adds its mean g(z) [m/s^2] as in
[Kulathunga23], eq. 1; the file names the nominal model and features it was trained on, and
the planner is built for exactly those; a file on velocity_history or velocity_change features
(the velocity one planner interval ago) makes the planner carry it along its horizon
(planners.velocity_history), its first node's from the measured velocities the companion
recorded over the last interval (companion.velocity_buffer). The reference is
time-parametrised and the NMPC's input reference is its velocity (feed-forward), so the nominal
planner already tracks well and what is left is the residual.

Besides planning, the planner states its own one-step velocity prediction for the command
that was actually sent (:meth:`CompanionNmpc.one_step_velocity`): that is what the flight log
records as ``pred_vel_*``, so the residual of exactly the model that flew can be computed.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import casadi as ca
import numpy as np

from companion.velocity_buffer import VelocityBuffer
from gp.errors import ModelFileError
from gp.features import feature_definition
from gp.model_io import ResidualModel, load_model
from gp.prediction_check import refusal, structure_only
from planners.model_names import MULTIROTOR_MODELS
from planners.model_vectors import state_vector
from planners.nmpc import NmpcPlanner
from planners.nmpc_formulation import NmpcConfig
from planners.nominal_models import HISTORY_STATES, INTEGRATOR_STATES, NominalModel, make_model
from planners.plan_result import PlanResult
from planners.reference import PlannerState, Reference, ReferenceSample
from planners.residual import ResidualTerm

_DT_TOLERANCE = 0.05
LATE_FALLBACK_S = 0.2  # oldest plan [s] flown on when a new plan comes back late
INTEGRATOR_GAP_S = 0.5  # plans further apart [s] restart the companion's integrator at 0


@dataclass(frozen=True)
class NmpcSettings:
    """How the companion's NMPC is set up.

    Attributes:
        speed_limit_mps: bound on each velocity command component [m/s].
        period_s: control loop period [s] (the one-step prediction's horizon).
        time_budget_s: a plan taking longer (wall clock) is late [s]: the companion flies it
            if it took at most LATE_FALLBACK_S, else the newest plan at most that old, else
            the safe command.
            In lockstep (in-process) flights simulated time stands still while the planner
            works, so a generous budget keeps flights deterministic on a loaded machine.
        nominal_model, nominal_params: the nominal model when flying without a residual model
            (with one, the model file decides); kinematic_4dof's residual_dt_s defaults to
            ``period_s``.
        horizon_steps, dt_s: NMPC horizon N and interval [s] ([Kulathunga23]: 20 x 0.1 s).
        yaw_rate_limit_radps: bound on the yaw-rate command [rad/s].
        max_iterations: SQP iterations per plan (None: the solver's default, 10 with early
            stop; 1 is the real-time iteration scheme).
        compile_functions: compile the symbolic linearisation to C (cached per machine and
            formulation; planners.sqp_solver); the default linearisation (one compiled
            routine per shape, or NumPy) ignores it.
        latency_s: the known time [s] from the measured state to the command taking effect
            (link delay plus solve time). Before planning, the state is predicted forward over
            it with the planner's own model (and residual) under the last command sent, and
            the plan starts at t + latency_s, as practical NMPCs compensate dead time. 0: off.
        feedforward: the input reference leads the reference velocity by the nominal model's
            time constants times the reference acceleration (u = v + tau a on a first-order
            lag; planners.model_vectors.reference_vectors); off: the reference velocity.
        n_obstacles: N_o obstacle slots per plan ([Kulathunga23] eq. 4); 0 flies without
            obstacle constraints (give the obstacles with :meth:`CompanionNmpc.set_obstacles`).
        safe_distance_m: d_o, the clearance kept from every obstacle [m].
    """

    speed_limit_mps: float
    period_s: float = 0.02
    time_budget_s: float = 0.02
    nominal_model: str = "kinematic_4dof"
    nominal_params: tuple[tuple[str, float], ...] = ()
    horizon_steps: int = 20
    dt_s: float = 0.1
    yaw_rate_limit_radps: float = 1.0
    max_iterations: int | None = None
    compile_functions: bool = False
    latency_s: float = 0.0
    feedforward: bool = False
    n_obstacles: int = 0
    safe_distance_m: float = 0.5

    def __post_init__(self) -> None:
        if not 0.0 <= self.latency_s < self.horizon_steps * self.dt_s:
            raise ValueError(
                f"latency_s must be in [0, {self.horizon_steps * self.dt_s:g}) s, got "
                f"{self.latency_s}"
            )
        if self.nominal_model not in MULTIROTOR_MODELS:
            raise ValueError(
                f"unknown NMPC model {self.nominal_model!r}; choose one of "
                f"{', '.join(MULTIROTOR_MODELS)}"
            )


class CompanionNmpc:
    """:class:`NmpcPlanner` on a multirotor nominal model, with an optional residual model
    (flown without its GP when the file says the GP does not beat the structure alone, see
    gp.prediction_check.structure_only).

    Attributes:
        model: the nominal model the NMPC plans with.
        residual_model: the learned residual, or None for the nominal planner.
        flown_model: what it plans with, in words (the flight log records it): the nominal
            model and its parameters, "+ GP on <features>" when the file's GP flies, "alone"
            when the file says it does not beat its structure.
    """

    def __init__(self, settings: NmpcSettings, residual_model: ResidualModel | None = None):
        self.residual_model = residual_model
        residual = None
        if residual_model is None:
            params = dict(settings.nominal_params)
            if settings.nominal_model == "kinematic_4dof":
                params.setdefault("residual_dt_s", settings.period_s)
            self.model = make_model(settings.nominal_model, **params)
            self.flown_model = _named(settings.nominal_model, params)
        else:
            check_residual_model(residual_model, settings.period_s, settings.dt_s)
            features = residual_model.features
            self.model = features.nominal()
            structure = _named(features.nominal_model, dict(features.nominal_params))
            self.flown_model = f"{structure} alone (the file's GP does not beat it)"
            if not structure_only(residual_model):
                self.flown_model = f"{structure} + GP on {features.name}"
                self.model = features.planner_model()
                residual = ResidualTerm(
                    residual_model.flight_mean_function(expand=False),
                    features.planner_map(self.model),
                    residual_model.flight_mean_batch(),
                )
        v, w = settings.speed_limit_mps, settings.yaw_rate_limit_radps
        config = NmpcConfig(
            horizon_steps=settings.horizon_steps,
            dt_s=settings.dt_s,
            input_max=(v, v, v, w),
            n_obstacles=settings.n_obstacles,
            safe_distance_m=settings.safe_distance_m,
            time_budget_s=settings.time_budget_s,
            max_iterations=settings.max_iterations,
            feedforward=settings.feedforward,
        )
        self._planner = NmpcPlanner(
            self.model, config, residual, compile_functions=settings.compile_functions
        )
        self._gp_flies = residual is not None
        self._one_step = _one_step_function(self.model, residual, settings.period_s)
        self._latency_s = settings.latency_s
        self._advance = None
        if settings.latency_s > 0:
            x, u = ca.SX.sym("x", self.model.nx), ca.SX.sym("u", self.model.nu)
            x_next = self.model.rk4_step(x, u, settings.latency_s, residual)
            self._advance = ca.Function("advance_latency", [x, u], [x_next])
        self._last_command: np.ndarray | None = None
        self._last_ok: tuple[float, PlanResult] | None = None
        self._dt_s = settings.dt_s
        self._ki = np.asarray(self.model.integrator_gains, dtype=float)
        self._vel_int = np.zeros(3)
        self._int_at: tuple[float, np.ndarray] | None = None  # (t [s], velocity [m/s])
        self._velocities = None  # the measured velocities, for a model that carries history
        if HISTORY_STATES[0] in self.model.state_names:
            self._velocities = VelocityBuffer(settings.dt_s, INTEGRATOR_GAP_S)
        self._vel_prev: np.ndarray | None = None  # the last plan's previous velocity [m/s]
        self._warm_up()

    def _warm_up(self) -> None:
        """Plan once on a dummy problem, so that the solver's linearisation is compiled (or
        loaded from the cache) now, before flight, not on the first plan in the air."""
        hover = PlannerState(np.array([0.0, 0.0, -3.0]), np.zeros(3), 0.0)
        self._planner.plan(hover, _HoverReference(), 0.0)
        self._planner.reset()
        self._last_command = None
        self._last_ok = None
        self._vel_int = np.zeros(3)
        self._int_at = None
        if self._velocities is not None:
            self._velocities.clear()
        self._vel_prev = None

    def set_obstacles(self, world: object | None) -> None:
        """Obstacles to keep d_o from: anything with ``clearance_m(points)`` and
        ``slots(points, count, safe_distance_m)`` (an ObstacleWorld, a PointObstacleMap), or
        None; used only when ``n_obstacles`` > 0."""
        self._planner.world = world

    @property
    def augmented(self) -> bool:
        return self.residual_model is not None

    def plan(self, state: PlannerState, reference: Reference, t_s: float) -> PlanResult:
        """One NMPC step (see :meth:`NmpcPlanner.plan`), from the state predicted over the
        known latency when ``latency_s`` is set, with the velocity measured one planner
        interval before the plan's start for a model that carries it; never raises."""
        history = self._velocities is not None and state.is_finite()
        if self._ki.size and state.is_finite():
            state = self._with_integrator(state, t_s)
        if history:
            self._velocities.record(t_s, state.vel_ned_mps)
            state = self._with_previous_velocity(state, t_s)
        if self._advance is not None and self._last_command is not None and state.is_finite():
            state = self._predicted(state, self._last_command)
            t_s = t_s + self._latency_s
            if history:
                state = self._with_previous_velocity(state, t_s)
        result = self._planner.plan(state, reference, t_s)
        late = self._planner.late_plan
        if result.ok:
            self._last_ok = (t_s, result)
        elif late is not None and late.solve_time_s <= LATE_FALLBACK_S:
            self._last_ok = (t_s, late)  # the newest plan there is, only later than the budget
        if result.reason.startswith("late") and self._last_ok is not None:
            result = self._previous_plan(t_s, result.solve_time_s) or result
        self._last_command = np.array(result.command, dtype=float)
        return result

    def _with_previous_velocity(self, state: PlannerState, t_s: float) -> PlannerState:
        """``state`` with the velocity measured one planner interval before ``t_s`` (from the
        recorded velocities, companion.velocity_buffer), kept for :meth:`one_step_velocity`."""
        self._vel_prev = self._velocities.at(t_s - self._dt_s)
        return replace(state, vel_prev_ned_mps=self._vel_prev)

    @property
    def velocity_integrator_mps2(self) -> np.ndarray:
        """The autopilot's velocity integrator (3,) [m/s^2] as this planner keeps it (relative
        to the settled hover at the first plan; zeros for a model without one)."""
        return self._vel_int.copy()

    def _with_integrator(self, state: PlannerState, t_s: float) -> PlannerState:
        """``state`` with the velocity integrator advanced to ``t_s``: I += Ki (u - v) dt
        with the last command this planner returned (the loop's CommandLimits may still
        saturate what is sent: the horizontal norm, climb and descent; such a cut is not seen
        here) and the mean of the last and current measured velocity; restarted at 0 on the
        first plan or after a gap over INTEGRATOR_GAP_S."""
        vel = np.asarray(state.vel_ned_mps, dtype=float)
        if self._int_at is None or self._last_command is None:
            self._vel_int = np.zeros(3)
        else:
            t_prev, vel_prev = self._int_at
            gap_s = t_s - t_prev
            if not 0.0 <= gap_s <= INTEGRATOR_GAP_S:
                self._vel_int = np.zeros(3)
            else:
                err = self._last_command[:3] - 0.5 * (vel + vel_prev)
                self._vel_int = self._vel_int + self._ki * err * gap_s
        self._int_at = (t_s, vel)
        return PlannerState(state.pos_ned_m, vel, state.yaw_rad, self._planned_integrator())

    def _planned_integrator(self) -> np.ndarray:
        """The integrator (3,) [m/s^2] the model starts from: as kept when a learned residual
        flies, 0 when none does (no model file, or one whose GP was refused: offset-free,
        d = -I held, see the module docstring)."""
        return self._vel_int.copy() if self._gp_flies else np.zeros(3)

    def _previous_plan(self, t_s: float, solve_time_s: float) -> PlanResult | None:
        """The newest good plan's input for time ``t_s`` (its row floor((t - t_plan) / dt)),
        as the answer to a plan that came back late (a busy computer), if that plan is at most
        LATE_FALLBACK_S old. The late plan itself is the newest when it took at most
        LATE_FALLBACK_S: it was solved from this tick's state and checked, only after the
        budget. Braking to a hover on a late solve costs more tracking than flying on a plan
        a few ticks old; under a sustained load, when most plans come back late, braking on
        each would stop the flight (measured over MAVSDK with a CPU hog at load 11: 64
        braking commands in 618 ticks, tracking 0.097 m instead of 0.018 m)."""
        t0, prev = self._last_ok
        age_s = t_s - t0
        row = int(np.floor(age_s / self._dt_s + 1e-9))
        if not 0.0 <= age_s <= LATE_FALLBACK_S or row >= prev.predicted_inputs.shape[0]:
            return None
        return PlanResult(
            prev.predicted_inputs[row],
            prev.predicted_trajectory,
            True,
            "",
            solve_time_s,
            prev.predicted_inputs[row:],
        )

    def _predicted(self, state: PlannerState, command: np.ndarray) -> PlannerState:
        """``state`` advanced by the latency under ``command`` with this planner's model."""
        x = np.asarray(self._advance(state_vector(self.model, state), command)).ravel()
        names = self.model.state_names
        pos = x[[names.index(c) for c in ("pos_n_m", "pos_e_m", "pos_d_m")]]
        vel = state.vel_ned_mps
        if self.model.carries_velocity:
            vel = x[[names.index(c) for c in ("vel_n_mps", "vel_e_mps", "vel_d_mps")]]
        yaw = float(x[names.index("yaw_rad")]) if "yaw_rad" in names else state.yaw_rad
        vel_int = state.vel_int_mps2
        if self._ki.size:
            vel_int = x[[names.index(c) for c in INTEGRATOR_STATES]]
        return PlannerState(pos, vel, yaw, vel_int)

    def one_step_velocity(
        self,
        vel_ned_mps: np.ndarray,
        cmd_vel_ned_mps: np.ndarray,
        pos_ned_m: np.ndarray | None = None,
    ) -> np.ndarray:
        """Velocity [m/s] (3,) this planner's model (with its residual) predicts one control
        period after sending ``cmd_vel_ned_mps`` (3,) at velocity ``vel_ned_mps`` (3,) and
        position ``pos_ned_m`` (3,) [m] (a residual on position features is evaluated there;
        None: the origin), with the velocity integrator the model plans from (0 when no
        learned residual flies: offset-free) and, for a model that carries it, the previous
        velocity the last plan started from; the yaw-rate command is taken as zero (the
        study's references hold their yaw)."""
        pos = np.zeros(3) if pos_ned_m is None else np.asarray(pos_ned_m, dtype=float)
        vel = np.asarray(vel_ned_mps, dtype=float)
        state = PlannerState(pos, vel, 0.0, self._planned_integrator(), self._vel_prev)
        x = state_vector(self.model, state)
        u = np.append(np.asarray(cmd_vel_ned_mps, dtype=float).reshape(3), 0.0)
        return np.asarray(self._one_step(x, u), dtype=float).reshape(3)


class _HoverReference:
    """Hold (0, 0, -3) m at rest: the warm-up problem."""

    duration_s = 1.0

    def sample(self, t_s: np.ndarray | float) -> ReferenceSample:
        n = np.size(t_s)
        pos = np.tile([0.0, 0.0, -3.0], (n, 1))
        zeros = np.zeros((n, 3))
        return ReferenceSample(pos, zeros, zeros, np.zeros(n), np.zeros(n))


def _one_step_function(
    model: NominalModel, residual: ResidualTerm | None, period_s: float
) -> ca.Function:
    """(x, u) -> velocity [m/s] after one period: the velocity state if the model has one,
    else the mean velocity of the position step (the kinematic model: u + dt g)."""
    x = ca.SX.sym("x", model.nx)
    u = ca.SX.sym("u", model.nu)
    x_next = model.rk4_step(x, u, period_s, residual)
    if model.carries_velocity:
        vel = model.velocity_of(x_next, u)
    else:
        pos = [model.state_names.index(n) for n in ("pos_n_m", "pos_e_m", "pos_d_m")]
        vel = (x_next[pos] - x[pos]) / period_s
    return ca.Function("one_step_velocity", [x, u], [vel])


def check_residual_model(model: ResidualModel, period_s: float, planner_dt_s: float = 0.1) -> None:
    """Raise ModelFileError (one line) unless the NMPC can fly ``model`` at this control period
    and planner interval ``planner_dt_s`` [s] (a velocity history must lag by one interval)."""
    refused = refusal(model)
    if refused is not None:
        raise ModelFileError(refused)
    features = model.features
    if features.nominal_model not in MULTIROTOR_MODELS:
        raise ModelFileError(
            f"residual model is taken against {features.nominal_model}; the NMPC flies "
            f"{' or '.join(MULTIROTOR_MODELS)}; refit with fit-gp --nominal kinematic_4dof"
        )
    nominal = features.nominal()
    try:
        features.planner_map(features.planner_model())
    except ValueError as exc:
        raise ModelFileError(f"residual model: {exc}; refit with fit-gp") from None
    lag_s = features.history_lag * period_s
    if features.history_lag and abs(lag_s - planner_dt_s) > _DT_TOLERANCE * planner_dt_s:
        raise ModelFileError(
            f"residual model's velocity history lags {lag_s:.3g} s but the NMPC's interval is "
            f"{planner_dt_s:g} s; refit with the residual over one planner interval"
        )
    dt_s = dict(features.nominal_params).get("residual_dt_s")
    off_rate = dt_s is None or abs(dt_s - period_s) > _DT_TOLERANCE * period_s
    if not nominal.carries_velocity and off_rate:
        its_rate = f"fly at its rate (companion --rate-hz {1.0 / dt_s:.4g}) or " if dt_s else ""
        raise ModelFileError(
            f"residual model was measured over steps of {dt_s} s but the control loop runs "
            f"every {period_s:g} s; {its_rate}refit from logs flown at this rate"
        )


def check_feature_set(features: str, nominal_model: str) -> None:
    """Raise ValueError (one line) unless the NMPC can build feature set ``features`` from the
    state and input of ``nominal_model`` (see FeatureDefinition.planner_map)."""

    definition = feature_definition(features, nominal_model)
    definition.planner_map(definition.planner_model())


def _named(model: str, params: dict[str, float]) -> str:
    """ "first_order_lag(tau_d_s=0.72, tau_s=0.72)"; a model without parameters by its name."""
    listed = ", ".join(f"{k}={v:.3g}" for k, v in sorted(params.items()))
    return f"{model}({listed})" if listed else model


def load_nmpc(settings: NmpcSettings, gp_model_path: Path | None) -> CompanionNmpc:
    """The nominal NMPC, or the augmented one with the model file at ``gp_model_path``.

    Raises:
        ModelFileError: missing, corrupt or mismatched model file (one line).
    """
    model = None if gp_model_path is None else load_model(gp_model_path)
    return CompanionNmpc(settings, model)
