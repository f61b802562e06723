"""Outputs written atomically: a reader sees the old file (or folder) or the new one, never half.

A file is written to a temporary sibling and renamed over the target (``os.replace`` is atomic
on one filesystem); a folder of outputs (a report with its plots, a model with its figures) is
filled in a temporary sibling folder and renamed into place as a whole, replacing an earlier
one. Errors on the output side become :class:`OutputError` with one line naming the path and
the fix, never a traceback. The temporaries are private (0600 / 0700) while filled; what
appears gets the mode the user's umask gives any new file or folder.
"""

from __future__ import annotations

import io
import os
import shutil
import tempfile
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path
from typing import Any


class OutputError(OSError):
    """An output that cannot be written; one line naming the path and what to do."""


def describe_os_error(path: Path, exc: OSError) -> str:
    """One line for an OSError on ``path``, with the fix."""
    reason = exc.strerror or str(exc)
    if isinstance(exc, PermissionError):
        return f"{path}: cannot write there ({reason}); choose a folder you can write to"
    if isinstance(exc, (NotADirectoryError, FileExistsError)):
        return f"{path}: a file stands where a folder is needed ({reason}); choose another path"
    if isinstance(exc, IsADirectoryError):
        return f"{path}: is a folder, a file is needed ({reason}); give a file name"
    return f"{path}: cannot write ({reason}); choose a path in a folder you can write to"


def _refuse_a_special_file(path: Path) -> None:
    """OutputError in one line when ``path`` is a device, a pipe or a socket: the rename that
    puts the new file in place would replace the node itself (``--out /dev/null`` run as root
    leaves /dev/null a regular file)."""
    if path.exists() and not (path.is_file() or path.is_dir()):
        raise OutputError(
            f"{path}: not a regular file (a device, a pipe or a socket); writing there would "
            "replace it: give a file name"
        )


def check_writable_file(path: str | Path) -> Path:
    """Make the parent folder and prove a file can be created there (before any flight or
    long computation); OutputError in one line otherwise."""
    path = Path(path)
    _refuse_a_special_file(path)
    try:
        if path.is_dir():
            raise IsADirectoryError(21, "Is a directory")
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.NamedTemporaryFile(dir=path.parent, prefix=f".{path.name}.", delete=True):
            pass
    except OSError as exc:
        raise OutputError(describe_os_error(path, exc)) from None
    return path


def check_not_an_input(path: str | Path, inputs: list[Path]) -> None:
    """OutputError in one line when the output ``path`` is one of the ``inputs`` being read:
    writing there would replace it (a converted log over the only copy of the flight, a flight
    log over its mission)."""
    out = Path(path)
    for source in inputs:
        if out.exists() and source.exists() and os.path.samefile(out, source):
            raise OutputError(
                f"{out}: is an input being read; writing there would replace it: choose "
                "another path"
            )


def check_writable_dir(path: str | Path) -> Path:
    """Prove an output folder can be put at ``path`` (before any long computation): no file in
    the way, and its parent writable. OutputError in one line otherwise."""
    path = Path(path)
    try:
        if path.exists() and not path.is_dir():
            raise NotADirectoryError(20, "Not a directory")
        path.parent.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryDirectory(dir=path.parent, prefix=f".{path.name}."):
            pass
    except OSError as exc:
        raise OutputError(describe_os_error(path, exc)) from None
    return path


def _umask_mode(full: int) -> int:
    """``full`` (0o666 for a file, 0o777 for a folder) less the process's umask."""
    return full & ~_process_umask()


def _process_umask() -> int:
    """The umask, read without changing it where the kernel reports it (Linux: the Umask line
    of /proc/self/status): setting and restoring it would, for an instant, give every file
    another thread of the companion creates mode 0666."""
    try:
        for line in Path("/proc/self/status").read_text().splitlines():
            if line.startswith("Umask:"):
                return int(line.split()[1], 8)
    except (OSError, ValueError, IndexError):
        pass
    umask = os.umask(0)
    os.umask(umask)
    return umask


def write_text_atomic(path: str | Path, text: str) -> Path:
    """Write ``text`` to ``path`` atomically (temporary sibling, then rename)."""
    return write_bytes_atomic(path, text.encode())


def write_figure_atomic(fig: Any, path: str | Path, **savefig: Any) -> Path:
    """Save a Matplotlib figure as PNG to ``path`` atomically, and close it (also when saving
    fails). ``savefig``: Matplotlib's options (dpi, bbox_inches, ...)."""
    import matplotlib.pyplot as plt

    png = io.BytesIO()
    try:
        fig.savefig(png, format="png", **savefig)
    finally:
        plt.close(fig)
    return write_bytes_atomic(path, png.getvalue())


def write_bytes_atomic(path: str | Path, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically (temporary sibling, synced to disk, then rename:
    without the sync a power cut soon after, as a vehicle's companion computer sees, can leave
    ``path`` renamed but empty)."""
    path = Path(path)
    _refuse_a_special_file(path)
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
        try:
            os.fchmod(fd, _umask_mode(0o666))
            with os.fdopen(fd, "wb") as fh:
                fh.write(data)
                fh.flush()
                os.fsync(fh.fileno())
            os.replace(tmp, path)
        except BaseException:
            Path(tmp).unlink(missing_ok=True)
            raise
    except OSError as exc:
        raise OutputError(describe_os_error(path, exc)) from None
    return path


@contextmanager
def atomic_output_dir(path: str | Path) -> Iterator[Path]:
    """Yield a temporary sibling folder to fill. On success a new ``path`` is that folder
    renamed as a whole; an existing ``path`` gets each output file renamed into it (each one
    atomic), and nothing else in it is touched: a user's folder never loses a file. On any
    error the temporary folder is removed and ``path`` is left as it was."""
    path = Path(path)
    try:
        if path.exists() and not path.is_dir():
            raise NotADirectoryError(20, "Not a directory")
        path.parent.mkdir(parents=True, exist_ok=True)
        tmp = Path(tempfile.mkdtemp(dir=path.parent, prefix=f".{path.name}."))
        tmp.chmod(_umask_mode(0o777))
    except OSError as exc:
        raise OutputError(describe_os_error(path, exc)) from None
    try:
        yield tmp
        if path.is_dir():
            for produced in sorted(tmp.rglob("*")):
                target = path / produced.relative_to(tmp)
                if produced.is_dir():
                    target.mkdir(exist_ok=True)
                else:
                    os.replace(produced, target)
            shutil.rmtree(tmp, ignore_errors=True)
        else:
            os.replace(tmp, path)
    except OSError as exc:
        shutil.rmtree(tmp, ignore_errors=True)
        raise OutputError(describe_os_error(path, exc)) from None
    except BaseException:
        shutil.rmtree(tmp, ignore_errors=True)
        raise
