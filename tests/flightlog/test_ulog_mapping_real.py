"""The ULog mapping topic by topic on a real PX4 v1.15 log (AUTO.TAKEOFF/LOITER/RTL)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from pyulog import ULog

from flightlog.reader import read_log
from flightlog.ulog import TOPICS

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
AUTO = FIXTURES / "quad_sitl_v1_15_auto.ulg"


def raw_topics() -> dict[str, dict[str, np.ndarray]]:
    ulog = ULog(str(AUTO), message_name_filter_list=list(TOPICS))
    return {d.name: d.data for d in ulog.data_list if d.multi_id == 0}


def test_command_is_the_velocity_controllers_setpoint_in_auto_modes():
    log, raw = read_log(AUTO), raw_topics()
    assert log.metadata["command_topic"] == "vehicle_local_position_setpoint"
    assert set(log["mode"]) == {"TAKEOFF", "HOLD", "RTL"}  # AUTO.* are position-controlled
    sp = raw["vehicle_local_position_setpoint"]
    # every kept command equals the setpoint last published at or before that row
    abs_us = np.round(log["t_s"] * 1e6) + _first_kept_us(log, raw)
    k = np.searchsorted(sp["timestamp"], abs_us, side="right") - 1
    np.testing.assert_allclose(log["cmd_vel_n_mps"], sp["vx"][k])
    np.testing.assert_allclose(log["cmd_vel_d_mps"], sp["vz"][k])
    assert np.all(np.isfinite(sp["vx"][k]))


def _first_kept_us(log, raw) -> float:
    pos = raw["vehicle_local_position"]
    idx = np.flatnonzero(
        np.isclose(pos["x"], log["pos_n_m"][0]) & np.isclose(pos["vx"], log["vel_n_mps"][0])
    )
    return float(pos["timestamp"][idx[0]])


def test_modes_armed_landed_validity_thrust_and_rates():
    log, raw = read_log(AUTO), raw_topics()
    meta = log.metadata
    assert np.all(log["armed"] == 1.0) and log.has("landed")
    pos = raw["vehicle_local_position"]
    start = max(
        raw["vehicle_attitude"]["timestamp"][0],
        raw["vehicle_local_position_setpoint"]["timestamp"][0],
    )
    rows = pos["timestamp"] >= start
    invalid = ~(
        (pos["xy_valid"] > 0)
        & (pos["z_valid"] > 0)
        & (pos["v_xy_valid"] > 0)
        & (pos["v_z_valid"] > 0)
    )[rows]
    assert meta["dropped_rows"]["estimator_invalid"] == int(invalid.sum()) > 0
    assert meta["rows_in_log"] == int(rows.sum())
    assert log.n_rows == meta["rows_in_log"] - sum(meta["dropped_rows"].values())
    assert meta["thrust_source"]["topic"] == "actuator_motors"
    assert meta["thrust_source"]["kind"] == "produced"
    assert 0.2 < float(np.median(log["thrust_norm"])) < 0.9
    assert meta["rates_hz"]["local_position"] == 10.0
    assert meta["rates_hz"]["velocity_command"] == 10.0
    assert meta["vehicle"] == {"mav_type": 2, "type": "quadrotor", "is_vtol": False}
    assert meta["firmware"] == "v1.15.0-dev"  # SITL: a development build
    assert meta["px4_params"]["MPC_THR_HOVER"] == 0.5


def test_rotor_speed_from_esc_rpm_of_the_rotors_only():
    log, raw = read_log(AUTO), raw_topics()
    esc = raw["esc_status"]
    assert int(esc["esc_count"][0]) == 6  # SITL reports 6 ESCs for a 4-rotor airframe
    source = log.metadata["rotor_speed_source"]
    assert source["topic"] == "esc_status" and source["rotors"] == 4
    abs_us = np.round(log["t_s"] * 1e6) + _first_kept_us(log, raw)
    rpm = np.column_stack(
        [np.interp(abs_us, esc["timestamp"], esc[f"esc[{i}].esc_rpm"]) for i in range(4)]
    )
    expected = np.sqrt(np.mean((rpm * 2 * np.pi / 60) ** 2, axis=1))
    np.testing.assert_allclose(log["rotor_speed_rms_radps"], expected, rtol=1e-6, atol=1e-6)
    assert float(np.max(log["rotor_speed_rms_radps"])) > 200.0  # airborne rotors spin
