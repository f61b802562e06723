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
