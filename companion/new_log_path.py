"""Where a flight's log goes when no ``--log`` is given: a new file, never an earlier flight's.

As PX4's logger names its SD-card logs by the UTC time the log started
(``log/2024-05-01/12_30_05.ulg``, [PX4-logger]) and never writes over one, the companion's
default log is ``out/flights/flight_YYYY-MM-DD_HH-MM-SS.csv`` (UTC); a second flight in the same
second gets ``_2``, ``_3`` ... The name is claimed by creating the file exclusively, so two
companions started at once cannot pick the same one.
"""

from __future__ import annotations

import os
from datetime import UTC, datetime
from pathlib import Path

from flightlog.atomic_output import OutputError, describe_os_error
from flightlog.schema import sidecar_path

DEFAULT_LOG_DIR = Path("out/flights")
MAX_SAME_SECOND = 1000  # flights started in one second before giving up


def claim_new_log_path(folder: Path = DEFAULT_LOG_DIR, now: datetime | None = None) -> Path:
    """Create and return an empty, new log file in ``folder`` named by ``now`` (UTC; default
    the current time); neither it nor its sidecar existed before.

    Raises:
        OutputError: the folder cannot be made or written (one line naming it and the fix).
    """
    stamp = (now or datetime.now(UTC)).astimezone(UTC).strftime("%Y-%m-%d_%H-%M-%S")
    try:
        folder.mkdir(parents=True, exist_ok=True)
        for n in range(1, MAX_SAME_SECOND + 1):
            path = folder / (f"flight_{stamp}.csv" if n == 1 else f"flight_{stamp}_{n}.csv")
            if sidecar_path(path).exists():
                continue
            try:
                os.close(os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
            except FileExistsError:
                continue
            return path
    except OSError as exc:
        raise OutputError(describe_os_error(folder, exc)) from None
    raise OutputError(
        f"{folder}: {MAX_SAME_SECOND} flight logs already named {stamp}; give --log PATH"
    )
