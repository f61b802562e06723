"""The line a command says on stderr before it builds compiled code for this machine.

The simulator's flight loops (numba, vehicle_sim.compile_notice) and the planner's C routines
(CasADi, planners.compiled_function) are compiled at first use and cached, so the first
command that needs one waits (seconds, up to half a minute for a flight loop) where later ones
do not: without a word, that first wait looked like a hang. Each build site says this one
line before the wait, on stderr (stdout may carry a report or JSON), and nothing when the
cache has the code. Kept in this leaf so that both say it alike.
"""

from __future__ import annotations

import sys
from pathlib import Path


def say_building(what: str, about_s: float) -> None:
    """Say on stderr that ``what`` (e.g. "the simulator's compiled flight loop") is being built
    for this machine, once, in about ``about_s`` [s] (rounded, at least 1), after the running
    command's name as its other messages begin ("diagnose: building ...")."""
    about = f"once, about {max(1, round(about_s))} s"
    print(
        f"{_command()}: building {what} for this machine ({about})...", file=sys.stderr, flush=True
    )


def _command() -> str:
    """The running command's name: its console script's, its module's for ``python -m`` (the
    package's for a package's __main__), "python" for ``python -c``."""
    script = Path(sys.argv[0]) if sys.argv and sys.argv[0] not in ("", "-c") else None
    if script is None:
        return "python"
    return script.parent.name if script.stem == "__main__" else script.stem
