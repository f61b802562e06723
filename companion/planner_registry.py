"""Planners the companion can fly with, by name (the CLI's ``--planner`` choices)."""

from __future__ import annotations

from pathlib import Path

from planners.reference import Planner

PLANNER_NAMES: tuple[str, ...] = ("pd", "nmpc", "nmpc_clutter")
OBSTACLE_PLANNERS: tuple[str, ...] = ("nmpc_clutter",)  # planners that honour obstacles
CLUTTER_N_OBSTACLES = 12  # N_o map points per plan ([Kulathunga23] eq. 4; our number)
CLUTTER_SAFE_DISTANCE_M = 0.5  # d_o [m] beyond a map point's radius (our number)
# Without a residual model the clutter NMPC predicts a first-order velocity lag with PX4's
# default velocity-loop gains (a = MPC_XY_VEL_P_ACC (v_sp - v), 1.8 and MPC_Z 4.0 1/s
# [PX4-params], so tau = 1/P): on the kinematic model it plans side-steps the lagging vehicle
# cannot fly and met trunks in 4 of 10 forest pairs (BENCHMARKS.md); a residual model
# carries its own structure.
CLUTTER_NOMINAL_MODEL = "first_order_lag"
CLUTTER_NOMINAL_PARAMS = (("tau_s", 1.0 / 1.8), ("tau_d_s", 1.0 / 4.0))


def honours_obstacles(name: str) -> bool:
    """True when planner ``name`` keeps clear of sensed obstacles (it may fly a mission with
    an obstacle world); the others would fly straight through them."""
    return name in OBSTACLE_PLANNERS


def clutter_nominal() -> dict[str, object]:
    """The NmpcSettings fields of the clutter NMPC flown without a residual model."""
    return {"nominal_model": CLUTTER_NOMINAL_MODEL, "nominal_params": CLUTTER_NOMINAL_PARAMS}


def make_planner(
    name: str,
    speed_limit_mps: float,
    *,
    gp_model: Path | None = None,
    rate_hz: float = 50.0,
    time_budget_s: float | None = None,
) -> Planner:
    """A planner with its paper defaults, its commands limited to ``speed_limit_mps`` [m/s]
    (the mission's horizontal command limit);
    ValueError listing the names for an unknown one.

    pd: [Kulathunga23]'s PD regulator, v = Kp e - Kd vel (horizontal 1.2 / 0.25, vertical
    0.9 / 0.25).
    nmpc: [Kulathunga23]'s NMPC on the kinematic model (20 x 0.1 s, velocity feed-forward),
    nominal, or augmented with the residual model file ``gp_model`` (from fit-gp, measured at
    ``rate_hz``). ``time_budget_s`` [s] defaults to one control period.
    nmpc_clutter: the same NMPC with each node's N_o nearest sensed obstacles as hard
    constraints, the incremental map, the replanner and regeneration
    (companion.clutter_planner); without a model file it predicts the velocity loop's lag
    (CLUTTER_NOMINAL_MODEL).

    Raises:
        ValueError: unknown name, a model file for a planner that takes none, or a missing,
            corrupt or mismatched model file (gp.errors.ModelFileError, one line).
    """
    if name not in PLANNER_NAMES:
        raise ValueError(f"unknown planner {name!r}; choose one of {', '.join(PLANNER_NAMES)}")
    if name == "pd":
        if gp_model is not None:
            raise ValueError("planner 'pd' takes no residual model; use --planner nmpc")
        from planners.pd_regulator import PdGains, PdRegulator

        return PdRegulator(PdGains(max_speed_mps=speed_limit_mps))
    from companion.nmpc_planner import NmpcSettings, load_nmpc

    period_s = 1.0 / rate_hz
    clutter = name == "nmpc_clutter"
    settings = NmpcSettings(
        speed_limit_mps=speed_limit_mps,
        period_s=period_s,
        time_budget_s=period_s if time_budget_s is None else time_budget_s,
        n_obstacles=CLUTTER_N_OBSTACLES if clutter else 0,
        safe_distance_m=CLUTTER_SAFE_DISTANCE_M,
        **(clutter_nominal() if clutter and gp_model is None else {}),
    )
    nmpc = load_nmpc(settings, gp_model)
    if not clutter:
        return nmpc
    from companion.clutter_planner import ClutterNmpc, ClutterSettings

    return ClutterNmpc(nmpc, ClutterSettings(max_speed_mps=speed_limit_mps))
