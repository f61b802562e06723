"""The experience of path repeating kept in a file, so that learning goes on across runs.

[Ostafew16] learns across trials and days: the experience bins of gp.local_gp are the robot's
memory of a path. This file (NumPy .npz, written atomically) holds every stored experience of
one path with its vertex and speed bin, the bin geometry, the path's vertices (an experience
file belongs to one path: a vertex index means nothing on another) and how many trials were
driven, plus the last speed schedule (N,) [m/s] when a speed scheduler set it, and one row
of figures per trial driven with it (:data:`HISTORY_COLUMNS`), so that a report covers every
run.
"""

from __future__ import annotations

import io
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flightlog.atomic_output import write_bytes_atomic
from gp.local_gp import LocalGP
from planners.rover.path import TaughtPath

FORMAT = "rover-path-experience-v1"
_PATH_ATOL_M = 1e-3
HISTORY_COLUMNS = (
    "trial", "max_e_lat_m", "rms_e_lat_m", "max_e_head_rad", "rms_e_head_rad", "travel_time_s"
)  # fmt: skip


class ExperienceFileError(ValueError):
    """An experience file that cannot be used; one line naming what and how to fix."""


@dataclass(frozen=True)
class Memory:
    """What a run starts from: trials driven before, the schedule they left (or None), and
    their figures, (trials_done, len(HISTORY_COLUMNS))."""

    trials_done: int
    schedule_mps: np.ndarray | None
    history: np.ndarray


def save_experience(
    file: Path,
    gp: LocalGP,
    path: TaughtPath,
    trials_done: int,
    schedule_mps: np.ndarray | None = None,
    history: np.ndarray | None = None,
) -> None:
    """Write ``gp``'s experiences of ``path`` to ``file`` atomically (OutputError if not)."""
    items = gp.stored()
    c = gp.config
    arrays = {
        "format": np.array(FORMAT),
        "vertex": np.array([v for v, _, _, _ in items], dtype=np.int64),
        "speed_bin": np.array([b for _, b, _, _ in items], dtype=np.int64),
        "query": np.array([a for _, _, a, _ in items]).reshape(-1, gp.n_features),
        "disturbance": np.array([g for _, _, _, g in items]).reshape(-1, gp.n_outputs),
        "path_xy_m": path.xy_m,
        "bins": np.array([c.speed_bin_mps, c.bin_capacity, c.vertex_window, c.speed_window]),
        "trials_done": np.array(trials_done),
        "schedule_mps": np.zeros(0) if schedule_mps is None else np.asarray(schedule_mps),
        "history": np.zeros((0, len(HISTORY_COLUMNS)))
        if history is None
        else np.asarray(history, dtype=float).reshape(-1, len(HISTORY_COLUMNS)),
    }
    buffer = io.BytesIO()
    np.savez(buffer, **arrays)
    write_bytes_atomic(file, buffer.getvalue())


def _same_path_resampled(xy: np.ndarray, length_m: float, path: TaughtPath) -> bool:
    """Whether vertices ``xy`` (n, 2) [m], a polyline ``length_m`` [m] long, are ``path`` read
    at another vertex spacing: another vertex count, the same ends, a length within 2 %."""
    if xy.ndim != 2 or len(xy) < 3 or len(xy) == len(path):
        return False
    ends_m = np.hypot(*(xy[[0, -1]] - path.xy_m[[0, -1]]).T)
    return bool(ends_m.max() <= _PATH_ATOL_M and abs(length_m - path.length_m) <= 0.02 * length_m)


def load_experience(file: Path, gp: LocalGP, path: TaughtPath) -> Memory:
    """Add the experiences in ``file`` to the empty ``gp``; a missing file is no experience.

    Raises:
        ExperienceFileError: not an experience file, damaged, non-finite, of another bin
            geometry, or learned on another path.
    """
    if not file.exists():
        return Memory(0, None, np.zeros((0, len(HISTORY_COLUMNS))))
    fix = "pass another --experience file (or delete this one to start learning anew)"
    try:
        with np.load(file, allow_pickle=False) as npz:
            data = {k: npz[k] for k in npz.files}
    except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
        raise ExperienceFileError(
            f"{file}: not a readable experience file ({type(exc).__name__}); {fix}"
        ) from None
    needed = ("format", "vertex", "speed_bin", "query", "disturbance", "path_xy_m", "bins",
              "trials_done", "schedule_mps", "history")  # fmt: skip
    missing = [k for k in needed if k not in data]
    if missing or str(data.get("format")) != FORMAT:
        what = f"lacks {', '.join(missing)}" if missing else f"is {str(data['format'])!r}"
        raise ExperienceFileError(f"{file}: not a {FORMAT} file (it {what}); {fix}")
    n = len(data["vertex"])
    shapes_ok = (
        data["query"].shape == (n, gp.n_features)
        and data["disturbance"].shape == (n, gp.n_outputs)
        and data["speed_bin"].shape == (n,)
        and data["history"].ndim == 2
        and data["history"].shape[1] == len(HISTORY_COLUMNS)
    )
    if not shapes_ok or not all(
        np.all(np.isfinite(data[k])) for k in ("query", "disturbance", "schedule_mps")
    ):
        raise ExperienceFileError(f"{file}: damaged (wrong shapes or non-finite values); {fix}")
    c = gp.config
    if not np.allclose(data["bins"], [c.speed_bin_mps, c.bin_capacity, c.vertex_window,
                                      c.speed_window]):  # fmt: skip
        raise ExperienceFileError(
            f"{file}: kept with other experience bins ({data['bins'].tolist()}); {fix}"
        )
    xy = data["path_xy_m"]
    if xy.shape != path.xy_m.shape or not np.allclose(xy, path.xy_m, atol=_PATH_ATOL_M):
        length = float(np.sum(np.hypot(*np.diff(xy, axis=0).T))) if xy.ndim == 2 else 0.0
        if _same_path_resampled(xy, length, path):
            spacing = length / (len(xy) - 1)
            raise ExperienceFileError(
                f"{file}: learned on this path at a vertex spacing of {spacing:.2f} m, not "
                f"{path.spacing_m:.2f} m; pass --spacing {spacing:.2f}, or {fix}"
            )
        raise ExperienceFileError(
            f"{file}: learned on another path ({len(xy)} vertices, {length:.1f} m; this one "
            f"has {len(path)} vertices, {path.length_m:.1f} m); {fix}"
        )
    for v, b, a, g in zip(data["vertex"], data["speed_bin"], data["query"], data["disturbance"],
                          strict=True):  # fmt: skip
        gp.add(int(v), (int(b) + 0.5) * c.speed_bin_mps, a, g)
    schedule = data["schedule_mps"]
    return Memory(
        int(data["trials_done"]),
        schedule if len(schedule) == len(path) else None,
        data["history"],
    )
