"""Which PX4 version logs which topic and field, as flightlog/ulog.py documents it, checked on
the real logs of tests/fixtures/ulog (the mapping reads each by presence, so every layout maps)."""

from __future__ import annotations

from pathlib import Path

import pytest
from pyulog import ULog

from flightlog.ulog import TOPICS, summarise_ulog

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
# file: (version, fields present, fields absent), as "topic.field" or "topic" (the topic itself)
LAYOUTS = {
    "quad_manual_v1_6.ulg": (
        "v1.6.0-dev",
        {"vehicle_status.is_rotary_wing", "actuator_controls_0.control[3]"},
        {"vehicle_status.vehicle_type", "vehicle_angular_velocity", "vehicle_thrust_setpoint"},
    ),
    "quad_mission_rtl_v1_9_esc.ulg": (
        "v1.9.0-beta",
        {
            "vehicle_local_position_setpoint.vx", "vehicle_local_position_setpoint.acc_x",
            "trajectory_setpoint.vx", "vehicle_status.is_rotary_wing",
            "actuator_controls_0.control[3]", "esc_status.esc[0].esc_rpm", "battery_status",
        },
        {
            "trajectory_setpoint.velocity[0]", "vehicle_local_position.dead_reckoning",
            "vehicle_angular_velocity", "vehicle_thrust_setpoint", "actuator_motors",
        },
    ),
    "vtol_manual_v1_11.ulg": (
        "v1.11.2-dev",
        {"vehicle_status.vehicle_type", "vehicle_angular_velocity.xyz[0]", "actuator_controls_0"},
        {"vehicle_status.is_rotary_wing", "vehicle_local_position.dead_reckoning",
         "vehicle_thrust_setpoint", "actuator_motors"},
    ),
    "quad_stab_ground_v1_12.ulg": (
        "v1.12.3-dev",
        {"vehicle_status.vehicle_type", "vehicle_angular_velocity.xyz[0]",
         "esc_status.esc[0].esc_rpm", "actuator_outputs.output[0]"},
        {"vehicle_status.is_rotary_wing", "vehicle_local_position.dead_reckoning",
         "vehicle_local_position_setpoint", "trajectory_setpoint", "actuator_motors"},
    ),
    "octo_altctl_v1_14.ulg": (
        "v1.14.0",
        {
            "vehicle_local_position.dead_reckoning", "trajectory_setpoint.velocity[0]",
            "vehicle_local_position_setpoint.acceleration[0]", "vehicle_thrust_setpoint.xyz[2]",
            "actuator_motors.control[0]",
        },
        {"actuator_controls_0", "trajectory_setpoint.vx", "vehicle_status.is_rotary_wing"},
    ),
    "quad_posctl_v1_15.ulg": (
        "v1.15.1",
        {"vehicle_local_position.dead_reckoning", "trajectory_setpoint.velocity[0]",
         "actuator_motors.control[0]", "vehicle_status.vehicle_type"},
        {"actuator_controls_0"},
    ),
    "quad_stab_nogps_v1_16_1.ulg": (
        "v1.16.1-rc",
        {"vehicle_local_position.dead_reckoning", "trajectory_setpoint.velocity[0]",
         "actuator_motors.control[0]", "vehicle_thrust_setpoint.xyz[2]"},
        {"actuator_controls_0", "esc_status"},
    ),
    "quad_offboard_v1_16.ulg": (
        "v1.16.0",
        {"vehicle_local_position.dead_reckoning", "trajectory_setpoint.velocity[0]",
         "actuator_motors.control[0]", "vehicle_thrust_setpoint.xyz[2]"},
        {"actuator_controls_0"},
    ),
}  # fmt: skip


def _fields(path: Path) -> set[str]:
    ulog = ULog(str(path), message_name_filter_list=list(TOPICS))
    out = set()
    for d in ulog.data_list:
        if d.multi_id == 0:
            out.add(d.name)
            out.update(f"{d.name}.{field}" for field in d.data)
    return out


@pytest.mark.parametrize("name", sorted(LAYOUTS))
def test_the_documented_layout_is_the_logged_one(name):
    version, present, absent = LAYOUTS[name]
    fields = _fields(FIXTURES / name)
    assert present <= fields, sorted(present - fields)
    assert not absent & fields, sorted(absent & fields)
    assert summarise_ulog(FIXTURES / name)["firmware"] == version
