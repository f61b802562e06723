"""Each distinct study flight flown once: planners that fly the same share its flight.

A study flight is lockstep and seeded: its vehicle, reference and seed and the planner decide
every figure but the wall-clock solve times, and the planner is built from its settings and
the model it flies (companion.nmpc_planner.CompanionNmpc). Several planner names often fly
the same planner: both selections' models refused (the nominal planner twice), or both
flying their structure alone, which is what the ablation flies too (a quick study flew 6
held-out flights of which 2 differed). :func:`flight_key` says what a job flies;
:func:`fly_once` flies each key once over a study run and gives every other job with that
key the flight relabelled as its own (FlightSummary.flown_as names the planner that flew it).
Jobs are told apart before they are handed out, so any Executor serves (local processes or a
Dask cluster, experiments.executors).
"""

from __future__ import annotations

import hashlib
import pickle
from collections.abc import Iterator
from concurrent.futures import Executor
from dataclasses import replace

from experiments.study.jobs import FlightJob, FlightSummary, flight_name, run_flight_job
from gp.prediction_check import structure_only

# A study run's flights: flight_key -> (the job that flew it, its summary).
FlownFlights = dict[str, tuple[FlightJob, FlightSummary]]


def flight_key(job: FlightJob) -> str:
    """A digest of what decides ``job``'s flight: its vehicle, reference, seed, the planner's
    settings (with ``compile_functions`` as run_flight_job sets it) and the model it flies.
    A model whose GP does not fly (gp.prediction_check.structure_only) counts as its
    structure flown without a model, the planner CompanionNmpc builds from both (no residual,
    the integrator offset-free); but without a model a px4_velocity_pi planner flies the
    gains the autopilot reports (experiments.study.flights.fly), a structure alone only
    those in its file: the two are kept apart.
    The digest is of the pickled content, as a worker receives it: equal digests, the same
    flight (content pickled differently only costs a reuse)."""
    settings = replace(job.settings, compile_functions=job.compile_functions)
    model = job.model
    if model is not None and structure_only(model):
        structure = model.features
        settings = replace(
            settings, nominal_model=structure.nominal_model, nominal_params=structure.nominal_params
        )
        model = None
    autopilot_gains = job.model is None and settings.nominal_model == "px4_velocity_pi"
    content = (job.vehicle, job.reference, job.seed, settings, model, autopilot_gains)
    return hashlib.sha256(pickle.dumps(content)).hexdigest()


def fly_once(
    jobs: list[FlightJob], pool: Executor, flown: FlownFlights
) -> Iterator[tuple[FlightSummary, FlightJob]]:
    """Per job of ``jobs``, in order: its flight's summary and the job that flew it (itself,
    or one flying the same, here or in an earlier call with the same ``flown``: its flight
    relabelled as this job's). Only jobs whose flight_key is not in ``flown`` fly (on
    ``pool``, all handed out at once); ``flown`` gains them."""
    keys = [flight_key(job) for job in jobs]
    new: dict[str, FlightJob] = {}
    for key, job in zip(keys, jobs, strict=True):
        if key not in flown:
            new.setdefault(key, job)
    summaries = pool.map(run_flight_job, new.values())
    for key, job in zip(keys, jobs, strict=True):
        if key not in flown:
            flown[key] = (job, next(summaries))
        flyer, summary = flown[key]
        yield (summary, job) if flyer is job else (relabelled(summary, job), flyer)


def relabelled(summary: FlightSummary, job: FlightJob) -> FlightSummary:
    """``summary`` of another job's flight that flew the same as ``job``, as ``job``'s: its
    names (also in the log's metadata, where ``augmented`` says whether a model was given, as
    experiments.study.flights.fly records it) and ``flown_as``, the planner that flew it."""
    metadata = {
        **summary.log.metadata,
        "mission": flight_name(job),
        "augmented": job.model is not None,
    }
    return replace(
        summary,
        trajectory=job.trajectory,
        planner=job.planner,
        log=replace(summary.log, metadata=metadata),
        flown_as=summary.planner,
    )
