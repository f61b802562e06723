"""The companion application: build link, planner and reference, fly, write the log.

This is the edge where files and connections are opened; ``scripts/companion_cli.py`` only
parses arguments into a :class:`CompanionConfig` and maps the outcome to an exit code.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Literal, get_args

from companion.flight_recorder import FlightRecorder
from companion.link import Link
from companion.mission import Mission, load_mission
from companion.mission_reference import reference_of
from companion.planner_registry import OBSTACLE_PLANNERS, honours_obstacles, make_planner
from companion.runner import FlightOutcome, RunnerConfig, fly_mission
from flightlog.atomic_output import OutputError, check_not_an_input
from flightlog.flight_log_files import (
    check_csv_log_name,
    claim_new_log_path,
    keep_earlier_log,
    restore_earlier_log,
)
from flightlog.live_log import LiveFlightLog
from flightlog.schema import sidecar_path

LinkKind = Literal["mavsdk", "pymavlink", "inprocess"]
LINK_KINDS: tuple[str, ...] = get_args(LinkKind)
DEFAULT_URL = "udpin://127.0.0.1:14540"
LOG_SOURCE = "companion"
LOG_VERSION = 1
LOCKSTEP_PLAN_BUDGET_S = 1.0  # simulated time stands still while planning in process [s]


class CompanionInputError(ValueError):
    """Bad mission, planner or vehicle, found before anything flies; one line."""


@dataclass(frozen=True)
class CompanionConfig:
    """One companion run.

    Attributes:
        mission_path: the mission file (TOML).
        link: "mavsdk", "pymavlink" or "inprocess".
        url: MAVLink connection URL (ignored in process).
        planner: planner name (see companion.planner_registry).
        gp_model: residual model file (from fit-gp) for the NMPC, or None for nominal.
        log_path: where the schema-v1 CSV log goes (sidecar beside it); a log already there is
            kept under a numbered name; None: a new file in ``out/flights/`` named by the time
            (flightlog.flight_log_files), never an earlier flight's log.
        replace_log: replace a log already at ``log_path`` instead of keeping it (for tools
            that own their output folder and write it anew each run: the demo, the showcase).
        seed: simulator seed (in process).
        vehicle: simulator preset or config file (in process).
        runner: timing of the mission sequence (loop rate, deadlines).
        verbose: let the MAVLink library's own log lines through.
    """

    mission_path: Path
    link: LinkKind = "mavsdk"
    url: str = DEFAULT_URL
    planner: str = "pd"
    gp_model: Path | None = None
    log_path: Path | None = None
    replace_log: bool = False
    seed: int = 0
    vehicle: str = "iris"
    runner: RunnerConfig = field(default_factory=RunnerConfig)
    verbose: bool = False

    def __post_init__(self) -> None:
        if self.link not in LINK_KINDS:
            raise ValueError(f"unknown link {self.link!r}; choose one of {', '.join(LINK_KINDS)}")


@dataclass(frozen=True)
class CompanionResult:
    """A finished run: the flight outcome and where its log went (None if nothing flown)."""

    outcome: FlightOutcome
    log_path: Path | None


def run_companion(config: CompanionConfig, progress: Callable[[str], None]) -> CompanionResult:
    """Fly ``config``'s mission and write its log.

    Raises:
        CompanionInputError: bad mission, planner or vehicle (before anything flies).
    """
    try:
        if config.seed < 0:
            raise ValueError(f"--seed must be >= 0, got {config.seed}")
        mission = load_mission(config.mission_path)
        world = _obstacle_world(config, mission)
        planner = make_planner(
            config.planner,
            mission.horizontal_command_limit_mps,
            gp_model=config.gp_model,
            rate_hz=config.runner.rate_hz,
            time_budget_s=LOCKSTEP_PLAN_BUDGET_S if config.link == "inprocess" else None,
        )
        reference = reference_of(mission)
        link = open_link(config, world)
    except ValueError as exc:  # MissionError, SimConfigError, unknown planner or URL
        raise CompanionInputError(str(exc)) from None
    flown = {}
    if hasattr(planner, "flown_model"):  # the NMPCs: which model flies, e.g. a GP left out
        flown = {"planner_model": planner.flown_model}
        progress(f"planner model: {planner.flown_model}")
    try:
        live, kept = _open_log(config, mission, link, progress, flown)
    except OutputError as exc:  # refused before take-off, not after landing
        link.close()
        raise CompanionInputError(f"--log {exc}") from None
    recorder = FlightRecorder(
        period_s=1.0 / config.runner.rate_hz,
        wall_clock_columns=config.link != "inprocess",
        on_row=live.append,
    )
    outcome: FlightOutcome | None = None
    try:
        outcome = fly_mission(
            link,
            planner,
            reference,
            mission,
            config.runner,
            recorder.record,
            progress,
            on_autopilot_metadata=live.add_metadata,
        )
    finally:
        link.close()
        log_path = _write_log(config, mission, link, recorder, outcome, live, progress)
        if log_path is None and kept is not None:
            restore_earlier_log(kept, live.path)
            progress(f"the earlier log is back at {live.path}")
    return CompanionResult(outcome, log_path)


def _open_log(
    config: CompanionConfig,
    mission: Mission,
    link: Link,
    progress: Callable[[str], None],
    extra: Mapping[str, object],
) -> tuple[LiveFlightLog, Path | None]:
    """The live log, before take-off: a new file without ``--log``; at ``--log`` otherwise,
    where a log already there is first kept under a numbered name (returned, else None).
    ``extra``: more metadata for its sidecar. Undoes both on an OutputError (one line), so
    nothing is lost or left behind."""
    metadata = _log_metadata(config, mission, link) | dict(extra)
    if config.log_path is None:
        path = claim_new_log_path()
        try:
            live = LiveFlightLog(path, metadata)
        except OutputError:
            path.unlink(missing_ok=True)
            sidecar_path(path).unlink(missing_ok=True)
            raise
        progress(f"flight log: {path} (a new file; --log PATH chooses another)")
        return live, None
    check_not_an_input(config.log_path, _inputs(config, mission))
    check_csv_log_name(config.log_path)
    kept = None if config.replace_log else keep_earlier_log(config.log_path)
    try:
        live = LiveFlightLog(config.log_path, metadata)
    except OutputError:
        if kept is not None:
            restore_earlier_log(kept, config.log_path)
        raise
    if kept is not None:
        progress(f"flight log: {config.log_path} (the log there before is kept as {kept})")
    return live, kept


def _inputs(config: CompanionConfig, mission: Mission) -> list[Path]:
    """The files the flight reads (mission, its world, GP model, vehicle config): a ``--log``
    there would move one of them aside."""
    files = (config.mission_path, mission.obstacles_world, config.gp_model, Path(config.vehicle))
    return [Path(f) for f in files if f is not None]


def _obstacle_world(config: CompanionConfig, mission: Mission) -> object | None:
    """The mission's obstacle world for the in-process simulator (None without one, or on a
    MAVLink link: there the vehicle's own sensor sees the world, e.g. vehicle-sim --world);
    refuses (CompanionInputError, one line) a mission whose obstacles the flight cannot
    honour: a planner that ignores obstacles, or a link that brings no range scans (MAVSDK
    has no OBSTACLE_DISTANCE telemetry). The planner itself brakes when scans stop coming."""
    if mission.obstacles_world is None:
        return None
    where = config.mission_path
    if not honours_obstacles(config.planner):
        raise CompanionInputError(
            f"{where}: obstacles_world is set, but planner {config.planner!r} ignores obstacles "
            f"and would fly through them; refusing (use --planner {' or '.join(OBSTACLE_PLANNERS)})"
        )
    if config.link == "mavsdk":
        raise CompanionInputError(
            f"{where}: obstacles_world is set, but the mavsdk link brings no range scans "
            "(OBSTACLE_DISTANCE) to the companion, so it would fly blind; refusing (use --link "
            "pymavlink or inprocess)"
        )
    from planners.world_file import load_world

    world = load_world(mission.obstacles_world)  # checked before flying, on every link
    return world if config.link == "inprocess" else None


def open_link(config: CompanionConfig, world: object | None = None) -> Link:
    """The link ``config`` asks for (not yet connected); in process, the simulator is put in
    ``world`` (obstacles it can hit and its range sensor sees)."""
    if config.link == "mavsdk":
        from companion.mavsdk_link import MavsdkLink

        return MavsdkLink(config.url, verbose=config.verbose)
    if config.link == "pymavlink":
        from companion.pymavlink_link import PymavlinkLink

        return PymavlinkLink(config.url)
    from companion.inprocess_link import InProcessLink

    return InProcessLink.from_vehicle(config.vehicle, config.seed, world)


def _log_metadata(config: CompanionConfig, mission: Mission, link: Link) -> dict[str, object]:
    return {
        "source": LOG_SOURCE,
        "companion_log_version": LOG_VERSION,
        "mission": mission.name,
        "planner": config.planner,
        "gp_model": None if config.gp_model is None else str(config.gp_model),
        "rate_hz": config.runner.rate_hz,
        **link.metadata(),
    }


def _write_log(
    config: CompanionConfig,
    mission: Mission,
    link: Link,
    recorder: FlightRecorder,
    outcome: FlightOutcome | None,
    live: LiveFlightLog,
    progress: Callable[[str], None],
) -> Path | None:
    """Replace the live log by the full one; None (and no files) when nothing was flown.

    Its sidecar keeps the live one's entries (the autopilot's, read before arming, even when
    the flight raised), updated with the run's as they are now (the link's contact count) and
    the outcome's; when the flight raised, the outcome is "companion_error"."""
    if len(recorder) == 0:
        live.close()
        live.path.unlink(missing_ok=True)
        sidecar_path(live.path).unlink(missing_ok=True)
        progress("no control steps flown; no flight log written")
        return None
    metadata = live.metadata | _log_metadata(config, mission, link)
    if outcome is None:  # the flight raised: the rows up to then are sound, the end is not
        metadata["outcome"] = "companion_error"
    else:
        metadata |= {
            "outcome": outcome.status,
            "goal_error_m": outcome.goal_error_m,
            "landed_error_m": outcome.landed_error_m,
            "loop_ticks": outcome.ticks,
            "loop_deadline_misses": outcome.deadline_misses,
        }
    path = live.finish(recorder.to_log(metadata))
    progress(f"flight log: {path} ({len(recorder)} rows)")
    return path
