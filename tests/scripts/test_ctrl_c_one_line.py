"""Ctrl-C in the middle of diagnose, fit-gp and bench: one line and exit 130, no traceback,
and no half-written output."""

from __future__ import annotations

import json
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from flightlog.schema import write_flight_log
from tests.gp.gp_synthetic_logs import record_log

REPO = Path(__file__).resolve().parents[2]
ULOGS = REPO / "tests" / "fixtures" / "ulog"


def run_and_interrupt(module: str, args: list[str], when: str) -> tuple[int, str, str]:
    """Run ``python -m module args``, send Ctrl-C (SIGINT) once a stderr line contains
    ``when``; returns the exit code, stdout and the rest of stderr."""
    proc = subprocess.Popen(
        [sys.executable, "-m", module, *args],
        cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    try:
        seen = []
        for line in proc.stderr:
            seen.append(line)
            if when in line:
                break
        else:
            pytest.fail(f"{module} ended before {when!r}: {''.join(seen)}")
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(5)
    return proc.returncode, out, err


def test_ctrl_c_during_a_diagnosis_is_one_line_exit_130_and_writes_nothing(tmp_path):
    logs = [str(ULOGS / f"{name}.ulg") for name in ("quad_sitl_v1_15_auto", "quad_posctl_v1_15")]
    out = tmp_path / "diag"
    args = [*logs, "--sim-config", "iris", "--out", str(out)]
    code, _, err = run_and_interrupt("scripts.diagnose", args, "read 2 log(s)")
    assert code == 130, err
    assert "Traceback" not in err
    assert err.strip().splitlines()[-1] == f"diagnose: stopped by Ctrl-C; nothing written to {out}"
    assert list(tmp_path.iterdir()) == []  # neither the report folder nor its temporary one


def test_ctrl_c_during_a_gp_fit_is_one_line_exit_130_and_writes_no_model(tmp_path):
    log = write_flight_log(tmp_path / "long.csv", record_log(n_rows=6000))  # a fit of seconds
    args = [str(log), "--out", str(tmp_path / "model"), "--m", "200", "--optimize-inducing"]
    code, out, err = run_and_interrupt("scripts.fit_gp", [*args, "--restarts", "10"], "fitting")
    assert code == 130, err
    assert "Traceback" not in err
    assert err.strip().splitlines()[-1] == "fit-gp: stopped by Ctrl-C; no model written"
    assert out == "" and sorted(p.name for p in tmp_path.iterdir()) == ["long.csv", "long.csv.json"]


@pytest.mark.slow
def test_ctrl_c_during_bench_is_one_line_exit_130_with_the_parts_done():
    args = ["--only", "sim", "--only", "diagnose", "--quick", "--json"]
    code, out, err = run_and_interrupt("scripts.bench", args, "[bench] diagnose ...")
    assert code == 130, err
    assert "Traceback" not in err
    assert err.strip().splitlines()[-1] == (
        "bench: stopped by Ctrl-C; the figures of the parts done are printed"
    )
    assert set(json.loads(out)) == {"sim_realtime_factor"}


CTRL_C_WHILE_LOADING = """
import os, signal, sys
from importlib.abc import MetaPathFinder

class CtrlCAsTheCommandLoads(MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.startswith("scripts.") and name != "scripts.launch":
            os.kill(os.getpid(), signal.SIGINT)

sys.meta_path.insert(0, CtrlCAsTheCommandLoads())
from scripts import launch
run, sys.argv = getattr(launch, sys.argv[1]), [sys.argv[1], "--help"]
sys.exit(run())
"""


def _console_scripts() -> dict[str, str]:
    """pyproject's [project.scripts]: command -> entry point."""
    import tomllib

    return tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["scripts"]


@pytest.mark.parametrize("command", sorted(_console_scripts()))
def test_ctrl_c_while_a_command_loads_is_one_line(command):
    """A Ctrl-C in the second or two a command spends loading its libraries was a
    KeyboardInterrupt traceback through importlib: now one line and exit 130."""
    entry = _console_scripts()[command]
    assert entry.startswith("scripts.launch:"), entry
    proc = subprocess.run(
        [sys.executable, "-c", CTRL_C_WHILE_LOADING, entry.split(":")[1]],
        cwd=REPO, capture_output=True, text=True, timeout=120,
        preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL),
    )  # fmt: skip
    assert proc.returncode == 130, proc.stderr
    assert proc.stderr == f"{command}: stopped by Ctrl-C while starting; nothing done\n"


@pytest.mark.parametrize("command", sorted(_console_scripts()))
def test_every_console_script_reaches_its_command(command, monkeypatch, capsys):
    from scripts import launch

    monkeypatch.setattr(sys, "argv", [command, "--help"])
    try:
        code = getattr(launch, _console_scripts()[command].split(":")[1])()
    except SystemExit as exc:  # some parsers exit on --help
        code = exc.code
    assert code in (0, None)
    assert capsys.readouterr().out.startswith(f"usage: {command}")


def test_a_console_script_returns_its_commands_failure_code(tmp_path, monkeypatch, capsys):
    """A command that fails (here: no such log) exits non-zero through its console script, so
    a shell or batch job sees the failure."""
    from scripts import launch
    from scripts.flightlog_cli import EXIT_BAD_INPUT

    monkeypatch.setattr(sys, "argv", ["flightlog", "info", str(tmp_path / "missing.ulg")])
    assert launch.flightlog() == EXIT_BAD_INPUT
    assert "no such flight log" in capsys.readouterr().err
