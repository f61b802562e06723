"""PX4 flight modes on the wire: HEARTBEAT custom_mode and DO_SET_MODE (main, sub) pairs.

PX4 packs its mode as ``custom_mode = main << 16 | sub << 24``; DO_SET_MODE carries main in
param2 and sub in param3. Only the modes the companion reads or sets are listed.
"""

from __future__ import annotations

from companion.link import FlightModeName

PX4_MAIN_SUB: dict[str, tuple[int, int]] = {
    "POSCTL": (3, 0),
    "ALTCTL": (2, 0),
    "HOLD": (4, 3),
    "TAKEOFF": (4, 2),
    "LAND": (4, 6),
    "RTL": (4, 5),
    "MISSION": (4, 4),
    "OFFBOARD": (6, 0),
    "MANUAL": (1, 0),  # a pilot's sticks: where an RC switch puts a rover
    "ORBIT": (3, 1),  # POSCTL's sub mode: MAV_CMD_DO_ORBIT from a ground station
    "STABILIZED": (7, 0),  # a pilot's modes on real PX4, read to name who took over
    "ACRO": (5, 0),
}


def custom_mode_of(name: str) -> int:
    """HEARTBEAT custom_mode of a mode name; ValueError listing the valid names otherwise."""
    try:
        main, sub = PX4_MAIN_SUB[name]
    except KeyError:
        raise ValueError(
            f"unknown PX4 mode {name!r}; choose one of {', '.join(PX4_MAIN_SUB)}"
        ) from None
    return main << 16 | sub << 24


_NAME_OF_CUSTOM_MODE = {custom_mode_of(n): n for n in PX4_MAIN_SUB}


def mode_name_of(custom_mode: int) -> FlightModeName:
    """Mode name of a HEARTBEAT custom_mode ("UNKNOWN" for modes not listed)."""
    return _NAME_OF_CUSTOM_MODE.get(int(custom_mode), "UNKNOWN")  # type: ignore[return-value]
