"""The study's closed-loop check decides on real flights: a model that tracked worse on the
training seeds than the one it replaces is refused, and the structure alone is the last resort."""

from __future__ import annotations

from dataclasses import replace

import pytest

from companion.nmpc_planner import NmpcSettings
from experiments.study.closed_loop import (
    STRUCTURE,
    ClosedLoopVerdict,
    compare_tracking,
    confirm_lineage,
)
from experiments.study.jobs import FlightJob, FlightSummary, run_flight_job
from experiments.study.metrics import pooled_rmse
from gp.model_io import load_model
from gp.prediction_check import structure_only
from planners.trajectory_generator import TrajectorySpec, generate_trajectories
from scripts.study import main as study_main

SEEDS = (0, 1)


def _lag(tau_s: float, tau_d_s: float) -> NmpcSettings:
    params = (("tau_d_s", tau_d_s), ("tau_s", tau_s))
    return NmpcSettings(2.5, nominal_model="first_order_lag", nominal_params=params)


@pytest.fixture(scope="module")
def flights() -> dict[str, list[FlightSummary]]:
    """Three planners flown on the same short path and seeds, ordered best to worst tracking:
    a first-order lag near the study vehicle's velocity loop, one 7x too fast, and the
    kinematic NMPC (whichever order they fly in, the test reads it from their flights)."""
    path = generate_trajectories(1, 0, TrajectorySpec(length_range_m=(8.0, 10.0)))[0]
    planners = {
        "near lag": _lag(0.7, 0.4),
        "fast lag": _lag(0.1, 0.1),
        "kinematic": NmpcSettings(2.5),
    }
    flown = {
        name: [
            run_flight_job(FlightJob(0, path, name, seed, "iris_study", settings, None, False))
            for seed in SEEDS
        ]
        for name, settings in planners.items()
    }
    for summaries in flown.values():
        assert all(f.status == "completed" for f in summaries)
    rmse = {name: _pooled(fl) for name, fl in flown.items()}
    ranked = sorted(flown, key=rmse.__getitem__)
    assert rmse[ranked[0]] < rmse[ranked[1]] < rmse[ranked[2]]
    return {
        role: flown[name] for role, name in zip(("best", "middle", "worst"), ranked, strict=True)
    }


def _pooled(flights: list[FlightSummary]) -> float:
    return pooled_rmse([f.tracking_rmse_m for f in flights], [f.n_residuals for f in flights])


def test_a_refit_that_tracks_worse_than_its_predecessor_is_refused(flights):
    verdict = confirm_lineage(
        [("first fit", flights["best"]), ("refit", flights["middle"])], flights["worst"]
    )
    assert verdict.flies == 0 and verdict.flies_name == "first fit"
    refit = verdict.comparisons[0]
    assert (refit.candidate, refit.incumbent, refit.passed) == ("refit", "first fit", False)
    assert refit.candidate_rmse_m == pytest.approx(_pooled(flights["middle"]))
    assert refit.incumbent_rmse_m == pytest.approx(_pooled(flights["best"]))
    [line] = verdict.refusals()
    assert line.startswith("refusing refit: it tracks worse in closed loop") and "\n" not in line
    assert f"{refit.candidate_rmse_m:.4f} m vs {refit.incumbent_rmse_m:.4f} m" in line
    assert line.endswith("first fit flies in its place")
    assert verdict.to_dict()["structure_flies"] is False


def test_a_better_refit_flies(flights):
    verdict = confirm_lineage(
        [("first fit", flights["middle"]), ("refit", flights["best"])], flights["worst"]
    )
    assert verdict.flies == 1 and verdict.refusals() == []
    assert [c.incumbent for c in verdict.comparisons] == ["first fit", STRUCTURE]


def test_the_structure_flies_when_every_learned_model_tracks_worse_than_it(flights):
    verdict = confirm_lineage(
        [("first fit", flights["middle"]), ("refit", flights["worst"])], flights["best"]
    )
    assert verdict.flies is None and verdict.flies_name == STRUCTURE
    assert verdict.to_dict()["structure_flies"] is True
    lines = verdict.refusals()
    assert len(lines) == 2 and lines[0].endswith("first fit flies in its place")
    assert lines[1].endswith(f"{STRUCTURE} flies in its place")


def test_a_model_that_flies_the_same_is_no_worse(flights):
    same = compare_tracking("refit", flights["middle"], "first fit", flights["middle"])
    assert same.passed and same.n_flights == len(SEEDS)


def test_flights_on_other_seeds_are_not_compared(flights):
    moved = [replace(f, seed=f.seed + len(SEEDS)) for f in flights["best"]]
    with pytest.raises(ValueError, match="same \\(trajectory, seed\\) pairs"):
        compare_tracking("refit", flights["middle"], "first fit", moved)


def test_lines_name_where_the_models_were_flown(flights):
    """The trial view flies each refit on the just-flown trial's seed, and says so."""
    where = "trial 3's seed"
    lost = compare_tracking("refit", flights["worst"], "first fit", flights["best"], where)
    [line] = ClosedLoopVerdict(None, STRUCTURE, (lost,)).refusals()
    assert line.startswith(f"refusing refit: it tracks worse in closed loop on {where} than")
    moved = [replace(f, seed=f.seed + len(SEEDS)) for f in flights["best"]]
    with pytest.raises(ValueError, match=f"fly both on {where}$"):
        compare_tracking("refit", flights["middle"], "first fit", moved, where)


@pytest.mark.slow(expected_s=100)
def test_wind_study_checks_its_models_in_closed_loop_on_training_seeds_only(tmp_path, capsys):
    """The smoke wind_field study (one refit round, the check on by its regime): every model
    that would fly is compared on the training seed with what it replaces, the verdict is in
    its model file and the report, and no check flight flies a held-out seed."""
    out = tmp_path / "study"  # without the trial view: its checks fly on trial seeds
    argv = ["--quick", "--regime", "wind_field", "--trials", "0", "--out", str(out)]
    assert study_main(argv) == 0
    err = capsys.readouterr().err
    check_flights = [line for line in err.splitlines() if "closed-loop check flight" in line]
    assert check_flights and all(line.split(" seed ")[1].startswith("0:") for line in check_flights)
    assert any(" structure alone (first_order_lag) seed 0" in line for line in check_flights)
    report = (out / "report.md").read_text()
    checked = 0
    for sel in ("low_speed", "cluster"):
        model = load_model(out / f"gp_{sel}.npz")
        record = model.training.get("closed_loop_check")
        if record is None:  # only a model the open-loop checks already kept off may skip it
            assert f"closed-loop check {sel}: none, " in err
            continue
        checked += 1
        comparisons = record["comparisons"]
        assert comparisons[-1]["incumbent"] == STRUCTURE
        for c in comparisons:
            assert c["n_flights"] == 2 and c["passed"] == (
                c["candidate_rmse_m"] <= c["incumbent_rmse_m"]
            )
        assert f"closed-loop check {sel}: {record['flies']} flies" in err
        assert f"- `{sel}` flew: {record['flies']}" in report
        assert structure_only(model) == record["structure_flies"]
    assert checked >= 1 and "Closed-loop check on the training seeds" in report
