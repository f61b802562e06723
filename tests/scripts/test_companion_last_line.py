"""The companion's last line says how the flight ended without empty clauses: no "landed n/a
from the goal" for a flight that never followed the reference, no "0 deadline misses in 0
steps" for one that never flew a step, and no status said twice."""

from __future__ import annotations

from pathlib import Path

import pytest

from companion.runner import FlightOutcome
from scripts.companion_cli import _summary


@pytest.mark.parametrize(
    ("status", "detail", "landed_m", "ticks", "line"),
    [
        (
            "failed", "no autopilot on udpin://127.0.0.1:14540 within 15 s", None, 0,
            "failed: no autopilot on udpin://127.0.0.1:14540 within 15 s",
        ),
        (
            "interrupted", "interrupted by Ctrl-C", None, 426,
            "interrupted by Ctrl-C; 1 deadline misses in 426 steps",
        ),
        (
            "completed", "reached the goal (0.15 m)", 0.07, 1755,
            "completed: reached the goal (0.15 m); landed 0.07 m from the goal; 1 deadline "
            "misses in 1755 steps",
        ),
    ],
)  # fmt: skip
def test_the_last_line_has_only_what_the_flight_did(status, detail, landed_m, ticks, line):
    outcome = FlightOutcome(status, detail, None, landed_m, True, ticks, 1 if ticks else 0)
    assert _summary(outcome) == line


def test_the_last_line_gives_the_tracking_error_the_log_holds(tmp_path, capsys):
    """Flown with and without ``--gp-model``, a flight said nothing of how closely it tracked
    the reference: the user had to compute it from the logs to see whether the learned model
    helped. The last line now gives the tracking RMSE over the OFFBOARD rows of its log."""
    from experiments.study.metrics import tracking_rmse_m
    from flightlog.reader import read_log
    from scripts import companion_cli

    mission = Path(__file__).resolve().parents[2] / "missions" / "line_20m.toml"
    log = tmp_path / "flight.csv"
    argv = [str(mission), "--link", "inprocess", "--planner", "nmpc", "--log", str(log)]
    assert companion_cli.main(argv) == 0
    last = capsys.readouterr().err.strip().splitlines()[-1]
    assert f"tracking RMSE {tracking_rmse_m(read_log(log)):.3f} m" in last, last
