"""What the data cannot support is said, not guessed."""

from __future__ import annotations

import numpy as np
import pytest

from diagnosis.diagnosis import diagnose
from diagnosis.excitation import schedule_from_mapping
from diagnosis.fly_schedule import fly_schedule
from diagnosis.identifiability import check_identifiability
from diagnosis.replay import windows
from experiments.hidden_effects import fly_hidden
from flightlog.schema import FlightLog
from vehicle_sim import load_sim_config

HOVER = schedule_from_mapping({"segment": [{"kind": "hover", "duration_s": 30.0}]})
HOVER_AND_MOVE = schedule_from_mapping(
    {
        "segment": [
            {"kind": "hover", "duration_s": 8.0},
            {"kind": "velocity", "duration_s": 4.0, "speed_mps": 3.0, "heading_deg": 60.0},
            {"kind": "velocity", "duration_s": 4.0, "climb_mps": 1.0},
            {"kind": "hover", "duration_s": 8.0},
        ]
    }
)


def without(log: FlightLog, *names: str) -> FlightLog:
    return FlightLog({k: v for k, v in log.columns.items() if k not in names}, log.metadata)


def test_hover_only_log_cannot_identify_drag_wind_ground_or_command_path():
    log = fly_schedule(load_sim_config("iris"), HOVER)
    missing = {n.name: n for n in check_identifiability([log])}
    expected = {
        "rotor_drag", "body_drag", "isotropic_drag", "wind", "ground_effect", "battery_sag",
        "command_delay", "motor_lag", "thrust_curve", "flight_control",
    }  # fmt: skip
    assert set(missing) == expected
    assert "speed sweeps" in missing["rotor_drag"].flight
    assert "altitude holds" in missing["ground_effect"].flight


@pytest.mark.slow
def test_payload_is_found_in_hover_and_the_rest_is_reported_not_identifiable():
    log = fly_schedule(load_sim_config("iris", {"payload": {"mass_ratio": 1.3}}), HOVER)
    result = diagnose([log], load_sim_config("iris"))
    assert result.verdict == ("payload",)
    assert result.causes[0].params["mass_ratio"] == pytest.approx(1.3, rel=0.02)
    listed = {c.name: c for c in result.causes}
    assert listed["ground_effect"].confidence == 0.0
    assert "not identifiable" in listed["ground_effect"].evidence


@pytest.mark.slow
def test_without_thrust_force_causes_are_not_identifiable_but_command_delay_is(tmp_path):
    logs = fly_hidden({"command_delay": {"delay_s": 0.15}}, tmp_path, seed=4)
    result = diagnose([without(logs[0], "thrust_n")], load_sim_config("iris"))
    assert result.verdict == ("command_delay",)
    assert result.causes[0].params["delay_s"] == pytest.approx(0.15, rel=0.1)
    evidence = {c.name: c.evidence for c in result.causes}
    assert "no thrust_n column" in evidence["payload"]
    assert result.force is None


def test_sensor_noise_neither_hides_rotor_drag_nor_counts_as_disturbance(tmp_path):
    logs = fly_hidden({"rotor_drag": {"k_n_per_mps": [0.45, 0.45, 0.1]}}, tmp_path, seed=9)
    rng = np.random.default_rng(0)
    cols = dict(logs[0].columns)
    for c in ("acc_n_mps2", "acc_e_mps2", "acc_d_mps2"):
        cols[c] = cols[c] + rng.normal(0.0, 0.3, len(cols[c]))
    cols["thrust_n"] = cols["thrust_n"] * (1.0 + rng.normal(0.0, 0.01, len(cols["thrust_n"])))
    noisy = FlightLog(cols, logs[0].metadata)
    result = diagnose([noisy], load_sim_config("iris"))
    assert result.verdict == ("rotor_drag",)
    assert result.causes[0].params["k_n_per_mps_x"] == pytest.approx(0.45, rel=0.15)


@pytest.mark.slow
def test_several_logs_are_diagnosed_together_and_non_offboard_rows_are_not_replayed():
    config = load_sim_config("iris", {"payload": {"mass_ratio": 1.35}})
    first = fly_schedule(config, HOVER_AND_MOVE, seed=1)
    second = fly_schedule(config, HOVER_AND_MOVE, seed=2)
    cols = dict(second.columns)
    cols["mode"] = np.where(cols["t_s"] < 5.0, "POSCTL", cols["mode"])
    second = FlightLog(cols, second.metadata)
    result = diagnose([first, second], load_sim_config("iris"))
    assert result.verdict == ("payload",)
    assert result.causes[0].params["mass_ratio"] == pytest.approx(1.35, rel=0.01)
    assert set(np.unique(result.force.segment)) == {0, 1}
    anchors = [w.t_anchor_s for w in windows([first, second]) if w.log_index == 1]
    assert min(anchors) >= 5.0 + 1.0  # OFFBOARD from 5 s, then the lead-in
    assert result.gain >= 3.0
