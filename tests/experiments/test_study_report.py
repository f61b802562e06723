"""The study's report says which model each selection's rows flew, and why."""

from __future__ import annotations

from dataclasses import replace

import pytest

from experiments.study.config import StudyConfig
from experiments.study.figures import PlannerFigures
from experiments.study.paper000 import NOMINAL, Paper000Result
from experiments.study.paper004 import TrialsResult
from experiments.study.report import render_report
from gp.prediction_check import PredictionCheck
from gp.training import TrainingConfig, train_residual_model
from planners.trajectory_generator import generate_trajectories
from tests.gp.gp_synthetic_logs import lag_plant_log


@pytest.fixture(scope="module")
def fit():
    """A first_order_lag + GP fit on a synthetic lag plant, not checked yet."""
    logs = [lag_plant_log(s, 0.4, 0.1) for s in range(2)]
    config = TrainingConfig(features="velocity", nominal="first_order_lag", m=8, restarts=1)
    return train_residual_model(logs, config)


def _report(fits: dict, flights: dict | None = None) -> str:
    """report.md for ``fits`` (and ``flights`` per planner) beside made-up figures (the rows'
    numbers do not matter here)."""
    figs = {
        name: PlannerFigures(name, 2, 2, 0.1, 0.05, 0.04, 1.0, 2.0) for name in (NOMINAL, *fits)
    }
    ref = generate_trajectories(1, seed=0)[0]
    trials = TrialsResult(ref, "low_speed", [], [], [])
    images = {"paths": [], "residuals": [], "trials": []}
    result = Paper000Result([ref], flights or {}, fits)
    return render_report(StudyConfig(), result, figs, trials, images, 1.0)


def _check(incumbent: str, candidate_m: float, incumbent_m: float) -> PredictionCheck:
    return PredictionCheck("learned", incumbent, candidate_m, incumbent_m, 2.0, 10)


def test_report_says_when_a_selection_flew_its_structure_alone_or_the_nominal_planner(fit):
    """The rows of a selection whose GP was refused are not the GP's: the report says so,
    with the check that refused it (they were only on stderr)."""
    structure_alone = replace(
        fit,
        check=_check("nominal kinematic_4dof", 0.08, 0.30),
        structure_check=_check("first_order_lag alone", 0.09, 0.05),
    )
    refused = replace(fit, check=_check("nominal kinematic_4dof", 0.40, 0.30))
    report = _report({"low_speed": structure_alone, "cluster": refused, "flown": fit})
    flew = report.split("What each selection's held-out flights flew:")[1].split("\n\n")[1]
    lines = {line.split("`")[1]: line for line in flew.splitlines()}
    assert "does NOT beat first_order_lag alone" in lines["low_speed"]
    assert "the structure flies alone" in lines["low_speed"]
    assert "its flights fly the nominal planner" in lines["cluster"]
    assert "the learned model flies (first_order_lag + GP)" in lines["flown"]


def test_report_says_which_rows_share_one_flight_and_so_its_solve_times(fit):
    """Rows flying the same planner share its flights (experiments.study.same_flights): their
    equal solve times are one measurement, and the report says so under the table."""
    import numpy as np

    from experiments.study.jobs import FlightSummary
    from flightlog.schema import FlightLog

    def flight(planner: str, flown_as: str | None = None) -> FlightSummary:
        log = FlightLog({"t_s": np.zeros(1)})
        return FlightSummary(0, planner, 1, "completed", 0.1, 0.05, 9, np.ones(3), log, flown_as)

    flights = {
        "low_speed": [flight("low_speed"), flight("low_speed")],
        "cluster": [flight("cluster"), flight("cluster", "low_speed")],
    }
    report = _report({"low_speed": fit, "cluster": fit}, flights)
    table_end = report.index("What each selection's held-out flights flew:")
    note = "- `cluster` flies the same planner as `low_speed` (1 of its 2 flights, the same "
    assert note in report[:table_end]
    assert "- `low_speed` flies the same planner" not in report


def test_path_legends_hide_no_path():
    """paths.png: each panel's legend sits beside the axes, not over the flown paths."""
    import numpy as np
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    from experiments.study.jobs import FlightSummary
    from experiments.study.plots import paths_figure
    from flightlog.schema import FlightLog

    refs = generate_trajectories(2, seed=0)
    flights = {}
    for planner in (NOMINAL, "low_speed"):
        for i, ref in enumerate(refs):
            pos = ref.sample(np.linspace(0.0, ref.duration_s, 50)).pos_ned_m
            log = FlightLog(
                {"pos_n_m": pos[:, 0], "pos_e_m": pos[:, 1], "mode": np.full(50, "OFFBOARD")}
            )
            summary = FlightSummary(i, planner, 0, "completed", 0.1, 0.05, 49, np.ones(3), log)
            flights.setdefault(planner, []).append(summary)
    fig = paths_figure(Paper000Result(refs, flights, {}))
    renderer = FigureCanvasAgg(fig).get_renderer()
    fig.draw(renderer)
    for ax in fig.axes:
        legend = ax.get_legend().get_window_extent(renderer)
        assert not any(legend.overlaps(other.get_window_extent(renderer)) for other in fig.axes)
        assert "tracking RMSE 0.050 m" in ax.get_legend().get_texts()[1].get_text()
