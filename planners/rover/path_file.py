"""A taught path as a file: CSV rows ``x_m,y_m`` under that header, read with one-line errors.

The frame is the path frame of planners.rover.path: x metres north and y metres west of the
vehicle's local (NED) origin. The rows are the path's vertices, ``spacing_m`` apart (the teach
pass resampled by arc length); :meth:`TaughtPath.from_csv_text` reads the text back.
"""

from __future__ import annotations

from pathlib import Path

from planners.rover.path import TaughtPath

HEADER = "x_m,y_m"


class PathFileError(ValueError):
    """A path file that cannot be used; the message is one line naming what and how to fix."""


def path_csv_text(path: TaughtPath) -> str:
    """The CSV text of ``path``: the header, then one ``x_m,y_m`` row per vertex (to 0.1 mm)."""
    rows = (f"{x:.4f},{y:.4f}" for x, y in path.xy_m)
    return "\n".join([HEADER, *rows]) + "\n"


def read_path_file(file: Path, spacing_m: float = 0.25) -> TaughtPath:
    """The path in ``file``, resampled to ``spacing_m`` [m].

    Raises:
        PathFileError: missing or unreadable file, a header other than ``x_m,y_m``, a row with
            other columns, fewer than 3 rows, a non-number or non-finite row, or too few
            distinct rows.
    """
    fix = "teach it again with `rover-path teach --out FILE`"
    try:
        text = file.read_text()
    except FileNotFoundError:
        raise PathFileError(f"{file}: no such path file; {fix}") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise PathFileError(f"{file}: cannot read it as a CSV text file ({exc}); {fix}") from None
    lines = [(n, line.strip()) for n, line in enumerate(text.splitlines(), 1) if line.strip()]
    if not lines:
        raise PathFileError(f"{file}: the file is empty; {fix}")
    if lines[0][1].replace(" ", "") != HEADER:
        raise PathFileError(
            f"{file}: first line is {lines[0][1][:40]!r}, expected the header {HEADER!r} "
            f"(metres north and west of the local origin); {fix}"
        )
    for n, line in lines[1:]:
        if line.count(",") != 1:
            columns = line.count(",") + 1
            raise PathFileError(
                f"{file}: line {n} has {columns} column{'s' if columns > 1 else ''}, expected 2 "
                f"({HEADER}); fix that row or {fix}"
            )
    if len(lines) - 1 < 3:
        rows = len(lines) - 1
        raise PathFileError(
            f"{file}: {rows} row{'' if rows == 1 else 's'} under its header; a path needs at "
            f"least 3; {fix}"
        )
    try:
        return TaughtPath.from_csv_text(text, spacing_m)
    except ValueError as exc:
        raise PathFileError(f"{file}: {exc}; {fix}") from None
