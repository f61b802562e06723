"""A batch diagnosis: every log diagnosed on its own, the jobs spread over an Executor.

Where ``diagnose LOGS...`` explains all logs together, ``diagnose --batch LOGS...`` asks the
question per log (e.g. one per airframe or per day of a fleet's flights) and writes one report
set per log plus a summary. Each job is a pure function of (log, config): the client reads the
files and ships the data, so a remote worker needs no access to them (see
:mod:`experiments.executors` for local processes vs a Dask cluster).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from concurrent.futures import Executor
from dataclasses import dataclass

from diagnosis.diagnosis import Diagnosis, diagnose
from diagnosis.report import headline
from flightlog.schema import FlightLog
from vehicle_sim import SimConfig


@dataclass(frozen=True, eq=False)
class DiagnosisJob:
    """One log to diagnose against a simulation config (plain data: picklable)."""

    name: str
    log: FlightLog
    sim_config: SimConfig


def run_diagnosis_job(job: DiagnosisJob) -> Diagnosis:
    """Diagnose one log in this process (the work unit)."""
    return diagnose([job.log], job.sim_config)


def diagnose_each(
    jobs: Sequence[DiagnosisJob], pool: Executor, progress: Callable[[str], None]
) -> list[Diagnosis]:
    """Diagnose every job on ``pool``; results in the jobs' order."""
    results = []
    for n, (job, result) in enumerate(
        zip(jobs, pool.map(run_diagnosis_job, jobs), strict=True), start=1
    ):
        progress(f"diagnosed {n}/{len(jobs)} {job.name}: {headline(result)}")
        results.append(result)
    return results
