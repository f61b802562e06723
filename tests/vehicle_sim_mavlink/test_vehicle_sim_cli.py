"""`vehicle-sim`: bad input gives one line and a non-zero exit; a run serves MAVLink and stops
cleanly on SIGINT/SIGTERM."""

from __future__ import annotations

import queue
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest
from mavlink_test_client import Client, free_udp_port

from flightlog.schema import read_flight_log
from scripts.vehicle_sim_cli import main, parse_args

REPO = Path(__file__).resolve().parents[2]


_BRIEF = ["--duration-s", "0.5"]  # a rover that were served would stop, not run on


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["--speed", "0"], "--speed 0.0: must be within"),
        (["--vehicle", "no_such_quad"], "no such config file or preset; use a multirotor (f450"),
        (["--vehicle", "husky"], "a rover (husky_50kg, roc6_150kg, dmrv_600kg)"),  # rovers too
        (["--effect", "lasers"], "unknown effect 'lasers'"),
        (["--effect", "rotor_drag.k_n_per_mps=[0.3,"], "not a TOML value"),
        (
            ["--signing-key", "missing.key"],
            "cannot read signing key file missing.key (No such file or directory); pass a text "
            "file holding the key: 64 hex digits or a passphrase",
        ),
        (["--frobnicate"], "unrecognized arguments"),
        (["--seed", "-1"], "--seed -1: must be >= 0"),
        (["--realtime-priority", "100"], "--realtime-priority 100: must be 0 (off) or 1..99"),
        (["--vehicle", "husky_50kg", "--world", "w.toml"], "--world: not for the rover"),
        # the rover serves the offboard link only, from a port of its own: not dropped silently
        (["--vehicle", "husky_50kg", "--gcs-port", "1", *_BRIEF], "--gcs-port: not for the rover"),
        (["--vehicle", "husky_50kg", "--offboard-bind-port", "0", *_BRIEF], "--offboard-bind-port"),
        (["--vehicle", "husky_50kg", "--gcs-bind-port", "0", *_BRIEF], "--gcs-bind-port: not for"),
        # the rover's loop died on its first heartbeat (OverflowError) after it had announced
        (["--vehicle", "husky_50kg", "--offboard-port", "99999", *_BRIEF], "--offboard-port 99999"),
        (["--gcs-port", "0"], "--gcs-port 0: must be a UDP port, 1..65535"),
        (["--offboard-bind-port", "-1"], "--offboard-bind-port -1: must be a UDP port, 0..65535"),
    ],
)
def test_bad_input_is_one_line_and_exit_2(capsys, argv, message):
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert message in err
    assert err.count("\n") == 1 and err.startswith("vehicle-sim: error:")


@pytest.mark.parametrize("where", ["folder", "under_a_file"])
def test_unwritable_log_refused_before_serving(capsys, tmp_path, where):
    """An onboard log that could not be written at exit is refused at the start (one line, exit
    2), not found out after a flight whose log is then lost."""
    (tmp_path / "plain").write_text("")
    log = tmp_path if where == "folder" else tmp_path / "plain" / "onboard.csv"
    argv = ["--log", str(log), "--duration-s", "0.5", "--offboard-bind-port", "0"]
    assert main([*argv, "--gcs-bind-port", "0"]) == 2
    out = capsys.readouterr()
    assert out.out == ""
    assert out.err.count("\n") == 1 and out.err.startswith(f"vehicle-sim: error: --log {log}")


@pytest.mark.parametrize("link", ["offboard", "gcs"])
def test_taken_port_is_reported_with_the_option_that_moves_it(capsys, link):
    """A port another simulator holds is one line naming the link, the port and the option
    that picks another one."""
    other = "gcs" if link == "offboard" else "offboard"
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        port = taken.getsockname()[1]
        argv = [f"--{link}-bind-port", str(port), f"--{other}-bind-port", "0"]
        assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1
    assert f"cannot bind link {link} to 127.0.0.1:{port}" in err
    assert f"pass --{link}-bind-port with a free port" in err


def test_an_address_this_machine_lacks_is_not_blamed_on_a_taken_port(capsys):
    argv = ["--host", "192.0.2.1", "--offboard-bind-port", "0", "--gcs-bind-port", "0"]
    assert main(argv) == 2  # 192.0.2.1: TEST-NET-1 (RFC 5737), no interface has it
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and "cannot bind link offboard to 192.0.2.1:0" in err
    assert "bind-port with a free port" not in err


def test_effect_flags_become_overrides():
    config = parse_args(
        [
            "--effect",
            "rotor_drag",
            "--effect",
            "wind.vel_ned_mps=[3, 0, 0]",
            "--effect",
            "rotor_drag.k_n_per_mps=[0.3, 0.3, 0.1]",
        ]
    )
    assert dict(config.effects) == {
        "rotor_drag": (("k_n_per_mps", [0.3, 0.3, 0.1]),),
        "wind": (("vel_ned_mps", [3, 0, 0]),),
    }


def read_lines(stream, lines: queue.Queue) -> None:
    for line in stream:
        lines.put(line.rstrip())


@pytest.mark.slow
@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_serves_mavlink_and_stops_cleanly_on_signal(sig):
    offboard_port, gcs_port = free_udp_port(), free_udp_port()
    gcs = Client(url=f"udpin:127.0.0.1:{gcs_port}")
    proc = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "scripts.vehicle_sim_cli",
            "--speed",
            "2",
            "--offboard-port",
            str(offboard_port),
            "--gcs-port",
            str(gcs_port),
            "--offboard-bind-port",
            "0",
            "--gcs-bind-port",
            "0",
        ],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    lines: queue.Queue = queue.Queue()
    reader = threading.Thread(target=read_lines, args=(proc.stdout, lines), daemon=True)
    reader.start()
    try:
        seen = []
        deadline = time.monotonic() + 30.0
        while f"MAVSDK: udpin://127.0.0.1:{offboard_port}" not in seen:
            seen.append(lines.get(timeout=max(0.1, deadline - time.monotonic())))
        assert gcs.hello(10.0).autopilot == 12
        assert gcs.command(400, 1).result == 0
        proc.send_signal(sig)
        assert proc.wait(10.0) == 0, proc.stderr.read()
        reader.join(5.0)  # the last lines are read once the pipe closes
        rest = []
        while not lines.empty():
            rest.append(lines.get())
        assert any("vehicle-sim: stopped at" in line for line in rest)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5.0)
        gcs.close()


def test_help_names_the_config_from_log_command(capsys):
    with pytest.raises(SystemExit) as exc:
        parse_args(["--help"])
    assert exc.value.code == 0
    assert "vehicle-sim config-from-log LOG --out my_vehicle.toml" in capsys.readouterr().out


@pytest.mark.slow
def test_a_killed_simulator_leaves_its_onboard_log_up_to_then(tmp_path):
    """--log streams the onboard log row by row, as PX4 writes its SD-card log while it flies:
    a SIGKILL (no exit handler runs) leaves a readable log of every row, acceleration and
    thrust included, marked incomplete; it was kept in memory until exit and lost."""
    log_path = tmp_path / "onboard.csv"
    proc = subprocess.Popen(
        [
            sys.executable, "-m", "scripts.vehicle_sim_cli", "--speed", "2",
            "--offboard-port", str(free_udp_port()), "--gcs-port", str(free_udp_port()),
            "--offboard-bind-port", "0", "--gcs-bind-port", "0", "--log", str(log_path),
        ],
        cwd=REPO, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
    )  # fmt: skip
    try:
        deadline = time.monotonic() + 30.0
        while time.monotonic() < deadline and (
            not log_path.exists() or len(log_path.read_text().splitlines()) < 101
        ):
            time.sleep(0.2)
        proc.kill()
        proc.wait(10.0)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5.0)
    log = read_flight_log(log_path)
    assert log.n_rows >= 100 and log.metadata["complete"] is False
    assert log.has("thrust_n", "acc_n_mps2") and float(np.min(log["thrust_n"])) >= 0.0


def _ports() -> list[str]:
    return [
        "--offboard-port", str(free_udp_port()), "--gcs-port", str(free_udp_port()),
        "--offboard-bind-port", "0", "--gcs-bind-port", "0",
    ]  # fmt: skip


def test_a_log_already_at_the_path_is_kept_not_emptied(tmp_path, capsys):
    """As the companion's --log: an earlier onboard log is moved to stem.1.csv, not streamed
    over; a session that cannot start puts it back."""
    log_path = tmp_path / "onboard.csv"
    log_path.write_text("an earlier flight\n")
    assert main(["--vehicle", "no_such_quad", "--log", str(log_path), *_ports()]) == 2
    assert log_path.read_text() == "an earlier flight\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["onboard.csv"]
    assert main(["--duration-s", "0.5", "--log", str(log_path), *_ports()]) == 0
    kept = tmp_path / "onboard.1.csv"
    assert f"kept as {kept}" in capsys.readouterr().out
    assert kept.read_text() == "an earlier flight\n"
    assert read_flight_log(log_path).n_rows > 0


def test_a_session_that_cannot_bind_puts_back_an_earlier_log_without_a_stray_sidecar(
    tmp_path, capsys
):
    """The onboard log is opened (CSV and sidecar) before the links bind: when binding fails,
    the earlier log (here one without a sidecar) is back exactly as it was."""
    log_path = tmp_path / "onboard.csv"
    log_path.write_text("an earlier flight\n")
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as taken:
        taken.bind(("127.0.0.1", 0))
        busy = str(taken.getsockname()[1])
        argv = ["--log", str(log_path), *_ports(), "--offboard-bind-port", busy]
        assert main(argv) == 2
        assert log_path.read_text() == "an earlier flight\n"
        assert sorted(p.name for p in tmp_path.iterdir()) == ["onboard.csv"]
        assert "kept as" not in capsys.readouterr().out  # it was not: it is back
        log_path.unlink()
        assert main(argv) == 2  # no earlier log: the session leaves none of its own
        assert list(tmp_path.iterdir()) == []


def test_a_log_at_the_vehicle_config_is_refused_not_moved_aside(tmp_path, capsys):
    vehicle = tmp_path / "quad.toml"
    preset = Path(__file__).resolve().parents[2] / "vehicle_sim" / "presets" / "iris.toml"
    vehicle.write_text(preset.read_text())
    assert main(["--vehicle", str(vehicle), "--log", str(vehicle), *_ports()]) == 2
    assert "is an input being read" in capsys.readouterr().err
    assert vehicle.read_text() == preset.read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["quad.toml"]


@pytest.mark.slow
def test_a_rover_preset_serves_a_px4_rover_on_the_offboard_link():
    """`vehicle-sim --vehicle husky_50kg`: HEARTBEAT as a PX4 ground rover, arming answered
    (to the sender), a clean stop on SIGINT."""
    offboard_port = free_udp_port()
    client = Client(url=f"udpin:127.0.0.1:{offboard_port}")
    proc = subprocess.Popen(
        [sys.executable, "-m", "scripts.vehicle_sim_cli", "--vehicle", "husky_50kg"]
        + ["--offboard-port", str(offboard_port)],
        cwd=REPO,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    try:
        hb = client.hello(30.0)
        assert (hb.type, hb.autopilot) == (10, 12)  # MAV_TYPE_GROUND_ROVER, PX4
        client.mav.command_long_send(1, 1, 400, 0, 1, 0, 0, 0, 0, 0, 0)
        ack = client.recv("COMMAND_ACK", 10.0, lambda m: m.command == 400)
        assert ack is not None and ack.result == 0
        assert getattr(ack, "target_system", 245) == 245
        proc.send_signal(signal.SIGINT)
        assert proc.wait(10.0) == 0, proc.stderr.read()
        assert "vehicle-sim: stopped at" in proc.stdout.read()
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5.0)
        client.close()
