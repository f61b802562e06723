"""Paper 004's trial view holds out a different quarter of each trial for the open-loop check:
on a repeated path, the last quarter of every trial is the same stretch, which a fit held out
there never learns."""

from __future__ import annotations

import numpy as np
import pytest

from experiments.study.fitting import fit_residual
from flightlog.schema import FlightLog, FlightLogRecorder
from tests.gp.gp_synthetic_logs import level_flight_row

PERIOD_S = 0.02


def repeated_path_log(seed: int, n_rows: int = 1500, tau_s: float = 0.4) -> FlightLog:
    """One trial of a repeated path: east at 1 m/s, weaving north; a velocity lag ``tau_s``
    [s] and, on the path's last stretch (east of 22 m), a push north of 0.6 m/s^2 that only
    a model trained there can know. ``seed``: the measurement noise (0.005 m/s)."""
    rng = np.random.default_rng(seed)
    rec = FlightLogRecorder({"source": "synthetic-repeated-path"})
    pos, vel = np.array([0.0, 0.0, -5.0]), np.zeros(3)
    decay = np.exp(-PERIOD_S / tau_s)
    for k in range(n_rows):
        t = k * PERIOD_S
        cmd = np.array([0.8 * np.sin(0.6 * t), 1.0, 0.0])
        rec.append(level_flight_row(t, pos, vel, cmd, mode="OFFBOARD"))
        push = np.array([0.6, 0.0, 0.0]) if pos[1] > 22.0 else np.zeros(3)
        new = cmd + (vel - cmd) * decay + PERIOD_S * push
        pos = pos + PERIOD_S * 0.5 * (vel + new)
        vel = new + 0.005 * rng.normal(size=3)
    return rec.to_log()


@pytest.mark.parametrize("rotate", [False, True])
def test_a_refit_on_a_repeated_path_is_judged_where_it_learnt(rotate):
    logs = [repeated_path_log(seed) for seed in range(2)]
    fit = fit_residual(
        logs, "random", PERIOD_S, features="position_velocity", m=15, restarts=1,
        rotate_held_out=rotate,
    )  # fmt: skip
    gain = fit.structure_check.gain  # over the identified lag alone, on the held-out quarters
    if rotate:  # each held-out quarter is a stretch the other trial trains on
        assert gain > 1.5, fit.structure_check.describe()
    else:  # both held out the last stretch: the push there was never learnt
        assert gain < 1.2, fit.structure_check.describe()
