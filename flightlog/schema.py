"""Flight log schema v1: the interchange between flying and learning.

One row per control step, CSV with a header, plus a JSON sidecar ``<log>.json`` holding
metadata (source, vehicle preset, ``mass_kg``, rates, schema version). Units are SI and frames
are local NED / body FRD, as the column names say.

This module is the leaf every other part may import; it has no dependency of its own beyond
NumPy. Ground truth of simulated effects is never written here: a log holds only what a real
vehicle could have measured.
"""

from __future__ import annotations

import csv
import io
import json
import math
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from flightlog.atomic_output import write_text_atomic

SCHEMA_VERSION = 1
GRAVITY_MPS2 = 9.80665
"""Standard gravity [m/s^2], the one g of every part (PX4's CONSTANTS_ONE_G)."""

REQUIRED_COLUMNS: tuple[str, ...] = (
    "t_s",
    "pos_n_m", "pos_e_m", "pos_d_m",
    "vel_n_mps", "vel_e_mps", "vel_d_mps",
    "q_w", "q_x", "q_y", "q_z",
    "cmd_vel_n_mps", "cmd_vel_e_mps", "cmd_vel_d_mps", "cmd_yaw_rate_radps",
)  # fmt: skip

OPTIONAL_NUMERIC_COLUMNS: tuple[str, ...] = (
    "acc_n_mps2", "acc_e_mps2", "acc_d_mps2",
    "rate_x_radps", "rate_y_radps", "rate_z_radps",
    "thrust_n", "thrust_norm", "rotor_speed_rms_radps", "battery_v", "armed", "landed",
    "pred_vel_n_mps", "pred_vel_e_mps", "pred_vel_d_mps",
    "pred_pos_n_m", "pred_pos_e_m", "pred_pos_d_m",
    "ref_pos_n_m", "ref_pos_e_m", "ref_pos_d_m",
    "solve_time_s", "planner_ok", "crash",
)  # fmt: skip

TEXT_COLUMNS: tuple[str, ...] = ("mode",)

SIDECAR_SUFFIX = ".json"
BINARY_SNIFF_BYTES = 4096  # a NUL byte among a file's first bytes: binary, not CSV
FIRST_LINE_SHOWN = 60  # characters of a foreign file's first line quoted in the refusal


class FlightLogError(ValueError):
    """A flight log that cannot be used; the message names the file, row and column."""


@dataclass(frozen=True)
class FlightLog:
    """A validated flight log held in memory.

    Attributes:
        columns: column name -> array of shape (n_rows,); float64 for numeric columns,
            str for text columns (``mode``).
        metadata: the sidecar's content (``schema_version``, ``source``, ``mass_kg``, ...).
        path: where it was read from, if anywhere (used in error messages).
    """

    columns: Mapping[str, np.ndarray]
    metadata: Mapping[str, object] = field(default_factory=dict)
    path: Path | None = None

    @property
    def n_rows(self) -> int:
        return len(self.columns["t_s"])

    def __getitem__(self, name: str) -> np.ndarray:
        try:
            return self.columns[name]
        except KeyError:
            raise KeyError(
                f"{self.where}: no column {name!r}; present: {', '.join(self.columns)}"
            ) from None

    def has(self, *names: str) -> bool:
        """True if every named column is present."""
        return all(n in self.columns for n in names)

    def stack(self, *names: str) -> np.ndarray:
        """Columns side by side, shape (n_rows, len(names))."""
        return np.column_stack([self[n] for n in names])

    def slice(self, start: int, stop: int) -> FlightLog:
        """Rows [start, stop) as a new log with the same metadata."""
        cols = {k: v[start:stop] for k, v in self.columns.items()}
        return FlightLog(cols, self.metadata, self.path)

    @property
    def where(self) -> str:
        """The log's file for messages, or ``<in-memory log>``."""
        return str(self.path) if self.path is not None else "<in-memory log>"


class FlightLogRecorder:
    """Collects one row per control step and builds a validated :class:`FlightLog`.

    Every row must carry the same keys as the first one; all required columns must be there.
    """

    def __init__(self, metadata: Mapping[str, object] | None = None) -> None:
        self._rows: list[dict[str, float | str]] = []
        self._keys: tuple[str, ...] | None = None
        self.metadata: dict[str, object] = dict(metadata or {})

    def __len__(self) -> int:
        return len(self._rows)

    def append(self, row: Mapping[str, float | str]) -> None:
        keys = tuple(row)
        if self._keys is None:
            missing = [c for c in REQUIRED_COLUMNS if c not in row]
            if missing:
                raise FlightLogError(f"flight log row is missing required columns {missing}")
            unknown = [k for k in keys if k not in _KNOWN_COLUMNS]
            if unknown:
                raise FlightLogError(
                    f"flight log row has unknown columns {unknown}; schema v1 knows "
                    f"{', '.join(_KNOWN_COLUMNS)}"
                )
            self._keys = keys
        elif set(keys) != set(self._keys):
            raise FlightLogError(
                f"flight log row {len(self._rows)} has columns {sorted(keys)}, "
                f"expected {sorted(self._keys)} as in the first row"
            )
        self._rows.append(dict(row))

    def to_log(self) -> FlightLog:
        if not self._rows:
            raise FlightLogError("flight log is empty: record at least one row before saving")
        assert self._keys is not None
        cols: dict[str, np.ndarray] = {}
        for k in self._keys:
            values = [r[k] for r in self._rows]
            cols[k] = np.asarray(values, dtype=str if k in TEXT_COLUMNS else np.float64)
        log = FlightLog(cols, {"schema_version": SCHEMA_VERSION, **self.metadata})
        validate_flight_log(log)
        return log


_KNOWN_COLUMNS = REQUIRED_COLUMNS + OPTIONAL_NUMERIC_COLUMNS + TEXT_COLUMNS


def sidecar_path(log_path: str | Path) -> Path:
    """The metadata sidecar of a log: ``flight.csv`` -> ``flight.csv.json``."""
    p = Path(log_path)
    return p.with_name(p.name + SIDECAR_SUFFIX)


def write_flight_log(path: str | Path, log: FlightLog) -> Path:
    """Write ``log`` as CSV at ``path`` and its metadata beside it, each atomically (the
    sidecar first); returns the CSV path. OutputError (one line) when it cannot be written."""
    path = Path(path)
    validate_flight_log(log)
    names = list(log.columns)
    out = io.StringIO(newline="")
    writer = csv.writer(out)
    writer.writerow(names)
    arrays = [log.columns[n] for n in names]
    for i in range(log.n_rows):
        writer.writerow([format_cell(a[i]) for a in arrays])
    write_sidecar(path, log.metadata)
    write_text_atomic(path, out.getvalue())
    return path


def write_sidecar(log_path: str | Path, metadata: Mapping[str, object]) -> Path:
    """Write a log's metadata sidecar atomically (with the schema version)."""
    meta = {"schema_version": SCHEMA_VERSION, **dict(metadata)}
    return write_text_atomic(
        sidecar_path(log_path), json.dumps(meta, indent=2, sort_keys=True) + "\n"
    )


def _not_text(path: Path, why: str) -> str:
    """The one-line refusal of a binary file given as a flight log."""
    return (
        f"{path}: a binary file, not a schema-v1 CSV ({why}); the commands read schema-v1 CSV "
        "and PX4 ULog (.ulg, from the vehicle's SD card), not MAVLink telemetry logs (.tlog) "
        "or ArduPilot logs (.bin)"
    )


def read_flight_log(path: str | Path, max_gap_s: float | None = None) -> FlightLog:
    """Read and validate a schema-v1 CSV log (and its sidecar, if present).

    Args:
        path: the CSV file.
        max_gap_s: if given, a time step larger than this is an error (use
            :func:`split_at_gaps` instead to keep the data).

    Raises:
        FlightLogError: one line naming the file, row (1-based data row) and column.
    """
    path = Path(path)
    if path.is_dir():
        raise FlightLogError(
            f"{path}: a folder, not a flight log; pass the log files in it (schema-v1 CSV or "
            "PX4 .ulg), e.g. DIR/*.csv"
        )
    if not path.is_file():
        raise FlightLogError(
            f"{path}: no such flight log; pass the path of a schema-v1 CSV file or a PX4 .ulg"
        )
    with path.open("rb") as fh:
        if b"\0" in fh.read(BINARY_SNIFF_BYTES):
            raise FlightLogError(_not_text(path, "it holds NUL bytes"))
    try:  # utf-8-sig: a spreadsheet's "CSV UTF-8" starts with a byte-order mark
        with path.open(newline="", encoding="utf-8-sig") as fh:
            reader = csv.reader(fh)
            header = next(reader, None)
            if not header:
                raise FlightLogError(
                    f"{path}: empty file, expected a CSV header with {REQUIRED_COLUMNS[0]}, ..."
                )
            header = [h.strip() for h in header]
            rows = list(reader)
    except UnicodeDecodeError as exc:
        raise FlightLogError(_not_text(path, exc.reason)) from None
    missing = [c for c in REQUIRED_COLUMNS if c not in header]
    if len(missing) == len(REQUIRED_COLUMNS):
        first = ",".join(header)
        first = first if len(first) <= FIRST_LINE_SHOWN else f"{first[:FIRST_LINE_SHOWN]}..."
        raise FlightLogError(
            f"{path}: not a schema-v1 flight log: its first line ({first!r}) names none of the "
            f"columns schema v1 needs ({', '.join(REQUIRED_COLUMNS)})"
        )
    if missing:
        raise FlightLogError(
            f"{path}: missing required column(s) {', '.join(missing)}; schema v1 needs "
            f"{', '.join(REQUIRED_COLUMNS)}"
        )
    if not rows:
        raise FlightLogError(
            f"{path}: header but no data rows (the recording stopped before its first row); "
            "give a log of a flight"
        )
    cols: dict[str, np.ndarray] = {}
    for j, name in enumerate(header):
        is_text = name in TEXT_COLUMNS
        values: list[object] = []
        for i, row in enumerate(rows):
            if len(row) != len(header):
                fix = (
                    "the file is cut short (copied while it was written?): delete its last "
                    "line to read the rows before it"
                    if i == len(rows) - 1
                    else "the file is corrupt"
                )
                raise FlightLogError(
                    f"{path}: row {i + 1} has {len(row)} fields, header has {len(header)}; {fix}"
                )
            cell = row[j].strip()
            if is_text:
                values.append(cell)
                continue
            try:
                values.append(float(cell))
            except ValueError:
                raise FlightLogError(
                    f"{path}: row {i + 1}, column {name}: {cell!r} is not a number"
                ) from None
        cols[name] = np.asarray(values, dtype=str if is_text else np.float64)
    meta: dict[str, object] = {}
    side = sidecar_path(path)
    if side.is_file():
        try:
            meta = json.loads(side.read_text())
        except json.JSONDecodeError as exc:
            raise FlightLogError(
                f"{side}: sidecar is not valid JSON ({exc.msg} at line {exc.lineno})"
            ) from None
        if not isinstance(meta, dict):
            raise FlightLogError(
                f"{side}: sidecar holds a JSON {type(meta).__name__}, not an object of metadata "
                f'({{"schema_version": {SCHEMA_VERSION}, ...}}); fix it or delete it'
            )
        version = meta.get("schema_version", SCHEMA_VERSION)
        if version != SCHEMA_VERSION:
            raise FlightLogError(
                f"{side}: schema_version {version!r}, this reader understands {SCHEMA_VERSION}"
            )
    log = FlightLog(cols, meta, path)
    validate_flight_log(log, max_gap_s=max_gap_s)
    return log


def validate_flight_log(log: FlightLog, max_gap_s: float | None = None) -> None:
    """Check required columns, finiteness and strictly increasing time.

    Raises:
        FlightLogError: naming the file, the first bad row (1-based) and the column.
    """
    where = log.where
    missing = [c for c in REQUIRED_COLUMNS if c not in log.columns]
    if missing:
        raise FlightLogError(f"{where}: missing required column(s) {', '.join(missing)}")
    n = log.n_rows
    for name, values in log.columns.items():
        if len(values) != n:
            raise FlightLogError(f"{where}: column {name} has {len(values)} rows, t_s has {n}")
        if name in TEXT_COLUMNS:
            continue
        bad = np.flatnonzero(~np.isfinite(values))
        if bad.size:
            i = int(bad[0])
            raise FlightLogError(
                f"{where}: row {i + 1}, column {name}: {values[i]} is not finite; "
                "drop or repair the row (NaN/inf are not allowed in schema v1)"
            )
    dt = np.diff(log.columns["t_s"])
    back = np.flatnonzero(dt <= 0.0)
    if back.size:
        i = int(back[0]) + 1
        raise FlightLogError(
            f"{where}: row {i + 1}, column t_s: time {log.columns['t_s'][i]} does not increase "
            f"(previous {log.columns['t_s'][i - 1]}); sort the rows or split the log"
        )
    if max_gap_s is not None:
        gaps = np.flatnonzero(dt > max_gap_s)
        if gaps.size:
            i = int(gaps[0]) + 1
            raise FlightLogError(
                f"{where}: row {i + 1}, column t_s: gap of {dt[i - 1]:.3f} s exceeds "
                f"{max_gap_s} s; split the log at gaps (split_at_gaps)"
            )


def split_at_gaps(log: FlightLog, max_gap_s: float) -> list[FlightLog]:
    """Split a log into segments with no time step larger than ``max_gap_s``."""
    dt = np.diff(log.columns["t_s"])
    cuts = [0, *(np.flatnonzero(dt > max_gap_s) + 1).tolist(), log.n_rows]
    return [log.slice(a, b) for a, b in zip(cuts[:-1], cuts[1:], strict=True) if b > a]


def format_cell(value: object) -> str:
    """A value as the CSV cell schema v1 writes (integers without a decimal point, floats in
    full precision, text as is)."""
    if isinstance(value, (str, np.str_)):
        return str(value)
    v = float(value)
    if math.isfinite(v) and v == int(v) and abs(v) < 1e15:
        return str(int(v))
    return repr(v)
