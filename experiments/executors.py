"""Where batch work runs: local processes (the default) or a Dask distributed cluster.

    with job_executor(workers=2, scheduler=None) as pool:        # this machine, spawn processes
        results = list(pool.map(fn, jobs))
    with job_executor(scheduler="tcp://host:8786") as pool:      # a Dask cluster's workers
        results = list(pool.map(fn, jobs))

Both are ``concurrent.futures.Executor`` s (Dask's through ``Client.get_executor``), so the
study and the batch diagnosis hand out the same work units either way. A work unit is a
top-level function of plain, picklable data (a config and a seed): it reads no global state,
so its result does not depend on the worker or machine that ran it.

Dask is optional (``pip install 'residual-companion[cluster]'``); it is imported only when a
scheduler address is given. Every worker must have this package installed at the same
version (the work units are pickled by reference to their module).
"""

from __future__ import annotations

from collections.abc import Iterator
from concurrent.futures import Executor, ProcessPoolExecutor
from contextlib import contextmanager
from multiprocessing import get_context

CLUSTER_EXTRA_HINT = "pip install 'residual-companion[cluster]'"
CONNECT_TIMEOUT_S = 30.0


class SchedulerError(ValueError):
    """The scheduler address is malformed, unreachable, or Dask is not installed."""


def check_scheduler_address(address: str) -> str:
    """``address`` if it looks like a Dask scheduler address (tcp://host:port), else
    SchedulerError naming the fix."""
    scheme, sep, rest = address.partition("://")
    host, colon, port = rest.rpartition(":")
    if not (sep and scheme in ("tcp", "tls", "inproc", "ws", "wss") and host and colon):
        raise SchedulerError(
            f"scheduler address {address!r} is not of the form tcp://HOST:PORT "
            "(e.g. tcp://10.0.0.5:8786, printed by `dask scheduler`)"
        )
    if scheme != "inproc" and not port.isdigit():
        raise SchedulerError(f"scheduler address {address!r}: port {port!r} is not a number")
    return address


@contextmanager
def job_executor(workers: int = 2, scheduler: str | None = None) -> Iterator[Executor]:
    """An Executor for batch jobs: ``workers`` local processes (spawned, so nothing is inherited
    by accident), or the workers of the Dask scheduler at ``scheduler`` (``workers`` is then
    ignored: the cluster has the workers it has).

    Raises:
        SchedulerError: bad address, Dask missing, or no scheduler answering within 30 s.
    """
    if scheduler is None:
        pool = ProcessPoolExecutor(workers, mp_context=get_context("spawn"))
        try:
            yield pool
        except BaseException:
            _stop_now(pool)
            raise
        pool.shutdown()
        return
    check_scheduler_address(scheduler)
    try:
        from distributed import Client
    except ImportError:
        raise SchedulerError(
            f"--scheduler needs Dask distributed; install it with {CLUSTER_EXTRA_HINT}"
        ) from None
    try:
        client = Client(scheduler, timeout=CONNECT_TIMEOUT_S, set_as_default=False)
    except OSError as exc:
        raise SchedulerError(f"no Dask scheduler answered at {scheduler}: {exc}") from None
    try:
        # pure=False: every submitted job runs (no result reuse by argument hash).
        pool = client.get_executor(pure=False)
        try:
            yield pool
        except BaseException:  # an error or a stop: cancel the cluster's jobs, do not wait
            pool.shutdown(wait=False)  # (leaving the executor's own context would wait)
            raise
        pool.shutdown()
    finally:
        client.close()


def _stop_now(pool: ProcessPoolExecutor) -> None:
    """Drop the jobs not started and end the running ones: on an error or a stop (Ctrl-C,
    SIGTERM) the caller wants nothing more from the pool, where a plain shutdown would wait
    for every queued job. The workers are the pool's own processes
    (ProcessPoolExecutor.terminate_workers from Python 3.14)."""
    workers = list((getattr(pool, "_processes", None) or {}).values())
    pool.shutdown(wait=False, cancel_futures=True)
    for process in workers:
        process.terminate()
    for process in workers:
        process.join()
