"""Every console script's --help says what its exit codes mean: vehicle-sim's, flightlog's and
study's said nothing, while the others' did (a script that wraps one needs them)."""

import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

REPO = Path(__file__).resolve().parents[2]
SCRIPTS = tomllib.loads((REPO / "pyproject.toml").read_text())["project"]["scripts"]


@pytest.mark.parametrize("name", sorted(SCRIPTS))
def test_help_names_the_exit_codes(name: str) -> None:
    module, function = SCRIPTS[name].split(":")
    run = f"import sys, {module} as m; sys.argv = [{name!r}, '--help']; sys.exit(m.{function}())"
    done = subprocess.run(
        [sys.executable, "-c", run], cwd=REPO, capture_output=True, text=True, timeout=120
    )
    assert done.returncode == 0, done.stderr
    assert "Exit codes: 0" in " ".join(done.stdout.split())
