"""A simulation config from a flight log: the vehicle's own PX4 tuning, a mass consistent with
its hover thrust, and the rest from the nearest preset, listed as assumed.

The log tells: the flight-control parameters ([PX4-params] MPC_*, MC_*) and the hover thrust
(MPC_THR_HOVER, or the median produced thrust while hovering). It cannot tell inertia, rotor
geometry, rotor speed or thrust coefficient: those come from the preset, and the mass follows
from hover thrust x the preset's maximum thrust / g, so the simulated vehicle hovers at the
log's hover thrust. The rate loop's gains stay the preset's too: they act in normalised
torque, so they suit only the torque and inertia they were tuned on (a real vehicle's on iris'
airframe swung about its command while yawing). A multirotor ULog whose flight no command can
read (flown in STAB, no position estimate) still gives its parameters; the hover thrust is then
MPC_THR_HOVER, and the config says so. Velocity-loop gains a log records under their names
before v1.11 are carried over in today's units (flightlog.velocity_loop_gains: x g /
MPC_THR_HOVER, else / the measured hover thrust).
"""

from __future__ import annotations

import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path

from flightlog.reader import read_log
from flightlog.schema import FlightLog, FlightLogError
from flightlog.ulog import (
    FLY_HINT,
    damage_note,
    is_ulog,
    parameters_give_a_config,
    summarise_ulog,
)
from flightlog.velocity_loop_gains import (
    HOVER_ESTIMATED,
    HOVER_PARAMETER,
    HOVER_SPEED_MPS,
    MIN_HOVER_ROWS,
    acceleration_gains,
    estimated_hover_thrust,
    hover_thrust_for_gains,
    is_hover_thrust,
)
from vehicle_sim.config import GRAVITY_MPS2, config_from_mapping, load_sim_config
from vehicle_sim.params import PX4_PARAMS

# [PX4-params] mc_rate_control: gains and integrator limits in normalised torque, which mean
# what they should only on the airframe they were tuned on.
RATE_LOOP_PARAMS = (
    *(f"MC_{axis}RATE_{term}" for axis in ("ROLL", "PITCH", "YAW") for term in ("P", "I", "D")),
    "MC_RR_INT_LIM",
    "MC_PR_INT_LIM",
    "MC_YR_INT_LIM",
)


@dataclass(frozen=True)
class ConfigFromLog:
    """The TOML text, and what came from the log and what was assumed (one line each)."""

    toml: str
    from_log: tuple[str, ...]
    assumed: tuple[str, ...]


def config_from_log(log: FlightLog, preset: str = "iris") -> ConfigFromLog:
    """Build a sim config TOML from ``log``'s PX4 parameters and hover thrust.

    Raises:
        ValueError: the log holds no PX4 parameters and no hover thrust (one line).
    """
    params = log.metadata.get("px4_params")
    params = dict(params) if isinstance(params, Mapping) else {}
    hover, hover_how = _hover_thrust(log, params)
    if hover is None:
        raise ValueError(
            f"{log.where}: no MPC_THR_HOVER parameter in (0, 1] and no produced thrust "
            "while hovering; use a PX4 ULog (it records parameters) or log actuator_motors"
        )
    vehicle = log.metadata.get("vehicle")
    kind = vehicle.get("type") if isinstance(vehicle, Mapping) else None
    notes = tuple(n for n in (damage_note(log), _thrust_not_read(log, hover_how)) if n)
    return _build(log.where, params, hover, hover_how, preset, notes, kind)


def _thrust_not_read(log: FlightLog, hover_how: str) -> str:
    """Why a log that has a thrust column gave its hover thrust by parameter: a thrust that is
    not the rotors' produced one (e.g. PX4's commanded actuator_controls_0) is not read as it
    ("" when the hover thrust was read from the flight, or the log has no thrust)."""
    source = log.metadata.get("thrust_source")
    if hover_how != HOVER_PARAMETER or not log.has("thrust_norm"):
        return ""
    if not isinstance(source, Mapping):
        return "the log does not say what its thrust is (thrust_source): not read as hover thrust"
    if source.get("kind") != "produced":
        what = f"{source.get('kind')} ({source.get('topic')})"
        return f"the log's thrust is {what}, not produced: not read as the hover thrust"
    return (
        f"no hovering stretch in the air ({MIN_HOVER_ROWS} rows slower than {HOVER_SPEED_MPS} "
        "m/s at a thrust a vehicle hovers at) to read the hover thrust from"
    )


def config_from_log_file(path: str | Path, preset: str = "iris") -> ConfigFromLog:
    """Build a sim config from the log at ``path``: from its flight and parameters when its
    flight can be read (:func:`config_from_log`); else, for a multirotor ULog whose flight the
    mapping refuses (flown in STAB or MANUAL, no position estimate, never armed), from its PX4
    parameters alone, the hover thrust being MPC_THR_HOVER, with a line saying why.

    Raises:
        FlightLogError: the log cannot be read, or is not a multirotor's ULog with parameters.
        ValueError: as :func:`config_from_log`.
    """
    path = Path(path)
    try:
        return config_from_log(read_log(path), preset)
    except FlightLogError as refused:
        if not is_ulog(path):
            raise
        summary = summarise_ulog(path)
        if not parameters_give_a_config(summary):
            raise refused from None
        params = summary["px4_params"]
        why = str(refused).removeprefix(f"{path}: ").replace(f"; {FLY_HINT}", "")
        hover = float(params["MPC_THR_HOVER"])
        note = (
            f"parameters only: its flight cannot be read ({why}), so the hover thrust is the "
            "MPC_THR_HOVER parameter, not measured"
        )
        return _build(
            str(path), params, hover, HOVER_PARAMETER, preset, (note,), summary.get("vehicle")
        )


def _build(
    where: str,
    params: Mapping[str, float],
    hover: float,
    hover_how: str,
    preset: str,
    notes: tuple[str, ...],
    vehicle: str | None = None,
) -> ConfigFromLog:
    """The config TOML: mass from ``hover`` (normalised thrust) x the preset's maximum thrust,
    the PX4 parameters ``params`` it knows, the rest from ``preset``; ``notes`` lead the lines
    of what came from the log. ``vehicle``: the log's vehicle type in words (MAV_TYPE), said
    among the assumptions when the preset's rotors cannot be its own (not a quadrotor)."""
    base = load_sim_config(preset)
    v = base.vehicle
    if hover_how == HOVER_PARAMETER and hover == PX4_PARAMS["MPC_THR_HOVER"].default:
        unset = f"MPC_THR_HOVER = {hover:g} is PX4's default: it may never have been set for "
        notes = (*notes, unset + "this vehicle, so the mass may be off")
    mass_kg = hover * 4 * v.max_rotor_thrust_n / GRAVITY_MPS2
    gains_hover, gains_hover_how = hover_thrust_for_gains(params, hover)
    legacy = acceleration_gains(params, gains_hover)
    params = {**params, **legacy}
    kept = [n for n in sorted(PX4_PARAMS) if n not in RATE_LOOP_PARAMS and n != "MPC_THR_HOVER"]
    tuned = {n: float(f"{float(params[n]):.7g}") for n in kept if n in params}
    clamped = _clamp_to_px4_ranges(tuned)
    defaults = [n for n in kept if n not in params]
    from_log = [
        *notes,
        f"mass_kg = {mass_kg:.4f}: what the preset's rotors (maximum thrust "
        f"{4 * v.max_rotor_thrust_n:.2f} N) hover at the log's hover thrust {hover:.3f} "
        f"({hover_how}); the vehicle's weight only if its rotors are the preset's",
        f"{len(tuned)} PX4 parameters: {', '.join(tuned) or 'none'}",
        *_legacy_note(legacy, gains_hover, gains_hover_how),
        *clamped,
    ]
    battery = _battery_from_params(params)
    if battery is not None:
        full_v, empty_v, how = battery
        from_log.append(f"battery full_v = {full_v:g}, empty_v = {empty_v:g}: {how}")
    else:
        full_v, empty_v = v.battery_full_v, v.battery_empty_v
    assumed = [
        f"inertia_kgm2, rotor geometry, rotor speed, thrust and torque coefficients, motor "
        f"time constant{'' if battery else ', battery voltages'}: from preset {preset!r}",
    ]
    rate_gains = [n for n in RATE_LOOP_PARAMS if n in params]
    if rate_gains:
        assumed.append(
            f"rate-loop gains {', '.join(rate_gains)}: from preset {preset!r}, not the log's "
            "(normalised torque: they fit only the airframe they were tuned on)"
        )
    if vehicle is not None and vehicle != "quadrotor":
        assumed.append(
            f"rotors: the log's vehicle ({vehicle}) flies as the {len(v.rotor_spin)} rotors of "
            f"preset {preset!r}: its mass and hover thrust stand for the whole vehicle, its rotor "
            "layout and torques do not (edit [rotors] and [vehicle] to match it)"
        )
    if defaults:
        assumed.append(f"PX4 defaults for {', '.join(defaults)} (not in the log)")
    lines = [f"# Built from {where} by vehicle-sim config-from-log.", "# From the log:"]
    lines += [f"#   {s}" for s in from_log]
    lines += ["# Assumed (the log cannot tell):"] + [f"#   {s}" for s in assumed]
    lines += [
        "",
        "[vehicle]",
        f"mass_kg = {mass_kg:.6g}  # the preset's rotors at the log's hover thrust",
        f"inertia_kgm2 = {list(v.inertia_kgm2)}  # assumed ({preset})",
        f"rotor_max_speed_radps = {v.rotor_max_speed_radps!r}  # assumed ({preset})",
        f"thrust_coeff_n_per_radps2 = {v.thrust_coeff_n_per_radps2!r}  # assumed ({preset})",
        f"torque_coeff_nm_per_radps2 = {v.torque_coeff_nm_per_radps2!r}  # assumed ({preset})",
        f"motor_time_constant_s = {v.motor_time_constant_s!r}  # assumed ({preset})",
        "",
        "[rotors]  # assumed (" + preset + ")",
        f"positions_frd_m = {[list(p) for p in v.rotor_positions_frd_m]}",
        f"spin = {list(v.rotor_spin)}",
        "",
        "[battery]  # " + ("from the log" if battery else f"assumed ({preset})"),
        f"full_v = {full_v!r}",
        f"empty_v = {empty_v!r}",
        "",
        "[px4_params]  # from the log",
        *(f"{n} = {x!r}" for n, x in tuned.items()),
        "",
    ]
    text = "\n".join(lines)

    config_from_mapping(tomllib.loads(text), preset_name="from_log")  # valid before written
    return ConfigFromLog(text, tuple(from_log), tuple(assumed))


def _legacy_note(legacy: Mapping[str, float], hover: float, hover_how: str) -> list[str]:
    """The line saying which velocity-loop gains came from their pre-v1.11 names, if any, and
    the hover thrust that scaled them (``hover_how``: its source)."""
    if not legacy:
        return []
    gains = ", ".join(f"{name} = {value:.4g}" for name, value in legacy.items())
    return [
        f"{gains}: logged as MPC_*_VEL_P/I/D (PX4 before v1.11, normalised thrust per m/s) "
        f"x g / hover thrust {hover:.3f} ({hover_how})"
    ]


def _battery_from_params(params: Mapping[str, float]) -> tuple[float, float, str] | None:
    """(full_v, empty_v, how) of the pack from PX4's battery parameters, or None.

    [PX4-params] BAT1_N_CELLS, BAT1_V_CHARGED, BAT1_V_EMPTY (v1.12+; BAT_N_CELLS,
    BAT_V_CHARGED, BAT_V_EMPTY before): cells in series and the per-cell voltage PX4 treats as
    full and as empty.
    """
    for prefix in ("BAT1_", "BAT_"):
        names = [f"{prefix}{n}" for n in ("N_CELLS", "V_CHARGED", "V_EMPTY")]
        if all(n in params for n in names):
            cells, charged, empty = (float(params[n]) for n in names)
            if cells >= 1 and charged > empty > 0:
                how = f"{cells:g} cells x {names[1]} {charged:g} V / {names[2]} {empty:g} V"
                return round(cells * charged, 4), round(cells * empty, 4), how
    return None


def _clamp_to_px4_ranges(tuned: dict[str, float]) -> list[str]:
    """Clamp, in place, values outside PX4's documented bounds (PX4 stores what it is sent, so
    real logs hold such values; the simulator refuses them); one note per clamped value."""
    notes = []
    for name, value in tuned.items():
        spec = PX4_PARAMS[name]
        try:
            spec.check(name, value)
        except ValueError:
            fixed = min(max(value, spec.lo), spec.hi)
            fixed = float(round(fixed)) if spec.type == "INT32" else fixed
            tuned[name] = fixed
            notes.append(
                f"{name} = {value:g} is outside PX4's documented range [{spec.lo:g}, "
                f"{spec.hi:g}]: clamped to {fixed:g}"
            )
    return notes


def _hover_thrust(log: FlightLog, params: Mapping[str, float]) -> tuple[float | None, str]:
    """Hover thrust (normalised): measured if the log has produced thrust, else MPC_THR_HOVER
    when a hover thrust (in (0, 1]: 0 would make a massless vehicle and infinite gains)."""
    measured = estimated_hover_thrust(log)
    if measured is not None:
        return measured, HOVER_ESTIMATED
    if "MPC_THR_HOVER" in params and is_hover_thrust(float(params["MPC_THR_HOVER"])):
        return float(params["MPC_THR_HOVER"]), HOVER_PARAMETER
    return None, ""
