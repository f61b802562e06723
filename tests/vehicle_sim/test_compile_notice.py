"""A jitted loop's first compile on a machine is said on stderr before the wait; a load from
numba's cache is not (the smallest function through the same path: a cached numba function
registered with announce_compiles)."""

from __future__ import annotations

import numba
from numba import njit

from vehicle_sim.compile_notice import announce_compiles

LINE = "building a test loop for this machine (once, about 2 s)...\n"


def fresh_loop(announced: bool = True):
    """A fresh dispatcher of the same cached function, as a new process has."""

    @njit(cache=True)
    def double(x):
        return 2.0 * x

    return announce_compiles(double, "a test loop", 1.6) if announced else double


def test_a_compile_is_said_and_a_load_from_the_cache_is_not(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    assert fresh_loop()(1.5) == 3.0
    out, err = capsys.readouterr()
    assert err.endswith(f": {LINE}") and err.count("\n") == 1 and out == ""
    assert fresh_loop()(2.5) == 5.0  # loaded from tmp_path
    assert capsys.readouterr() == ("", "")
    assert fresh_loop()(2) == 4.0  # new argument types: compiled again, and said
    assert capsys.readouterr().err.endswith(LINE)


def test_a_function_not_registered_compiles_silently(tmp_path, monkeypatch, capsys):
    monkeypatch.setattr(numba.config, "CACHE_DIR", str(tmp_path))
    assert fresh_loop(announced=False)(1.5) == 3.0
    assert capsys.readouterr() == ("", "")
