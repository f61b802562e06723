"""A reader that closes the output early (``flightlog info LOG | head``) ends the command
quietly, as SIGPIPE ends a program: no BrokenPipeError traceback."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
LOG = REPO / "tests" / "fixtures" / "ulog" / "quad_posctl_v1_15.ulg"


def test_flightlog_info_into_a_closed_pipe_ends_without_a_traceback() -> None:
    command = "from scripts.launch import flightlog; raise SystemExit(flightlog())"
    proc = subprocess.Popen(
        [sys.executable, "-c", command, "info", str(LOG)],
        cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
    )  # fmt: skip
    proc.stdout.close()  # the reader is gone before the command prints its first line
    err = proc.stderr.read().decode()
    assert proc.wait(timeout=120) == 141, err
    assert "Traceback" not in err and "BrokenPipeError" not in err


def test_a_broken_pipe_of_the_command_s_own_is_not_taken_for_a_closed_output() -> None:
    """A BrokenPipeError out of a command whose standard output is still read (a pipe or
    socket of its own broke) is a failure with its traceback, not the quiet exit 141."""
    command = (
        "import sys, types; from scripts.launch import run\n"
        "def main():\n"
        "    raise BrokenPipeError(32, 'Broken pipe (a socket of its own)')\n"
        "sys.modules['scripts.own_pipe'] = types.SimpleNamespace(main=main)\n"
        "raise SystemExit(run('own_pipe', 'own-pipe'))"
    )
    proc = subprocess.run(
        [sys.executable, "-c", command], cwd=REPO, capture_output=True, text=True, timeout=120
    )
    assert proc.returncode == 1, proc.stderr
    assert "BrokenPipeError: [Errno 32] Broken pipe (a socket of its own)" in proc.stderr


def test_flightlog_info_into_a_socket_whose_peer_has_gone_ends_without_a_traceback() -> None:
    """Standard output a socket (a service's connection) whose peer closed: as a closed pipe."""
    import socket

    ours, theirs = socket.socketpair()
    command = "from scripts.launch import flightlog; raise SystemExit(flightlog())"
    with ours, theirs:
        ours.close()  # the peer is gone before the command prints its first line
        proc = subprocess.run(
            [sys.executable, "-c", command, "info", str(LOG)],
            cwd=REPO, stdout=theirs.fileno(), stderr=subprocess.PIPE, text=True, timeout=120,
        )  # fmt: skip
    assert proc.returncode == 141, proc.stderr
    assert "Traceback" not in proc.stderr
