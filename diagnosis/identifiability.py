"""Can the data support a cause at all? Checks per cause, with the flight that would fix it.

A cause the data cannot separate is not fitted and not named; the report says why and what to
fly instead of guessing. Each effect declares what it needs (``NEEDS``, names from
:data:`vehicle_sim.effects.base.REQUIREMENTS`) and what to fly (``EXCITE``); this module holds
one check per requirement and runs them over the registry.
"""

from __future__ import annotations

from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass

import numpy as np

from diagnosis.command_path import FLIGHT_CONTROL
from diagnosis.force_model import BatteryModel
from flightlog.battery_pack import CELL_RANGE_V, PackReading, cell_counts, counts_in_words
from flightlog.schema import FlightLog
from vehicle_sim.effects import EFFECT_CLASSES

NEAR_GROUND_M = 0.3  # ground effect acts below about two rotor radii
MIN_NEAR_GROUND_SPAN_M = 0.05
MIN_SPEED_SPAN_MPS = 3.0
MIN_HEADING_SPREAD = 0.3  # smallest eigenvalue share of horizontal velocity directions
MIN_VOLTAGE_DROP_V = 0.02
MIN_SETPOINT_STEP_MPS = 0.5
MIN_SETPOINT_STEPS = 4

DIAGNOSED_ROLES = ("force", "command")
# flight_control is PX4's velocity-loop gains, a cause the diagnosis fits but not a plant effect
FLIGHT_CONTROL_NEEDS = ("setpoint_steps",)
# What to fly to excite each cause: said when the data cannot identify it, and when it was
# examined but did not stand out from the noise (a weak effect on a short flight).
FLIGHT_FOR: dict[str, str] = {
    **{n: c.EXCITE for n, c in EFFECT_CLASSES.items() if c.ROLE in DIAGNOSED_ROLES},
    FLIGHT_CONTROL: EFFECT_CLASSES["command_delay"].EXCITE,
}
_NEEDS: dict[str, tuple[str, ...]] = {
    **{n: c.NEEDS for n, c in EFFECT_CLASSES.items() if c.ROLE in DIAGNOSED_ROLES},
    FLIGHT_CONTROL: FLIGHT_CONTROL_NEEDS,
}


@dataclass(frozen=True)
class NotIdentifiable:
    """A cause the logs cannot support: ``reason`` and the ``flight`` that would fix it."""

    name: str
    reason: str
    flight: str


@dataclass(frozen=True)
class Flights:
    """What the checks read: the logs, and the config's battery (None: not known), against
    which the logged voltage is read."""

    logs: Sequence[FlightLog]
    battery: BatteryModel | None = None


# A check returns None when the flights meet the requirement, else (reason, fix or None: the
# effect's own excitation flight).
Check = Callable[[Flights], tuple[str, str | None] | None]


def check_identifiability(
    logs: Sequence[FlightLog], known: Collection[str] = (), battery: BatteryModel | None = None
) -> tuple[NotIdentifiable, ...]:
    """The causes that ``logs`` cannot identify (empty when all can be); ``known``: effects the
    config already has (an effect that acts through drag is identifiable only if a drag is
    known or identifiable); ``battery``: the config's, against which the logged voltage is
    read (None: not). Requirements are checked in the order of :data:`CHECKS`; a cause is
    listed once, with the first requirement it misses."""
    out: dict[str, NotIdentifiable] = {}
    flights = Flights(logs, battery)
    for requirement, check in CHECKS.items():
        needing = [n for n, needs in _NEEDS.items() if requirement in needs and n not in out]
        if not needing:
            continue
        failed = check(flights)
        if failed is None:
            continue
        reason, fix = failed
        for name in needing:
            out[name] = NotIdentifiable(name, reason, fix or FLIGHT_FOR[name])
    for name, cls in EFFECT_CLASSES.items():
        through = cls.ACTS_THROUGH
        if (
            cls.ROLE not in DIAGNOSED_ROLES
            or not through
            or name in out
            or set(through) & set(known)
        ):
            continue
        if all(t in out for t in through):
            # without identifiable drag it would carry the drag fit under another name (issue 18)
            out[name] = NotIdentifiable(
                name,
                f"{name} acts through drag, which this flight cannot identify",
                f"{FLIGHT_FOR[cls.FIT_WITH or through[0]]}; {FLIGHT_FOR[name]}",
            )
    return tuple(out.values())


def _thrust(flights: Flights) -> tuple[str, str | None] | None:
    logs = flights.logs
    if all(log.has("thrust_n") for log in logs):
        return None
    return (
        "no thrust_n column: the force residual cannot be formed",
        "log total rotor thrust (from motor RPM telemetry and the thrust coefficient)",
    )


def _horizontal_velocity(logs: Sequence[FlightLog]) -> np.ndarray:
    return np.vstack([log.stack("vel_n_mps", "vel_e_mps") for log in logs])


def _speed_span(flights: Flights) -> tuple[str, str | None] | None:
    logs = flights.logs
    vel = _horizontal_velocity(logs)
    span = float(np.ptp(np.hypot(vel[:, 0], vel[:, 1])))
    if span >= MIN_SPEED_SPAN_MPS:
        return None
    return f"horizontal speed spans only {span:.1f} m/s", None


def _crossing_headings(flights: Flights) -> tuple[str, str | None] | None:
    logs = flights.logs
    vel = _horizontal_velocity(logs)
    moving = vel[np.hypot(vel[:, 0], vel[:, 1]) > 1.0]
    spread = 0.0
    if len(moving) > 10:
        dirs = moving / np.linalg.norm(moving, axis=1, keepdims=True)
        eig = np.linalg.eigvalsh(dirs.T @ dirs / len(dirs))
        spread = float(eig[0] / eig[1])
    if spread >= MIN_HEADING_SPREAD:
        return None
    return "flight directions do not cover two crossing headings", None


def _near_ground(flights: Flights) -> tuple[str, str | None] | None:
    logs = flights.logs
    alt = np.concatenate([-log["pos_d_m"] for log in logs])
    low = alt[(alt > 0.01) & (alt < NEAR_GROUND_M)]
    if len(low) >= 20 and np.ptp(low) >= MIN_NEAR_GROUND_SPAN_M:
        return None
    return f"no altitude change below {NEAR_GROUND_M} m", None


def _voltage_drop(flights: Flights) -> tuple[str, str | None] | None:
    """A logged pack voltage that changes, of a pack the config's battery can be (the same
    cell count, when both tell one: :mod:`flightlog.battery_pack`)."""
    volts = [log["battery_v"] for log in flights.logs if log.has("battery_v")]
    if not volts:
        return "no battery_v column", None
    pack = PackReading.of(volts)
    if pack is None:
        return "battery_v holds no finite value", None
    battery = flights.battery
    # (a config may model a pack below one cell: its own logs read as it)
    floor_v = CELL_RANGE_V[0] if battery is None else min(CELL_RANGE_V[0], battery.empty_v)
    if not pack.is_pack(floor_v):
        return (
            f"battery_v is no pack voltage (median {pack.median_v:.2f} V, below one cell's "
            f"{CELL_RANGE_V[0]:.1f} V)",
            "log the pack's voltage (a power module's battery_status.voltage_v)",
        )
    if battery is not None:
        configured = cell_counts(battery.empty_v, battery.full_v)
        if configured and not set(pack.cells()) & set(configured):
            return (
                f"battery_v {pack.least_v:.1f}-{pack.most_v:.1f} V is a pack of "
                f"{counts_in_words(pack.cells())} cells, the config's battery "
                f"({battery.empty_v:.1f}-{battery.full_v:.1f} V) one of "
                f"{counts_in_words(configured)}",
                "give this vehicle's pack as the config's [battery] full_v and empty_v (a config "
                "from vehicle-sim config-from-log: check the log's BAT1_N_CELLS)",
            )
    finite = [v[np.isfinite(v)] for v in volts]
    if max(float(np.ptp(v)) for v in finite if v.size) >= MIN_VOLTAGE_DROP_V:
        return None
    return "battery voltage does not change", None


def _setpoint_steps(flights: Flights) -> tuple[str, str | None] | None:
    logs = flights.logs
    steps = 0
    for log in logs:
        cmd = log.stack("cmd_vel_n_mps", "cmd_vel_e_mps", "cmd_vel_d_mps")
        steps += int(np.sum(np.linalg.norm(np.diff(cmd, axis=0), axis=1) > MIN_SETPOINT_STEP_MPS))
    if steps >= MIN_SETPOINT_STEPS:
        return None
    return f"only {steps} setpoint steps larger than {MIN_SETPOINT_STEP_MPS} m/s", None


# One check per multirotor requirement, in the order they are tried.
CHECKS: dict[str, Check] = {
    "thrust": _thrust,
    "speed_span": _speed_span,
    "crossing_headings": _crossing_headings,
    "near_ground": _near_ground,
    "voltage_drop": _voltage_drop,
    "setpoint_steps": _setpoint_steps,
}
