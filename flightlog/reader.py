"""One reader for every command: schema-v1 CSV or PX4 ULog, chosen by the file's content.

A file that starts with the ULog magic bytes is read as a ULog whatever its name; a ``.ulg``
without them is refused (it is not a ULog); anything else is read as schema-v1 CSV.
"""

from __future__ import annotations

import hashlib
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from flightlog.schema import FlightLog, FlightLogError, read_flight_log
from flightlog.ulog import is_ulog, read_ulog

# What each command needs of a log [Hz]: the velocity command and the time base (positions /
# velocities) at least this fast, so one control step is resolved.
NEEDS_HZ: dict[str, dict[str, float]] = {
    "fit-gp": {"velocity_command": 5.0, "local_position": 10.0},
    "diagnose": {"velocity_command": 5.0, "local_position": 10.0},
}
# PX4's logger writes a topic at most once per its interval (100 ms for vehicle_local_position
# in the default profile), so a 10 Hz topic comes out a little slower on average: 9.78-9.84 Hz
# in v1.8 and older logs, 10.0 Hz in v1.15. A rate within this fraction of a need meets it.
LOGGER_JITTER_FRACTION = 0.05


def read_log(path: str | Path) -> FlightLog:
    """Read a flight log (CSV schema v1 or PX4 ULog, by content). Raises FlightLogError."""
    path = Path(path)
    if is_ulog(path):
        return read_ulog(path)
    if path.suffix.lower() == ".ulg" and path.is_file():
        with path.open("rb") as f:
            first = f.readline(4096)
        if not first:
            raise FlightLogError(
                f"{path}: empty file (0 bytes); copy the log again from the vehicle"
            )
        header = first.decode("utf-8", "replace").removeprefix("\ufeff").split(",")
        if "t_s" in (name.strip() for name in header):  # the CSV reader's own header rules
            raise FlightLogError(
                f"{path}: named .ulg but a schema-v1 CSV (its header has t_s); rename it .csv"
            )
        raise FlightLogError(
            f"{path}: named .ulg but does not start with the ULog magic bytes; "
            "copy the log again from the vehicle (or pass a schema-v1 CSV)"
        )
    return read_flight_log(path)


def require_distinct(paths: Sequence[Path]) -> None:
    """Raise FlightLogError when one flight is given twice (the same file, or a copy of it):
    counted twice, its held-out rows would also be training rows, and a check on them would
    test the model on what it learned. Compared by content (sha256); unreadable paths are left
    to the reader."""
    seen: dict[str, Path] = {}
    for path in paths:
        try:
            digest = hashlib.sha256(Path(path).read_bytes()).hexdigest()
        except OSError:
            continue
        if digest in seen:
            raise FlightLogError(
                f"{path}: the same flight as {seen[digest]} (given twice); pass each log once, "
                "or held-out rows would also be training rows"
            )
        seen[digest] = path


def log_rates_hz(log: FlightLog) -> dict[str, float]:
    """Rates per signal [Hz]: a ULog's recorded rates, else the CSV's time base for all."""
    rates = log.metadata.get("rates_hz")
    if isinstance(rates, Mapping):
        return {str(k): float(v) for k, v in rates.items()}
    dt = np.diff(log["t_s"])
    base = round(1.0 / float(np.median(dt)), 2) if dt.size else 0.0
    return {"local_position": base, "velocity_command": base}


def rate_shortfalls(log: FlightLog, command: str) -> list[str]:
    """Signals slower than ``command`` needs, as 'name at X Hz (needs >= Y Hz)'."""
    rates = log_rates_hz(log)
    return [
        f"{name} at {rates.get(name, 0.0):g} Hz (needs >= {need:g} Hz)"
        for name, need in NEEDS_HZ[command].items()
        if rates.get(name, 0.0) < need * (1.0 - LOGGER_JITTER_FRACTION)
    ]


def require_rates(log: FlightLog, command: str) -> None:
    """Raise FlightLogError naming the signals too slow for ``command`` and the rate needed."""
    short = rate_shortfalls(log, command)
    if short:
        raise FlightLogError(
            f"{log.where}: {command} needs faster signals: {'; '.join(short)}; log "
            "vehicle_local_position and vehicle_local_position_setpoint faster (SDLOG_PROFILE "
            "default or high rate) or record the companion's own log"
        )


def require_modes(logs: Sequence[FlightLog], modes: Sequence[str] | None) -> None:
    """--mode filters need a ``mode`` column and at least one row in a named mode."""
    if not modes:
        return
    for log in logs:
        if not log.has("mode"):
            raise FlightLogError(
                f"{log.where}: --mode {','.join(modes)} given but the log has no mode "
                "column; drop --mode or use a log that records modes (a PX4 ULog has them)"
            )
    flown = sorted({str(m) for log in logs for m in np.unique(log["mode"])})
    if not any(m in flown for m in modes):
        raise FlightLogError(
            f"no rows in mode {', '.join(modes)}; the logs hold {', '.join(flown)}"
        )
