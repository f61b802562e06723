"""fit-gp's px4_velocity_pi takes the logs' gains as one tuning when they are the same gains
as the different-vehicles check takes them: a float32 read over MAVLink (1.7999999523) is the
1.8 of a log flown in process."""

from __future__ import annotations

import numpy as np
import pytest

from flightlog.schema import FlightLog
from flightlog.velocity_loop_gains import VELOCITY_LOOP_PARAMS
from gp.errors import DatasetError
from gp.velocity_integrator import logged_velocity_loop_gains

GAINS = {"vel_p_xy": 1.8, "vel_i_xy": 0.4, "vel_d_xy": 0.2, "vel_p_z": 4.0, "vel_i_z": 2.0,
         "vel_d_z": 0.0}  # fmt: skip


def _log(gains: dict[str, float], where: str) -> FlightLog:
    return FlightLog({"t_s": np.zeros(1)}, {"velocity_loop_gains": gains}, where)


def test_gains_read_as_float32_are_the_same_tuning_and_other_gains_are_not() -> None:
    as_float32 = {n: float(np.float32(v)) for n, v in GAINS.items()}
    assert as_float32 != GAINS  # 1.8 read over MAVLink is 1.7999999523
    read = logged_velocity_loop_gains([_log(GAINS, "inprocess.csv"), _log(as_float32, "sim.csv")])
    assert read == GAINS
    retuned = {**GAINS, "vel_p_xy": 2.0}
    with pytest.raises(DatasetError, match="differ from the other logs'"):
        logged_velocity_loop_gains([_log(GAINS, "a.csv"), _log(retuned, "b.csv")])
    assert set(GAINS) == set(VELOCITY_LOOP_PARAMS)
