"""Small pure pieces: waypoint reference timing, PX4 mode codes, MAVLink URL forms."""

from __future__ import annotations

import numpy as np
import pytest

from companion.px4_modes import PX4_MAIN_SUB, custom_mode_of, mode_name_of
from companion.pymavlink_link import pymavlink_device
from companion.waypoint_reference import WaypointReference

# PX4 custom_mode values as docs/mavlink_protocol.md lists them (checked against PX4's
# px4_custom_mode.h).
PROTOCOL_CUSTOM_MODES = {
    "POSCTL": 196608, "ALTCTL": 131072, "HOLD": 50593792, "TAKEOFF": 33816576, "LAND": 100925440,
    "RTL": 84148224, "MISSION": 67371008, "OFFBOARD": 393216, "MANUAL": 65536,
    "ORBIT": 16973824,
}  # fmt: skip
# Modes only a pilot on a real PX4 selects (px4_custom_mode.h: main 7 STABILIZED, 5 ACRO).
PILOT_ONLY_CUSTOM_MODES = {"STABILIZED": 458752, "ACRO": 327680}


def test_px4_custom_modes_match_the_protocol() -> None:
    for name, value in {**PROTOCOL_CUSTOM_MODES, **PILOT_ONLY_CUSTOM_MODES}.items():
        assert custom_mode_of(name) == value
        assert mode_name_of(value) == name
    assert set(PX4_MAIN_SUB) == set(PROTOCOL_CUSTOM_MODES) | set(PILOT_ONLY_CUSTOM_MODES)
    assert mode_name_of(12345) == "UNKNOWN"
    with pytest.raises(ValueError, match="choose one of POSCTL"):
        custom_mode_of("RATTITUDE")


@pytest.mark.parametrize(
    ("url", "device"),
    [
        ("udpin://127.0.0.1:14540", "udpin:127.0.0.1:14540"),
        ("udpout://10.0.0.2:14550", "udpout:10.0.0.2:14550"),
    ],
)
def test_mavsdk_style_urls_map_to_pymavlink_devices(url: str, device: str) -> None:
    assert pymavlink_device(url) == device


@pytest.mark.parametrize("url", ["udp://127.0.0.1:14540", "udpin:127.0.0.1:14540", "tcp://h:1"])
def test_unsupported_urls_are_refused_with_the_accepted_forms(url: str) -> None:
    with pytest.raises(ValueError, match="use udpin://HOST:PORT"):
        pymavlink_device(url)


def test_waypoint_reference_moves_at_constant_speed_and_rests_at_the_ends() -> None:
    ref = WaypointReference(np.array([[0, 0, -2], [3, 0, -2], [3, 4, -2]]), speed_mps=2.0)
    assert ref.duration_s == pytest.approx(3.5)
    np.testing.assert_allclose(ref.x_ref(1.0), [2.0, 0.0, -2.0, 0.0])
    np.testing.assert_allclose(ref.x_ref(2.5), [3.0, 2.0, -2.0, 0.0])
    np.testing.assert_allclose(ref.u_ref(1.0), [2.0, 0.0, 0.0, 0.0])
    np.testing.assert_allclose(ref.u_ref(2.5), [0.0, 2.0, 0.0, 0.0])
    np.testing.assert_allclose(ref.x_ref(np.array([-1.0, 10.0]))[:, :3], [[0, 0, -2], [3, 4, -2]])
    np.testing.assert_allclose(ref.u_ref(np.array([-1.0, 10.0])), np.zeros((2, 4)))
    sample = ref.sample(np.linspace(0.0, 3.4, 35))
    steps = np.linalg.norm(np.diff(sample.pos_ned_m, axis=0), axis=1)
    np.testing.assert_allclose(steps[steps > 0.199], 0.2, atol=1e-9)


def test_waypoint_reference_refuses_bad_input() -> None:
    with pytest.raises(ValueError, match=r"shape \(N >= 2, 3\)"):
        WaypointReference(np.zeros((1, 3)), 1.0)
    with pytest.raises(ValueError, match="speed_mps must be positive"):
        WaypointReference(np.zeros((2, 3)), 0.0)


def test_manual_is_named_not_unknown() -> None:
    """PX4's MANUAL (main mode 1), where an RC switch puts a rover, reads as MANUAL, so the
    companion can say who took the vehicle."""
    assert mode_name_of(1 << 16) == "MANUAL"
