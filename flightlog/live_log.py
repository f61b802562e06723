"""A flight log as it is flown, so that no fault loses a row.

Before take-off the sidecar is written (marked ``"complete": false``) and the CSV opened with
the columns every row has (by default schema v1's required ones plus ``armed`` and ``mode``,
the companion's; the simulator's onboard log streams all of its own). What is learnt later
(the autopilot's velocity-loop gains, read before arming) is added to the sidecar at once.
Each row is appended and flushed, so a SIGKILL, a lost link or a crash leaves a readable
schema-v1 log of every row up to that moment, with that metadata. At the end the full log
(with every optional column: acceleration, thrust, planner columns) replaces it atomically.
"""

from __future__ import annotations

import csv
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import TextIO

from flightlog.atomic_output import OutputError, check_writable_file, describe_os_error
from flightlog.schema import (
    REQUIRED_COLUMNS,
    FlightLog,
    format_cell,
    write_flight_log,
    write_sidecar,
)

STREAMED_COLUMNS: tuple[str, ...] = (*REQUIRED_COLUMNS, "armed", "mode")


class LiveFlightLog:
    """A schema-v1 log written row by row (see the module docstring).

    Attributes:
        metadata: the sidecar's entries so far (without ``"complete"``).
        columns: the streamed columns, in file order (every row must hold them).

    Raises:
        OutputError: the log cannot be written there (one line), at construction: before
            anything flies.
    """

    def __init__(
        self,
        path: str | Path,
        metadata: Mapping[str, object],
        columns: Sequence[str] = STREAMED_COLUMNS,
    ) -> None:
        self.path = check_writable_file(path)
        self.columns = tuple(columns)
        self.metadata: dict[str, object] = dict(metadata)
        write_sidecar(self.path, {**self.metadata, "complete": False})
        try:
            self._fh: TextIO | None = self.path.open("w", newline="")
        except OSError as exc:
            raise OutputError(describe_os_error(self.path, exc)) from None
        self._writer = csv.writer(self._fh)
        self._writer.writerow(self.columns)
        self._fh.flush()
        self.rows = 0

    def add_metadata(self, metadata: Mapping[str, object]) -> None:
        """Add ``metadata`` to :attr:`metadata` and rewrite the sidecar with it at once (still
        marked incomplete)."""
        self.metadata |= metadata
        write_sidecar(self.path, {**self.metadata, "complete": False})

    def append(self, row: Mapping[str, float | str | None]) -> None:
        """Write one row's streamed columns and flush it to the file."""
        if self._fh is None:
            return
        self._writer.writerow([format_cell(row[c]) for c in self.columns])
        self._fh.flush()
        self.rows += 1

    def finish(self, log: FlightLog) -> Path:
        """Replace the streamed rows by the full log (atomically, sidecar first)."""
        self.close()
        return write_flight_log(self.path, log)

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None
