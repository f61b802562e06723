"""Can the data support a cause at all? Checks per cause, with the flight that would fix it.

A cause the data cannot separate is not fitted and not named; the report says why and what to
fly instead of guessing.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from diagnosis.candidates import FORCE_CAUSES
from flightlog.schema import FlightLog

NEAR_GROUND_M = 0.3  # ground effect acts below about two rotor radii
MIN_NEAR_GROUND_SPAN_M = 0.05
MIN_SPEED_SPAN_MPS = 3.0
MIN_HEADING_SPREAD = 0.3  # smallest eigenvalue share of horizontal velocity directions
MIN_VOLTAGE_DROP_V = 0.02
MIN_SETPOINT_STEP_MPS = 0.5
MIN_SETPOINT_STEPS = 4

_STEPS = "fly sharp velocity setpoint steps (e.g. 0 -> 3 m/s and back, several headings)"
# What to fly to excite each cause: said when the data cannot identify it, and when it was
# examined but did not stand out from the noise (a weak effect on a short flight).
FLIGHT_FOR: dict[str, str] = {
    "rotor_drag": "fly speed sweeps from hover to 8 m/s in several headings",
    "body_drag": "fly speed sweeps from hover to 8 m/s in several headings",
    "isotropic_drag": "fly speed sweeps from hover to 8 m/s in several headings",
    "wind": "fly out and back along at least two crossing headings at the same speed",
    "ground_effect": "fly altitude holds at 0.05, 0.1, 0.2 and 0.5 m above flat ground",
    "battery_sag": "log battery voltage over a long flight (several minutes of hover)",
    "payload": "hover and fly vertical steps (climb and descend at 1-2 m/s)",
    "command_delay": _STEPS,
    "motor_lag": _STEPS,
    "flight_control": _STEPS,
}


@dataclass(frozen=True)
class NotIdentifiable:
    """A cause the logs cannot support: ``reason`` and the ``flight`` that would fix it."""

    name: str
    reason: str
    flight: str


def check_identifiability(logs: Sequence[FlightLog]) -> tuple[NotIdentifiable, ...]:
    """The causes that ``logs`` cannot identify (empty when all can be)."""
    out: list[NotIdentifiable] = []
    if not all(log.has("thrust_n") for log in logs):
        for name in FORCE_CAUSES:
            out.append(
                NotIdentifiable(
                    name,
                    "no thrust_n column: the force residual cannot be formed",
                    "log total rotor thrust (from motor RPM telemetry and the thrust coefficient)",
                )
            )
    else:
        out.extend(_force_checks(logs))
    steps = sum(_setpoint_steps(log) for log in logs)
    if steps < MIN_SETPOINT_STEPS:
        for name in ("command_delay", "motor_lag", "flight_control"):
            out.append(
                NotIdentifiable(
                    name,
                    f"only {steps} setpoint steps larger than {MIN_SETPOINT_STEP_MPS} m/s",
                    FLIGHT_FOR[name],
                )
            )
    return tuple(out)


def _force_checks(logs: Sequence[FlightLog]) -> list[NotIdentifiable]:
    out = []
    vel = np.vstack([log.stack("vel_n_mps", "vel_e_mps") for log in logs])
    speed = np.hypot(vel[:, 0], vel[:, 1])
    span = float(np.ptp(speed))
    if span < MIN_SPEED_SPAN_MPS:
        for name in ("rotor_drag", "body_drag", "isotropic_drag"):
            out.append(
                NotIdentifiable(
                    name,
                    f"horizontal speed spans only {span:.1f} m/s",
                    FLIGHT_FOR[name],
                )
            )
    moving = vel[speed > 1.0]
    spread = 0.0
    if len(moving) > 10:
        dirs = moving / np.linalg.norm(moving, axis=1, keepdims=True)
        eig = np.linalg.eigvalsh(dirs.T @ dirs / len(dirs))
        spread = float(eig[0] / eig[1])
    if spread < MIN_HEADING_SPREAD:
        out.append(
            NotIdentifiable(
                "wind",
                "flight directions do not cover two crossing headings",
                FLIGHT_FOR["wind"],
            )
        )
    alt = np.concatenate([-log["pos_d_m"] for log in logs])
    low = alt[(alt > 0.01) & (alt < NEAR_GROUND_M)]
    if len(low) < 20 or np.ptp(low) < MIN_NEAR_GROUND_SPAN_M:
        out.append(
            NotIdentifiable(
                "ground_effect",
                f"no altitude change below {NEAR_GROUND_M} m",
                FLIGHT_FOR["ground_effect"],
            )
        )
    volts = [log["battery_v"] for log in logs if log.has("battery_v")]
    drop = max((float(np.ptp(v)) for v in volts), default=0.0)
    if drop < MIN_VOLTAGE_DROP_V:
        what = "no battery_v column" if not volts else "battery voltage does not change"
        out.append(
            NotIdentifiable(
                "battery_sag",
                what,
                FLIGHT_FOR["battery_sag"],
            )
        )
    return out


def _setpoint_steps(log: FlightLog) -> int:
    cmd = log.stack("cmd_vel_n_mps", "cmd_vel_e_mps", "cmd_vel_d_mps")
    return int(np.sum(np.linalg.norm(np.diff(cmd, axis=0), axis=1) > MIN_SETPOINT_STEP_MPS))
