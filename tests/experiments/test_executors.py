"""Batch work on a Dask cluster gives exactly the local result; bad addresses are refused."""

from __future__ import annotations

import os
import time

import numpy as np
import psutil
import pytest

from companion.nmpc_planner import NmpcSettings
from experiments.executors import SchedulerError, check_scheduler_address, job_executor
from experiments.study.jobs import FlightJob, run_flight_job
from planners.trajectory_generator import TrajectorySpec, generate_trajectories
from scripts.study import main as study_main


@pytest.mark.slow(expected_s=40)
def test_flights_on_a_dask_cluster_equal_the_local_run():
    distributed = pytest.importorskip("distributed")
    refs = generate_trajectories(2, seed=7, spec=TrajectorySpec(length_range_m=(5.0, 6.0)))
    settings = NmpcSettings(2.5)
    jobs = [
        FlightJob(i, ref, "nominal", seed, "iris_study", settings, compile_functions=False)
        for i, ref in enumerate(refs)
        for seed in (0, 1)
    ]
    # One local process flies all four in turn, the cluster's two workers take them as they
    # come: a result that depended on the process or on the job flown before it would differ.
    with job_executor(workers=1) as pool:
        local = list(pool.map(run_flight_job, jobs))
    with (
        distributed.LocalCluster(
            n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
        ) as cluster,
        job_executor(scheduler=cluster.scheduler_address) as pool,
    ):
        remote = list(pool.map(run_flight_job, jobs))
    assert [(s.trajectory, s.seed) for s in remote] == [(j.trajectory, j.seed) for j in jobs]
    for a, b in zip(local, remote, strict=True):
        assert a.status == b.status == "completed"
        assert a.tracking_rmse_m == b.tracking_rmse_m
        assert a.residual_rmse_mps == b.residual_rmse_mps
        assert set(a.log.columns) == set(b.log.columns)
        for name in a.log.columns:
            np.testing.assert_array_equal(a.log[name], b.log[name], err_msg=name)
    # Different seeds fly different gusts: the comparison above is not trivially equal.
    assert local[0].tracking_rmse_m != local[1].tracking_rmse_m


@pytest.mark.parametrize(
    "address", ["localhost:8786", "tcp://:8786", "tcp://host", "http://host:8786", "tcp://h:x"]
)
def test_malformed_scheduler_address_is_refused_naming_the_form(address):
    with pytest.raises(SchedulerError, match="tcp://"):
        check_scheduler_address(address)


def test_study_with_a_malformed_scheduler_exits_2_in_one_line(tmp_path, capsys):
    code = study_main(["--quick", "--out", str(tmp_path / "s"), "--scheduler", "host:8786"])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert "tcp://HOST:PORT" in err[-1] and "host:8786" in err[-1]


def _write_pid_and_wait(path: str) -> None:
    """A job that says where it runs, then takes long."""
    with open(path, "a") as fh:
        fh.write(f"{os.getpid()}\n")
    time.sleep(60.0)


def test_a_stop_in_the_caller_cancels_queued_jobs_and_ends_running_ones(tmp_path):
    """Ctrl-C or SIGTERM in the study: its queued flights must not run on, nor its workers
    outlive it (a plain shutdown waits for every queued job)."""
    pids = tmp_path / "pids"
    with pytest.raises(KeyboardInterrupt), job_executor(workers=1) as pool:
        futures = [pool.submit(_write_pid_and_wait, str(pids)) for _ in range(4)]
        while not pids.exists():
            time.sleep(0.05)
        raise KeyboardInterrupt
    assert sum(f.cancelled() for f in futures) >= 2  # the pool hands one more out early
    (pid,) = map(int, pids.read_text().split())
    assert not psutil.pid_exists(pid) or psutil.Process(pid).status() == psutil.STATUS_ZOMBIE


@pytest.mark.slow
def test_a_stop_in_the_caller_cancels_the_clusters_jobs_instead_of_waiting_for_them(tmp_path):
    """On a Dask cluster too: leaving Dask's executor by its own context waits for every job
    (here 4 x 60 s); a stop must cancel them, so only the job already running ever started."""
    distributed = pytest.importorskip("distributed")
    pids = tmp_path / "pids"
    with distributed.LocalCluster(
        n_workers=1, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster:
        with (
            pytest.raises(KeyboardInterrupt),
            job_executor(scheduler=cluster.scheduler_address) as pool,
        ):
            futures = [pool.submit(_write_pid_and_wait, str(pids)) for _ in range(4)]
            while not pids.exists():
                time.sleep(0.05)
            raise KeyboardInterrupt
        assert len(pids.read_text().split()) == 1  # the queued three never ran
    assert sum(f.cancelled() for f in futures) >= 3
