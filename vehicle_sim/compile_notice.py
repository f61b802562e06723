"""Say when a jitted loop of the simulator is compiled for this machine, not loaded from cache.

numba compiles a jitted function at its first call with new argument types and, with
``cache=True``, keeps the machine code on disk (in ``__pycache__`` beside the source, or in
``$NUMBA_CACHE_DIR``) for the processes after it. The simulator's flight loops take 5-15 s
each to compile, so the first command that flies the simulator on a fresh install (``diagnose``
compiles two: about 20-30 s) waited without a word. numba broadcasts its "numba:compile" event
when a dispatcher compiles, before the work, and not when it loads the code from its cache
([numba-events]); a listener on it says flightlog.build_notice's line for the functions
registered here, and nothing for the rest (their compiles take a fraction of a second).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar
from weakref import WeakKeyDictionary

from numba.core import event

from flightlog.build_notice import say_building

Jitted = TypeVar("Jitted", bound=Callable[..., object])

# dispatcher -> (what it is, about how long it takes to compile [s])
_ANNOUNCED: WeakKeyDictionary[Callable[..., object], tuple[str, float]] = WeakKeyDictionary()


def announce_compiles(dispatcher: Jitted, what: str, about_s: float) -> Jitted:
    """``dispatcher`` (a cached numba function), registered so that a compile of it (not a load
    from numba's cache) is said first: "building ``what`` for this machine (once, about
    ``about_s`` s)..." on stderr."""
    _ANNOUNCED[dispatcher] = (what, about_s)
    return dispatcher


class _CompileNotice(event.Listener):
    def on_start(self, ev: event.Event) -> None:
        announced = _ANNOUNCED.get(ev.data["dispatcher"])
        if announced is not None:
            say_building(*announced)

    def on_end(self, ev: event.Event) -> None:
        pass


event.register("numba:compile", _CompileNotice())
