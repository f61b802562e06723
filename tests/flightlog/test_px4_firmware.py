"""The firmware a ULog names: ver_sw_release's version and its release type (dev, alpha, beta,
rc, nothing for a release), read back as a version for the nav_state tables."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from flightlog import px4
from flightlog.ulog import summarise_ulog

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"


@pytest.mark.parametrize(
    ("ver_sw_release", "firmware"),
    [
        (0x010F01FF, "v1.15.1"),  # release (255)
        (0x011100C0, "v1.17.0-rc"),  # PX4's FIRMWARE_TYPE_RC
        (0x010E0080, "v1.14.0-beta"),
        (0x010E0040, "v1.14.0-alpha"),
        (0x010E0041, "v1.14.0-alpha"),  # MAVLink: 65 is the second alpha
        (0x010F0000, "v1.15.0-dev"),
        (0, None),
        (None, None),
    ],
)
def test_the_release_type_is_kept_and_the_version_reads_back(ver_sw_release, firmware):
    assert px4.firmware_version(ver_sw_release) == firmware
    if firmware is not None:
        major, minor, patch = (ver_sw_release >> s & 0xFF for s in (24, 16, 8))
        assert px4.firmware_tuple(firmware) == (major, minor, patch)


def test_the_nav_state_tables_follow_the_version_whatever_the_type():
    for firmware in ("v1.15.0", "v1.15.0-rc", "v1.15.0-dev", "v1.16.0-beta"):
        assert px4.nav_state_names(firmware)[6] == "POSITION_SLOW"
        assert 6 in px4.position_controlled_nav_states(firmware)
    for firmware in ("v1.14.0", "v1.14.0-beta", "v1.14.3-dev", None, "custom"):
        assert px4.nav_state_names(firmware)[6] == "AUTO_RCRECOVER"
        assert 6 not in px4.position_controlled_nav_states(firmware)


@pytest.mark.parametrize(
    ("name", "firmware"),
    [
        ("fixedwing_v1_17rc_status.ulg", "v1.17.0-rc"),
        ("quad_mission_rtl_v1_9_esc.ulg", "v1.9.0-beta"),
        ("quad_sitl_v1_15_auto.ulg", "v1.15.0-dev"),
        ("quad_offboard_v1_16.ulg", "v1.16.0"),
    ],
)
def test_real_logs_name_their_release_type(name, firmware):
    assert summarise_ulog(FIXTURES / name)["firmware"] == firmware


def test_an_unreadable_firmware_string_has_no_version():
    assert px4.firmware_tuple("custom") is None
    assert px4.firmware_tuple(None) is None


def test_position_controlled_modes_are_those_with_a_velocity_setpoint():
    """By name: POSCTL, the AUTO modes, OFFBOARD, ORBIT, DESCEND (and POSITION_SLOW from
    v1.15); not MANUAL, ALTCTL, STAB, ACRO, nor the external modes."""
    auto = {"MISSION", "HOLD", "RTL", "AUTO_LANDENGFAIL", "AUTO_LANDGPSFAIL", "TAKEOFF", "LAND"}
    auto |= {"FOLLOW_TARGET", "PRECLAND", "VTOL_TAKEOFF"}
    expected = {"POSCTL", "OFFBOARD", "ORBIT", "DESCEND"} | auto
    for firmware, more in (("v1.14.0", set()), ("v1.15.0", {"POSITION_SLOW"})):
        names = px4.nav_state_names(firmware)
        states = px4.position_controlled_nav_states(firmware)
        assert {names[s] for s in states} == expected | more


def test_motor_commands_outside_zero_to_one_are_no_thrust_and_full_thrust():
    """PX4's motor outputs saturate: a command under 0 is no thrust, over 1 the maximum;
    in between T = fac u^2 + (1 - fac) u, e.g. 0.5 * 0.25 + 0.5 * 0.5 = 0.375 at u = 0.5."""
    np.testing.assert_allclose(
        px4.motor_thrust_fraction(np.array([-0.2, 0.5, 1.3]), 0.5), [0.0, 0.375, 1.0]
    )


def test_external_modes_are_named_from_v1_15_and_unknown_before():
    """nav_state 23-30 are EXTERNAL1-8 from v1.15; an older log's 23 is an unknown value."""
    assert list(px4.mode_names(np.array([23, 30]), "v1.15.0")) == ["EXTERNAL1", "EXTERNAL8"]
    assert list(px4.mode_names(np.array([23]), "v1.14.0")) == ["NAV_STATE_23"]
