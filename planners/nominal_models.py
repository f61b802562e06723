"""Nominal motion models, defined once in CasADi and usable as NumPy functions.

Each model is continuous time, ``x_dot = f(x, u)``, discretised with RK4. A learned residual
plugs in as ``x_dot = f(x, u) + B_z g(z)`` ([Kulathunga23], eq. 1): ``g`` returns a 3-vector of
velocity-rate residuals in m/s^2 (NED), and ``residual_map`` (B_z) says how it enters the state.

Models:
    kinematic_4dof: [Kulathunga23]'s planner model. State (pos_n, pos_e, pos_d [m], yaw [rad]);
        input (vel_n, vel_e, vel_d [m/s], yaw_rate [rad/s]). The vehicle is assumed to fly the
        commanded velocity; a residual y [m/s^2] corrects that velocity by ``y * residual_dt_s``,
        exactly as the residual was measured: y = (v_actual - v_cmd) / dt.
    first_order_lag: adds the velocity to the state, v_dot = (v_cmd - v) / tau per axis (tau_s
        horizontal, tau_d_s vertical: PX4 tunes the two loops apart); a residual adds to v_dot.
        State (pos[3], vel[3], yaw), same input.
    px4_velocity_pi: PX4's velocity loop ([PX4-params] MPC_XY_VEL_P/I/D_ACC, MPC_Z_VEL_P/I/D_ACC)
        on the velocity command, per axis (1 + Kd) v_dot = Kp (u - v) + I, I_dot = Ki (u - v)
        ([PX4-params]'s D acts on the measured acceleration; no acceleration feed-forward in
        OFFBOARD velocity control). I [m/s^2] is the autopilot's velocity integrator relative to
        its value in the settled hover before the flight (which cancels the disturbance there):
        a state the companion integrates itself from its commands and the measured velocity
        (companion.nmpc_planner), 0 at the switch to OFFBOARD; the disturbance at the start is
        held. State (pos[3], vel[3], vel_int[3], yaw), input as the lag's; a residual adds to
        v_dot.
    unicycle: [Ostafew16]'s ground robot. State (x_n, x_e [m], heading [rad]); input (speed [m/s],
        turn rate [rad/s]); a residual (3-vector) adds to the state rates directly.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import casadi as ca
import numpy as np

VELOCITY_STATES: tuple[str, ...] = ("vel_n_mps", "vel_e_mps", "vel_d_mps")
INTEGRATOR_STATES: tuple[str, ...] = ("vel_int_n_mps2", "vel_int_e_mps2", "vel_int_d_mps2")
HISTORY_STATES: tuple[str, ...] = ("vel_prev_n_mps", "vel_prev_e_mps", "vel_prev_d_mps")


@dataclass(frozen=True)
class NominalModel:
    """A continuous-time model ``x_dot = f(x, u)`` with its residual map.

    Attributes:
        name: identifier recorded in model files and logs.
        state_names, input_names: element names with units, in order.
        f: CasADi Function (x[nx], u[nu]) -> x_dot[nx].
        residual_map: B_z, shape (nx, 3): how a residual g(z) in m/s^2 enters x_dot.
        velocity_of: CasADi Function (x, u) -> the velocity [m/s] the model says the vehicle has
            (the command itself for the kinematic model, the velocity state for the lag model).
        params_from_logs: the model's parameters that flight logs decide when a user does not
            give them (the residual's time base from the log rate; a velocity lag's time
            constants by identification, see gp.lag_identification; an autopilot's velocity
            loop gains as recorded with the logs, see gp.velocity_integrator).
        velocity_lead_s: per NED axis, how far [s] the velocity input must lead the velocity
            the model should fly: u = v + lead * a keeps a first-order lag on a reference of
            velocity v and acceleration a (its time constants); empty for a model that flies
            its command at once.
        untracked_states: states with no reference (an autopilot's integrator): their cost
            weight defaults to 0.
        integrator_gains: per NED axis, the I gain [1/s] of an autopilot velocity integrator
            the model carries as INTEGRATOR_STATES; empty for a model without one.
        history: (state index, source state index) pairs: a state that holds its source's
            value one planner interval ago (planners.velocity_history); held within an
            interval, shifted at its end by :meth:`interval_step`; empty for most models.
    """

    name: str
    state_names: tuple[str, ...]
    input_names: tuple[str, ...]
    f: ca.Function
    residual_map: np.ndarray
    velocity_of: ca.Function
    params_from_logs: tuple[str, ...] = ()
    velocity_lead_s: tuple[float, ...] = ()
    untracked_states: tuple[str, ...] = ()
    integrator_gains: tuple[float, ...] = ()
    history: tuple[tuple[int, int], ...] = ()

    @property
    def nx(self) -> int:
        return len(self.state_names)

    @property
    def nu(self) -> int:
        return len(self.input_names)

    @property
    def carries_velocity(self) -> bool:
        """Whether the velocity [m/s] is part of the state (a model of the velocity loop, e.g.
        first_order_lag), so ``velocity_of`` is what the vehicle does, not what it was told."""
        return all(n in self.state_names for n in VELOCITY_STATES)

    def xdot(self, x, u, residual=None):
        """Symbolic (or DM) state derivative, with an optional residual 3-vector [m/s^2]."""
        out = self.f(x, u)
        if residual is not None:
            out = out + ca.DM(self.residual_map) @ residual
        return out

    def rk4_step(self, x, u, dt_s: float, residual_fn=None):
        """One RK4 step of length ``dt_s`` (symbolic or DM).

        ``residual_fn(x, u)`` -> 3-vector, if given, is evaluated at every RK4 stage.
        """

        def rate(xs):
            r = residual_fn(xs, u) if residual_fn is not None else None
            return self.xdot(xs, u, r)

        k1 = rate(x)
        k2 = rate(x + dt_s / 2 * k1)
        k3 = rate(x + dt_s / 2 * k2)
        k4 = rate(x + dt_s * k3)
        return x + dt_s / 6 * (k1 + 2 * k2 + 2 * k3 + k4)

    def interval_step(self, x, u, dt_s: float, residual_fn=None):
        """One planner interval (symbolic): :meth:`rk4_step`, then each ``history`` state takes
        its source's value at the interval's start, so node j + 1 holds node j's value. The
        RK4 step itself for a model without history."""
        x_next = self.rk4_step(x, u, dt_s, residual_fn)
        if not self.history:
            return x_next
        source = dict(self.history)
        return ca.vertcat(*(x[source[i]] if i in source else x_next[i] for i in range(self.nx)))

    def step_function(self, dt_s: float) -> ca.Function:
        """CasADi Function (x, u) -> x_next for a fixed step, without residual."""
        x = ca.SX.sym("x", self.nx)
        u = ca.SX.sym("u", self.nu)
        return ca.Function(
            f"{self.name}_rk4", [x, u], [self.rk4_step(x, u, dt_s)], ["x", "u"], ["x_next"]
        )

    def xdot_np(self, x: np.ndarray, u: np.ndarray) -> np.ndarray:
        """NumPy x_dot for a batch: x (n, nx) or (nx,), u (n, nu) or (nu,) -> same leading shape."""
        return _batch_call(self.f, x, u, self.nx, self.nu)

    def step_np(self, x: np.ndarray, u: np.ndarray, dt_s: float) -> np.ndarray:
        """NumPy RK4 step for a batch, shapes as :meth:`xdot_np`."""
        return _batch_call(self.step_function(dt_s), x, u, self.nx, self.nu)

    def predicted_velocity_np(self, x: np.ndarray, u: np.ndarray, dt_s: float) -> np.ndarray:
        """Velocity [m/s] the model predicts ``dt_s`` after state x under input u, shape (n, 3).

        This is v_bar in [Kulathunga23]'s residual y = (v_actual - v_bar) / dt.
        """
        x_next = self.step_np(x, u, dt_s)
        return _batch_call(self.velocity_of, x_next, u, self.nx, self.nu)


def _batch_call(fn: ca.Function, x: np.ndarray, u: np.ndarray, nx: int, nu: int) -> np.ndarray:
    x = np.asarray(x, dtype=float)
    u = np.asarray(u, dtype=float)
    single = x.ndim == 1
    x2 = np.atleast_2d(x)
    u2 = np.atleast_2d(u)
    if x2.shape[1] != nx or u2.shape[1] != nu or x2.shape[0] != u2.shape[0]:
        raise ValueError(
            f"{fn.name()}: expected x of shape (n, {nx}) and u of shape (n, {nu}), "
            f"got {x.shape} and {u.shape}"
        )
    out = np.asarray(fn.map(x2.shape[0])(x2.T, u2.T)).T
    return out[0] if single else out


def kinematic_4dof(residual_dt_s: float = 0.05) -> NominalModel:
    """Paper 000's 4-DOF kinematic model; ``residual_dt_s`` is δ_v, the residual's time base."""
    if not (math.isfinite(residual_dt_s) and residual_dt_s > 0):
        raise ValueError(
            f"kinematic_4dof: residual_dt_s must be > 0 s and finite, got {residual_dt_s}"
        )
    x = ca.SX.sym("x", 4)
    u = ca.SX.sym("u", 4)
    f = ca.Function("kinematic_4dof", [x, u], [u], ["x", "u"], ["x_dot"])
    b = np.zeros((4, 3))
    b[:3, :3] = residual_dt_s * np.eye(3)
    vel = ca.Function("kinematic_4dof_velocity", [x, u], [u[:3]], ["x", "u"], ["vel"])
    return NominalModel(
        "kinematic_4dof",
        ("pos_n_m", "pos_e_m", "pos_d_m", "yaw_rad"),
        ("vel_n_mps", "vel_e_mps", "vel_d_mps", "yaw_rate_radps"),
        f,
        b,
        vel,
        params_from_logs=("residual_dt_s",),
    )


def first_order_lag(tau_s: float = 0.3, tau_d_s: float | None = None) -> NominalModel:
    """Velocity follows the command with time constant ``tau_s`` [s] in north and east and
    ``tau_d_s`` [s] in down (default: ``tau_s``)."""
    tau_d_s = tau_s if tau_d_s is None else tau_d_s
    for name, value in (("tau_s", tau_s), ("tau_d_s", tau_d_s)):
        if not (math.isfinite(value) and value > 0):
            raise ValueError(f"first_order_lag: {name} must be > 0 s and finite, got {value}")
    x = ca.SX.sym("x", 7)
    u = ca.SX.sym("u", 4)
    vel_dot = (u[:3] - x[3:6]) / ca.DM([tau_s, tau_s, tau_d_s])
    f = ca.Function(
        "first_order_lag", [x, u], [ca.vertcat(x[3:6], vel_dot, u[3])], ["x", "u"], ["x_dot"]
    )
    b = np.zeros((7, 3))
    b[3:6, :3] = np.eye(3)
    vel = ca.Function("first_order_lag_velocity", [x, u], [x[3:6]], ["x", "u"], ["vel"])
    return NominalModel(
        "first_order_lag",
        ("pos_n_m", "pos_e_m", "pos_d_m", "vel_n_mps", "vel_e_mps", "vel_d_mps", "yaw_rad"),
        ("vel_n_mps", "vel_e_mps", "vel_d_mps", "yaw_rate_radps"),
        f,
        b,
        vel,
        params_from_logs=("tau_s", "tau_d_s"),
        velocity_lead_s=(tau_s, tau_s, tau_d_s),
    )


def px4_velocity_pi(
    vel_p_xy: float = 1.8,
    vel_i_xy: float = 0.4,
    vel_d_xy: float = 0.2,
    vel_p_z: float = 4.0,
    vel_i_z: float = 2.0,
    vel_d_z: float = 0.0,
    drag_xy_per_s: float = 0.0,
    drag_z_per_s: float = 0.0,
) -> NominalModel:
    """PX4's velocity PI(D) loop with its integrator as a state (see the module docstring).

    Gains as PX4 names them ([PX4-params]; defaults: PX4 v1.14's): vel_p_* = MPC_*_VEL_P_ACC
    [1/s], vel_i_* = MPC_*_VEL_I_ACC [1/s^2 per m/s, PX4 writes 1/s], vel_d_* = MPC_*_VEL_D_ACC
    [1]; *_xy for north and east, *_z for down. drag_*_per_s [1/s]: linear drag per unit mass
    (acceleration per m/s of velocity, e.g. rotor drag / mass), relative to the hover (the
    steady wind's part is in the integrator); 0: left to a residual."""
    gains = {"vel_p_xy": vel_p_xy, "vel_p_z": vel_p_z}
    gains.update({"vel_i_xy": vel_i_xy, "vel_i_z": vel_i_z, "vel_d_xy": vel_d_xy})
    gains.update({"vel_d_z": vel_d_z, "drag_xy_per_s": drag_xy_per_s})
    gains["drag_z_per_s"] = drag_z_per_s
    for name, value in gains.items():
        if not (math.isfinite(value) and (value > 0 if name.startswith("vel_p") else value >= 0)):
            raise ValueError(
                f"px4_velocity_pi: {name} must be > 0 (P) or >= 0 (I, D, drag) and finite, "
                f"got {value}"
            )
    kp = ca.DM([vel_p_xy, vel_p_xy, vel_p_z])
    ki = ca.DM([vel_i_xy, vel_i_xy, vel_i_z])
    inertia = ca.DM([1 + vel_d_xy, 1 + vel_d_xy, 1 + vel_d_z])
    x = ca.SX.sym("x", 10)
    u = ca.SX.sym("u", 4)
    err = u[:3] - x[3:6]
    drag = ca.DM([drag_xy_per_s, drag_xy_per_s, drag_z_per_s])
    vel_dot = (kp * err + x[6:9] - drag * x[3:6]) / inertia
    xdot = ca.vertcat(x[3:6], vel_dot, ki * err, u[3])
    f = ca.Function("px4_velocity_pi", [x, u], [xdot], ["x", "u"], ["x_dot"])
    b = np.zeros((10, 3))
    b[3:6, :3] = np.eye(3)
    vel = ca.Function("px4_velocity_pi_velocity", [x, u], [x[3:6]], ["x", "u"], ["vel"])
    lead = ((1 + vel_d_xy) / vel_p_xy, (1 + vel_d_xy) / vel_p_xy, (1 + vel_d_z) / vel_p_z)
    return NominalModel(
        "px4_velocity_pi",
        ("pos_n_m", "pos_e_m", "pos_d_m", *VELOCITY_STATES, *INTEGRATOR_STATES, "yaw_rad"),
        ("vel_n_mps", "vel_e_mps", "vel_d_mps", "yaw_rate_radps"),
        f,
        b,
        vel,
        params_from_logs=("vel_p_xy", "vel_i_xy", "vel_d_xy", "vel_p_z", "vel_i_z", "vel_d_z"),
        velocity_lead_s=lead,
        untracked_states=INTEGRATOR_STATES,
        integrator_gains=(vel_i_xy, vel_i_xy, vel_i_z),
    )


def unicycle() -> NominalModel:
    """Paper 004's unicycle: (x_n, x_e, heading) driven by (speed, turn rate)."""
    x = ca.SX.sym("x", 3)
    u = ca.SX.sym("u", 2)
    xdot = ca.vertcat(u[0] * ca.cos(x[2]), u[0] * ca.sin(x[2]), u[1])
    f = ca.Function("unicycle", [x, u], [xdot], ["x", "u"], ["x_dot"])
    vel = ca.Function(
        "unicycle_velocity",
        [x, u],
        [ca.vertcat(u[0] * ca.cos(x[2]), u[0] * ca.sin(x[2]), 0)],
        ["x", "u"],
        ["vel"],
    )
    return NominalModel(
        "unicycle",
        ("pos_n_m", "pos_e_m", "heading_rad"),
        ("speed_mps", "turn_rate_radps"),
        f,
        np.eye(3),
        vel,
    )


MODELS = {
    "kinematic_4dof": kinematic_4dof,
    "first_order_lag": first_order_lag,
    "px4_velocity_pi": px4_velocity_pi,
    "unicycle": unicycle,
}


def make_model(name: str, **params: float) -> NominalModel:
    """Build a model by name; a bad name raises ValueError listing the valid ones."""
    try:
        factory = MODELS[name]
    except KeyError:
        raise ValueError(
            f"unknown nominal model {name!r}; choose one of {', '.join(MODELS)}"
        ) from None
    return factory(**params)
