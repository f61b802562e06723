"""What the produced thrust does that the config's rotors do not: the one-row-ahead thrust error.

    python -m experiments.thrust_mismatch --config FILE LOGS...

The replay's follower, anchored to the measured state at every row, commands what the real
controller commanded (:mod:`diagnosis.thrust_response`); stepped one row, its rotor thrust is
compared with the logged one. The error e = logged - simulated [N] is then regressed by least
squares on the features a missing thrust term would follow:

- ``1``: a constant offset (thrust telemetry scale, hover thrust),
- ``T - T_hover``: a thrust-curve gain (the change of thrust per change of command differs
  from the rotors' ``T_max n^2``; PX4 calls its shape THR_MDL_FAC),
- ``(T - T_hover)^2``: curvature of that curve,
- ``v_bz``: the air velocity along the body z axis, propeller inflow (momentum theory: the
  thrust of a rotor at a given speed falls as air flows through its disc).

Prints the RMS error, the coefficients and the RMS left by each nested model. Used on the
JSBSim F450 logs (``experiments.jsbsim_diagnosis``) to ask which term the vocabulary lacks.
"""

from __future__ import annotations

import argparse
from collections.abc import Sequence
from pathlib import Path

import numpy as np

from diagnosis.forces import rotation_matrices
from diagnosis.replay import windows
from diagnosis.thrust_response import track_thrust
from flightlog.schema import FlightLog, read_flight_log
from vehicle_sim import load_sim_config

FEATURES = ("1", "T - T_hover", "(T - T_hover)^2", "v_bz")


def row_features(logs: Sequence[FlightLog], wins) -> np.ndarray:
    """(m, 2) logged thrust [N] and body-z velocity [m/s] one row after each row of ``wins``,
    in the order :func:`diagnosis.thrust_response.track_thrust` returns its rows."""
    out = []
    for i, log in enumerate(logs):
        row_window = np.full(log.n_rows, -1)
        for k, w in enumerate(wins):
            if w.log_index == i:
                row_window[w.anchor : w.stop - 1] = k
        rows = np.flatnonzero(row_window >= 0) + 1
        rot = rotation_matrices(log.stack("q_w", "q_x", "q_y", "q_z"))
        vel = log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps")
        v_body = np.einsum("nji,nj->ni", rot[rows], vel[rows])
        out.append(np.column_stack([log["thrust_n"][rows], v_body[:, 2]]))
    return np.vstack(out)


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", required=True, help="config TOML or preset name")
    parser.add_argument("logs", nargs="+", type=Path)
    args = parser.parse_args(argv)
    logs = [read_flight_log(p) for p in args.logs]
    wins = windows(logs)
    tracked = track_thrust(load_sim_config(args.config), logs, wins)
    err = tracked.meas_thrust_n - tracked.sim_thrust_n
    feats = row_features(logs, wins)
    dt = feats[:, 0] - np.median(feats[:, 0])
    columns = np.column_stack([np.ones(len(err)), dt, dt * dt, feats[:, 1]])
    print(f"rows {len(err)}, one-row-ahead thrust error RMS {np.sqrt(np.mean(err**2)):.3f} N")
    for k in range(1, len(FEATURES) + 1):
        coef, *_ = np.linalg.lstsq(columns[:, :k], err, rcond=None)
        left = float(np.sqrt(np.mean((err - columns[:, :k] @ coef) ** 2)))
        shown = ", ".join(f"{n}: {c:.4g}" for n, c in zip(FEATURES, coef, strict=False))
        print(f"  [{shown}] -> RMS left {left:.3f} N")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
