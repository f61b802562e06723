"""The console scripts' entry points (pyproject's ``[project.scripts]``): each loads its
command's module, then runs its ``main``.

A command's libraries (NumPy, SciPy, CasADi, Matplotlib, MAVSDK) take a second or two to load,
before ``main`` can catch anything: a Ctrl-C then (a user who sees a typo in the command line
just entered) was a KeyboardInterrupt traceback through importlib. Here it ends in one line and
exit 130, as a Ctrl-C later on does; nothing has been done yet.

A reader of the output that stops early (``flightlog info LOG | head``) closes the pipe: the
next write was a BrokenPipeError traceback. The command ends there quietly, as a program that
SIGPIPE stops does (exit 141): its reader has what it wanted. Only then: a BrokenPipeError of
anything else (a pipe or socket of the command's own) while its standard output is still read
is the failure it is, not a quiet exit.
"""

from __future__ import annotations

import importlib
import os
import select
import sys

EXIT_INTERRUPTED = 130
EXIT_BROKEN_PIPE = 128 + 13  # SIGPIPE's number, as the shell reports a process it stopped


def run(module: str, prog: str) -> int:
    """Load ``scripts.<module>`` and return its ``main()``'s exit code; a Ctrl-C while it loads
    is one line naming ``prog`` and exit 130, a closed standard output exit 141."""
    try:
        main = importlib.import_module(f"scripts.{module}").main
    except KeyboardInterrupt:
        print(f"{prog}: stopped by Ctrl-C while starting; nothing done", file=sys.stderr)
        return EXIT_INTERRUPTED
    try:
        code = main()
        sys.stdout.flush()
    except BrokenPipeError:
        if not _stdout_closed():
            raise
        # What is still buffered would fail again when Python flushes it on exit.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_BROKEN_PIPE
    return code


def _stdout_closed() -> bool:
    """Whether standard output is a pipe or socket whose reader has gone (poll reports an
    error or a hang-up on it); False for an output that is no file (nothing of it can be
    broken)."""
    try:
        poller = select.poll()
        poller.register(sys.stdout.fileno(), select.POLLOUT)
    except (OSError, ValueError):
        return False
    return any(events & (select.POLLERR | select.POLLHUP) for _, events in poller.poll(0))


def vehicle_sim() -> int:
    return run("vehicle_sim_cli", "vehicle-sim")


def companion() -> int:
    return run("companion_cli", "companion")


def fit_gp() -> int:
    return run("fit_gp", "fit-gp")


def diagnose() -> int:
    return run("diagnose", "diagnose")


def bench() -> int:
    return run("bench", "bench")


def study() -> int:
    return run("study", "study")


def flightlog() -> int:
    return run("flightlog_cli", "flightlog")


def rover_path() -> int:
    return run("rover_path", "rover-path")
