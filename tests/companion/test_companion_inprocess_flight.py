"""Whole missions in process (lockstep): reach the goal, land, log; deterministic; fault-proof."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from companion.app import CompanionConfig, run_companion
from companion.autopilot_gains import velocity_loop_gains
from companion.flight_recorder import FlightRecorder
from companion.inprocess_link import InProcessLink
from companion.link import VelocityCommand
from companion.mission import load_mission
from companion.mission_reference import reference_of
from companion.planner_registry import make_planner
from companion.runner import RunnerConfig, fly_mission
from flightlog.schema import read_flight_log, sidecar_path, write_flight_log
from scripts.companion_cli import main
from vehicle_sim import Simulator, load_sim_config

REPO = Path(__file__).resolve().parents[2]
LINE = REPO / "missions" / "line_20m.toml"


class RecordingInProcessLink(InProcessLink):
    """The real in-process link, also keeping every command it sent."""

    def __init__(self, sim: Simulator) -> None:
        super().__init__(sim)
        self.sent: list[VelocityCommand] = []

    def send_velocity(self, command: VelocityCommand) -> None:
        self.sent.append(command)
        super().send_velocity(command)


class FaultyPlanner:
    """The real PD regulator, except that it raises on calls 100-104 and returns NaN on 200-202."""

    def __init__(self) -> None:
        self._pd = make_planner("pd", 3.0)
        self.calls = 0

    def plan(self, state, reference, t_s):
        self.calls += 1
        if 100 <= self.calls < 105:
            raise RuntimeError("injected planner fault")
        result = self._pd.plan(state, reference, t_s)
        if 200 <= self.calls < 203:
            return type(result)(
                np.full(4, np.nan), result.predicted_trajectory, True, "", result.solve_time_s
            )
        return result


def fly(planner, seed: int = 0, rate_hz: float = 50.0):
    sim = Simulator(load_sim_config("iris"), seed=seed)
    link = RecordingInProcessLink(sim)
    mission = load_mission(LINE)
    recorder = FlightRecorder(period_s=1.0 / rate_hz, wall_clock_columns=False)
    outcome = fly_mission(
        link,
        planner,
        reference_of(mission),
        mission,
        RunnerConfig(rate_hz=rate_hz),
        recorder.record,
        lambda message: None,
    )
    return sim, link, recorder, outcome


def test_20m_mission_reaches_the_goal_lands_and_logs_the_commands_sent(tmp_path: Path) -> None:
    sim, link, recorder, outcome = fly(make_planner("pd", 3.0))
    assert outcome.status == "completed", outcome.detail
    assert outcome.goal_error_m < 0.5
    assert outcome.landed_error_m < 0.5
    assert outcome.disarmed and not sim.state.armed
    assert outcome.deadline_misses == 0
    log = read_flight_log(write_flight_log(tmp_path / "f.csv", recorder.to_log({"source": "t"})))
    sent = np.array([(*c.vel_ned_mps, c.yaw_rate_radps) for c in link.sent])
    logged = log.stack("cmd_vel_n_mps", "cmd_vel_e_mps", "cmd_vel_d_mps", "cmd_yaw_rate_radps")
    np.testing.assert_array_equal(logged, sent)
    assert log.has("acc_n_mps2", "thrust_n", "battery_v", "ref_pos_n_m", "planner_ok")
    assert set(log["mode"]) <= {"HOLD", "OFFBOARD"} and "OFFBOARD" in set(log["mode"])
    assert np.all(log["planner_ok"] == 1.0)
    assert float(np.max(log["pos_n_m"])) == pytest.approx(20.0, abs=0.5)
    assert float(np.max(np.hypot(log["cmd_vel_n_mps"], log["cmd_vel_e_mps"]))) <= 3.0 + 1e-9


def test_same_seed_gives_identical_logs(tmp_path: Path) -> None:
    logs = []
    for i in range(2):
        out = tmp_path / f"f{i}.csv"
        assert main([str(LINE), "--link", "inprocess", "--seed", "7", "--log", str(out)]) == 0
        logs.append((out.read_bytes(), sidecar_path(out).read_bytes()))
    assert logs[0] == logs[1]
    assert len(logs[0][0]) > 10_000


def test_planner_faults_give_safe_commands_with_reasons_and_the_flight_goes_on() -> None:
    _, link, recorder, outcome = fly(FaultyPlanner())
    assert outcome.status == "completed", outcome.detail
    assert outcome.goal_error_m < 0.5
    log = recorder.to_log({"source": "t"})
    assert int(np.sum(log["planner_ok"] == 0.0)) == 8
    bad = log["planner_ok"] == 0.0
    assert np.all(log.stack("cmd_vel_n_mps", "cmd_vel_e_mps", "cmd_vel_d_mps")[bad] == 0.0)
    reasons = [(e["count"], e["reason"]) for e in log.metadata["safe_command_events"]]
    assert reasons[0] == (5, "planner raised RuntimeError: injected planner fault")
    assert reasons[1][0] == 3 and "unusable command" in reasons[1][1]


def test_cli_flies_in_process_and_writes_a_readable_log(tmp_path: Path, capsys) -> None:
    out = tmp_path / "flight.csv"
    code = main([str(LINE), "--link", "inprocess", "--log", str(out), "--rate-hz", "30"])
    err = capsys.readouterr().err
    assert code == 0, err
    log = read_flight_log(out)
    assert log.metadata["link"] == "inprocess"
    assert log.metadata["outcome"] == "completed"
    assert log.metadata["rate_hz"] == 30.0
    # the autopilot's velocity-loop gains, which fit-gp's px4_velocity_pi structure needs
    reported = dict(velocity_loop_gains(InProcessLink.from_vehicle("iris", 0)))
    assert log.metadata["velocity_loop_gains"] == reported
    np.testing.assert_allclose(np.diff(log["t_s"]), 1.0 / 30.0, atol=0.003)
    assert "completed" in err


def test_the_velocity_loop_gains_reach_the_sidecar_when_read_and_survive_a_raising_flight(
    tmp_path: Path,
) -> None:
    log_path = tmp_path / "flight.csv"
    config = CompanionConfig(mission_path=LINE, link="inprocess", log_path=log_path)
    sidecar_when_armed: dict[str, object] = {}

    def progress(message: str) -> None:
        if message.startswith("armed;"):  # the gains are read just before arming
            sidecar_when_armed.update(json.loads(sidecar_path(log_path).read_text()))
        if message.startswith("offboard;"):  # after the setpoint stream's rows
            raise RuntimeError("the caller's progress display broke")

    with pytest.raises(RuntimeError, match="progress display broke"):
        run_companion(config, progress)
    reported = dict(velocity_loop_gains(InProcessLink.from_vehicle("iris", 0)))
    assert sidecar_when_armed["complete"] is False
    assert sidecar_when_armed["velocity_loop_gains"] == reported
    log = read_flight_log(log_path)
    assert log.n_rows > 0 and log.metadata["outcome"] == "companion_error"  # the flight raised
    assert log.metadata["velocity_loop_gains"] == reported


@pytest.mark.parametrize("mission", ["square", "s_curve"])
def test_cli_flies_the_demo_square_and_the_bspline_s_curve_to_their_goals(
    mission: str, tmp_path: Path, capsys
) -> None:
    path = REPO / "missions" / f"{mission}.toml"
    out = tmp_path / "flight.csv"
    code = main([str(path), "--link", "inprocess", "--log", str(out)])
    assert code == 0, capsys.readouterr().err
    log = read_flight_log(out)
    assert log.metadata["goal_error_m"] < 0.3
    ref = log.stack("ref_pos_n_m", "ref_pos_e_m", "ref_pos_d_m")
    pos = log.stack("pos_n_m", "pos_e_m", "pos_d_m")
    offboard = log["mode"] == "OFFBOARD"
    assert float(np.max(np.linalg.norm(ref[offboard] - pos[offboard], axis=1))) < 3.0
    assert float(np.ptp(log["pos_e_m"])) > 5.0


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (["--link", "inprocess", "--vehicle", "no_such_preset"], "no such config file or preset"),
        (["--link", "pymavlink", "--url", "serial:/dev/x"], "unsupported MAVLink URL"),
        (["--link", "inprocess", "--seed", "-1"], "--seed must be >= 0, got -1"),
    ],
)
def test_cli_bad_vehicle_or_url_is_one_line_and_exit_2(
    args: list[str], match: str, tmp_path: Path, capsys
) -> None:
    code = main([str(LINE), *args, "--log", str(tmp_path / "f.csv")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and match in err


@pytest.mark.parametrize(
    ("args", "match"),
    [
        (
            ["--link", "mavsdk", "--vehicle", "iris_study"],
            "--vehicle chooses the in-process simulator; over --link mavsdk the vehicle is the "
            "one answering at --url",
        ),
        (["--link", "pymavlink", "--seed", "3", "--vehicle", "f450"], "--vehicle and --seed"),
        (
            ["--link", "inprocess", "--url", "udpin://0.0.0.0:14540"],
            "--url is for the mavsdk and pymavlink links, not --link inprocess",
        ),
    ],
)
def test_cli_an_option_the_link_would_ignore_is_one_line_and_exit_2(
    args: list[str], match: str, tmp_path: Path, capsys
) -> None:
    """--vehicle iris_study over MAVSDK was silently ignored: the flight flew whatever vehicle
    answered at --url, its log saying nothing of the option."""
    with pytest.raises(SystemExit) as exc:
        main([str(LINE), *args, "--log", str(tmp_path / "f.csv")])
    err = capsys.readouterr().err
    assert exc.value.code == 2
    assert err.count("\n") == 1 and match in err
    assert list(tmp_path.iterdir()) == []


def test_cli_bad_mission_is_one_line_and_exit_2(tmp_path: Path, capsys) -> None:
    bad = tmp_path / "bad.toml"
    bad.write_text('altitude_m = 2.0\nspeed_limit_mps = 1.0\n[reference]\nkind = "spiral"\n')
    code = main([str(bad), "--link", "inprocess", "--log", str(tmp_path / "f.csv")])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1
    assert err.startswith("companion: error: ") and "choose one of waypoints, bspline" in err
    assert not (tmp_path / "f.csv").exists()


class SetpointDroppingLink(InProcessLink):
    """The real in-process link, but its setpoints never reach the vehicle."""

    def send_velocity(self, command: VelocityCommand) -> None:
        """Dropped: the vehicle sees no setpoint stream."""


def test_refused_offboard_fails_the_flight_safely_and_lands() -> None:
    sim = Simulator(load_sim_config("iris"), seed=0)
    mission = load_mission(LINE)
    messages: list[str] = []
    outcome = fly_mission(
        SetpointDroppingLink(sim),
        make_planner("pd", 3.0),
        reference_of(mission),
        mission,
        RunnerConfig(),
        lambda tick: None,
        messages.append,
    )
    assert outcome.status == "failed"
    assert outcome.detail.startswith("OFFBOARD refused: Offboard denied")
    assert outcome.goal_error_m is None
    assert outcome.disarmed and not sim.state.armed
    assert -sim.state.pos_ned_m[2] < 0.05
    assert messages[-1].startswith("safe stop: landed and disarmed")


def test_cli_log_onto_the_mission_file_is_refused_and_the_mission_kept(
    tmp_path: Path, capsys
) -> None:
    mission = tmp_path / "line.toml"
    mission.write_text(LINE.read_text())
    code = main([str(mission), "--link", "inprocess", "--log", str(mission)])
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "is an input being read" in err, err
    assert mission.read_text() == LINE.read_text()


class RecordingLink(InProcessLink):
    """The real in-process link, recording what the companion sends once ``recording``."""

    def __init__(self, sim: Simulator) -> None:
        super().__init__(sim)
        self.recording = False
        self.sent: list[object] = []

    def send_velocity(self, command: VelocityCommand) -> None:
        if self.recording:
            self.sent.append(command)
        super().send_velocity(command)

    def hold(self):
        if self.recording:
            self.sent.append("hold")
        return super().hold()

    def land(self):
        if self.recording:
            self.sent.append("land")
        return super().land()


def test_ctrl_c_while_following_brakes_before_holding_and_landing() -> None:
    """A flight ended mid-mission sends zero velocity first (the vehicle brakes even if HOLD
    never comes), then HOLD, then LAND, and nothing else."""
    sim = Simulator(load_sim_config("iris"), seed=0)
    link = RecordingLink(sim)
    mission = load_mission(LINE)

    following_since: list[float] = []

    def operator(tick) -> None:  # Ctrl-C after 3 s of following, at speed
        if tick.state.mode == "OFFBOARD":
            following_since.append(tick.t_s)
            if tick.t_s - following_since[0] >= 3.0:
                link.recording = True
                raise KeyboardInterrupt

    outcome = fly_mission(
        link, make_planner("pd", 3.0), reference_of(mission), mission, RunnerConfig(), operator,
        lambda _m: None,
    )  # fmt: skip
    assert outcome.status == "interrupted" and outcome.disarmed
    assert link.sent == [VelocityCommand((0.0, 0.0, 0.0), 0.0), "hold", "land"]


def test_a_vehicle_slow_but_short_of_the_goal_has_not_reached_it() -> None:
    """Commands limited to 0.2 m/s cover 0.2 m/s x (the reference's 6.7 s + 5 s of settle time)
    = 2.3 m of the 20 m line: slower than arrive_speed_mps (0.3 m/s) but 17.7 m short, so the
    goal is not reached (slow is not arrived)."""
    sim = Simulator(load_sim_config("iris"), seed=0)
    mission = load_mission(LINE)
    reference = reference_of(mission)
    outcome = fly_mission(
        InProcessLink(sim), make_planner("pd", 0.2), reference, mission,
        RunnerConfig(settle_timeout_s=5.0), lambda _tick: None, lambda _m: None,
    )  # fmt: skip
    assert outcome.status == "goal_not_reached", outcome.detail
    assert outcome.goal_error_m == pytest.approx(20.0 - 0.2 * (reference.duration_s + 5.0), abs=0.5)
    assert outcome.disarmed
