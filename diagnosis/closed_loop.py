"""Closed-loop tracking: the config and the extended config fly the logged setpoint schedule.

Unlike the replay, which re-anchors at the measured state every ``window_s``, here a simulated
vehicle is anchored once, at the start of each airborne segment (state, thrust and the velocity
integral behind it), and then flies the whole segment freely on the logged setpoints under its
own flight control, as the real vehicle did. Its velocity is compared with the measured one (the
measured log stands for the real vehicle) on the held-out rows only.

Honest scoring (issue 18): each airborne run is cut into segments at ``NEAR_GROUND_ALT_M``:
flight segments and ground holds, each anchored at its start. A simulated vehicle that touches
down while the measured one is airborne is re-anchored to the measured state there, and its
segment no longer counts: the gain is computed only over segments both configs flew whole, and
the ground holds are scored apart, so a vehicle sitting on the ground does not decide the
tracking figure.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from diagnosis import sim_anchor
from diagnosis.replay import LogArrays, Window, airborne_runs
from flightlog.schema import FlightLog
from vehicle_sim import LandedState, SimConfig

NEAR_GROUND_ALT_M = 0.5  # measured rows lower than this are ground holds, scored apart
# a simulated vehicle on the ground is re-anchored only where the measured one is clearly
# airborne: a few centimetres decide a touchdown in a ground hold (landing-gear geometry)
REANCHOR_ALT_M = 0.15


@dataclass(frozen=True)
class ClosedLoopResult:
    """Closed-loop tracking of the logged setpoints, scored on held-out rows.

    Attributes:
        t_s: (m,) log time of each held-out row [s].
        meas_vel_ned_mps: (m, 3) measured velocity NED [m/s].
        baseline_vel_ned_mps, extended_vel_ned_mps: (m, 3) velocity NED [m/s] flown by the
            config and by the extended config.
        run: (m,) index of the airborne segment (over all logs) each row belongs to.
        near_ground: (m,) rows of the ground holds (measured altitude < ``NEAR_GROUND_ALT_M``).
        whole: (m,) rows of segments both configs flew without being re-anchored.
        segments: number of airborne segments; reanchored: of them, those either config had to
            be re-anchored in (it touched down where the vehicle flew);
            reanchored_baseline, reanchored_extended: the same per config.
    """

    t_s: np.ndarray
    meas_vel_ned_mps: np.ndarray
    baseline_vel_ned_mps: np.ndarray
    extended_vel_ned_mps: np.ndarray
    run: np.ndarray
    near_ground: np.ndarray
    whole: np.ndarray
    segments: int = 0
    reanchored: int = 0
    reanchored_baseline: int = 0
    reanchored_extended: int = 0

    @property
    def scored(self) -> np.ndarray:
        """(m,) rows the tracking figure uses: whole segments, ground holds left out."""
        return self.whole & ~self.near_ground

    def baseline_rmse_mps(self) -> float:
        """RMS over scored rows of the 3-D velocity error of the config [m/s]."""
        rows = self.scored
        return _rmse(self.baseline_vel_ned_mps[rows] - self.meas_vel_ned_mps[rows])

    def extended_rmse_mps(self) -> float:
        """RMS over scored rows of the 3-D velocity error of the extended config [m/s]."""
        rows = self.scored
        return _rmse(self.extended_vel_ned_mps[rows] - self.meas_vel_ned_mps[rows])

    def gain(self) -> float:
        """Baseline / extended closed-loop velocity RMSE over scored rows (nan without any)."""
        return self.baseline_rmse_mps() / max(self.extended_rmse_mps(), 1e-9)

    def ground_hold_gain(self) -> float:
        """The same over the ground-hold rows of whole segments (nan without any)."""
        rows = self.whole & self.near_ground
        base = _rmse(self.baseline_vel_ned_mps[rows] - self.meas_vel_ned_mps[rows])
        ext = _rmse(self.extended_vel_ned_mps[rows] - self.meas_vel_ned_mps[rows])
        return base / max(ext, 1e-9)


def closed_loop(
    base_config: SimConfig,
    extended_config: SimConfig,
    logs: Sequence[FlightLog],
    held_out: Sequence[Window],
) -> ClosedLoopResult:
    """Fly every airborne segment of ``logs`` on both configs; score the rows of ``held_out``."""
    masks = [
        _held_out_rows(log.n_rows, [w for w in held_out if w.log_index == i])
        for i, log in enumerate(logs)
    ]
    meas, t_s, run, low = [], [], [], []
    for i, log in enumerate(logs):
        for start, stop, near_ground in segments(log):
            rows = np.arange(start + 1, stop)
            rows = rows[masks[i][rows]]
            meas.append(log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps")[rows])
            t_s.append(log["t_s"][rows])
            run.append(np.full(len(rows), len(run)))
            low.append(np.full(len(rows), near_ground))
    baseline, cut_base = _fly(base_config, logs, masks)
    if extended_config == base_config:
        extended, cut_ext = baseline, cut_base
    else:
        extended, cut_ext = _fly(extended_config, logs, masks)
    runs = _cat(run, 1).astype(int)
    cut = cut_base | cut_ext
    return ClosedLoopResult(
        _cat(t_s, 1),
        _cat(meas, 3),
        baseline,
        extended,
        runs,
        _cat(low, 1).astype(bool),
        ~cut[runs] if len(cut) else np.zeros(0, bool),
        len(cut),
        int(cut.sum()),
        int(cut_base.sum()),
        int(cut_ext.sum()),
    )


def _fly(
    config: SimConfig, logs: Sequence[FlightLog], masks: list[np.ndarray]
) -> tuple[np.ndarray, np.ndarray]:
    """(m, 3) velocity flown by ``config`` at the scored rows, in the order of ``closed_loop``,
    and per segment whether it had to be re-anchored (it touched down where the log flew)."""
    template = sim_anchor.hovering_template(config)
    out, cut = [], []
    for log, mask in zip(logs, masks, strict=True):
        a = LogArrays.of(log)
        alt = -log["pos_d_m"]
        for start, stop, _ in segments(log):
            sim = sim_anchor.fresh_copy(template)
            sim.anchor(a.anchor(start, lead=False), integral="reset")
            sim.set_velocity_setpoint(a.setpoint[start])
            if a.thrust[start] > 0.0:
                sim.anchor(a.anchor(start, lead=True), integral="match_thrust")
            vel = np.zeros((stop - start, 3))
            reanchored = False
            for r in range(start, stop - 1):
                if r > start:
                    sim.set_velocity_setpoint(a.setpoint[r])
                sim.advance(a.t[r + 1] - a.t[r])
                vel[r + 1 - start] = sim.vel_ned_mps
                if sim.landed_state is LandedState.ON_GROUND and alt[r + 1] > REANCHOR_ALT_M:
                    lead = bool(a.thrust[r + 1] > 0.0)
                    sim.anchor(a.anchor(r + 1, lead), integral="match_thrust" if lead else "keep")
                    reanchored = True
            out.append(vel[1:][mask[start + 1 : stop]])
            cut.append(reanchored)
    return _cat(out, 3), np.asarray(cut, dtype=bool)


def segments(log: FlightLog) -> list[tuple[int, int, bool]]:
    """[start, stop) rows of the flight segments and ground holds (flag True) of ``log``: its
    airborne runs cut where the measured altitude crosses ``NEAR_GROUND_ALT_M``; pieces of fewer
    than 3 rows join the one before."""
    low = -log["pos_d_m"] < NEAR_GROUND_ALT_M
    out: list[tuple[int, int, bool]] = []
    for start, stop in airborne_runs(log):
        cuts = [
            start,
            *(start + 1 + np.flatnonzero(low[start + 1 : stop] != low[start : stop - 1])),
        ]
        cuts = [int(c) for c in cuts] + [stop]
        for a, b in zip(cuts[:-1], cuts[1:], strict=True):
            if out and out[-1][1] == a and b - a < 3:
                out[-1] = (out[-1][0], b, out[-1][2])
            else:
                out.append((a, b, bool(low[a])))
    return out


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
