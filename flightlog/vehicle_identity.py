"""Which vehicle a log was flown on, from its metadata, and whether several logs agree.

What a log's sidecar (or a ULog's header and parameters) says about the vehicle, compared only
where two logs both say it:

- ``vehicle preset``: the simulator preset (``vehicle`` of a vehicle-sim onboard log,
  ``vehicle_preset`` of an in-process companion log);
- ``simulator backend``: vehicle-sim's physics (``backend``: builtin or jsbsim);
- ``mass_kg``: the configured mass (equal within :data:`MASS_REL_TOL`);
- ``vehicle type``: a ULog's MAV_TYPE name (quadrotor, hexarotor ...);
- ``airframe``: a ULog's SYS_AUTOSTART ([PX4-params]), PX4's airframe id;
- ``hardware``: a ULog's flight-controller board (ver_hw);
- ``velocity_loop_gains``: the PX4 velocity-loop gains the companion read before arming, or a
  ULog's MPC_*_VEL_*_ACC parameters (those it records under their names before v1.11 scaled to
  today's units; flightlog.velocity_loop_gains), each equal within :data:`GAIN_REL_TOL` (over
  MAVLink a parameter is a float32, so 1.8 read in process is 1.7999999523 read from
  vehicle-sim or PX4). A log whose gains cannot be read (old gains, no hover thrust) is left
  out of this field, as a log that does not record it.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence

from flightlog.schema import FlightLog
from flightlog.velocity_loop_gains import VELOCITY_LOOP_PARAMS, is_number, velocity_loop_gains

MASS_REL_TOL = 1e-3  # masses closer than this (relative) are the same configured mass
GAIN_REL_TOL = 1e-6  # gains closer than this (relative) are the same (float32 keeps ~6e-8)


def _preset(log: FlightLog) -> object:
    for key in ("vehicle", "vehicle_preset"):
        if isinstance(log.metadata.get(key), str):
            return log.metadata[key]
    return None


def _backend(log: FlightLog) -> object:
    backend = log.metadata.get("backend")
    return backend if isinstance(backend, str) else None


def _hardware(log: FlightLog) -> object:
    hardware = log.metadata.get("hardware")
    return hardware if isinstance(hardware, str) else None


def _vehicle_type(log: FlightLog) -> object:
    vehicle = log.metadata.get("vehicle")
    return vehicle.get("type") if isinstance(vehicle, Mapping) else None


def _airframe(log: FlightLog) -> object:
    params = log.metadata.get("px4_params")
    value = params.get("SYS_AUTOSTART") if isinstance(params, Mapping) else None
    return int(value) if is_number(value) else None


def _mass(log: FlightLog) -> object:
    mass = log.metadata.get("mass_kg")
    return float(mass) if is_number(mass) else None


def _gains(log: FlightLog) -> object:
    return velocity_loop_gains(log).gains


IDENTITY_FIELDS: tuple[tuple[str, Callable[[FlightLog], object]], ...] = (
    ("vehicle preset", _preset),
    ("simulator backend", _backend),
    ("mass_kg", _mass),
    ("vehicle type", _vehicle_type),
    ("airframe (SYS_AUTOSTART)", _airframe),
    ("hardware", _hardware),
    ("velocity_loop_gains", _gains),
)


def _close(a: float, b: float, rel_tol: float) -> bool:
    return abs(a - b) <= rel_tol * max(abs(a), abs(b))


def same_gains(a: Mapping[str, float], b: Mapping[str, float]) -> bool:
    """The same velocity-loop gains: the same names, each value within GAIN_REL_TOL."""
    return a.keys() == b.keys() and all(_close(a[k], b[k], GAIN_REL_TOL) for k in a)


def _same(a: object, b: object) -> bool:
    """Equal identity values: masses within MASS_REL_TOL, gains each within GAIN_REL_TOL."""
    if isinstance(a, float) and isinstance(b, float):
        return _close(a, b, MASS_REL_TOL)
    if isinstance(a, dict) and isinstance(b, dict):
        return same_gains(a, b)
    return a == b


def _text(value: object, gains_shown: Sequence[str]) -> str:
    """An identity value in words: gains as ``[MPC_XY_VEL_P_ACC 1.6, ...]``, only those named
    in ``gains_shown``; numbers to 4 significant digits (a float32 parameter's
    1.600000023841858 is 1.6)."""
    if isinstance(value, dict):
        shown = (f"{VELOCITY_LOOP_PARAMS.get(k, k)} {value[k]:.4g}" for k in gains_shown)
        return f"[{', '.join(shown)}]"
    return f"{value:.4g}" if isinstance(value, float) else str(value)


def _differing_gains(values: Sequence[object]) -> list[str]:
    """The gain names on which the gains among ``values`` differ (beyond GAIN_REL_TOL)."""
    gains = [v for v in values if isinstance(v, dict)]
    names = list(gains[0]) if gains else []
    return [k for k in names if not all(_close(g[k], gains[0][k], GAIN_REL_TOL) for g in gains)]


def mixed_vehicle_fields(logs: Sequence[FlightLog]) -> list[str]:
    """One clause per identity field on which the logs that record it disagree, naming each
    value with its logs, e.g. ``airframe (SYS_AUTOSTART) 4001 in a.ulg, 4003 in b.ulg``
    (velocity-loop gains by their PX4 names, those that differ); [] when every field
    recorded by two or more logs agrees."""
    clauses = []
    for name, read in IDENTITY_FIELDS:
        groups: list[tuple[object, list[str]]] = []
        for log in logs:
            value = read(log)
            if value is None:
                continue
            group = next((g for g in groups if _same(g[0], value)), None)
            if group is None:
                groups.append((value, [log.where]))
            else:
                group[1].append(log.where)
        if len(groups) > 1:
            shown = _differing_gains([value for value, _ in groups])
            values = ", ".join(
                f"{_text(value, shown)} in {' and '.join(where)}" for value, where in groups
            )
            clauses.append(f"{name} {values}")
    return clauses


def airframe_mismatch(config_px4_params: Mapping[str, float], logs: Sequence[FlightLog]) -> str:
    """A sentence naming the logs flown on another airframe (SYS_AUTOSTART) than the one a
    config was built for (its PX4 parameters, e.g. from ``vehicle-sim config-from-log`` of
    another log); "" when they agree or either does not say."""
    configured = config_px4_params.get("SYS_AUTOSTART")
    if not is_number(configured):
        return ""
    others = [(log.where, _airframe(log)) for log in logs]
    others = [(where, a) for where, a in others if a is not None and a != int(configured)]
    if not others:
        return ""
    flown = ", ".join(f"{a} in {where}" for where, a in others)
    return (
        f"the config was built for airframe (SYS_AUTOSTART) {int(configured)}, the log(s) flew "
        f"{flown}: its mass, thrust and gains may be another vehicle's; build the config from "
        "this vehicle's log (vehicle-sim config-from-log)"
    )
