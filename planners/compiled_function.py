"""Compile a CasADi Function to C once per machine and load it back.

The C code is generated from our own formulation at first use, built with the system C
compiler (``$CC``, a command line as make takes it, e.g. "ccache gcc"; default ``cc``) into a
user cache directory (``$RESIDUAL_COMPANION_CACHE``, else
``$XDG_CACHE_HOME/residual-companion``, else ``~/.cache/residual-companion``) under a name
that hashes the source, so a changed formulation gets a new library and concurrent processes
never see a half-written one; the library is synced to disk before it is renamed into place,
and a cached library that does not load (left empty by a power cut, damaged) is built again.
Without a working compiler (or with a $CC that is no command line, e.g. an unclosed quote) the
Function is returned unchanged (the CasADi virtual machine evaluates it, slower but identical).
A build is said first, in one line on stderr (flightlog.build_notice), with its time estimated
from the source's length; a library loaded from the cache is not.
"""

from __future__ import annotations

import hashlib
import os
import shlex
import shutil
import signal
import subprocess
import tempfile
from pathlib import Path

import casadi as ca

from flightlog.build_notice import say_building

# C source the compiler gets through per second at -O2 (CasADi's generated code, measured on
# two shared cores: 16 kB in 0.5 s, 104 kB in 1.6 s, 160 kB in 1.9 s): a build's rough time.
C_SOURCE_BYTES_PER_S = 80_000.0


def cache_dir() -> Path:
    """Directory for compiled libraries (created on demand)."""
    explicit = os.environ.get("RESIDUAL_COMPANION_CACHE")
    if explicit:
        return Path(explicit)
    base = os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache"
    return Path(base) / "residual-companion"


def compiled(fn: ca.Function) -> ca.Function:
    """``fn`` compiled to C and loaded as an external Function, or ``fn`` if that fails."""
    name = fn.name()
    with tempfile.TemporaryDirectory() as tmp:
        c_file = Path(tmp) / f"{name}.c"
        gen = ca.CodeGenerator(c_file.name, {"with_header": False})
        gen.add(fn)
        gen.generate(tmp + os.sep)
        source = c_file.read_text()
    digest = hashlib.sha256(source.encode()).hexdigest()[:20]
    directory = cache_dir()
    library = directory / f"{name}_{digest}.so"
    if library.exists():
        loaded = _load(name, library)
        if loaded is not None:
            return loaded
    built = _load(name, library) if _build(source, library, name) else None
    return fn if built is None else built


def _load(name: str, library: Path) -> ca.Function | None:
    """The Function ``name`` of ``library``, or None when it does not load."""
    try:
        return ca.external(name, str(library))
    except RuntimeError:
        return None


def _build(source: str, library: Path, name: str) -> bool:
    """Compile ``source`` into ``library``, said first when there is a compiler to run (a
    machine without one falls back at once, every time: nothing is built, nothing said)."""
    try:
        compiler = shlex.split(os.environ.get("CC") or "cc")
        if not compiler or shutil.which(compiler[0]) is None:
            return False
        say_building(f"the compiled C routine {name}", len(source) / C_SOURCE_BYTES_PER_S)
        library.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=library.parent) as tmp:
            c_file = Path(tmp) / "source.c"
            c_file.write_text(source)
            out = Path(tmp) / library.name
            cmd = [
                *compiler,
                "-O2",
                "-shared",
                "-fPIC",
                str(c_file),
                "-o",
                str(out),
            ]
            if not _run_compiler(cmd, timeout_s=300.0):
                return False
            with open(out, "rb") as fh:
                os.fsync(fh.fileno())
            os.replace(out, library)
        return True
    except (OSError, subprocess.SubprocessError, ValueError):  # ValueError: $CC unparsable
        return False


def _run_compiler(cmd: list[str], timeout_s: float) -> bool:
    """Run ``cmd`` in its own process group; on timeout kill the whole group (cc and cc1)."""
    proc = subprocess.Popen(
        cmd, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )
    try:
        return proc.wait(timeout=timeout_s) == 0
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.wait()
        return False
