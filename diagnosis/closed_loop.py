"""Closed-loop tracking: the config and the extended config fly the logged setpoint schedule.

Unlike the replay, which re-anchors at the measured state every ``window_s``, here a simulated
vehicle is anchored once, at the start of each airborne run (state, thrust and the velocity
integral behind it), and then flies the whole run freely on the logged setpoints under its own
flight control, as the real vehicle did. Its velocity is compared with the measured one (the
measured log stands for the real vehicle) on the held-out rows only.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from diagnosis import sim_anchor
from diagnosis.replay import LogArrays, Window, airborne_runs
from flightlog.schema import FlightLog
from vehicle_sim import SimConfig


@dataclass(frozen=True)
class ClosedLoopResult:
    """Closed-loop tracking of the logged setpoints, scored on held-out rows.

    Attributes:
        t_s: (m,) log time of each scored row [s].
        meas_vel_ned_mps: (m, 3) measured velocity NED [m/s].
        baseline_vel_ned_mps, extended_vel_ned_mps: (m, 3) velocity NED [m/s] flown by the
            config and by the extended config.
        run: (m,) index of the airborne run (over all logs) each row belongs to.
    """

    t_s: np.ndarray
    meas_vel_ned_mps: np.ndarray
    baseline_vel_ned_mps: np.ndarray
    extended_vel_ned_mps: np.ndarray
    run: np.ndarray

    def baseline_rmse_mps(self) -> float:
        """RMS over rows of the 3-D velocity error of the config [m/s]."""
        return _rmse(self.baseline_vel_ned_mps - self.meas_vel_ned_mps)

    def extended_rmse_mps(self) -> float:
        """RMS over rows of the 3-D velocity error of the extended config [m/s]."""
        return _rmse(self.extended_vel_ned_mps - self.meas_vel_ned_mps)

    def gain(self) -> float:
        """Baseline / extended closed-loop velocity RMSE."""
        return self.baseline_rmse_mps() / max(self.extended_rmse_mps(), 1e-9)


def closed_loop(
    base_config: SimConfig,
    extended_config: SimConfig,
    logs: Sequence[FlightLog],
    held_out: Sequence[Window],
) -> ClosedLoopResult:
    """Fly every airborne run of ``logs`` on both configs; score the rows of ``held_out``."""
    masks = [
        _held_out_rows(log.n_rows, [w for w in held_out if w.log_index == i])
        for i, log in enumerate(logs)
    ]
    meas, t_s, run = [], [], []
    for i, log in enumerate(logs):
        for start, stop in airborne_runs(log):
            rows = np.arange(start + 1, stop)
            rows = rows[masks[i][rows]]
            meas.append(log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps")[rows])
            t_s.append(log["t_s"][rows])
            run.append(np.full(len(rows), len(run)))
    baseline = _fly(base_config, logs, masks)
    extended = baseline if extended_config == base_config else _fly(extended_config, logs, masks)
    return ClosedLoopResult(
        _cat(t_s, 1), _cat(meas, 3), baseline, extended, _cat(run, 1).astype(int)
    )


def _fly(config: SimConfig, logs: Sequence[FlightLog], masks: list[np.ndarray]) -> np.ndarray:
    """(m, 3) velocity flown by ``config`` at the scored rows, in the order of ``closed_loop``."""
    template = sim_anchor.hovering_template(config)
    out = []
    for log, mask in zip(logs, masks, strict=True):
        a = LogArrays(log)
        for start, stop in airborne_runs(log):
            sim = sim_anchor.fresh_copy(template)
            sim.anchor(a.anchor(start, lead=False), integral="reset")
            sim.set_velocity_setpoint(a.setpoint[start])
            if a.thrust[start] > 0.0:
                sim.anchor(a.anchor(start, lead=True), integral="match_thrust")
            vel = np.zeros((stop - start, 3))
            for r in range(start, stop - 1):
                if r > start:
                    sim.set_velocity_setpoint(a.setpoint[r])
                vel[r + 1 - start] = sim.step(a.t[r + 1] - a.t[r]).vel_ned_mps
            out.append(vel[1:][mask[start + 1 : stop]])
    return _cat(out, 3)


def _held_out_rows(n_rows: int, wins: Sequence[Window]) -> np.ndarray:
    """(n_rows,) bool: the rows the replay compares for ``wins``."""
    mask = np.zeros(n_rows, bool)
    for w in wins:
        mask[w.anchor + 1 : w.stop + 1] = True
    return mask


def _cat(parts: list[np.ndarray], width: int) -> np.ndarray:
    if not parts:
        return np.zeros((0, width)) if width > 1 else np.zeros(0)
    return np.concatenate(parts)


def _rmse(err: np.ndarray) -> float:
    if len(err) == 0:
        return float("nan")
    return float(np.sqrt(np.mean(np.sum(err * err, axis=1))))
