"""Ordinary missions (missions/*.toml: the square, the S-curve, the demo B-spline) flown by the
companion in process on a simulated Iris with hidden effects, logged as the diagnosis would read
them. For the diagnosis' tests on flights that were not designed to excite anything (issue 18):
the truth stays with the caller, never in the log."""

from __future__ import annotations

from pathlib import Path

from companion.flight_recorder import FlightRecorder
from companion.inprocess_link import InProcessLink
from companion.mission import load_mission
from companion.mission_reference import reference_of
from companion.planner_registry import make_planner
from companion.runner import RunnerConfig, fly_mission
from flightlog.schema import FlightLog, read_flight_log, write_flight_log
from vehicle_sim import Simulator, load_sim_config

MISSIONS_DIR = Path(__file__).resolve().parents[1] / "missions"
ORDINARY_MISSIONS = ("square", "s_curve", "demo_bspline")


class MissionFlightError(RuntimeError):
    """The companion did not complete the mission; the message gives its outcome."""


def fly_ordinary_mission(
    mission: str, truth: dict, tmp_path: Path, seed: int, rate_hz: float = 20.0
) -> FlightLog:
    """Fly ``missions/<mission>.toml`` with [Kulathunga23]'s PD regulator at ``rate_hz`` [Hz]
    on an Iris with the effects ``truth`` on; the log as written and read back."""
    plan = load_mission(MISSIONS_DIR / f"{mission}.toml")
    sim = Simulator(load_sim_config("iris", truth), seed=seed)
    recorder = FlightRecorder(period_s=1.0 / rate_hz, wall_clock_columns=False)
    outcome = fly_mission(
        InProcessLink(sim),
        make_planner("pd", plan.speed_limit_mps, rate_hz=rate_hz),
        reference_of(plan),
        plan,
        RunnerConfig(rate_hz=rate_hz),
        recorder.record,
        lambda message: None,
    )
    if outcome.status != "completed":
        raise MissionFlightError(f"{mission}: {outcome.status} ({outcome.detail})")
    log = recorder.to_log({"source": "mission-flight", "mission": mission})
    return read_flight_log(write_flight_log(tmp_path / f"{mission}_{seed}.csv", log))
