"""`rover-path teach` / `rover-path repeat`: the user's teach-and-repeat workflow, end to end
against `vehicle-sim --vehicle husky_50kg` and in process; every refusal is one line."""

import json
import math
import signal
import subprocess
import sys
import threading
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np
import pytest

from experiments.rover import learner
from experiments.rover.experience_file import save_experience
from planners.rover.path import TaughtPath
from planners.rover.path_file import path_csv_text
from scripts.rover_path import main, parse_args
from tests.free_port import free_udp_port
from vehicle_sim.rover import RoverSim, rover_preset
from vehicle_sim.rover.mavlink_rover import RoverMavlinkEndpoint

REPO = Path(__file__).resolve().parents[2]
OPEN = "2:0,1.5:0.5,1:0"  # an open path of 4.5 m, turning left
LOOP = "2:0,4.712:0.667,2:0,4.712:0.667"  # 13.4 m, back where it started


def _one_line_error(capsys: pytest.CaptureFixture[str]) -> str:
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1, err
    return err[0]


@pytest.fixture
def files(tmp_path: Path) -> dict[str, Path]:
    """A straight 6 m open path, a 16 m loop, and an experience file of the open one."""
    open_path = TaughtPath.from_segments([(6.0, 0.0)])
    loop = TaughtPath.from_segments([(3.0, 0.0), (5.0 * math.pi / 2, 0.4)] * 2)
    out = {"open": tmp_path / "open.csv", "loop": tmp_path / "loop.csv"}
    out["open"].write_text(path_csv_text(open_path))
    out["loop"].write_text(path_csv_text(loop))
    out["open_exp"] = tmp_path / "open.npz"
    save_experience(out["open_exp"], learner.make_history_gp(), open_path, 1)
    return out


def test_help_says_each_exit_code_once(capsys):
    with pytest.raises(SystemExit) as done:
        parse_args(["--help"])
    assert done.value.code == 0
    out = capsys.readouterr().out
    assert out.count("Exit codes") == 1 and "143 SIGTERM" in out


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["repeat", "--path", "{tmp}/missing.csv"], "no such path file; teach it again"),
        (["repeat", "--path", "{tmp}/nan.csv"], "nan.csv: path line 3"),
        (["repeat", "--path", "{tmp}/cols.csv"], "line 2 has 3 columns, expected 2"),
        (["repeat", "--path", "{tmp}/header.csv"], "expected the header 'x_m,y_m'"),
        (["repeat", "--path", "{tmp}/short.csv"], "short.csv: 1 row under its header; a path"),
        (["repeat", "--path", "{tmp}/empty.csv"], "empty.csv: 0 rows under its header; a path"),
        (["repeat", "--path", "{tmp}/one.csv"], "line 3 has 1 column, expected 2"),
        (["repeat", "--path", "{tmp}/binary.csv"], "cannot read it as a CSV text file"),
        (["repeat", "--path", "{loop}", "--experience", "{open_exp}"], "learned on another path"),
        (["repeat", "--path", "{loop}", "--experience", "{tmp}/junk.npz"], "not a readable"),
        (["repeat", "--path", "{open}", "--trials", "2"], "is open (its end is 6.0 m"),
        (["repeat", "--path", "{loop}", "--scheduler", "fast"], "--scheduler 'fast' is unknown"),
        (["repeat", "--path", "{loop}", "--speed=-1"], "--speed: must be a finite number"),
        (["repeat", "--path", "{loop}", "--trials", "0"], "--trials: must be >= 1"),
        (["repeat", "--path", "{open}", "--drive-back", "sideways"], "invalid choice: 'sideways'"),
        (["repeat", "--path", "{loop}", "--url", "tcp:1.2.3.4:5"], "unsupported MAVLink URL"),
        (["repeat", "--path", "{loop}", "--link", "inprocess", "--vehicle", "x"], "unknown rover"),
        (["teach", "--out", "{tmp}/p.csv", "--link", "inprocess"], "pass --drive"),
        (["teach", "--out", "{tmp}/p.csv", "--drive", "3"], "is not LENGTH_M:CURVATURE_1PM"),
        (["teach", "--out", "{tmp}/p.csv", "--drive=-3:0"], "need a length > 0"),
        (["teach", "--out", "{tmp}"], "--out"),
        (["teach", "--out", "{tmp}/p.csv", "--vehicle", "dmrv_600kg"], "--vehicle is for --link"),
        (["repeat", "--path", "{loop}", "--seed", "3"], "--seed is for --link inprocess"),
        (["repeat", "--path", "{loop}", "--link", "inprocess", "--url", "udp://:1"], "--url is"),
        (["repeat", "--path", "{open}", "--drive", "3:0"], "unrecognized arguments: --drive"),
        (["repeat", "--path", "{loop}", "--out", "{open}"], "error: --out "),
        (["repeat", "--path", "{loop}", "--experience", "{loop}"], "error: --experience "),
        (["repeat", "--path", "{loop}", "--experience", "{open}/e.npz"], "error: --experience "),
    ],
)
def test_bad_input_is_one_line_and_exit_2(
    tmp_path: Path, files: dict[str, Path], capsys, argv: list[str], message: str
) -> None:
    (tmp_path / "nan.csv").write_text("x_m,y_m\n0,0\n1,nan\n2,0\n3,0\n")
    (tmp_path / "cols.csv").write_text("x_m,y_m\n0,0,1\n1,0\n2,0\n")
    (tmp_path / "header.csv").write_text("north,east\n0,0\n1,0\n2,0\n")
    (tmp_path / "short.csv").write_text("x_m,y_m\n0,0\n")
    (tmp_path / "empty.csv").write_text("x_m,y_m\n")
    (tmp_path / "one.csv").write_text("x_m,y_m\n0,0\n1\n2,0\n")
    (tmp_path / "binary.csv").write_bytes(b"\xff\xfe\x00\x89")
    (tmp_path / "junk.npz").write_text("not numpy")
    names = {"tmp": tmp_path, **files}
    args = [a.format(**names) for a in argv]
    assert main(args) == 2
    line = _one_line_error(capsys)
    assert line.startswith("rover-path") and "error:" in line and message in line, line


def test_a_teach_pass_with_too_little_motion_is_one_line_exit_1(tmp_path: Path, capsys) -> None:
    out = tmp_path / "p.csv"
    argv = ["teach", "--link", "inprocess", "--drive", "0.5:0", "--out", str(out)]
    assert main(argv) == 1
    err = capsys.readouterr().err.strip().splitlines()
    assert "drove 0." in err[-1] and "teach again" in err[-1]
    assert not out.exists()


def test_a_vertex_spacing_longer_than_the_drive_says_to_choose_a_smaller_one(
    tmp_path: Path, capsys
) -> None:
    """3 m driven at --spacing 100: the pass is too short for 3 vertices, and the line says it
    is the spacing, not "a path needs at least 300 m: drive it along the path" alone."""
    out = tmp_path / "p.csv"
    argv = ["teach", "--link", "inprocess", "--drive", "3:0", "--spacing", "100", "--out", str(out)]
    assert main(argv) == 1
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert "at least 300 m (3 vertices 100 m apart)" in last and "smaller --spacing" in last, last
    assert not out.exists()


def _json(folder: Path) -> dict:
    return json.loads((folder / "repeat.json").read_text())


def test_a_speed_above_the_rovers_is_reported_as_driven_not_as_asked(
    tmp_path: Path, files: dict[str, Path], capsys
) -> None:
    """The Husky drives at most 1 m/s: asked for 5 m/s on the 6 m open path, its trial line
    and repeat.json say the speed it drove (the path over the travel time) beside the one
    scheduled; the line said "at 5.00 m/s mean" of a trial driven at 0.9 m/s."""
    rep = tmp_path / "rep"
    argv = ["repeat", "--link", "inprocess", "--path", str(files["open"]), "--trials", "1",
            "--speed", "5", "--experience", str(tmp_path / "e.npz"), "--out", str(rep)]  # fmt: skip
    assert main(argv) == 0
    line = capsys.readouterr().out.strip()
    driven = _json(rep)["driven_speed_mps"][0]
    assert 0.7 < driven <= 1.0
    assert f"at {driven:.2f} m/s mean (5.00 m/s scheduled)" in line, line


@pytest.mark.parametrize(
    ("options", "tuning", "said"),
    [
        (["--tuning", "roc6_150kg"], "roc6_150kg", "NMPC tuned for roc6_150kg"),
        (["--vehicle", "husky_50kg"], "husky_50kg", "NMPC tuned for husky_50kg"),
    ],
)
def test_repeat_says_and_records_the_nmpc_tuning_it_drove_with(
    tmp_path: Path, files: dict[str, Path], capsys, options, tuning, said
) -> None:
    """A run's weights decide how it tracks (the 600 kg rover: 5 mm or 0.2 m off), so its
    first line and repeat.json name them; neither did, and two runs' figures could not be
    told apart by what drove them."""
    rep = tmp_path / "rep"
    argv = ["repeat", "--link", "inprocess", "--path", str(files["open"]), "--trials", "1",
            "--experience", str(tmp_path / "e.npz"), "--out", str(rep), *options]  # fmt: skip
    assert main(argv) == 0
    assert said in capsys.readouterr().err.splitlines()[0]
    assert _json(rep)["nmpc_tuning"] == tuning


@pytest.mark.slow
def test_teach_and_repeat_in_process_go_on_learning_across_runs(tmp_path: Path, capsys) -> None:
    path, exp, rep = tmp_path / "loop.csv", tmp_path / "loop.npz", tmp_path / "rep"
    assert main(["teach", "--link", "inprocess", "--drive", LOOP, "--out", str(path)]) == 0
    assert "(a loop)" in capsys.readouterr().err
    common = ["repeat", "--link", "inprocess", "--path", str(path), "--experience", str(exp)]
    assert main([*common, "--trials", "2", "--out", str(rep)]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert [line.split(":")[0] for line in out] == ["trial 1", "trial 2"]
    first = _json(rep)
    assert first["trial"] == [1, 2] and first["status"] == "completed"
    assert first["experiences"][0] < first["experiences"][1]
    assert (rep / "repeat.png").stat().st_size > 5_000
    assert main([*common, "--trials", "1", "--scheduler", "experiment_2", "--out", str(rep)]) == 0
    captured = capsys.readouterr()
    assert f"{first['experiences_after']} experiences from 2 trials" in captured.err
    assert captured.out.startswith("trial 3:")
    second = _json(rep)
    assert second["trials_before"] == 2 and second["trial"] == [3]
    assert second["experiences_after"] > first["experiences_after"]
    assert second["all_trials"]["trial"] == [1, 2, 3]  # the report covers every run
    assert second["all_trials"]["max_e_lat_m"][:2] == first["max_e_lat_m"]


@pytest.mark.slow(expected_s=120)
def test_teach_and_repeat_against_vehicle_sim(tmp_path: Path) -> None:
    """The README's recipe: `vehicle-sim --vehicle husky_50kg`, a scripted teach drive of an
    open path, a trial with --drive-back, then a second run that reloads the experience and
    goes on learning (several trials in one run: the in-process tests)."""
    port = free_udp_port()
    sim = subprocess.Popen(
        [sys.executable, "-m", "scripts.vehicle_sim_cli", "--vehicle", "husky_50kg",
         "--offboard-port", str(port)],
        cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip

    def rover_path(*argv: str) -> subprocess.CompletedProcess:
        return subprocess.run(
            [sys.executable, "-m", "scripts.rover_path", *argv, "--url", f"udpin:127.0.0.1:{port}"],
            cwd=REPO, capture_output=True, text=True, timeout=400,
        )  # fmt: skip

    path, exp, rep = tmp_path / "open.csv", tmp_path / "open.npz", tmp_path / "rep"
    try:
        taught = rover_path("teach", "--drive", OPEN, "--drive-speed", "0.9", "--out", str(path))
        assert taught.returncode == 0, taught.stderr
        assert "open: its end is" in taught.stderr
        assert path.read_text().startswith("x_m,y_m\n")
        common = ["--path", str(path), "--experience", str(exp), "--out", str(rep)]
        run1 = rover_path("repeat", *common, "--trials", "1", "--speed", "0.9", "--drive-back")
        assert run1.returncode == 0, run1.stderr
        assert "driving back to the start" in run1.stderr
        size1, first = exp.stat().st_size, _json(rep)
        assert first["trial"] == [1] and all(first["reached_end"]) and first["experiences"][0] > 0
        run2 = rover_path("repeat", *common, "--trials", "1", "--speed", "0.9", "--drive-back")
        assert run2.returncode == 0, run2.stderr
        assert "experiences from 1 trial; NMPC on the planner's defaults" in run2.stderr
        assert run2.stdout.startswith("trial 2:")
        second = _json(rep)
        assert second["trial"] == [2] and second["all_trials"]["trial"] == [1, 2]
        assert second["experiences_after"] > first["experiences_after"]
        assert exp.stat().st_size > size1
    finally:
        sim.terminate()
        sim.wait(10.0)


def _endpoint(port: int) -> RoverMavlinkEndpoint:
    endpoint = RoverMavlinkEndpoint(
        RoverSim(rover_preset("husky_50kg")), port, setpoint_timeout_s=2.0, mode="udpout"
    )
    endpoint.start()
    return endpoint


def _repeat_while(
    path: Path, tmp_path: Path, event: Callable[[RoverMavlinkEndpoint], None]
) -> tuple[RoverMavlinkEndpoint, int]:
    """`rover-path repeat` of ``path`` against a simulated rover on which ``event`` happens 4 s
    in (a pilot's mode switch, the link going); returns the endpoint, closed, and the exit
    code."""
    port = free_udp_port()
    endpoint = _endpoint(port)
    timer = threading.Timer(4.0, event, args=(endpoint,))
    timer.start()
    argv = ["repeat", "--path", str(path), "--url", f"udpin://127.0.0.1:{port}",
            "--experience", str(tmp_path / "e.npz"), "--out", str(tmp_path / "rep")]  # fmt: skip
    try:
        return endpoint, main(argv)
    finally:
        timer.cancel()
        endpoint.close()


@pytest.mark.slow
def test_a_pilot_switching_to_manual_mid_repeat_ends_it_with_exit_3(
    files: dict[str, Path], tmp_path: Path, capsys
) -> None:
    endpoint, code = _repeat_while(
        files["loop"],
        tmp_path,
        lambda e: e._set_mode(1, 0),  # MANUAL, as an RC switch
    )
    err = capsys.readouterr().err
    assert code == 3, err
    assert "left OFFBOARD for MANUAL during trial 1" in err
    assert not endpoint.holding  # nothing was commanded over the pilot
    assert _json(tmp_path / "rep")["status"] == "handed_over"


@pytest.mark.slow
def test_a_lost_link_mid_repeat_stops_with_exit_1(
    files: dict[str, Path], tmp_path: Path, capsys
) -> None:
    _, code = _repeat_while(files["loop"], tmp_path, lambda e: e.close())  # the radio goes
    err = capsys.readouterr().err
    assert code == 1, err
    assert "trial 1 stopped: link lost" in err and "sent Hold" in err
    summary = _json(tmp_path / "rep")
    assert summary["status"] == "stopped" and summary["reached_end"] == [False]
    assert np.isfinite(summary["max_e_lat_m"][0])


def _wait_for(proc: subprocess.Popen, text: str, timeout_s: float = 60.0) -> None:
    """Read the process's stderr until a line holds ``text``."""
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        line = proc.stderr.readline()
        if text in line:
            return
        assert line or proc.poll() is None, f"exited {proc.returncode} before {text!r}"
    raise AssertionError(f"no {text!r} within {timeout_s} s")


def _repeat_loop(files: dict[str, Path], tmp_path: Path, port: int) -> subprocess.Popen:
    """`rover-path repeat` of the taught loop against udpin port ``port``, as a process."""
    return subprocess.Popen(
        [sys.executable, "-m", "scripts.rover_path", "repeat", "--path", str(files["loop"]),
         "--url", f"udpin://127.0.0.1:{port}", "--experience", str(tmp_path / "e.npz"),
         "--out", str(tmp_path / "rep")],
        cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip


@pytest.mark.slow
@pytest.mark.parametrize(
    ("sig", "code", "said"),
    [(signal.SIGINT, 130, "interrupted: Ctrl-C"), (signal.SIGTERM, 143, "terminated: SIGTERM")],
)
def test_ctrl_c_or_sigterm_mid_repeat_sends_hold(
    files: dict[str, Path], tmp_path: Path, sig: signal.Signals, code: int, said: str
) -> None:
    port = free_udp_port()
    endpoint = _endpoint(port)
    proc = _repeat_loop(files, tmp_path, port)
    try:
        _wait_for(proc, "no experience yet")
        deadline = time.monotonic() + 30.0
        while not endpoint.offboard and time.monotonic() < deadline:
            time.sleep(0.1)
        assert endpoint.offboard
        time.sleep(1.0)  # driving
        proc.send_signal(sig)
        assert proc.wait(30.0) == code, proc.stderr.read()
        last = proc.stderr.read().strip().splitlines()[-1]  # not "interrupted: interrupted ..."
        assert last == f"rover-path: {said}; the rover was sent Hold", last
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5.0)
        endpoint.close()
    assert endpoint.holding and not endpoint.offboard  # the rover was sent Hold


def test_ctrl_c_before_any_vehicle_answered_says_nothing_was_sent(
    files: dict[str, Path], tmp_path: Path
) -> None:
    """Ctrl-C while repeat still waits for a vehicle (none on the port): the last line does
    not claim the rover was sent Hold."""
    proc = _repeat_loop(files, tmp_path, free_udp_port())
    try:
        _wait_for(proc, "no experience yet")
        time.sleep(0.5)
        proc.send_signal(signal.SIGINT)
        assert proc.wait(30.0) == 130
        last = proc.stderr.read().strip().splitlines()[-1]
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5.0)
    assert last == "rover-path: interrupted: Ctrl-C before any vehicle answered; nothing sent", last


@pytest.mark.slow
def test_ctrl_c_ends_a_pilot_driven_teach_and_writes_the_path(tmp_path: Path) -> None:
    """A pilot drives in MANUAL; Ctrl-C on the companion ends the recording and the path so
    far is written. Started with SIGINT ignored, as a shell's background job or nohup starts
    it (its children inherit that): the Ctrl-C still ends it."""
    port = free_udp_port()
    endpoint = _endpoint(port)
    out = tmp_path / "p.csv"
    proc = subprocess.Popen(
        [sys.executable, "-m", "scripts.rover_path", "teach", "--out", str(out),
         "--url", f"udpin://127.0.0.1:{port}"],
        cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_IGN),
    )  # fmt: skip
    try:
        _wait_for(proc, "teaching over pymavlink")
        endpoint.sim.arm()
        endpoint.sim.set_setpoint(0.8, 0.0)
        _wait_for(proc, "armed: recording")
        time.sleep(4.0)
        proc.send_signal(signal.SIGINT)
        assert proc.wait(30.0) == 0, proc.stderr.read()
        err = proc.stderr.read()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5.0)
        endpoint.close()
    assert "recording ended: Ctrl-C" in err
    assert out.read_text().startswith("x_m,y_m\n")


@pytest.mark.parametrize("link", ["pymavlink", "mavsdk"])
@pytest.mark.parametrize("command", ["teach", "repeat"])
def test_a_multicopter_on_the_link_is_refused_and_sent_nothing(tmp_path, capsys, command, link):
    """Another vehicle answering on the port is a quadrotor (PX4 SITL, a wrong --url): neither
    the teach pass nor the repeat arms it or switches its mode."""
    from tests.companion.test_companion_mission_on_every_link import Vehicle, free_udp_port

    path = tmp_path / "loop.csv"
    assert main(["teach", "--link", "inprocess", "--drive", LOOP, "--out", str(path)]) == 0
    port = free_udp_port()
    quad = Vehicle(port)
    try:
        url = ["--link", link, "--url", f"udpin://127.0.0.1:{port}"]
        if command == "teach":
            argv = ["teach", *url, "--drive", "3:0", "--out", str(tmp_path / "p.csv")]
        else:
            argv = ["repeat", *url, "--path", str(path), "--out", str(tmp_path / "out")]
        capsys.readouterr()
        assert main(argv) == 2
        state = quad.state
    finally:
        quad.endpoint.stop()
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert "is a multirotor" in last and "rover-path drives only rovers" in last
    assert not state.armed and state.mode.name != "OFFBOARD"


@pytest.mark.parametrize(
    ("options", "tuning"),
    [
        (["--link", "inprocess", "--vehicle", "dmrv_600kg"], "dmrv_600kg"),
        (["--link", "inprocess"], "husky_50kg"),
        (["--link", "pymavlink"], None),
        (["--link", "pymavlink", "--tuning", "roc6_150kg"], "roc6_150kg"),
    ],
)
def test_repeat_drives_with_the_rovers_own_tuning(options, tuning) -> None:
    assert parse_args(["repeat", "--path", "p.csv", *options]).tuning == tuning


@pytest.fixture
def sent_to_rover(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """The names of the Link calls that command the in-process rover, in the order sent."""
    from companion.inprocess_rover_link import InProcessRoverLink

    sent: list[str] = []

    def recorded(name: str) -> Callable[..., object]:
        call = getattr(InProcessRoverLink, name)

        def record(link: InProcessRoverLink, *args: object) -> object:
            sent.append(name)
            return call(link, *args)

        return record

    for name in ("send_velocity", "arm", "start_offboard", "hold"):
        monkeypatch.setattr(InProcessRoverLink, name, recorded(name))
    return sent


def _ctrl_c(*_args: object) -> None:
    raise KeyboardInterrupt


@pytest.mark.parametrize(
    ("pressed_in", "sent", "said"),
    [
        ("read_state", [], "Ctrl-C before the first trial drove; nothing was sent to the rover"),
        ("start_offboard", ["send_velocity", "arm", "send_velocity", "hold"],
         "Ctrl-C; the rover was sent Hold"),
    ],
)  # fmt: skip
def test_ctrl_c_after_connecting_says_whether_the_rover_was_sent_hold(
    files: dict[str, Path], tmp_path: Path, capsys, monkeypatch, sent_to_rover,
    pressed_in: str, sent: list[str], said: str,
) -> None:  # fmt: skip
    """Ctrl-C once the rover answered but before the first trial drove (while checking it is a
    rover) was reported as 'the rover was sent Hold', and nothing was sent; Ctrl-C while
    arming and switching to OFFBOARD sent no Hold though the rover was armed."""
    from companion.inprocess_rover_link import InProcessRoverLink

    monkeypatch.setattr(InProcessRoverLink, pressed_in, _ctrl_c)
    argv = ["repeat", "--link", "inprocess", "--path", str(files["loop"]), "--trials", "1",
            "--experience", str(tmp_path / "e.npz"), "--out", str(tmp_path / "rep")]  # fmt: skip
    assert main(argv) == 130
    assert capsys.readouterr().err.strip().splitlines()[-1] == f"rover-path: interrupted: {said}"
    assert sent_to_rover == sent
