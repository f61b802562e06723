"""Realistic, seeded sensor noise on what a flight log holds.

A simulated log is exact; a real one is not. :func:`add_sensor_noise` turns the former into
something like the latter, for tests and the demo alike:

- acceleration (``acc_*``): white noise plus a bias that drifts as a slow random walk (an IMU
  after the estimator's bias correction),
- velocity (``vel_*``) and attitude (quaternion, a small random rotation per row),
- thrust telemetry (``thrust_n`` / ``thrust_norm``): multiplicative white noise,
- timestamps: jitter on the logged times, and the rows thinned to a logging rate.

The levels are drawn by :func:`draw_sensor_noise` inside realistic ranges (issue 18's list:
IMU 0.2-0.4 m/s^2, velocity 0.03-0.08 m/s, attitude 0.3-1 deg, thrust 1-5 %, 25-50 Hz). Pure:
no I/O, the same seed gives the same log.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from flightlog.schema import FlightLog


@dataclass(frozen=True)
class SensorNoise:
    """Noise levels (1-sigma) of a logged flight.

    Attributes:
        acc_mps2: acceleration white noise per axis [m/s^2].
        acc_bias_walk_mps2_per_sqrt_s: random-walk intensity of the acceleration bias
            [m/s^2 / sqrt(s)]; the bias starts at zero.
        vel_mps: velocity white noise per axis [m/s].
        attitude_deg: attitude noise per axis [deg] (small-angle rotation).
        thrust_fraction: thrust telemetry multiplicative noise [fraction].
        time_jitter_s: timestamp jitter [s] (kept monotonic).
        log_rate_hz: logging rate the rows are thinned to [Hz]; 0 keeps every row.
    """

    acc_mps2: float = 0.3
    acc_bias_walk_mps2_per_sqrt_s: float = 0.002
    vel_mps: float = 0.05
    attitude_deg: float = 0.5
    thrust_fraction: float = 0.02
    time_jitter_s: float = 0.001
    log_rate_hz: float = 50.0

    @classmethod
    def none(cls) -> SensorNoise:
        """No noise and every row kept: :func:`add_sensor_noise` gives the log back exact. The
        start for noise on one measurement alone, e.g.
        ``dataclasses.replace(SensorNoise.none(), thrust_fraction=0.05)``."""
        return cls(**{level.name: 0.0 for level in fields(cls)})


def draw_sensor_noise(rng: np.random.Generator, acc_mps2: float | None = None) -> SensorNoise:
    """Noise levels drawn within realistic ranges; ``acc_mps2`` fixes the IMU level."""
    u = rng.uniform
    return SensorNoise(
        acc_mps2=float(u(0.2, 0.4)) if acc_mps2 is None else float(acc_mps2),
        acc_bias_walk_mps2_per_sqrt_s=float(u(0.0005, 0.003)),
        vel_mps=float(u(0.03, 0.08)),
        attitude_deg=float(u(0.3, 1.0)),
        thrust_fraction=float(u(0.01, 0.05)),
        time_jitter_s=float(u(0.0, 0.002)),
        log_rate_hz=float(rng.choice([25.0, 30.0, 40.0, 50.0])),
    )


def add_sensor_noise(log: FlightLog, noise: SensorNoise, seed: int) -> FlightLog:
    """``log`` thinned to ``noise.log_rate_hz`` with noise on every measured column.

    Commands, mode and flags are left exact (they are what was sent, not measured).
    """
    rng = np.random.default_rng(seed)
    log = _thin(log, noise.log_rate_hz)
    cols = {k: np.array(v, copy=True) for k, v in log.columns.items()}
    n = log.n_rows
    t = cols["t_s"]
    dt = np.diff(t, prepend=t[0])
    for axis in "ned":
        name = f"acc_{axis}_mps2"
        if name in cols:
            walk = rng.normal(0.0, noise.acc_bias_walk_mps2_per_sqrt_s, n) * np.sqrt(dt)
            cols[name] = cols[name] + np.cumsum(walk) + rng.normal(0.0, noise.acc_mps2, n)
        cols[f"vel_{axis}_mps"] = cols[f"vel_{axis}_mps"] + rng.normal(0.0, noise.vel_mps, n)
    q = np.column_stack([cols[k] for k in ("q_w", "q_x", "q_y", "q_z")])
    half = 0.5 * np.radians(noise.attitude_deg) * rng.normal(size=(n, 3))
    dq = np.column_stack([np.ones(n), half])
    dq /= np.linalg.norm(dq, axis=1, keepdims=True)
    q = _quat_mul(q, dq)
    for i, k in enumerate(("q_w", "q_x", "q_y", "q_z")):
        cols[k] = q[:, i]
    for name in ("thrust_n", "thrust_norm"):
        if name in cols:
            cols[name] = cols[name] * (1.0 + rng.normal(0.0, noise.thrust_fraction, n))
    if noise.time_jitter_s > 0.0 and n > 1:
        jitter = rng.uniform(-noise.time_jitter_s, noise.time_jitter_s, n)
        half_gap = 0.45 * np.min(np.diff(t))
        cols["t_s"] = t + np.clip(jitter, -half_gap, half_gap)
    meta = dict(log.metadata)
    meta["sensor_noise"] = "simulated"
    return FlightLog(cols, meta, log.path)


def _thin(log: FlightLog, rate_hz: float) -> FlightLog:
    if rate_hz <= 0.0 or log.n_rows < 2:
        return log
    t = log["t_s"]
    slot = np.floor((t - t[0]) * rate_hz + 1e-9).astype(int)
    keep = np.flatnonzero(np.diff(slot, prepend=-1) > 0)
    return FlightLog({k: np.asarray(v)[keep] for k, v in log.columns.items()}, log.metadata)


def _quat_mul(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """(n, 4) Hamilton products a * b, [w, x, y, z]."""
    aw, ax, ay, az = a.T
    bw, bx, by, bz = b.T
    return np.column_stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ]
    )
