"""The same mission, runner and control loop on all three links.

The MAVLink cases fly against the simulator's real MAVLink endpoint (started in this process on
free loopback ports) with the real clients: MAVSDK 4.x and pymavlink, in real time. The
Ctrl-C case runs the `companion` CLI as a subprocess and interrupts it in the air.
"""

from __future__ import annotations

import math
import re
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

from companion.autopilot_gains import VELOCITY_LOOP_PARAMS
from companion.control_loop import run_fixed_rate
from companion.decision import Decision, HoverPolicy
from companion.flight_recorder import FlightRecorder
from companion.inprocess_link import InProcessLink
from companion.link import Link, VelocityCommand
from companion.mavsdk_link import MavsdkLink
from companion.mission import load_mission
from companion.mission_reference import reference_of
from companion.planner_registry import make_planner
from companion.pymavlink_link import PymavlinkLink
from companion.runner import RunnerConfig, fly_mission
from companion.waiting import command_until_accepted, wait_for
from flightlog.schema import read_flight_log, write_flight_log
from tests.free_port import free_udp_port  # noqa: F401 (imported from here too)
from vehicle_sim import LandedState, Simulator, load_sim_config
from vehicle_sim.mavlink import EndpointConfig, LinkConfig, MavlinkEndpoint

REPO = Path(__file__).resolve().parents[2]
LINE = REPO / "missions" / "line_20m.toml"
GOAL_NED_M = np.array([20.0, 0.0, -2.5])


class Vehicle:
    """A simulator, and (for MAVLink) its endpoint sending to ``port`` on loopback."""

    def __init__(self, port: int | None) -> None:
        self.sim = Simulator(load_sim_config("iris"), seed=3)
        self.endpoint: MavlinkEndpoint | None = None
        if port is not None:
            links = (LinkConfig("offboard", remote=("127.0.0.1", port)),)
            self.endpoint = MavlinkEndpoint(self.sim, EndpointConfig(links=links)).start()

    @property
    def state(self):
        return self.sim.state if self.endpoint is None else self.endpoint.state


@pytest.fixture
def vehicle_port() -> Iterator[tuple[Vehicle, int]]:
    port = free_udp_port()
    vehicle = Vehicle(port)
    yield vehicle, port
    vehicle.endpoint.stop()


def open_link(kind: str, port: int, vehicle: Vehicle) -> Link:
    if kind == "inprocess":
        return InProcessLink(vehicle.sim)
    url = f"udpin://127.0.0.1:{port}"
    return MavsdkLink(url) if kind == "mavsdk" else PymavlinkLink(url)


@pytest.mark.parametrize(
    "kind",
    [
        "inprocess",
        pytest.param("pymavlink", marks=pytest.mark.slow),
        pytest.param("mavsdk", marks=pytest.mark.slow),
    ],
)
def test_20m_mission_ends_within_half_a_metre_of_the_goal_and_lands(
    kind: str, tmp_path: Path
) -> None:
    port = free_udp_port()
    vehicle = Vehicle(None if kind == "inprocess" else port)
    link = open_link(kind, port, vehicle)
    mission = load_mission(LINE)
    recorder = FlightRecorder(period_s=1.0 / 50.0)
    messages: list[str] = []
    try:
        outcome = fly_mission(
            link,
            make_planner("pd", 3.0),
            reference_of(mission),
            mission,
            RunnerConfig(),
            recorder.record,
            messages.append,
        )
    finally:
        link.close()
        if vehicle.endpoint is not None:
            vehicle.endpoint.stop()
    assert outcome.status == "completed", (outcome.detail, messages)
    assert outcome.goal_error_m < 0.5
    final = vehicle.state
    assert not final.armed
    assert final.landed_state == LandedState.ON_GROUND
    assert float(np.hypot(*(final.pos_ned_m[:2] - GOAL_NED_M[:2]))) < 0.5
    # the velocity-loop gains a flight log keeps, read over this link (MAVLink: as float32)
    reported = outcome.autopilot_metadata["velocity_loop_gains"]
    expected = {k: vehicle.sim.params.get(p) for k, p in VELOCITY_LOOP_PARAMS.items()}
    assert reported == pytest.approx(expected, rel=1e-6)
    log = read_flight_log(write_flight_log(tmp_path / "f.csv", recorder.to_log(link.metadata())))
    assert log.metadata["link"] == kind
    assert "OFFBOARD" in set(log["mode"])
    commanded_speed = np.hypot(log["cmd_vel_n_mps"], log["cmd_vel_e_mps"])
    assert 2.5 < float(np.max(commanded_speed)) <= mission.speed_limit_mps + 1e-9
    assert float(np.max(log["pos_n_m"])) > 19.5


class StderrReader:
    """Collects a subprocess's stderr lines on a thread; waits for a line with a deadline."""

    def __init__(self, proc: subprocess.Popen) -> None:
        self.proc = proc
        self.lines: list[str] = []
        self._thread = threading.Thread(target=self._read, args=(proc,), daemon=True)
        self._thread.start()

    def _read(self, proc: subprocess.Popen) -> None:
        for line in proc.stderr:
            self.lines.append(line.rstrip("\n"))

    def wait_for(self, text: str, timeout_s: float) -> None:
        deadline = time.monotonic() + timeout_s
        while not any(text in line for line in self.lines):
            if time.monotonic() > deadline or self.proc.poll() is not None:
                raise AssertionError(f"no {text!r} on stderr within {timeout_s} s: {self.lines}")
            time.sleep(0.05)

    def text(self) -> str:
        self._thread.join(5.0)
        return "\n".join(self.lines)


def _as_a_background_job() -> None:
    signal.signal(signal.SIGINT, signal.SIG_IGN)


@pytest.mark.slow
@pytest.mark.parametrize(
    ("sig", "code_expected", "said", "status"),
    [
        (signal.SIGINT, 130, "interrupted by Ctrl-C", "interrupted"),
        (signal.SIGTERM, 143, "terminated by SIGTERM", "terminated"),
    ],
    ids=["SIGINT", "SIGTERM"],
)
def test_ctrl_c_or_sigterm_in_the_air_holds_then_lands_and_exits_128_plus_signal(
    vehicle_port, tmp_path: Path, sig: int, code_expected: int, said: str, status: str
) -> None:
    vehicle, port = vehicle_port
    log_path = tmp_path / "flight.csv"
    cmd = [
        sys.executable, "-m", "scripts.companion_cli", str(LINE), "--link", "mavsdk",
        "--url", f"udpin://127.0.0.1:{port}", "--log", str(log_path),
    ]  # fmt: skip
    # Started as a shell starts a background job (SIGINT ignored, inherited across exec): the
    # companion must still answer the operator's Ctrl-C with a safe stop.
    proc = subprocess.Popen(
        cmd, cwd=REPO, stderr=subprocess.PIPE, text=True, preexec_fn=_as_a_background_job
    )
    stderr = StderrReader(proc)
    try:
        stderr.wait_for("following the reference", timeout_s=60.0)
        time.sleep(2.0)  # flying north at about 3 m/s
        north_at_interrupt_m = float(vehicle.state.pos_ned_m[0])
        assert vehicle.state.armed and -vehicle.state.pos_ned_m[2] > 2.0
        proc.send_signal(sig)
        code = proc.wait(timeout=60.0)
    finally:
        if proc.poll() is None:
            proc.kill()
    text = stderr.text()
    assert code == code_expected, text
    assert all(line.startswith("companion: ") for line in text.splitlines()), text  # no MAVSDK
    assert f"{said}: holding and landing" in text
    hold_at = text.index("safe stop: hold accepted")
    assert hold_at < text.index("safe stop: land accepted") < text.index("safe stop: landed and")
    assert "safe stop: landed and disarmed" in text
    last = text.strip().splitlines()[-1]  # not "interrupted: interrupted ...; landed n/a ..."
    assert re.fullmatch(rf"companion: {said}; \d+ deadline misses in \d+ steps", last), last
    final = vehicle.state
    assert not final.armed and final.landed_state == LandedState.ON_GROUND
    # No stale setpoint: the vehicle braked near where it was, instead of flying on north.
    assert north_at_interrupt_m > 1.0
    assert abs(float(final.pos_ned_m[0]) - north_at_interrupt_m) < 2.5
    log = read_flight_log(log_path)
    assert log.metadata["outcome"] == status
    assert set(log.metadata["velocity_loop_gains"]) == set(VELOCITY_LOOP_PARAMS)


class TurnInPlace:
    """Zero velocity and a constant yaw rate."""

    def __init__(self, yaw_rate_radps: float) -> None:
        self.command = VelocityCommand((0.0, 0.0, 0.0), yaw_rate_radps)

    def decide(self, state, t_s: float) -> Decision:
        return Decision(self.command)


@pytest.mark.parametrize(
    "kind",
    [
        "inprocess",
        pytest.param("pymavlink", marks=pytest.mark.slow),
        pytest.param("mavsdk", marks=pytest.mark.slow),
    ],
)
def test_yaw_rate_commands_turn_the_vehicle_on_every_link(kind: str) -> None:
    port = free_udp_port()
    vehicle = Vehicle(None if kind == "inprocess" else port)
    link = open_link(kind, port, vehicle)
    yaw_rate_radps, turn_s = 0.5, 3.0
    try:
        link.connect(15.0)
        command_until_accepted(link, link.arm, 10.0, "arm")
        command_until_accepted(link, lambda: link.takeoff(2.0), 10.0, "takeoff")
        wait_for(link, lambda s: s.altitude_m > 1.7, 30.0, "takeoff")
        policy = TurnInPlace(yaw_rate_radps)
        run_fixed_rate(
            link,
            HoverPolicy(np.zeros(3)),
            rate_hz=50.0,
            until=lambda s, t: False,
            timeout_s=1.0,
            on_tick=lambda tick: None,
        )
        assert link.start_offboard().accepted
        yaw_start = link.read_state().yaw_rad
        run_fixed_rate(
            link,
            policy,
            rate_hz=50.0,
            until=lambda s, t: False,
            timeout_s=turn_s,
            on_tick=lambda tick: None,
        )
        turned_rad = math.remainder(link.read_state().yaw_rad - yaw_start, 2.0 * math.pi)
        assert link.hold().accepted and link.land().accepted
        wait_for(link, lambda s: not s.armed, 60.0, "landing")
    finally:
        link.close()
        if vehicle.endpoint is not None:
            vehicle.endpoint.stop()
    assert turned_rad == pytest.approx(yaw_rate_radps * turn_s, abs=0.4)


@pytest.mark.slow
def test_losing_the_vehicle_mid_flight_fails_the_mission_within_deadlines() -> None:
    port = free_udp_port()
    vehicle = Vehicle(port)
    link = PymavlinkLink(f"udpin://127.0.0.1:{port}")
    mission = load_mission(LINE)
    messages: list[str] = []

    def cut_the_link_once_following(tick) -> None:
        if tick.state.mode == "OFFBOARD" and vehicle.endpoint.running:
            vehicle.endpoint.stop()

    started = time.monotonic()
    try:
        outcome = fly_mission(
            link,
            make_planner("pd", 3.0),
            reference_of(mission),
            mission,
            RunnerConfig(),
            cut_the_link_once_following,
            messages.append,
        )
    finally:
        link.close()
        if vehicle.endpoint.running:
            vehicle.endpoint.stop()
    assert outcome.status == "failed"
    assert outcome.detail.startswith("link lost: no autopilot heartbeat")
    assert not outcome.disarmed
    assert any(m.startswith("safe stop: hold refused") for m in messages), messages
    assert any(m.endswith("; stopping safely") for m in messages), messages  # in the air: said
    assert time.monotonic() - started < 40.0


def test_no_vehicle_fails_on_the_ground_and_leaves_the_saying_to_the_last_line() -> None:
    """Nobody on the port: the outcome says so, and the runner's lines do not (the command's
    last line is the outcome: said twice before, one line apart)."""
    link = PymavlinkLink(f"udpin://127.0.0.1:{free_udp_port()}")
    mission = load_mission(LINE)
    messages: list[str] = []
    try:
        outcome = fly_mission(
            link,
            make_planner("pd", 3.0),
            reference_of(mission),
            mission,
            RunnerConfig(connect_timeout_s=0.5),
            lambda tick: None,
            messages.append,
        )
    finally:
        link.close()
    assert (outcome.status, outcome.ticks) == ("failed", 0)
    assert outcome.detail.startswith("no autopilot heartbeat on udpin://127.0.0.1:")
    assert not any(outcome.detail in m for m in messages), messages


@pytest.mark.slow
def test_sigkill_mid_flight_leaves_a_readable_log_of_every_row_flown(
    vehicle_port, tmp_path: Path
) -> None:
    vehicle, port = vehicle_port
    log_path = tmp_path / "flight.csv"
    cmd = [
        sys.executable, "-m", "scripts.companion_cli", str(LINE), "--link", "pymavlink",
        "--url", f"udpin://127.0.0.1:{port}", "--log", str(log_path),
    ]  # fmt: skip
    # Started as a shell starts a background job (SIGINT ignored, inherited across exec): the
    # companion must still answer the operator's Ctrl-C with a safe stop.
    proc = subprocess.Popen(
        cmd, cwd=REPO, stderr=subprocess.PIPE, text=True, preexec_fn=_as_a_background_job
    )
    stderr = StderrReader(proc)
    try:
        stderr.wait_for("following the reference", timeout_s=60.0)
        time.sleep(2.0)
        rows_seen = len(log_path.read_text().splitlines()) - 1
        proc.kill()
        proc.wait(timeout=10.0)
    finally:
        if proc.poll() is None:
            proc.kill()
    log = read_flight_log(log_path)  # schema v1, validated: finite, strictly increasing time
    assert log.n_rows >= rows_seen > 100
    assert log.metadata["complete"] is False and log.metadata["source"] == "companion"
    assert set(log.metadata["velocity_loop_gains"]) == set(VELOCITY_LOOP_PARAMS)  # read pre-arm
    steps = np.diff(log["t_s"])
    assert float(np.max(steps)) < 0.5  # no hole: every row flown up to the kill
    assert "OFFBOARD" in set(log["mode"])


def test_an_unwritable_log_is_refused_before_take_off(tmp_path: Path) -> None:
    blocker = tmp_path / "not_a_folder"
    blocker.write_text("a file where the log's folder should be\n")
    proc = subprocess.run(
        [
            sys.executable, "-m", "scripts.companion_cli", str(LINE), "--link", "inprocess",
            "--log", str(blocker / "flight.csv"),
        ],
        cwd=REPO, capture_output=True, text=True, timeout=120,
    )  # fmt: skip
    assert proc.returncode == 2, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.strip()]
    assert len(lines) == 1 and "--log" in lines[0] and "folder" in lines[0], proc.stderr
    assert "armed" not in proc.stderr
