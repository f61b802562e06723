"""Planners that fly the same fly once per study run (experiments.study.same_flights), and
every planner's figures stay those of its own flight."""

from __future__ import annotations

from collections.abc import Iterator
from concurrent.futures import Executor
from contextlib import contextmanager
from dataclasses import fields, replace

import numpy as np
import pytest

from companion.nmpc_planner import NmpcSettings
from experiments.executors import job_executor
from experiments.study.jobs import FlightJob, FlightSummary, run_flight_job
from experiments.study.paper000 import IDENTIFIED_LAG, _fly_all
from experiments.study.same_flights import flight_key
from gp.training import TrainingConfig, train_residual_model
from planners.trajectory_generator import TrajectorySpec, generate_trajectories
from tests.gp.gp_synthetic_logs import lag_plant_log

NMPC = NmpcSettings(2.5)
REFERENCE = generate_trajectories(1, seed=7, spec=TrajectorySpec(length_range_m=(5.0, 6.0)))[0]


@pytest.fixture(scope="module")
def learned():
    """A first_order_lag + GP model (its GP flies) fitted on a synthetic lag plant."""
    logs = [lag_plant_log(s, 0.4, 0.1) for s in range(2)]
    config = TrainingConfig(features="velocity", nominal="first_order_lag", m=8, restarts=1)
    return train_residual_model(logs, config).model


def _structure_alone(model):
    """``model`` as the closed-loop check leaves it when its structure flies without the GP."""
    return replace(
        model, training={**model.training, "closed_loop_check": {"structure_flies": True}}
    )


def _lag(model) -> NmpcSettings:
    """The nominal planner on ``model``'s structure, as the study's ablation flies it."""
    features = model.features
    return replace(
        NMPC, nominal_model=features.nominal_model, nominal_params=features.nominal_params
    )


def _job(planner, settings=NMPC, model=None, seed=1, reference=REFERENCE) -> FlightJob:
    return FlightJob(0, reference, planner, seed, "iris_study", settings, model, False)


def test_a_structure_alone_flies_what_the_nominal_planner_on_that_structure_flies(learned):
    alone = _job("low_speed", model=_structure_alone(learned))
    assert flight_key(alone) == flight_key(_job(IDENTIFIED_LAG, _lag(learned)))
    assert flight_key(_job("low_speed")) == flight_key(_job("cluster"))  # both refused
    assert flight_key(alone) != flight_key(_job("low_speed", model=learned))  # the GP flies
    assert flight_key(alone) != flight_key(_job("low_speed"))  # kinematic_4dof
    assert flight_key(alone) != flight_key(_job("low_speed", model=learned, seed=2))
    other = generate_trajectories(1, seed=8, spec=TrajectorySpec(length_range_m=(5.0, 6.0)))[0]
    assert flight_key(_job("cluster")) != flight_key(_job("cluster", reference=other))
    assert flight_key(_job("cluster")) != flight_key(_job("cluster", NmpcSettings(3.0)))


def test_the_px4_structure_alone_is_not_the_nominal_pi_planner_which_takes_the_autopilots_gains(
    learned,
):
    """Without a model the px4_velocity_pi planner flies the gains the autopilot reports
    (experiments.study.flights.fly), the structure alone its file's: not the same flight."""
    features = replace(learned.features, nominal_model="px4_velocity_pi", nominal_params=())
    alone = _structure_alone(replace(learned, features=features))
    pi = replace(NMPC, nominal_model="px4_velocity_pi")
    assert flight_key(_job("low_speed", model=alone)) != flight_key(_job(IDENTIFIED_LAG, pi))
    assert flight_key(_job("low_speed", model=alone)) == flight_key(_job("cluster", model=alone))


class _CountingExecutor(Executor):
    """Hands every job to ``pool``; counts the flights handed out."""

    def __init__(self, pool: Executor):
        self.pool = pool
        self.flights = 0

    def submit(self, fn, /, *args, **kwargs):
        self.flights += fn is run_flight_job
        return self.pool.submit(fn, *args, **kwargs)


def _study_like_jobs(learned) -> tuple[list[FlightJob], list[FlightJob]]:
    """Held-out flights where both selections were refused (both fly the nominal planner)
    beside the ablation (the structure alone), then a round whose model flies its structure
    alone: 4 jobs, 2 distinct flights."""
    held_out = [_job("low_speed"), _job("cluster"), _job(IDENTIFIED_LAG, _lag(learned))]
    return held_out, [_job("low_speed", model=_structure_alone(learned))]


@contextmanager
def _executor(where: str) -> Iterator[Executor]:
    """Two local worker processes, or a two-worker Dask LocalCluster."""
    if where == "local processes":
        with job_executor(workers=2) as pool:
            yield pool
        return
    distributed = pytest.importorskip("distributed")
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        job_executor(scheduler=cluster.scheduler_address) as pool,
    ):
        yield pool


@pytest.fixture(scope="module")
def flown_again(learned):
    """The reused jobs flown each on its own, as the study flew them before."""
    held_out, later = _study_like_jobs(learned)
    return {"held-out": run_flight_job(held_out[1]), "later": run_flight_job(later[0])}


@pytest.mark.slow(expected_s=40)
@pytest.mark.parametrize("where", ["local processes", "a Dask cluster"])
def test_planners_flying_the_same_fly_once_with_the_figures_of_their_own_flights(
    where, learned, flown_again
):
    held_out, later = _study_like_jobs(learned)
    lines: list[str] = []
    with _executor(where) as pool:
        counting, distinct = _CountingExecutor(pool), {}
        first = _fly_all(held_out, counting, distinct, "held-out", lines.append)
        assert counting.flights == 2
        second = _fly_all(later, counting, distinct, "later", lines.append)
    assert counting.flights == 2
    assert [s.planner for s in [*first, *second]] == [j.planner for j in [*held_out, *later]]
    assert "held-out: 1 of 3 flights reused: same planner as low_speed for cluster" in lines
    assert (
        "later: 1 of 1 flights reused: same planner as structure alone (first_order_lag) "
        "for low_speed"
    ) in lines
    _assert_same_flight(first[1], flown_again["held-out"])
    _assert_same_flight(second[0], flown_again["later"])
    assert (first[1].flown_as, second[0].flown_as) == ("low_speed", IDENTIFIED_LAG)
    # the nominal planner and the lag fly differently: the comparisons above are not trivial
    assert first[0].tracking_rmse_m != first[2].tracking_rmse_m


def _assert_same_flight(reused: FlightSummary, flown: FlightSummary) -> None:
    """Every figure, log row and log field of the flight as flown on its own; the solve
    times are wall clock (and the reused one says whose they are)."""
    for field in fields(FlightSummary):
        if field.name not in ("solve_times_s", "flown_as", "log"):
            assert getattr(reused, field.name) == getattr(flown, field.name), field.name
    assert reused.solve_times_s.shape == flown.solve_times_s.shape
    assert dict(reused.log.metadata) == dict(flown.log.metadata)
    assert set(reused.log.columns) == set(flown.log.columns)
    for name in flown.log.columns:
        np.testing.assert_array_equal(reused.log[name], flown.log[name], err_msg=name)
