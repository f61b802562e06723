"""Schema-v1 flight log rows from control-loop ticks (pure: no file I/O here).

One row per tick: telemetry (as the link saw it), the command sent, and the planner columns
(reference, prediction, solve time, ok). Ticks with non-finite telemetry are not written as
rows (schema v1 forbids NaN); they are counted as events with their reason, like every safe
command. Optional columns (acceleration, thrust, battery, predictions) are kept only when every
row has them, so a log never mixes filled and missing values.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass

import numpy as np

from companion.control_loop import Tick
from flightlog.schema import FlightLog, FlightLogRecorder

_AXES_NED = ("n", "e", "d")
_AXES_FRD = ("x", "y", "z")


@dataclass(frozen=True)
class SafeCommandEvent:
    """A run of consecutive ticks that sent the safe command for the same reason."""

    t_first_s: float
    t_last_s: float
    count: int
    reason: str

    def as_dict(self) -> dict[str, object]:
        return {
            "t_first_s": self.t_first_s,
            "t_last_s": self.t_last_s,
            "count": self.count,
            "reason": self.reason,
        }


class FlightRecorder:
    """Collects ticks; ``to_log`` builds a validated schema-v1 :class:`FlightLog`.

    Args:
        period_s: the loop period [s], used for the nominal one-step prediction.
        wall_clock_columns: log ``solve_time_s`` (a wall-clock measurement). Lockstep
            (in-process) flights leave it out, so that the same seed gives byte-identical logs.
        on_row: called with every row as it is recorded (the live log writes it at once).
    """

    def __init__(
        self,
        period_s: float,
        wall_clock_columns: bool = True,
        on_row: Callable[[Mapping[str, float | str | None]], None] | None = None,
    ) -> None:
        self._period_s = period_s
        self._wall_clock_columns = wall_clock_columns
        self._on_row = on_row
        self._rows: list[dict[str, float | str | None]] = []
        self.events: list[SafeCommandEvent] = []

    def __len__(self) -> int:
        return len(self._rows)

    def record(self, tick: Tick) -> None:
        """Add one tick (a row, and an event when the safe command was sent)."""
        decision = tick.decision
        if not decision.ok:
            self._note_event(tick.t_s, decision.reason)
        if not tick.state.is_finite():
            return
        if self._rows and tick.t_s <= float(self._rows[-1]["t_s"]):
            return
        row = _row(tick)
        if not self._wall_clock_columns:
            del row["solve_time_s"]
        self._rows.append(row)
        if self._on_row is not None:
            self._on_row(row)

    def to_log(self, metadata: Mapping[str, object]) -> FlightLog:
        """The validated log; ``metadata`` goes to the sidecar, with the safe-command events."""
        rec = FlightLogRecorder(
            {**metadata, "safe_command_events": [e.as_dict() for e in self.events]}
        )
        rows = self._rows
        if any(r["pred_vel_n_mps"] is not None for r in rows):
            rows = [self._with_nominal_prediction(r) for r in rows]
        keep = [k for k in rows[0] if all(r[k] is not None for r in rows)] if rows else []
        for row in rows:
            rec.append({k: row[k] for k in keep})
        return rec.to_log()

    def _with_nominal_prediction(
        self, row: dict[str, float | str | None]
    ) -> dict[str, float | str | None]:
        if row["pred_vel_n_mps"] is not None:
            return row
        out = dict(row)
        for a in _AXES_NED:
            cmd = float(row[f"cmd_vel_{a}_mps"])
            out[f"pred_vel_{a}_mps"] = cmd
            out[f"pred_pos_{a}_m"] = float(row[f"pos_{a}_m"]) + cmd * self._period_s
        return out

    def _note_event(self, t_s: float, reason: str) -> None:
        last = self.events[-1] if self.events else None
        if last is not None and last.reason == reason:
            self.events[-1] = SafeCommandEvent(last.t_first_s, t_s, last.count + 1, reason)
        else:
            self.events.append(SafeCommandEvent(t_s, t_s, 1, reason))


def _row(tick: Tick) -> dict[str, float | str | None]:
    s, d = tick.state, tick.decision
    row: dict[str, float | str | None] = {"t_s": float(tick.t_s)}
    row |= _vec("pos", "m", _AXES_NED, s.pos_ned_m)
    row |= _vec("vel", "mps", _AXES_NED, s.vel_ned_mps)
    row |= dict(zip(("q_w", "q_x", "q_y", "q_z"), map(float, s.q_wxyz), strict=True))
    row |= _vec("cmd_vel", "mps", _AXES_NED, d.command.vel_ned_mps)
    row["cmd_yaw_rate_radps"] = float(d.command.yaw_rate_radps)
    row |= _vec("rate", "radps", _AXES_FRD, s.rates_frd_radps)
    row |= _vec("acc", "mps2", _AXES_NED, s.acc_ned_mps2)
    row["thrust_n"] = None if s.thrust_n is None else float(s.thrust_n)
    row["battery_v"] = None if s.battery_v is None else float(s.battery_v)
    row["armed"] = float(s.armed)
    row["mode"] = s.mode
    row |= _vec("ref_pos", "m", _AXES_NED, d.ref_pos_ned_m)
    row |= _vec("pred_pos", "m", _AXES_NED, d.pred_pos_ned_m)
    row |= _vec("pred_vel", "mps", _AXES_NED, d.pred_vel_ned_mps)
    row["solve_time_s"] = float(d.solve_time_s)
    row["planner_ok"] = float(d.ok)
    return row


def _vec(
    prefix: str, unit: str, axes: tuple[str, str, str], values: object
) -> dict[str, float | None]:
    if values is None:
        return {f"{prefix}_{a}_{unit}": None for a in axes}
    arr = np.asarray(values, dtype=float)
    if not np.all(np.isfinite(arr)):
        return {f"{prefix}_{a}_{unit}": None for a in axes}
    return {f"{prefix}_{a}_{unit}": float(v) for a, v in zip(axes, arr, strict=True)}
