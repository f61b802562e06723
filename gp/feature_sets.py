"""The built-in feature sets: which logged columns, at which lags, form the GP's input vector.

Names and columns only, apart from CasADi (gp.features turns a set into the definition a model
records and the NMPC's query), so that a command line lists the names at once. Outputs are
always the NED velocity-rate residuals in m/s^2.

Built-in sets:
    velocity: [Kulathunga23]. z = measured velocity (vel_n, vel_e, vel_d) [m/s].
    state_input: measured velocity and the command: (vel_ned [m/s], cmd_vel_ned [m/s],
        cmd_yaw_rate [rad/s]), 7 features.
    position_state: state_input plus the horizontal position (pos_n, pos_e [m]) in front, 9
        features: for a disturbance that depends on where the vehicle is (a wind field on a
        repeated path, [Ostafew16]'s path-dependent disturbance).
    position_velocity: the horizontal position and the measured velocity (pos_n, pos_e [m],
        vel_ned [m/s]), 5 features, no command: the residual of a spatial disturbance on top
        of a model that already carries the command's effect (first_order_lag). Without the
        command among its inputs the NMPC cannot exploit the GP through its decision variable
        (a GP fitted on the nominal planner's commands is wrong off them).
    history: [Ostafew16]'s a_k = (x_k, v_{k-1}, u_k, u_{k-1}) for a velocity-commanded
        multirotor: the velocity state now and one step ago, the command now and one step ago
        (vel_ned[k], vel_ned[k-1], cmd_vel_ned[k], cmd_vel_ned[k-1]), 12 features in m/s.
    velocity_history: the part of it the NMPC can carry along its horizon without the command:
        the measured velocity now and one residual interval ago (vel_ned[k], vel_ned[k-H],
        H = residual_steps log steps: 0.1 s, the planner's interval), 6 features in m/s, on a
        model with a velocity state. The planner adds the previous velocity as states
        (planners.velocity_history: node j's is node j-1's predicted velocity, node 0's the
        velocity measured one interval before now). The command stays out: the optimiser
        exploits a GP that sees its decision variable (experiments.study.regimes, agile).
    velocity_change: the same information as the velocity now and its change over that
        interval (vel_ned[k], vel_ned[k] - vel_ned[k-H]), 6 features in m/s: a stationary
        kernel with one length scale per input reaches a function of the change directly,
        where on (v[k], v[k-H]), two nearly equal inputs, it needs short scales on both.
"""

from __future__ import annotations

VEL_COLUMNS: tuple[str, ...] = ("vel_n_mps", "vel_e_mps", "vel_d_mps")
CMD_COLUMNS: tuple[str, ...] = ("cmd_vel_n_mps", "cmd_vel_e_mps", "cmd_vel_d_mps")
POS_COLUMNS: tuple[str, ...] = ("pos_n_m", "pos_e_m", "pos_d_m")

# In FEATURE_SETS, lags of one residual interval (the definition's residual_steps log steps,
# resolved by gp.features.feature_definition): the value that far back, and the change since.
INTERVAL = "interval"
CHANGE = "change"

FEATURE_SETS: dict[str, tuple[tuple[str, int | str], ...]] = {
    "velocity": tuple((c, 0) for c in VEL_COLUMNS),
    "state_input": tuple((c, 0) for c in (*VEL_COLUMNS, *CMD_COLUMNS, "cmd_yaw_rate_radps")),
    "position_state": tuple(
        (c, 0) for c in ("pos_n_m", "pos_e_m", *VEL_COLUMNS, *CMD_COLUMNS, "cmd_yaw_rate_radps")
    ),
    "position_velocity": tuple((c, 0) for c in ("pos_n_m", "pos_e_m", *VEL_COLUMNS)),
    "history": tuple(
        [(c, 0) for c in VEL_COLUMNS] + [(c, 1) for c in VEL_COLUMNS]
        + [(c, 0) for c in CMD_COLUMNS] + [(c, 1) for c in CMD_COLUMNS]
    ),
    "velocity_history": tuple(
        [(c, 0) for c in VEL_COLUMNS] + [(c, INTERVAL) for c in VEL_COLUMNS]
    ),
    "velocity_change": tuple([(c, 0) for c in VEL_COLUMNS] + [(c, CHANGE) for c in VEL_COLUMNS]),
}  # fmt: skip
