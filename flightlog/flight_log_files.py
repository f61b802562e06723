"""Where a flight's log goes, never over an earlier flight's log.

As PX4's logger writes each SD-card log to a new file named by the UTC time logging started
([PX4-logger]), the companion's default log is ``out/flights/flight_YYYY-MM-DD_HH-MM-SS.csv``
(UTC); a second flight in the same second gets ``_2``, ``_3`` ... An explicit ``--log PATH``
is written there, as every command's output option is, but a log already there is not lost:
it is kept as ``PATH-stem.1.csv`` (``.2``, ... the first free number), with its sidecar, and put
back when the flight records no row (refused before take-off). Names are claimed by creating
the file exclusively, so two companions started at once cannot pick the same one.
``vehicle-sim --log`` keeps an earlier onboard log the same way. A CSV log is never written
under a ``.ulg`` name, which every reader would take for a damaged PX4 ULog, nor under a
``.json`` one, a sidecar's.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from datetime import UTC, datetime
from pathlib import Path

from flightlog.atomic_output import OutputError, describe_os_error
from flightlog.schema import sidecar_path

DEFAULT_LOG_DIR = Path("out/flights")
MAX_NAMES = 1000  # numbered names tried before giving up


def check_csv_log_name(path: Path) -> None:
    """Raise OutputError when a schema-v1 CSV log would be written under a ``.ulg`` name (every
    reader would take it for a damaged PX4 ULog and refuse it) or a ``.json`` one (a sidecar's
    name: the log ``F.csv.json`` would move ``F.csv``'s sidecar aside as an earlier log)."""
    suffix = Path(path).suffix.lower()
    if suffix == ".ulg":
        raise OutputError(
            f"{path}: a .ulg name for a schema-v1 CSV log, which every command would then "
            "refuse as a damaged ULog; name it .csv"
        )
    if suffix == ".json":
        raise OutputError(
            f"{path}: a .json name for a schema-v1 CSV log, the name of a log's sidecar "
            "(LOG.csv.json); name it .csv"
        )


def claim_new_log_path(folder: Path = DEFAULT_LOG_DIR, now: datetime | None = None) -> Path:
    """Create and return an empty, new log file in ``folder`` named by ``now`` (UTC; default
    the current time); neither it nor its sidecar existed before.

    Raises:
        OutputError: the folder cannot be made or written (one line naming it and the fix).
    """
    stamp = (now or datetime.now(UTC)).astimezone(UTC).strftime("%Y-%m-%d_%H-%M-%S")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise OutputError(describe_os_error(folder, exc)) from None
    names = (f"flight_{stamp}.csv" if n == 1 else f"flight_{stamp}_{n}.csv" for n in _counts())
    return _claim(folder / name for name in names)


def keep_earlier_log(path: Path) -> Path | None:
    """Move the log at ``path`` (and its sidecar) to ``stem.N.csv`` with the first free N;
    its new path, or None when no file is at ``path``.

    Raises:
        OutputError: it cannot be moved (one line naming the path and the fix).
    """
    if not path.is_file():
        return None
    kept = _claim(path.with_name(f"{path.stem}.{n}{path.suffix}") for n in _counts())
    try:
        os.replace(path, kept)
    except OSError as exc:
        kept.unlink(missing_ok=True)
        raise OutputError(describe_os_error(path, exc)) from None
    try:
        if sidecar_path(path).is_file():
            os.replace(sidecar_path(path), sidecar_path(kept))
    except OSError as exc:
        os.replace(kept, path)  # the log goes back beside its sidecar, as it was
        raise OutputError(describe_os_error(sidecar_path(path), exc)) from None
    return kept


def restore_earlier_log(kept: Path, path: Path) -> None:
    """Put the log :func:`keep_earlier_log` moved to ``kept`` back at ``path``, with its sidecar;
    a sidecar the refused session left at ``path`` goes when the earlier log had none."""
    os.replace(kept, path)
    if sidecar_path(kept).is_file():
        os.replace(sidecar_path(kept), sidecar_path(path))
    else:
        sidecar_path(path).unlink(missing_ok=True)


def _counts() -> range:
    return range(1, MAX_NAMES + 1)


def _claim(candidates: Iterable[Path]) -> Path:
    """Create the first candidate path that neither exists nor has a sidecar; return it."""
    last = Path()
    for path in candidates:
        last = path
        if sidecar_path(path).exists():
            continue
        try:
            os.close(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
        except FileExistsError:
            continue
        except OSError as exc:
            raise OutputError(describe_os_error(path, exc)) from None
        return path
    raise OutputError(
        f"{last}: {MAX_NAMES} names like it are taken; move earlier logs away or choose "
        "another --log PATH"
    )
