"""The mission sequence: takeoff, stream, offboard, follow, hold, land - with a safe exit.

The reference's clock starts only once the vehicle has settled over the point it took off to
(PX4 holds it there while the companion streams; see RunnerConfig's start hold): a reference
started while the wind still blows the vehicle off its start would begin with an offset the
planner did not make.

``fly_mission`` never leaves the vehicle with a stale setpoint: whatever the companion itself
detects that ends the flight early (a refused command, a timeout, a lost link, Ctrl-C,
SIGTERM) makes it send a zero-velocity setpoint, leave OFFBOARD for HOLD, command LAND and wait
(with a deadline) for the vehicle to disarm.

It never fights a pilot: when the vehicle leaves OFFBOARD because someone else (an RC pilot,
a ground station, a PX4 failsafe) chose another mode, the companion stops streaming at once,
commands no mode and ends with status "handed_over" ("pilot took control in POSCTL at t=12.3 s;
mission abandoned"; a failsafe the vehicle announced is named with its text; for another
automatic mode such as RTL it names the mode and does not guess who chose it), as a PX4
offboard application must. The outcome is returned, never raised.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from typing import Literal

import numpy as np

from companion.autopilot_gains import velocity_loop_metadata
from companion.control_loop import LoopCounters, Tick, run_fixed_rate
from companion.decision import CommandLimits, HoverPolicy
from companion.handover import handover_detail
from companion.link import ZERO_VELOCITY, CommandOutcome, LandedPhase, Link, LinkError, LinkState
from companion.mission import Mission
from companion.planner_policy import PlannerPolicy
from companion.realtime import MAX_RT_PRIORITY, realtime_section
from companion.waiting import command_until_accepted, describe, wait_for
from planners.reference import Planner, Reference

FlightStatus = Literal[
    "completed",
    "goal_not_reached",
    "failed",
    "interrupted",
    "terminated",
    "handed_over",
    "refused",
]


_MODES_OF_THE_CLIMB = ("TAKEOFF", "HOLD")  # PX4 climbs in AUTO.TAKEOFF, then loiters
COMPANION_RT_PRIORITY = 10
"""The companion's default SCHED_FIFO priority: above every normal process, below the
kernel's own real-time threads (50) and below a simulator standing in for a flight
controller on its own processor (experiments.sim_endpoint)."""


class _HandedOver(Exception):
    """Someone else chose another mode while the companion was still climbing."""

    def __init__(self, mode: str, t_s: float) -> None:
        super().__init__(mode)
        self.mode, self.t_s = mode, t_s


class Terminated(KeyboardInterrupt):
    """The process was asked to stop (SIGTERM): handled like Ctrl-C, reported as SIGTERM."""


@dataclass(frozen=True)
class RunnerConfig:
    """Timing of the mission sequence; every wait has a deadline (link clock seconds).

    Attributes:
        rate_hz: control loop rate [Hz].
        stream_s: setpoint stream before switching to OFFBOARD [s].
        connect_timeout_s, arm_timeout_s, takeoff_timeout_s, offboard_timeout_s,
        land_timeout_s: deadlines of each phase [s].
        settle_timeout_s: time allowed after the reference ends to arrive at the goal [s].
        start_position_tolerance_m, start_speed_tolerance_mps, start_settle_timeout_s: the
            start hold. After the setpoint stream the vehicle stays in PX4's HOLD over the
            point it took off to until it is within start_position_tolerance_m of that point
            [m] and slower than start_speed_tolerance_mps [m/s], and only then is switched to
            OFFBOARD and the reference's clock started; after start_settle_timeout_s [s] of
            holding it starts anyway and says so. A reference started while the vehicle is
            still being blown off its start point (a takeoff in wind; 0.6-0.75 m in the 4 m/s
            jet of the study's wind_field regime) begins with an initial-condition error, not
            a tracking one. 0.1 m and 0.1 m/s: a settled PX4 hover in 0.2 m/s gusts holds
            0.02-0.10 m and 0.01-0.02 m/s (95th percentiles, the study vehicles, the jet
            included), so a vehicle that can hold its position meets them; PX4's hold
            closes the jet's offset to 0.1 m in 11-12 s (hence the 30 s), and a calm takeoff
            meets them before the stream ends (nothing waits).
        arrive_speed_mps: speed below which the vehicle counts as stopped at the goal [m/s].
        offboard_grace_s: time allowed after the switch for telemetry to report OFFBOARD
            (it may lag a mode change by one heartbeat); once OFFBOARD was reported, any other
            mode is a takeover at once [s].
        vertical_limit_up_mps, vertical_limit_down_mps: command limits [m/s].
        realtime_priority: SCHED_FIFO priority (1-99) the flight runs at when its link's
            clock is the wall clock, as a companion computer runs its control loop
            (companion.realtime; where the system does not permit it, the flight says so and
            runs at normal priority); 0 keeps the normal priority. Lockstep flights never
            change it (they never sleep).
    """

    rate_hz: float = 50.0
    stream_s: float = 1.0
    connect_timeout_s: float = 15.0
    arm_timeout_s: float = 10.0
    takeoff_timeout_s: float = 30.0
    offboard_timeout_s: float = 5.0
    settle_timeout_s: float = 20.0
    start_position_tolerance_m: float = 0.1
    start_speed_tolerance_mps: float = 0.1
    start_settle_timeout_s: float = 30.0
    land_timeout_s: float = 60.0
    arrive_speed_mps: float = 0.3
    offboard_grace_s: float = 2.5
    vertical_limit_up_mps: float = 1.5
    vertical_limit_down_mps: float = 1.0
    realtime_priority: int = COMPANION_RT_PRIORITY

    def __post_init__(self) -> None:
        if not 1.0 <= self.rate_hz <= 500.0:
            raise ValueError(f"rate_hz must be within [1, 500] Hz, got {self.rate_hz}")
        if not (self.start_position_tolerance_m > 0 and self.start_speed_tolerance_mps > 0):
            raise ValueError(
                "start_position_tolerance_m and start_speed_tolerance_mps must be > 0, got "
                f"{self.start_position_tolerance_m}, {self.start_speed_tolerance_mps}"
            )
        if not self.start_settle_timeout_s >= 0:
            raise ValueError(
                f"start_settle_timeout_s must be >= 0 (0: no start hold), "
                f"got {self.start_settle_timeout_s}"
            )
        if not 0 <= self.realtime_priority <= MAX_RT_PRIORITY:
            raise ValueError(
                f"realtime_priority must be 0 (off) or 1..{MAX_RT_PRIORITY}, "
                f"got {self.realtime_priority}"
            )


@dataclass(frozen=True)
class FlightOutcome:
    """How the flight went.

    Attributes:
        status: "completed" (goal reached, landed, disarmed), "goal_not_reached" (followed
            until the deadline, landed), "failed" (a phase failed; safe stop done),
            "interrupted" (Ctrl-C; safe stop done), "terminated" (SIGTERM; safe stop done) or
            "handed_over" (someone else switched the vehicle out of OFFBOARD; the companion
            stopped streaming and commanded nothing) or "refused" (the mission asks more than
            the vehicle's PX4 limits allow; nothing was commanded).
        detail: one line saying what happened.
        goal_error_m: distance to the goal when following ended [m], None if never followed.
        landed_error_m: horizontal distance from the goal after landing [m], or None.
        disarmed: True if the vehicle was seen disarmed at the end.
        ticks, deadline_misses: control loop counts over the whole flight.
        tracking_rmse_m: RMSE [m] of the distance from the reference position over the
            following steps in OFFBOARD (what a learned model should lower), None if none.
        autopilot_metadata: what the autopilot reported before flying that a flight log
            keeps (its velocity-loop gains, companion.autopilot_gains; empty when not read).
    """

    status: FlightStatus
    detail: str
    goal_error_m: float | None
    landed_error_m: float | None
    disarmed: bool
    ticks: int
    deadline_misses: int
    autopilot_metadata: Mapping[str, object] = field(default_factory=dict)
    tracking_rmse_m: float | None = None


def fly_mission(
    link: Link,
    planner: Planner,
    reference: Reference,
    mission: Mission,
    config: RunnerConfig,
    on_tick: Callable[[Tick], None],
    progress: Callable[[str], None],
    *,
    on_autopilot_metadata: Callable[[Mapping[str, object]], None] | None = None,
) -> FlightOutcome:
    """Fly ``mission`` over a connected-or-not ``link``; see the module docstring.

    ``on_autopilot_metadata``, when given, receives FlightOutcome.autopilot_metadata as soon
    as it is read (before arming), so that a log keeps it even if the flight then raises.
    """
    priority = config.realtime_priority if link.clock.real_time else 0
    with realtime_section(priority, "control loop", progress):
        return _fly(
            link, planner, reference, mission, config, on_tick, progress, on_autopilot_metadata
        )


def not_a_multicopter(link: Link) -> str:
    """'' if the vehicle may be a multicopter (its link says so, or says nothing), else why
    the companion will not arm it: it takes off and flies velocity setpoints in the air."""
    kind = link.read_state().vehicle_kind
    if kind in (None, "multirotor", "VTOL", "other"):  # a VTOL takes off as a multicopter
        return ""
    hint = "; repeat a rover's path with rover-path" if kind in ("rover", "boat") else ""
    return (
        f"the vehicle on the {link.name} link is a {kind} (its HEARTBEAT's MAV_TYPE), not a "
        f"multicopter: the companion arms and takes off only multicopters{hint}"
    )


def _fly(
    link: Link,
    planner: Planner,
    reference: Reference,
    mission: Mission,
    config: RunnerConfig,
    on_tick: Callable[[Tick], None],
    progress: Callable[[str], None],
    on_autopilot_metadata: Callable[[Mapping[str, object]], None] | None,
) -> FlightOutcome:
    counters = LoopCounters()
    goal = np.asarray(mission.goal_ned_m, dtype=float)
    airborne = False
    goal_error_m: float | None = None
    tracking_rmse_m: float | None = None
    status: FlightStatus = "failed"
    detail = ""
    autopilot: dict[str, object] = {}
    try:
        link.connect(config.connect_timeout_s)
        progress(f"connected over {link.name}; {describe(link.read_state())}")
        wait_for(link, lambda s: s.is_finite(), config.connect_timeout_s, "finite telemetry")
        problem = not_a_multicopter(link) or mission_beyond_vehicle_limits(
            link, mission, config, reference.duration_s
        )
        if problem:
            progress(f"refused: {problem}")
            return FlightOutcome("refused", problem, None, None, False, 0, 0)
        autopilot = velocity_loop_metadata(link)
        if on_autopilot_metadata is not None:
            on_autopilot_metadata(autopilot)
        command_until_accepted(link, link.arm, config.arm_timeout_s, "arm")
        airborne = True
        progress("armed; taking off")
        ground = link.read_state()
        start_ned_m = np.array([ground.pos_ned_m[0], ground.pos_ned_m[1], -mission.altitude_m])
        command_until_accepted(
            link, lambda: link.takeoff(mission.altitude_m), config.arm_timeout_s, "takeoff"
        )
        t_climb_s = link.clock.now_s()

        def climbed(s: LinkState) -> bool:
            if s.mode not in _MODES_OF_THE_CLIMB:  # a pilot took over during the climb
                raise _HandedOver(s.mode, link.clock.now_s() - t_climb_s)
            return s.altitude_m >= mission.altitude_m - 0.25 and s.landed != LandedPhase.TAKEOFF

        hover = wait_for(
            link, climbed, config.takeoff_timeout_s, f"takeoff to {mission.altitude_m:g} m"
        )
        progress(f"airborne at {hover.altitude_m:.2f} m; streaming setpoints")
        _start_offboard(link, config, start_ned_m, counters, on_tick, progress)
        progress("offboard; following the reference")
        last = _follow(link, planner, reference, mission, config, counters, on_tick, progress)
        goal_error_m = float(np.linalg.norm(last.state.pos_ned_m - goal))
        tracking_rmse_m = last.tracking_rmse_m
        if last.stop_reason == "handed_over":
            link.stop_streaming()
            airborne = False  # the vehicle is the pilot's now: no safe stop, no command
            status, detail = "handed_over", last.detail
            progress(f"{detail}; streaming stopped, no command sent")
        elif last.stop_reason == "done":
            status, detail = "completed", f"reached the goal ({goal_error_m:.2f} m)"
        else:
            status = "goal_not_reached"
            detail = f"{last.detail}; {goal_error_m:.2f} m from the goal"
        if airborne:
            progress(f"following ended: {detail}; holding")
            _require(link.hold(), "hold")
            _require(link.land(), "land")
            progress("landing")
            wait_for(link, lambda s: not s.armed, config.land_timeout_s, "landing and disarm")
            airborne = False
    except _HandedOver as exc:
        airborne = False  # the pilot's vehicle now: no safe stop, no command
        status = "handed_over"
        detail = handover_detail(link, exc.mode, exc.t_s)
        progress(f"{detail}; nothing more sent")
    except Terminated:
        status, detail = "terminated", "terminated by SIGTERM"
        progress(f"{detail}: holding and landing")
    except KeyboardInterrupt:
        status, detail = "interrupted", "interrupted by Ctrl-C"
        progress(f"{detail}: holding and landing")
    except LinkError as exc:
        status, detail = "failed", str(exc)
        if airborne:  # the safe stop's lines follow; on the ground the last line says it once
            progress(f"failed: {detail}; stopping safely")
    finally:
        if airborne:
            _safe_stop(link, config, progress)
    final = _final_state(link)
    disarmed = final is not None and not final.armed
    if status == "handed_over":
        disarmed = False  # not ours to say: the pilot flies it
    if status == "completed" and not disarmed:
        status, detail = "failed", f"{detail}, but the vehicle was not seen to disarm"
    landed_error_m = None
    if final is not None and goal_error_m is not None:
        landed_error_m = float(np.hypot(*(final.pos_ned_m[:2] - goal[:2])))
    return FlightOutcome(
        status=status,
        detail=detail,
        goal_error_m=goal_error_m,
        landed_error_m=landed_error_m,
        disarmed=disarmed,
        ticks=counters.ticks,
        deadline_misses=counters.deadline_misses,
        autopilot_metadata=autopilot,
        tracking_rmse_m=tracking_rmse_m,
    )


def mission_beyond_vehicle_limits(
    link: Link, mission: Mission, config: RunnerConfig, reference_s: float
) -> str:
    """One line naming the limit the mission or the runner would exceed, "" if none.

    PX4 clips setpoints to MPC_XY_VEL_MAX and MPC_Z_VEL_MAX_UP/DN ([PX4-params]): a plan that
    counts on more would be flown slower than planned, so it is refused before take-off; so
    is a flight (climb, setpoint stream, the start hold at its longest, reference, settling,
    descent) longer than the mission's ``endurance_s`` leaves before the vehicle's BAT_LOW_THR
    reserve. Limits the autopilot does not report are not checked.
    """
    if mission.endurance_s is not None:
        reserve = link.read_param("BAT_LOW_THR") or 0.0
        usable_s = mission.endurance_s * (1.0 - reserve)
        flight_s = (
            config.stream_s
            + config.start_settle_timeout_s
            + reference_s
            + config.settle_timeout_s
            + mission.altitude_m / config.vertical_limit_up_mps
            + mission.altitude_m / config.vertical_limit_down_mps
        )
        if flight_s > usable_s:
            return (
                f"the mission needs about {flight_s:.0f} s of flight but endurance_s "
                f"{mission.endurance_s:g} s leaves {usable_s:.0f} s above the BAT_LOW_THR "
                f"reserve {reserve:.0%}; shorten the mission or fly a fuller battery"
            )
    asks = (
        ("MPC_XY_VEL_MAX", mission.horizontal_command_limit_mps, "the mission's command limit"),
        ("MPC_Z_VEL_MAX_UP", config.vertical_limit_up_mps, "the companion's climb limit"),
        ("MPC_Z_VEL_MAX_DN", config.vertical_limit_down_mps, "the companion's descent limit"),
    )
    for param, wanted_mps, what in asks:
        limit = link.read_param(param)
        if limit is not None and wanted_mps > limit + 1e-9:
            return (
                f"{what} {wanted_mps:g} m/s exceeds the vehicle's {param} {limit:g} m/s; "
                "lower it in the mission or raise the parameter"
            )
    return ""


def _start_offboard(
    link: Link,
    config: RunnerConfig,
    start_ned_m: np.ndarray,
    counters: LoopCounters,
    on_tick: Callable[[Tick], None],
    progress: Callable[[str], None],
) -> None:
    """Stream zero-velocity setpoints for ``config.stream_s`` and on while PX4 holds the
    vehicle over ``start_ned_m`` (3,) [m], until it has settled there (the start hold, see
    RunnerConfig), then switch to OFFBOARD (stream more and retry, unless a pilot has chosen
    another mode meanwhile: _HandedOver)."""
    clock = link.clock
    policy = HoverPolicy(start_ned_m)

    def stream(timeout_s: float, until: Callable[[LinkState, float], bool]) -> str:
        return run_fixed_rate(
            link,
            policy,
            rate_hz=config.rate_hz,
            until=until,
            timeout_s=timeout_s,
            on_tick=on_tick,
            counters=counters,
        ).stop_reason

    stream(config.stream_s, _never)
    t_hold_s = clock.now_s()
    last: list[LinkState] = []

    def settled(state: LinkState, t_s: float) -> bool:
        if state.mode not in _MODES_OF_THE_CLIMB:  # a pilot took over during the hold
            raise _HandedOver(state.mode, t_s - t_hold_s)
        last[:] = [state]
        off_m = float(np.linalg.norm(state.pos_ned_m - start_ned_m))
        speed = float(np.linalg.norm(state.vel_ned_mps))
        return off_m <= config.start_position_tolerance_m and (
            speed <= config.start_speed_tolerance_mps
        )

    if stream(config.start_settle_timeout_s, settled) == "timeout":
        off_m = float(np.linalg.norm(last[0].pos_ned_m - start_ned_m))
        progress(
            f"not settled at the start after {config.start_settle_timeout_s:g} s of holding "
            f"({off_m:.2f} m off); starting the reference anyway"
        )
    elif clock.now_s() > t_hold_s:
        progress(f"settled at the start after {clock.now_s() - t_hold_s:.1f} s more of holding")
    deadline_s = clock.now_s() + config.offboard_timeout_s

    def not_handed_over(state: LinkState, t_s: float) -> bool:
        if state.mode not in (*_MODES_OF_THE_CLIMB, "OFFBOARD"):  # a pilot took over: no retry
            raise _HandedOver(state.mode, t_s - t_hold_s)
        return False

    while True:
        outcome = link.start_offboard()
        if outcome.accepted:
            return
        if clock.now_s() >= deadline_s:
            raise LinkError(f"OFFBOARD refused: {outcome.detail or 'no reason given'}")
        stream(config.stream_s, not_handed_over)


def _never(_state: LinkState, _t_s: float) -> bool:
    """A stream that runs until its timeout."""
    return False


@dataclass(frozen=True)
class _FollowEnd:
    state: LinkState
    stop_reason: Literal["done", "timeout", "handed_over"]
    detail: str
    tracking_rmse_m: float | None


def _follow(
    link: Link,
    planner: Planner,
    reference: Reference,
    mission: Mission,
    config: RunnerConfig,
    counters: LoopCounters,
    on_tick: Callable[[Tick], None],
    progress: Callable[[str], None],
) -> _FollowEnd:
    goal = np.asarray(mission.goal_ned_m, dtype=float)
    limits = CommandLimits(
        horizontal_mps=mission.horizontal_command_limit_mps,
        up_mps=config.vertical_limit_up_mps,
        down_mps=config.vertical_limit_down_mps,
    )
    t0_s = link.clock.now_s()
    policy = PlannerPolicy(planner, reference, t0_s, limits)
    monitor = _FollowMonitor(t0_s, goal, reference.duration_s, mission, config, progress)
    squared_errors_m2: list[float] = []

    def on_follow_tick(tick: Tick) -> None:
        monitor.sent(tick.decision.reason if not tick.decision.ok else "")
        ref = tick.decision.ref_pos_ned_m
        if tick.state.mode == "OFFBOARD" and ref is not None:
            squared_errors_m2.append(float(np.sum((tick.state.pos_ned_m - ref) ** 2)))
        on_tick(tick)

    result = run_fixed_rate(
        link,
        policy,
        rate_hz=config.rate_hz,
        until=monitor.finished,
        timeout_s=reference.duration_s + config.settle_timeout_s,
        on_tick=on_follow_tick,
        counters=counters,
    )
    tracking = float(np.sqrt(np.mean(squared_errors_m2))) if squared_errors_m2 else None
    if monitor.taken_over is not None:
        mode, t_s, seen = monitor.taken_over
        if seen:
            detail = handover_detail(link, mode, t_s)
        else:
            detail = (
                f"the vehicle never reported OFFBOARD (it reports {mode} after {t_s:.1f} s); "
                "mission abandoned"
            )
        return _FollowEnd(result.last_state, "handed_over", detail, tracking)
    if result.stop_reason == "timeout":
        return _FollowEnd(result.last_state, "timeout", "follow deadline passed", tracking)
    return _FollowEnd(result.last_state, "done", "", tracking)


class _FollowMonitor:
    """Decides when following is over (arrived, or someone took the vehicle out of OFFBOARD,
    or it never reported OFFBOARD); reports progress, with how many steps since the last
    report sent the safe command (brake and hover) and the last reason why, so that a vehicle
    hovering in place says why (no range scan, infeasible solves, stale telemetry)."""

    def __init__(
        self,
        t0_s: float,
        goal_ned_m: np.ndarray,
        duration_s: float,
        mission: Mission,
        config: RunnerConfig,
        progress: Callable[[str], None],
    ) -> None:
        self._t0_s = t0_s
        self._goal_ned_m = goal_ned_m
        self._duration_s = duration_s
        self._mission = mission
        self._config = config
        self._progress = progress
        self._next_report_s = t0_s
        self._seen_offboard = False
        self._steps = 0
        self._braked = 0
        self._brake_reason = ""
        self.taken_over: tuple[str, float, bool] | None = None

    def sent(self, brake_reason: str) -> None:
        """Count a control step: ``brake_reason`` is why the safe command was sent, "" when
        the planner's command was."""
        self._steps += 1
        if brake_reason:
            self._braked += 1
            self._brake_reason = brake_reason

    def finished(self, state: LinkState, t_s: float) -> bool:
        elapsed_s = t_s - self._t0_s
        if state.mode == "OFFBOARD":
            self._seen_offboard = True
        elif self._seen_offboard or elapsed_s > self._config.offboard_grace_s:
            self.taken_over = (state.mode, elapsed_s, self._seen_offboard)
            return True
        distance_m = float(np.linalg.norm(state.pos_ned_m - self._goal_ned_m))
        if t_s >= self._next_report_s:
            braked = (
                f"; braked in {self._braked} of {self._steps} steps ({self._brake_reason})"
                if self._braked
                else ""
            )
            self._progress(f"t={elapsed_s:5.1f} s  {distance_m:6.2f} m to goal{braked}")
            self._next_report_s += 2.0
            self._steps = self._braked = 0
        return (
            elapsed_s >= self._duration_s
            and distance_m <= self._mission.goal_tolerance_m
            and float(np.linalg.norm(state.vel_ned_mps)) <= self._config.arrive_speed_mps
        )


def _final_state(link: Link) -> LinkState | None:
    """The last telemetry, or None when the link can no longer tell."""
    try:
        return link.read_state()
    except LinkError:
        return None


def _require(outcome: CommandOutcome, what: str) -> None:
    if not outcome.accepted:
        raise LinkError(f"{what} refused: {outcome.detail or 'no reason given'}")


def _safe_stop(link: Link, config: RunnerConfig, progress: Callable[[str], None]) -> None:
    """Zero velocity, HOLD, LAND, wait for disarm; each step tried even if one fails."""
    try:
        link.send_velocity(ZERO_VELOCITY)
    except LinkError as exc:
        progress(f"safe stop: zero velocity failed: {exc}")
    for what, command in (("hold", link.hold), ("land", link.land)):
        try:
            outcome = command()
        except LinkError as exc:
            progress(f"safe stop: {what} failed: {exc}")
            continue
        if outcome.accepted:
            progress(f"safe stop: {what} accepted")
        else:
            progress(f"safe stop: {what} refused: {outcome.detail or 'no reason given'}")
    try:
        state = wait_for(link, lambda s: not s.armed, config.land_timeout_s, "landing and disarm")
        progress(f"safe stop: landed and disarmed; {describe(state)}")
    except LinkError as exc:
        progress(f"safe stop: {exc}")
