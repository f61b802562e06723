"""The firmware a ULog names: ver_sw_release's version and its release type (dev, alpha, beta,
rc, nothing for a release), read back as a version for the nav_state tables."""

from __future__ import annotations

from pathlib import Path

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
