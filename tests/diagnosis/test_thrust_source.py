"""Where the diagnosis takes its thrust from: logged, ESC rotor speed checked against the
weight in hover, or the normalised thrust."""

from __future__ import annotations

import numpy as np
import pytest

from diagnosis.excitation import schedule_from_mapping
from diagnosis.fly_schedule import fly_schedule
from diagnosis.forces import with_thrust_n
from flightlog.schema import FlightLog
from vehicle_sim import load_sim_config

HOVER = schedule_from_mapping(
    {
        "segment": [
            {"kind": "hover", "duration_s": 4.0},
            {"kind": "velocity", "duration_s": 2.0, "speed_mps": 2.0, "heading_deg": 0.0},
        ]
    }
)


@pytest.fixture(scope="module")
def esc_log():
    """A flight as a PX4 log with ESC telemetry would give it: rotor speed, no thrust_n."""
    config = load_sim_config("iris")
    flight = fly_schedule(config, HOVER)
    v = config.vehicle
    n = len(v.rotor_spin)
    rms = np.sqrt(flight["thrust_n"] / (n * v.thrust_coeff_n_per_radps2))
    cols = {k: c for k, c in flight.columns.items() if k != "thrust_n"}
    cols["rotor_speed_rms_radps"] = rms
    cols["thrust_norm"] = flight["thrust_n"] / (n * v.max_rotor_thrust_n) * 1.1  # 10 % off
    return FlightLog(cols, {}), flight["thrust_n"], config


def test_esc_rotor_speed_with_the_right_coefficient_gives_the_thrust(esc_log):
    log, truth, config = esc_log
    v = config.vehicle
    n = len(v.rotor_spin)
    out, source = with_thrust_n(
        log, n * v.max_rotor_thrust_n, v.thrust_coeff_n_per_radps2, n, config.mass_kg
    )
    assert source.startswith("ESC rotor speed")
    np.testing.assert_allclose(out["thrust_n"], truth, rtol=1e-9)


def test_esc_rotor_speed_refused_when_its_hover_thrust_is_not_the_weight(esc_log):
    log, truth, config = esc_log
    v = config.vehicle
    n = len(v.rotor_spin)
    wrong_coeff = 2.0 * v.thrust_coeff_n_per_radps2  # e.g. a wrong pole count in the ESC
    out, source = with_thrust_n(log, n * v.max_rotor_thrust_n, wrong_coeff, n, config.mass_kg)
    assert source.startswith("normalised thrust") and "2.00 x the weight" in source
    np.testing.assert_allclose(out["thrust_n"], 1.1 * truth, rtol=1e-9)
