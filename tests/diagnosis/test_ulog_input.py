"""PX4 ULog topics mapped onto schema v1, normalised thrust turned into force, and a truncated
ULog's diagnosis saying so."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from diagnosis.diagnosis import diagnose
from diagnosis.excitation import schedule_from_mapping
from diagnosis.fly_schedule import fly_schedule
from experiments.hidden_effects import draw
from flightlog.schema import FlightLog, FlightLogError
from flightlog.ulog import flight_log_from_topics, read_ulog
from tests.flightlog.ulog_damage import corrupt_copy
from vehicle_sim import load_sim_config

FIXTURES_ULOG = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
HOVER = schedule_from_mapping(
    {
        "segment": [
            {"kind": "hover", "duration_s": 10.0},
            {"kind": "velocity", "duration_s": 3.0, "speed_mps": 2.0, "heading_deg": 30.0},
            {"kind": "hover", "duration_s": 7.0},
        ]
    }
)


def topics_of(log: FlightLog) -> dict[str, dict[str, np.ndarray]]:
    """The PX4 topics a vehicle flying ``log`` would have logged (attitude at other times)."""
    t_us = np.round(log["t_s"] * 1e6) + 1_000_000
    att_us = t_us - 3_000
    q = log.stack("q_w", "q_x", "q_y", "q_z")
    q_att = np.column_stack([np.interp(att_us, t_us, q[:, i]) for i in range(4)])
    return {
        "vehicle_local_position": {
            "timestamp": t_us, "x": log["pos_n_m"], "y": log["pos_e_m"], "z": log["pos_d_m"],
            "vx": log["vel_n_mps"], "vy": log["vel_e_mps"], "vz": log["vel_d_mps"],
            "ax": log["acc_n_mps2"], "ay": log["acc_e_mps2"], "az": log["acc_d_mps2"],
        },
        "vehicle_attitude": {"timestamp": att_us, **{f"q[{i}]": q_att[:, i] for i in range(4)}},
        "trajectory_setpoint": {
            "timestamp": t_us, "yawspeed": log["cmd_yaw_rate_radps"],
            **{f"velocity[{i}]": log[f"cmd_vel_{a}_mps"] for i, a in enumerate("ned")},
        },
        "battery_status": {"timestamp": t_us, "voltage_v": log["battery_v"]},
        "vehicle_thrust_setpoint": {"timestamp": t_us, "xyz[2]": -log["thrust_n"] / 28.27},
    }  # fmt: skip


def test_topics_map_onto_the_schema():
    log = fly_schedule(load_sim_config("iris"), HOVER)
    mapped = flight_log_from_topics(topics_of(log))
    for name in ("pos_n_m", "vel_e_mps", "cmd_vel_n_mps", "acc_d_mps2", "battery_v"):
        np.testing.assert_allclose(mapped[name], log[name], atol=1e-9)
    np.testing.assert_allclose(mapped["q_w"], log["q_w"], atol=1e-3)
    np.testing.assert_allclose(mapped["thrust_norm"], log["thrust_n"] / 28.27)
    assert mapped["t_s"][0] == 0.0 and mapped.metadata["source"] == "px4_ulog"


def test_missing_topic_and_unreadable_file_are_one_line_errors(tmp_path):
    with pytest.raises(FlightLogError, match="lacks topic.*trajectory_setpoint"):
        flight_log_from_topics({"vehicle_local_position": {}, "vehicle_attitude": {}})
    bad = tmp_path / "flight.ulg"
    bad.write_bytes(b"not a ulog at all")
    with pytest.raises(FlightLogError, match="not a ULog file"):
        read_ulog(bad)


def test_payload_is_found_from_normalised_thrust():
    truth, _ = draw("payload", np.random.default_rng(12))
    config = load_sim_config("iris", truth)
    log = fly_schedule(config, HOVER)
    v = config.vehicle
    cols = {k: c for k, c in log.columns.items() if k != "thrust_n"}
    cols["thrust_norm"] = log["thrust_n"] / (4 * v.max_rotor_thrust_n)
    result = diagnose([FlightLog(cols, log.metadata)], load_sim_config("iris"))
    assert result.verdict == ("payload",)
    fitted = result.causes[0].params["mass_ratio"]
    assert fitted == pytest.approx(truth["payload"]["mass_ratio"], rel=0.01)


def test_a_diagnosis_of_a_truncated_ulog_says_so_in_its_headline(tmp_path):
    whole = (FIXTURES_ULOG / "quad_posctl_v1_15.ulg").read_bytes()
    (tmp_path / "crashed.ulg").write_bytes(whole[: len(whole) // 2])
    result = diagnose([read_ulog(tmp_path / "crashed.ulg")], load_sim_config("iris"))
    assert any(w.startswith("crashed.ulg is truncated") for w in result.warnings), result.warnings


def test_a_diagnosis_of_a_corrupt_ulog_calls_it_corrupt_not_truncated(tmp_path):
    damaged, offset = corrupt_copy(tmp_path, "size")
    result = diagnose([read_ulog(damaged)], load_sim_config("iris"))
    named = [w for w in result.warnings if w.startswith("damaged.ulg is")]
    assert len(named) == 1 and named[0].startswith(f"damaged.ulg is corrupt at byte {offset}")
