"""The console scripts' entry points (pyproject's ``[project.scripts]``): each loads its
command's module, then runs its ``main``.

A command's libraries (NumPy, SciPy, CasADi, Matplotlib, MAVSDK) take a second or two to load,
before ``main`` can catch anything: a Ctrl-C then (a user who sees a typo in the command line
just entered) was a KeyboardInterrupt traceback through importlib. Here it ends in one line and
exit 130, as a Ctrl-C later on does; nothing has been done yet.
"""

from __future__ import annotations

import importlib
import sys

EXIT_INTERRUPTED = 130


def run(module: str, prog: str) -> int:
    """Load ``scripts.<module>`` and return its ``main()``'s exit code; a Ctrl-C while it loads
    is one line naming ``prog`` and exit 130."""
    try:
        main = importlib.import_module(f"scripts.{module}").main
    except KeyboardInterrupt:
        print(f"{prog}: stopped by Ctrl-C while starting; nothing done", file=sys.stderr)
        return EXIT_INTERRUPTED
    return main()


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
