import os
import shlex
import shutil

import casadi as ca
import numpy as np
import pytest

from planners.compiled_function import compiled


def small_function() -> ca.Function:
    x = ca.SX.sym("x", 3)
    y = ca.SX.sym("y", 2)
    return ca.Function("small_fn", [x, y], [ca.sin(x) * y[0], ca.sumsqr(x) + y[1]])


def assert_compiled_matches(fn: ca.Function) -> None:
    """``compiled(fn)`` is a loaded library that gives ``fn``'s outputs (1e-14)."""
    fast = compiled(fn)
    assert fast.is_a("External")
    x, y = np.array([0.1, -2.0, 3.0]), np.array([1.5, -0.5])
    for a, b in zip(fn(x, y), fast(x, y), strict=True):
        np.testing.assert_allclose(np.asarray(a), np.asarray(b), rtol=1e-14)


@pytest.mark.skipif(
    shutil.which(shlex.split(os.environ.get("CC") or "cc")[0]) is None, reason="needs a C compiler"
)
def test_compiled_matches_and_is_cached(tmp_path, monkeypatch):
    monkeypatch.setenv("RESIDUAL_COMPANION_CACHE", str(tmp_path))
    fn = small_function()
    assert_compiled_matches(fn)
    libs = list(tmp_path.glob("*.so"))
    assert len(libs) == 1
    stamp = libs[0].stat().st_mtime_ns
    compiled(small_function())
    assert libs[0].stat().st_mtime_ns == stamp  # reused, not rebuilt


@pytest.mark.skipif(
    shutil.which(shlex.split(os.environ.get("CC") or "cc")[0]) is None, reason="needs a C compiler"
)
def test_a_build_is_said_on_stderr_first_and_a_cached_library_is_not(tmp_path, monkeypatch, capsys):
    # a first build waited without a word (the NMPC's routines 1-2 s, a learned GP's 14 s)
    monkeypatch.setenv("RESIDUAL_COMPANION_CACHE", str(tmp_path))
    compiled(small_function())
    out, err = capsys.readouterr()
    line = "building the compiled C routine small_fn for this machine (once, about 1 s)...\n"
    assert err.endswith(f": {line}") and err.count("\n") == 1 and out == ""
    compiled(small_function())
    assert capsys.readouterr() == ("", "")


def test_without_compiler_returns_the_function(tmp_path, monkeypatch, capsys):
    monkeypatch.setenv("RESIDUAL_COMPANION_CACHE", str(tmp_path))
    monkeypatch.setenv("CC", str(tmp_path / "no-such-compiler"))
    fn = small_function()
    assert compiled(fn) is fn
    assert not list(tmp_path.glob("*.so"))
    assert capsys.readouterr() == ("", "")  # nothing is built, so nothing is said


def test_a_cc_that_is_no_command_line_returns_the_function(tmp_path, monkeypatch):
    # an unclosed quote in $CC: shlex's "No closing quotation" came out of every planner's
    # construction as a traceback, where a missing compiler falls back to the NumPy path
    monkeypatch.setenv("RESIDUAL_COMPANION_CACHE", str(tmp_path))
    monkeypatch.setenv("CC", 'cc "-O3')
    fn = small_function()
    assert compiled(fn) is fn


@pytest.mark.skipif(
    shutil.which(shlex.split(os.environ.get("CC") or "cc")[0]) is None, reason="needs a C compiler"
)
def test_a_damaged_cached_library_is_built_again(tmp_path, monkeypatch):
    # a power cut soon after the first build can leave the library renamed but empty: every
    # planner built afterwards raised CasADi's 'Cannot load shared library' instead of planning
    monkeypatch.setenv("RESIDUAL_COMPANION_CACHE", str(tmp_path))
    compiled(small_function())
    (library,) = tmp_path.glob("*.so")
    library.write_bytes(b"")
    fn = small_function()
    assert_compiled_matches(fn)
    assert library.stat().st_size > 0


@pytest.mark.skipif(shutil.which("cc") is None, reason="needs a C compiler")
def test_a_compiler_named_with_its_options_compiles(tmp_path, monkeypatch):
    # $CC as make takes it, a command line ("ccache gcc", "gcc -m64"): it was run as one
    # program name, not found, and the planner fell back to the slower path without a word
    monkeypatch.setenv("RESIDUAL_COMPANION_CACHE", str(tmp_path))
    monkeypatch.setenv("CC", f"{shutil.which('cc')} -Wall")
    assert compiled(small_function()).is_a("External")
