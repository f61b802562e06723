"""MANUAL_CONTROL on the wire -> normalised sticks, as PX4's mavlink receiver reads it.

[MAVLink] MANUAL_CONTROL: ``x`` (pitch, forward), ``y`` (roll, right) and ``r`` (yaw) in
[-1000, 1000]; ``z`` (thrust) in [0, 1000] with 500 the centre for a multirotor (MAVSDK's
manual_control and QGC's virtual joystick send it so); INT16_MAX marks an axis as invalid.
PX4 divides by 1000 and constrains the throttle to [0, 1] (Sticks.cpp); here every axis out of
its range is constrained and the pilot is told, and a message with an axis marked invalid is
ignored as a whole (it neither flies nor keeps the manual-control-loss failsafe quiet), since
what an invalid axis should hold is not for the simulator to guess.
"""

from __future__ import annotations

from dataclasses import dataclass

from vehicle_sim.manual_control import Sticks

INT16_MAX = 32767
AXIS_RANGES = (("x", -1000, 1000), ("y", -1000, 1000), ("z", 0, 1000), ("r", -1000, 1000))
"""(axis, lowest, highest) raw values of MANUAL_CONTROL's stick fields."""


@dataclass(frozen=True)
class StickParse:
    """What a MANUAL_CONTROL message amounts to.

    Attributes:
        sticks: the normalised sticks, or None when the message is ignored.
        problem: a one-line reason for the pilot (clamped or ignored axes), or "".
    """

    sticks: Sticks | None
    problem: str = ""


def parse_manual_control(x: int, y: int, z: int, r: int) -> StickParse:
    """The sticks of one MANUAL_CONTROL (raw int16 fields)."""
    raw = {"x": int(x), "y": int(y), "z": int(z), "r": int(r)}
    invalid = [name for name, value in raw.items() if value == INT16_MAX]
    if invalid:
        return StickParse(
            None,
            f"Sticks ignored: axis {', '.join(invalid)} invalid (INT16_MAX)",
        )
    clamped: list[str] = []
    values: dict[str, float] = {}
    for name, lo, hi in AXIS_RANGES:
        value = raw[name]
        if not lo <= value <= hi:
            clamped.append(f"{name} {value} not in {lo}..{hi}")
            value = min(max(value, lo), hi)
        values[name] = value / 1000.0
    problem = f"Sticks clamped: {', '.join(clamped)}" if clamped else ""
    return StickParse(Sticks(**values), problem)
