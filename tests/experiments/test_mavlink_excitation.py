"""An excitation schedule flown over MAVLink against a real `vehicle-sim` endpoint: the vehicle's
onboard log holds the OFFBOARD flight with the commands as sent, and the acceleration and
thrust MAVLink does not carry."""

from __future__ import annotations

import math

import numpy as np
import pytest

from companion.pymavlink_link import PymavlinkLink
from diagnosis.excitation import schedule_from_mapping
from experiments.mavlink_excitation import fly_schedule_over_link
from experiments.sim_endpoint import SimEndpoint
from flightlog.schema import read_flight_log


@pytest.mark.slow
def test_schedule_flown_over_mavlink_lands_in_the_onboard_log(tmp_path):
    rng = np.random.default_rng(5)
    speed, heading = float(rng.uniform(1.0, 3.0)), float(rng.uniform(0.0, 360.0))
    schedule = schedule_from_mapping(
        {
            "name": "short",
            "takeoff_alt_m": 2.0,
            "segment": [
                {"kind": "hover", "duration_s": 1.0},
                {"kind": "velocity", "duration_s": 3.0, "speed_mps": speed, "heading_deg": heading},
                {"kind": "hover", "duration_s": 1.0},
            ],
        }
    )
    onboard = tmp_path / "onboard.csv"
    with SimEndpoint("iris", 5, tmp_path / "vehicle_sim.log", onboard) as sim:
        link = PymavlinkLink(sim.mavsdk_url)
        try:
            link.connect(120.0)
            fly_schedule_over_link(link, schedule)
        finally:
            link.close()
    log = read_flight_log(onboard)
    offboard = log["mode"] == "OFFBOARD"
    t = log["t_s"][offboard]
    assert t[-1] - t[0] == pytest.approx(schedule.duration_s, abs=0.5)
    assert np.median(np.diff(t)) == pytest.approx(0.02, abs=0.003)  # 50 Hz of simulated time
    cmd = log.stack("cmd_vel_n_mps", "cmd_vel_e_mps")[offboard]
    want = speed * np.array([math.cos(math.radians(heading)), math.sin(math.radians(heading))])
    sent = np.all(np.isclose(cmd, want, atol=1e-3), axis=1)
    held_s = np.diff(t, append=t[-1])  # each row's command holds until the next row
    assert 2.5 < held_s[sent].sum() < 3.5  # the velocity segment's commands, as sent
    vel = log.stack("vel_n_mps", "vel_e_mps")[offboard]
    assert np.max(vel @ want / speed) > 0.8 * speed  # and flown
    assert np.all(np.isfinite(log["thrust_n"][offboard]))
    assert np.all(np.isfinite(log["acc_d_mps2"][offboard]))
