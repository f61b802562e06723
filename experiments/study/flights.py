"""One study flight: a reference flown in process (lockstep) by the companion's NMPC.

The flight is the companion's own mission sequence (takeoff, offboard, follow, land) over the
in-process link; only the reference comes from the caller (e.g. a generated trajectory).
Everything is deterministic for a given vehicle, seed and residual model.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np

from companion.app import LOCKSTEP_PLAN_BUDGET_S
from companion.autopilot_gains import velocity_loop_gains
from companion.control_loop import Tick
from companion.flight_recorder import FlightRecorder
from companion.inprocess_link import InProcessLink
from companion.mission import Mission
from companion.nmpc_planner import CompanionNmpc, NmpcSettings
from companion.runner import FlightOutcome, RunnerConfig, fly_mission
from flightlog.schema import FlightLog
from gp.model_io import ResidualModel
from planners.bspline import BSplineReference


@dataclass(frozen=True)
class FlightSpec:
    """What to fly.

    Attributes:
        name: flight name (for logs and reports).
        reference: the trajectory (starts at its first waypoint, at rest).
        vehicle: simulator preset or config file.
        seed: simulator seed (gusts).
    """

    name: str
    reference: BSplineReference
    vehicle: str
    seed: int


@dataclass(frozen=True, eq=False)
class FlightRecord:
    """A flown study flight.

    Attributes:
        spec: what was flown; augmented: whether a residual model flew.
        log: the schema-v1 log (with pred_vel_*, ref_pos_*).
        outcome: how the mission ended.
        solve_times_s: (n,) wall-clock planner time of each following step [s].
    """

    spec: FlightSpec
    augmented: bool
    log: FlightLog
    outcome: FlightOutcome
    solve_times_s: np.ndarray


def fly(
    spec: FlightSpec,
    settings: NmpcSettings,
    residual_model: ResidualModel | None = None,
    progress: Callable[[str], None] = lambda message: None,
) -> FlightRecord:
    """Fly ``spec`` with the NMPC of ``settings`` (its speed limit is the command limit, its
    period the loop's), nominal or augmented with ``residual_model``; a px4_velocity_pi
    planner takes the velocity loop's gains the autopilot reports, unless ``settings`` give
    them. The planner's time budget is raised to LOCKSTEP_PLAN_BUDGET_S: in lockstep a slow
    plan costs no flight time."""
    settings = replace(settings, time_budget_s=LOCKSTEP_PLAN_BUDGET_S)
    link = InProcessLink.from_vehicle(spec.vehicle, spec.seed)
    if settings.nominal_model == "px4_velocity_pi" and residual_model is None:
        gains = dict(velocity_loop_gains(link)) | dict(settings.nominal_params)
        settings = replace(settings, nominal_params=tuple(gains.items()))
    period_s = settings.period_s
    rate_hz = 1.0 / period_s
    planner = CompanionNmpc(settings, residual_model)
    points = spec.reference.waypoints_ned_m
    mission = Mission(
        name=spec.name,
        altitude_m=float(-points[0, 2]),
        speed_limit_mps=settings.speed_limit_mps,
        reference_kind="bspline",
        points_ned_m=tuple(tuple(float(c) for c in p) for p in points),
        goal_tolerance_m=0.5,
    )
    recorder = FlightRecorder(period_s=period_s, wall_clock_columns=False)
    solve_times: list[float] = []

    def on_tick(tick: Tick) -> None:
        recorder.record(tick)
        if tick.decision.ref_pos_ned_m is not None and tick.state.mode == "OFFBOARD":
            solve_times.append(tick.decision.solve_time_s)

    runner = RunnerConfig(rate_hz=rate_hz)
    outcome = fly_mission(link, planner, spec.reference, mission, runner, on_tick, progress)
    metadata = {
        "source": "companion-study",
        "mission": spec.name,
        "planner": "nmpc",
        "augmented": planner.augmented,
        "nominal_model": planner.model.name,
        "rate_hz": rate_hz,
        "outcome": outcome.status,
        **link.metadata(),
        **outcome.autopilot_metadata,
    }
    return FlightRecord(
        spec, planner.augmented, recorder.to_log(metadata), outcome, np.asarray(solve_times)
    )
