"""What PX4 means by the numbers it logs: navigation states, vehicle types, thrust curve.

Enumerations from PX4's uORB message definitions ([PX4-msgs] msg/vehicle_status.msg,
msg/vehicle_local_position.msg) and its MAVLink vehicle types ([MAVLink] MAV_TYPE). Which
firmware versions carry which field is written beside each use in flightlog/ulog.py.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

# vehicle_status.nav_state, v1.9 to v1.16 [PX4-msgs] vehicle_status.msg at each release tag.
# Names follow the MAVLink mode names our simulator and logs use (HOLD is PX4's AUTO.LOITER).
# 0-5, 10, 12-15 and 17-21 mean the same in every release; 6 and 7 (RCRECOVER, RTGS) were
# retired in v1.11 and 6 returned as POSITION_SLOW in v1.15; 8 is unused from v1.14, 9 from
# v1.13, 16 (RATTITUDE) from v1.12; 22 is VTOL_TAKEOFF from v1.13; 23-30 are EXTERNAL1-8 (modes
# of external components) from v1.15.
NAV_STATE_NAMES: dict[int, str] = {
    0: "MANUAL", 1: "ALTCTL", 2: "POSCTL", 3: "MISSION", 4: "HOLD", 5: "RTL",
    6: "AUTO_RCRECOVER", 7: "AUTO_RTGS", 8: "AUTO_LANDENGFAIL", 9: "AUTO_LANDGPSFAIL",
    10: "ACRO", 11: "UNUSED", 12: "DESCEND", 13: "TERMINATION", 14: "OFFBOARD",
    15: "STAB", 16: "RATTITUDE", 17: "TAKEOFF", 18: "LAND", 19: "FOLLOW_TARGET",
    20: "PRECLAND", 21: "ORBIT", 22: "VTOL_TAKEOFF",
}  # fmt: skip
NAV_STATE_NAMES_V1_15: dict[int, str] = {
    **NAV_STATE_NAMES, 6: "POSITION_SLOW", **{22 + k: f"EXTERNAL{k}" for k in range(1, 9)},
}  # fmt: skip

# Modes in which PX4's position controller runs and so receives a velocity setpoint
# (POSCTL, AUTO.*, OFFBOARD, ORBIT, DESCEND); ALTCTL/STAB/ACRO/MANUAL give no horizontal one.
# External modes (v1.15+) may command anything and are left out.
POSITION_CONTROLLED_NAV_STATES = frozenset({2, 3, 4, 5, 8, 9, 12, 14, 17, 18, 19, 20, 21, 22})
POSITION_CONTROLLED_NAV_STATES_V1_15 = POSITION_CONTROLLED_NAV_STATES | {6}


def firmware_tuple(firmware: str | None) -> tuple[int, int, int] | None:
    """'v1.15.1' or 'v1.15.1-rc' (firmware_version) -> (1, 15, 1), the release type left out;
    None for None or an unreadable string."""
    number = str(firmware).lstrip("v").partition("-")[0]
    try:
        major, minor, patch = (int(x) for x in number.split("."))
    except ValueError:
        return None
    return major, minor, patch


def _v1_15_or_later(firmware: str | None) -> bool:
    version = firmware_tuple(firmware)
    return version is not None and version >= (1, 15, 0)


def nav_state_names(firmware: str | None = None) -> dict[int, str]:
    """nav_state -> mode name for ``firmware`` ('vA.B.C[-type]'; None: the pre-v1.15 table)."""
    return NAV_STATE_NAMES_V1_15 if _v1_15_or_later(firmware) else NAV_STATE_NAMES


def position_controlled_nav_states(firmware: str | None = None) -> frozenset[int]:
    """The nav_state values in which PX4's velocity controller runs, for ``firmware``."""
    if _v1_15_or_later(firmware):
        return POSITION_CONTROLLED_NAV_STATES_V1_15
    return POSITION_CONTROLLED_NAV_STATES


# vehicle_status.arming_state: ARMED is 2 in every version v1.9 to v1.16 (STANDBY 1 up to
# v1.14, DISARMED 1 from v1.15).
ARMING_STATE_ARMED = 2

# vehicle_status.vehicle_type (v1.10+; up to v1.9 is_rotary_wing instead).
VEHICLE_TYPE_ROTARY_WING = 1
VEHICLE_TYPE_FIXED_WING = 2
VEHICLE_TYPE_ROVER = 3
MAV_TYPE_GROUND_ROVER = 10

# [MAVLink] MAV_TYPE (parameter MAV_TYPE in PX4): multirotors and VTOLs.
MAV_TYPE_MULTIROTOR: dict[int, str] = {
    2: "quadrotor", 3: "coaxial", 4: "helicopter", 13: "hexarotor", 14: "octorotor",
    15: "tricopter", 29: "dodecarotor", 35: "decarotor", 43: "generic multirotor",
}  # fmt: skip
MAV_TYPE_VTOL = frozenset({19, 20, 21, 22, 23, 24, 25})
MAV_TYPE_NAMES: dict[int, str] = {
    **MAV_TYPE_MULTIROTOR, 0: "generic vehicle", 1: "fixed wing", 10: "ground rover",
    11: "surface boat", 12: "submarine", 19: "VTOL tailsitter duo", 20: "VTOL tailsitter quad",
    21: "VTOL tiltrotor", 22: "VTOL standard", 23: "VTOL tailsitter",
}  # fmt: skip


def no_airframe_set(params: Mapping[str, float]) -> bool:
    """Whether PX4 parameters are those of a board never given an airframe: SYS_AUTOSTART 0 and
    MAV_TYPE 0 ([PX4-params]). Such a log says nothing of the vehicle: MAV_TYPE 0 is then no
    "generic vehicle" but PX4's default."""
    return params.get("SYS_AUTOSTART") == 0 and params.get("MAV_TYPE") == 0


def vehicle_name(mav_type: int | None) -> str | None:
    """A MAV_TYPE in words ("quadrotor", "generic vehicle" for 0, "MAV_TYPE 42" for one not
    listed); None when the log has no MAV_TYPE (0 is a type, not a missing one)."""
    return None if mav_type is None else MAV_TYPE_NAMES.get(mav_type, f"MAV_TYPE {mav_type}")


def mode_names(nav_state: np.ndarray, firmware: str | None = None) -> np.ndarray:
    """nav_state integers -> mode names (``NAV_STATE_<n>`` for unknown values), dtype str."""
    names = nav_state_names(firmware)
    return np.asarray([names.get(int(s), f"NAV_STATE_{int(s)}") for s in nav_state])


def motor_thrust_fraction(command: np.ndarray, thr_mdl_fac: float) -> np.ndarray:
    """Normalised motor command u in [0, 1] -> thrust as a fraction of that motor's maximum.

    PX4 linearises thrust with the model T = fac * u^2 + (1 - fac) * u ([PX4-params]
    THR_MDL_FAC); fac = 0 means thrust proportional to the command.
    """
    u = np.clip(command, 0.0, 1.0)
    return thr_mdl_fac * u**2 + (1.0 - thr_mdl_fac) * u


# ver_sw_release's type byte TT: PX4's FIRMWARE_TYPE (src/lib/version/version.c: dev 0, alpha
# 64, beta 128, rc 192, release 255), MAVLink's FIRMWARE_VERSION_TYPE, whose values are each
# type's first (65 would be a second alpha), so read as ranges, as pyulog's get_version_info
# does. PX4 sets it from characters of its git tag (version_tag_to_number): a 't' anywhere
# makes beta, so a build of a modified tree ('v1.15.0-dirty') logs as beta too.
# Named as QGroundControl names them (Vehicle::firmwareVersionTypeString: dev, alpha, beta, rc;
# nothing for a release), after a dash as PX4's tags carry them ('v1.14.0-beta1', 'v1.14.0-rc2':
# src/lib/version/px_update_git_header.py), without the number the byte does not keep.
FIRMWARE_TYPES = ((192, "rc"), (128, "beta"), (64, "alpha"), (0, "dev"))
FIRMWARE_TYPE_RELEASE = 255


def firmware_version(ver_sw_release: int | None) -> str | None:
    """PX4's ver_sw_release (uint32 0xAABBCCTT) -> 'vA.B.C' for a release, 'vA.B.C-<type>'
    otherwise (type dev, alpha, beta or rc: FIRMWARE_TYPES); None if absent or 0."""
    if not ver_sw_release:
        return None
    v = int(ver_sw_release)
    number = f"v{(v >> 24) & 0xFF}.{(v >> 16) & 0xFF}.{(v >> 8) & 0xFF}"
    kind = v & 0xFF
    if kind == FIRMWARE_TYPE_RELEASE:
        return number
    return f"{number}-{next(name for first, name in FIRMWARE_TYPES if kind >= first)}"
