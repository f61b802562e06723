"""The ULog mapping on PX4 topics built from a simulated flight: command source per mode,
validity drops, VTOL phases, vehicle type refusals, thrust sources, slow setpoints."""

from __future__ import annotations

import numpy as np
import pytest
from px4_topics import topics_of

from diagnosis.excitation import schedule_from_mapping
from diagnosis.fly_schedule import fly_schedule
from flightlog.reader import require_modes, require_rates
from flightlog.schema import FlightLogError
from flightlog.ulog import flight_log_from_topics
from vehicle_sim import load_sim_config

SCHEDULE = schedule_from_mapping(
    {
        "segment": [
            {"kind": "hover", "duration_s": 3.0},
            {"kind": "velocity", "duration_s": 3.0, "speed_mps": 2.0, "heading_deg": 30.0},
            {"kind": "hover", "duration_s": 2.0},
        ]
    }
)


@pytest.fixture(scope="module")
def flight():
    return fly_schedule(load_sim_config("iris"), SCHEDULE)


def test_offboard_command_comes_from_the_controllers_setpoint_not_trajectory_setpoint(flight):
    topics = topics_of(flight)
    t = topics["vehicle_local_position_setpoint"]["timestamp"]
    topics["trajectory_setpoint"] = {
        "timestamp": t, "yawspeed": 0 * t, **{f"velocity[{i}]": 9.0 + 0 * t for i in range(3)}
    }  # fmt: skip
    log = flight_log_from_topics(topics)
    assert log.metadata["command_topic"] == "vehicle_local_position_setpoint"
    np.testing.assert_allclose(log["cmd_vel_n_mps"], flight["cmd_vel_n_mps"])
    assert set(log["mode"]) == {"OFFBOARD"}
    del topics["vehicle_local_position_setpoint"]
    fallback = flight_log_from_topics(topics)
    assert fallback.metadata["command_topic"] == "trajectory_setpoint"
    assert np.all(fallback["cmd_vel_n_mps"] == 9.0)


def test_posctl_kept_manual_dropped_and_mode_filters(flight):
    topics = topics_of(flight, nav_state=2)
    t = topics["vehicle_local_position"]["timestamp"]
    mid = t[len(t) // 2]
    topics["vehicle_status"] = {
        "timestamp": np.array([t[0], mid]), "nav_state": np.array([2, 0]),
        "arming_state": np.array([2, 2]), "is_vtol": np.array([0, 0]),
    }  # fmt: skip
    log = flight_log_from_topics(topics)
    assert set(log["mode"]) == {"POSCTL"}
    assert log.metadata["dropped_rows"]["not_position_controlled"] == int(np.sum(t >= mid))
    require_modes([log], ["POSCTL"])
    with pytest.raises(FlightLogError, match="no rows in mode OFFBOARD; the logs hold POSCTL"):
        require_modes([log], ["OFFBOARD"])


def test_estimator_invalid_rows_are_dropped_with_a_count(flight):
    topics = topics_of(flight)
    pos = topics["vehicle_local_position"]
    pos["v_xy_valid"] = pos["v_xy_valid"].copy()
    pos["v_xy_valid"][10:40] = 0
    pos["dead_reckoning"] = np.zeros(len(pos["timestamp"]))
    pos["dead_reckoning"][60:65] = 1
    log = flight_log_from_topics(topics)
    assert log.metadata["dropped_rows"]["estimator_invalid"] == 35
    assert log.n_rows == len(pos["timestamp"]) - 35
    for flag in ("xy_valid", "z_valid", "v_xy_valid", "v_z_valid"):
        pos[flag] = np.zeros(len(pos["timestamp"]))
    with pytest.raises(
        FlightLogError, match=r"no valid motion: .* estimator_invalid; flown in OFFBOARD; fly"
    ) as err:
        flight_log_from_topics(topics)
    assert "\n" not in str(err.value)


def test_rover_log_refused_saying_rover_ulogs_are_not_read(flight):
    """A PX4 ground rover (MAV_TYPE 10, or vehicle_type ROVER when MAV_TYPE is not logged): one
    line that says rover ULogs are not read, where the ground rovers are learned and what does
    read a rover's drive."""
    topics = topics_of(flight)
    vehicle = flight_log_from_topics(topics).metadata["vehicle"]  # a multirotor's vehicle_type
    assert vehicle["type"] == "multirotor (MAV_TYPE not logged)"  # was labelled "fixed wing"
    said = "a PX4 rover's ULog is not read here .* scripts.rover --help.* teach --from-log"
    with pytest.raises(FlightLogError, match=rf"a ground rover log \(MAV_TYPE 10\), .*{said}"):
        flight_log_from_topics(topics, params={"MAV_TYPE": 10})
    topics["vehicle_status"]["vehicle_type"] = np.full(
        len(topics["vehicle_status"]["nav_state"]), 3
    )
    with pytest.raises(FlightLogError, match=rf"a ground rover log, not a multirotor; .*{said}"):
        flight_log_from_topics(topics)


def test_mav_type_0_is_named_not_none(flight):
    """MAV_TYPE 0 (MAV_TYPE_GENERIC) is a type the log states, not a missing one: its refusal
    named it 'a None log' (the name was taken only for a truthy MAV_TYPE)."""
    with pytest.raises(FlightLogError, match=r"a generic vehicle log \(MAV_TYPE 0\), not a") as err:
        flight_log_from_topics(topics_of(flight), params={"MAV_TYPE": 0})
    assert "None" not in str(err.value)


def test_fixed_wing_refused_vtol_multicopter_phase_kept_with_segments(flight):
    topics = topics_of(flight)
    with pytest.raises(FlightLogError, match="fixed wing log .MAV_TYPE 1., not a multirotor"):
        flight_log_from_topics(topics, params={"MAV_TYPE": 1})
    t = topics["vehicle_local_position"]["timestamp"]
    third = t[len(t) // 3]
    topics["vehicle_status"] = {
        "timestamp": np.array([t[0], third]), "nav_state": np.array([3, 3]),
        "arming_state": np.array([2, 2]), "is_vtol": np.array([1, 1]),
        "vehicle_type": np.array([1, 2]), "in_transition_mode": np.array([0, 0]),
    }  # fmt: skip
    log = flight_log_from_topics(topics, params={"MAV_TYPE": 22})
    assert log.metadata["vehicle"]["is_vtol"] is True
    assert log.metadata["dropped_rows"]["not_multicopter_phase"] == int(np.sum(t >= third))
    (segment,) = log.metadata["vtol_multicopter_segments_s"]
    assert segment[0] == 0.0 and segment[1] < (third - t[0]) * 1e-6


def test_thrust_sources_in_order_and_marked(flight):
    topics = topics_of(flight)
    log = flight_log_from_topics(topics)
    assert log.metadata["thrust_source"] == {
        "topic": "vehicle_thrust_setpoint",
        "kind": "commanded",
    }
    t = topics["vehicle_local_position"]["timestamp"]
    u = 0.6 + 0 * t
    topics["actuator_outputs"] = {
        "timestamp": t,
        **{f"output[{i}]": 1000 + 1000 * u for i in range(4)},
    }
    params = {"MAV_TYPE": 2, "PWM_MAIN_MIN": 1000, "PWM_MAIN_MAX": 2000, "THR_MDL_FAC": 0.3}
    log = flight_log_from_topics(topics, params=params)
    assert log.metadata["thrust_source"]["kind"] == "produced"
    np.testing.assert_allclose(log["thrust_norm"], 0.3 * 0.36 + 0.7 * 0.6)
    del topics["vehicle_thrust_setpoint"], topics["actuator_outputs"]
    log = flight_log_from_topics(topics)
    assert log.metadata["thrust_source"] == {"topic": None, "kind": "none"}
    assert not log.has("thrust_norm")


def test_two_hz_setpoints_refused_with_the_rate_needed(flight):
    log = flight_log_from_topics(topics_of(flight, setpoint_hz=2.0))
    assert log.metadata["rates_hz"]["velocity_command"] == pytest.approx(2.0, rel=0.05)
    with pytest.raises(FlightLogError, match=r"velocity_command at 2 Hz \(needs >= 5 Hz\)"):
        require_rates(log, "fit-gp")


def test_esc_rpm_kept_as_rotor_speed_only_when_every_rotor_reports(flight):
    topics = topics_of(flight)
    t = topics["vehicle_local_position"]["timestamp"]
    rpm = 6000.0 + 0 * t
    topics["esc_status"] = {
        "timestamp": t, "esc_count": 4 + 0 * t, **{f"esc[{i}].esc_rpm": rpm for i in range(4)}
    }  # fmt: skip
    log = flight_log_from_topics(topics, params={"MAV_TYPE": 2})
    np.testing.assert_allclose(log["rotor_speed_rms_radps"], 6000.0 * 2 * np.pi / 60)
    assert log.metadata["rotor_speed_source"]["rotors"] == 4
    assert log.metadata["thrust_source"]["topic"] == "vehicle_thrust_setpoint"  # kept apart
    topics["esc_status"]["esc_count"] = 3 + 0 * t  # a hexarotor's count would be 6: too few
    assert not flight_log_from_topics(topics, params={"MAV_TYPE": 2}).has("rotor_speed_rms_radps")
    topics["esc_status"] = {
        "timestamp": t,
        "esc_count": 4 + 0 * t,
        **{f"esc[{i}].esc_rpm": 0 * t for i in range(4)},
    }  # ESCs without telemetry report zeros
    assert not flight_log_from_topics(topics, params={"MAV_TYPE": 2}).has("rotor_speed_rms_radps")


def test_nav_state_6_is_position_slow_from_v1_15_and_retired_before(flight):
    topics = topics_of(flight, nav_state=6)
    log = flight_log_from_topics(topics, firmware="v1.15.1")
    assert set(log["mode"]) == {"POSITION_SLOW"}  # position-controlled: kept
    with pytest.raises(FlightLogError, match="not_position_controlled"):
        flight_log_from_topics(topics, firmware="v1.10.0")  # AUTO_RCRECOVER then


def test_default_ten_hz_logging_with_logger_jitter_is_fast_enough(flight):
    """PX4's logger writes vehicle_local_position once per 100 ms interval at most, so the
    default profile's 10 Hz comes out at 9.78 Hz on average in a v1.8 log (102.2 ms between
    samples); such a log is used, while the v1.9 hardware log's 8 Hz is not."""
    topics = topics_of(flight)
    t = topics["vehicle_local_position"]["timestamp"]
    every = round(100_000 / float(np.median(np.diff(t))))  # the flight's rows to one of 10 Hz
    for name in ("vehicle_local_position", "vehicle_local_position_setpoint"):
        topics[name] = {k: v[::every] for k, v in topics[name].items()}
    for topic in topics.values():
        topic["timestamp"] = t[0] + (topic["timestamp"] - t[0]) * 1.0225
    log = flight_log_from_topics(topics)
    assert log.metadata["rates_hz"]["local_position"] == pytest.approx(9.78, abs=0.01)
    require_rates(log, "diagnose")
    require_rates(log, "fit-gp")


def test_info_says_a_log_recorded_disarmed_on_the_ground_gives_the_commands_nothing(flight):
    """A v1.8 log kept on the ground after an RTL (disarmed throughout): its rows map and its
    rates suffice, but fit-gp and diagnose find no flight in it, and info says so."""
    from flightlog.info import describe_log

    topics = topics_of(flight)
    topics["vehicle_status"]["arming_state"] = np.array([1])  # standby: disarmed
    lines = describe_log(flight_log_from_topics(topics))
    assert f"armed: 0 of {flight.n_rows} rows (0 flying)" in lines
    for command in ("fit-gp", "diagnose"):
        assert f"{command}: cannot use this log: no armed row (the vehicle never flew)" in lines
    topics["vehicle_status"]["arming_state"] = np.array([2])
    topics["vehicle_land_detected"] = {"timestamp": topics["vehicle_status"]["timestamp"],
                                       "landed": np.array([1])}  # fmt: skip
    lines = describe_log(flight_log_from_topics(topics))
    assert "diagnose: cannot use this log: no airborne row (armed on the ground only)" in lines
    assert "fit-gp: rates sufficient" in lines


def test_commanded_thrust_is_the_upward_thrust_setpoint(flight):
    """vehicle_thrust_setpoint's z points down (NED): -xyz[2] is the thrust fraction."""
    log = flight_log_from_topics(topics_of(flight))
    np.testing.assert_allclose(log["thrust_norm"], flight["thrust_n"] / 28.27)
    assert np.all(log["thrust_norm"] > 0.0)


def test_pwm_limits_prefer_the_main_outputs_and_must_be_a_range(flight):
    topics = topics_of(flight)
    t = topics["vehicle_local_position"]["timestamp"]
    topics["actuator_outputs"] = {
        "timestamp": t,
        **{f"output[{i}]": 1600 + 0 * t for i in range(4)},
    }
    both = {"MAV_TYPE": 2, "PWM_MIN": 1100, "PWM_MAX": 1900, "PWM_MAIN_MIN": 1000}
    log = flight_log_from_topics(topics, params={**both, "PWM_MAIN_MAX": 2000})
    np.testing.assert_allclose(log["thrust_norm"], 0.6)  # (1600 - 1000) / (2000 - 1000)
    swapped = {"MAV_TYPE": 2, "PWM_MAIN_MIN": 2000, "PWM_MAIN_MAX": 1000}
    log = flight_log_from_topics(topics, params=swapped)
    assert log.metadata["thrust_source"]["topic"] == "vehicle_thrust_setpoint"


def test_motor_controls_with_gaps_give_way_to_the_next_thrust_source(flight):
    topics = topics_of(flight)
    t = topics["vehicle_local_position"]["timestamp"]
    controls = {f"control[{i}]": 0.5 + 0 * t for i in range(4)}
    controls["control[3]"] = np.full(len(t), np.nan)  # a motor that does not report
    topics["actuator_motors"] = {"timestamp": t, **controls}
    log = flight_log_from_topics(topics, params={"CA_ROTOR_COUNT": 4})
    assert log.metadata["thrust_source"]["topic"] == "vehicle_thrust_setpoint"


def test_a_vtol_by_mav_type_is_read_though_its_status_does_not_say_vtol(flight):
    log = flight_log_from_topics(topics_of(flight), params={"MAV_TYPE": 22})
    assert log.metadata["vehicle"]["is_vtol"] is True


def test_vtol_transitions_are_not_multicopter_phase(flight):
    topics = topics_of(flight)
    t = topics["vehicle_local_position"]["timestamp"]
    third = t[len(t) // 3]
    topics["vehicle_status"] = {
        "timestamp": np.array([t[0], third]), "nav_state": np.array([3, 3]),
        "arming_state": np.array([2, 2]), "is_vtol": np.array([1, 1]),
        "vehicle_type": np.array([1, 1]), "in_transition_mode": np.array([0, 1]),
    }  # fmt: skip
    log = flight_log_from_topics(topics, params={"MAV_TYPE": 22})
    assert log.metadata["dropped_rows"]["not_multicopter_phase"] == int(np.sum(t >= third))


def test_rows_are_dropped_for_their_first_reason_only(flight):
    """Estimator invalid in rows 0-9, mode unknown until row 20: 10 rows each."""
    topics = topics_of(flight)
    pos = topics["vehicle_local_position"]
    pos["v_xy_valid"] = pos["v_xy_valid"].copy()
    pos["v_xy_valid"][:10] = 0
    topics["vehicle_status"] = {**topics["vehicle_status"], "timestamp": pos["timestamp"][20:21]}
    dropped = flight_log_from_topics(topics).metadata["dropped_rows"]
    assert dropped["estimator_invalid"] == 10 and dropped["mode_unknown"] == 10


def test_a_single_usable_row_is_no_valid_motion(flight):
    topics = topics_of(flight)
    pos = topics["vehicle_local_position"]
    pos["v_xy_valid"] = np.zeros(len(pos["timestamp"]))
    pos["v_xy_valid"][5] = 1
    with pytest.raises(FlightLogError, match="no valid motion"):
        flight_log_from_topics(topics)


def test_rows_start_once_the_velocity_command_is_logged(flight):
    topics = topics_of(flight)
    sp = topics["vehicle_local_position_setpoint"]
    topics["vehicle_local_position_setpoint"] = {k: v[20:] for k, v in sp.items()}
    log = flight_log_from_topics(topics)
    assert log.metadata["rows_in_log"] == len(topics["vehicle_local_position"]["timestamp"]) - 20


def test_attitude_is_a_unit_quaternion_and_a_missing_yaw_rate_is_zero(flight):
    """PX4 logs NaN for a yaw rate it was not given, and a quaternion only nearly unit."""
    topics = topics_of(flight)
    att = topics["vehicle_attitude"]
    topics["vehicle_attitude"] = {
        k: v * (1.0 if k == "timestamp" else 1.01) for k, v in att.items()
    }
    sp = topics["vehicle_local_position_setpoint"]
    sp["yawspeed"] = np.full(len(sp["timestamp"]), np.nan)
    log = flight_log_from_topics(topics)
    q = log.stack("q_w", "q_x", "q_y", "q_z")
    np.testing.assert_allclose(np.linalg.norm(q, axis=1), 1.0)
    assert np.all(log["cmd_yaw_rate_radps"] == 0.0)
