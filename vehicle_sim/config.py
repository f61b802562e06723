"""Simulator configuration: vehicle preset + effects, loaded from TOML and validated.

A config file has the sections ``[vehicle]``, ``[rotors]``, ``[battery]``, optional ``[sim]``,
optional ``[px4_params]`` (PX4-named flight-control parameters overriding PX4's defaults, see
vehicle_sim/params.py) and optional ``[effects.<name>]`` tables (see ``presets/iris.toml``).
Every numeric key carries its unit in its name; ``[sim] backend`` names the physics backend
(one of ``BACKEND_NAMES``).
Any problem raises :class:`SimConfigError` with one line naming the key and the fix.
"""

from __future__ import annotations

import difflib
import math
import tomllib
from collections.abc import Iterable, Mapping
from dataclasses import dataclass, field, replace
from pathlib import Path
from typing import Any

from flightlog.schema import GRAVITY_MPS2
from vehicle_sim.effects import EFFECT_CLASSES, EFFECT_NAMES, Effect, make_effect
from vehicle_sim.effects.base import SimConfigError

PRESET_DIR = Path(__file__).with_name("presets")
PRESET_NAMES: tuple[str, ...] = tuple(sorted(p.stem for p in PRESET_DIR.glob("*.toml")))
FLIGHT_LOG_SUFFIXES = (".ulg", ".csv")  # logs config-from-log reads, passed as a config by mistake
BACKEND_NAMES: tuple[str, ...] = ("builtin", "jsbsim")
"""Physics backends a config can name: the built-in rigid body, or JSBSim's F450."""

# section -> key -> (kind, lo, hi, unit, required)
_SCHEMA: dict[str, dict[str, tuple[str, float, float, str, bool]]] = {
    "vehicle": {
        "mass_kg": ("float", 0.05, 100.0, "kg", True),
        "inertia_kgm2": ("vec3", 1e-5, 100.0, "kg m^2", True),
        "rotor_max_speed_radps": ("float", 10.0, 1e4, "rad/s", True),
        "thrust_coeff_n_per_radps2": ("float", 1e-9, 1.0, "N/(rad/s)^2", True),
        "torque_coeff_nm_per_radps2": ("float", 1e-12, 1.0, "N m/(rad/s)^2", True),
        "motor_time_constant_s": ("float", 0.005, 0.5, "s", True),
    },
    "rotors": {
        "positions_frd_m": ("vec3x4", -5.0, 5.0, "m", True),
        "spin": ("spin4", -1.0, 1.0, "+1 ccw / -1 cw seen from above", True),
    },
    "battery": {
        "full_v": ("float", 1.0, 100.0, "V", True),
        "empty_v": ("float", 1.0, 100.0, "V", True),
    },
    "sim": {"physics_dt_s": ("float", 1e-4, 0.01, "s", False)},
}
# section -> key -> the names it may take (optional keys)
_CHOICES: dict[str, dict[str, tuple[str, ...]]] = {"sim": {"backend": BACKEND_NAMES}}
# Top-level keys of the project's other TOML files, given where a config belongs by mistake.
_OTHER_FILE_KINDS: dict[str, str] = {
    "reference": "a companion mission",
    "segment": "an excitation schedule",
    "cylinder": "an obstacle world",
    "sphere": "an obstacle world",
    "box": "an obstacle world",
}


@dataclass(frozen=True)
class VehicleSpec:
    """The nominal vehicle (what its preset claims).

    Attributes:
        mass_kg: take-off mass [kg].
        inertia_kgm2: (3,) principal moments of inertia about body FRD axes [kg m^2].
        rotor_max_speed_radps: rotor speed at full command [rad/s].
        thrust_coeff_n_per_radps2: rotor thrust per speed squared [N/(rad/s)^2].
        torque_coeff_nm_per_radps2: rotor drag torque per speed squared [N m/(rad/s)^2].
        motor_time_constant_s: first-order lag of rotor speed [s].
        rotor_positions_frd_m: (4, 3) rotor hub positions in body FRD [m].
        rotor_spin: (4,) +1 counter-clockwise seen from above (reaction torque +yaw), -1 cw.
        battery_full_v, battery_empty_v: battery voltage full and empty [V].
    """

    mass_kg: float
    inertia_kgm2: tuple[float, float, float]
    rotor_max_speed_radps: float
    thrust_coeff_n_per_radps2: float
    torque_coeff_nm_per_radps2: float
    motor_time_constant_s: float
    rotor_positions_frd_m: tuple[tuple[float, float, float], ...]
    rotor_spin: tuple[int, ...]
    battery_full_v: float
    battery_empty_v: float

    @property
    def max_rotor_thrust_n(self) -> float:
        """Thrust of one rotor at full speed [N]."""
        return self.thrust_coeff_n_per_radps2 * self.rotor_max_speed_radps**2

    @property
    def hover_thrust_norm(self) -> float:
        """Collective normalised thrust that holds the nominal mass (PX4's MPC_THR_HOVER)."""
        return self.mass_kg * GRAVITY_MPS2 / (len(self.rotor_spin) * self.max_rotor_thrust_n)


@dataclass(frozen=True)
class SimConfig:
    """Everything a :class:`~vehicle_sim.simulator.Simulator` is built from.

    Attributes:
        preset_name: name of the vehicle preset (file stem), recorded in log sidecars.
        vehicle: the nominal vehicle.
        effects: enabled effects, at most one per name (ground truth: never logged).
        physics_dt_s: physics and control step [s].
        backend: physics backend the simulator flies when not told otherwise (one of
            ``BACKEND_NAMES``).
        px4_params: (name, value) PX4 parameters the flight controller uses instead of its
            defaults (MPC_THR_HOVER excluded: it follows from mass and rotors).
    """

    preset_name: str
    vehicle: VehicleSpec
    effects: tuple[Effect, ...] = ()
    physics_dt_s: float = 0.002
    backend: str = "builtin"
    px4_params: tuple[tuple[str, float], ...] = ()
    effect_names: tuple[str, ...] = field(init=False)

    def __post_init__(self) -> None:
        _check_choice("sim.backend", self.backend, BACKEND_NAMES)
        names = tuple(e.name for e in self.effects)
        dup = sorted({n for n in names if names.count(n) > 1})
        if dup:
            raise SimConfigError(f"effects.{dup[0]}: given twice; keep one {dup[0]} entry")
        for name, cls in EFFECT_CLASSES.items():
            through = cls.ACTS_THROUGH
            if name in names and through and not set(through) & set(names):
                raise SimConfigError(
                    f"effects.{name}: acts only through drag; also enable "
                    f"{', '.join(through[:-1])} or {through[-1]}"
                )
        v = self.vehicle
        if v.hover_thrust_norm > 0.8:
            raise SimConfigError(
                f"vehicle.thrust_coeff_n_per_radps2: the rotors give only "
                f"{1 / v.hover_thrust_norm:.2f} x the weight of mass_kg = {v.mass_kg}; "
                "raise the coefficient or rotor_max_speed_radps (needs > 1.25)"
            )
        if v.battery_empty_v >= v.battery_full_v:
            raise SimConfigError(
                f"battery.empty_v = {v.battery_empty_v} must be below full_v = "
                f"{v.battery_full_v}; swap or fix the voltages"
            )
        object.__setattr__(self, "effect_names", names)

    @property
    def mass_kg(self) -> float:
        """Nominal mass [kg] (what the preset says; a payload effect is not included)."""
        return self.vehicle.mass_kg

    def effect(self, name: str) -> Effect | None:
        """The enabled effect called ``name``, or None."""
        return next((e for e in self.effects if e.name == name), None)

    def with_effects(
        self, effects: Mapping[str, Mapping[str, Any] | None] | Iterable[Effect]
    ) -> SimConfig:
        """A copy with these effects added (replacing any of the same name)."""
        new = _build_effects(effects)
        names = {e.name for e in new}
        kept = tuple(e for e in self.effects if e.name not in names)
        return replace(self, effects=kept + new)

    def without_effects(self, *names: str) -> SimConfig:
        """A copy with the named effects switched off."""
        for n in names:
            if n not in EFFECT_NAMES:
                raise SimConfigError(f"effects.{n}: unknown effect; choose from {EFFECT_NAMES}")
        return replace(self, effects=tuple(e for e in self.effects if e.name not in names))


def no_such_config(src: str, others: str = "") -> str:
    """The line for a ``src`` that is neither a preset nor a config file; ``others``: more
    names the caller also takes, in words (vehicle-sim's rovers)."""
    presets = ", ".join(PRESET_NAMES)
    if others:
        return (
            f"{src}: no such config file or preset; use a multirotor ({presets}), {others} or "
            "the path of a TOML file"
        )
    return f"{src}: no such config file or preset; use one of {presets} or the path of a TOML file"


def load_sim_config(
    path_or_preset_name: str | Path,
    effects: Mapping[str, Mapping[str, Any] | None] | Iterable[Effect] | None = None,
) -> SimConfig:
    """Load a preset by name (a file in ``presets/``: "iris", "m100") or a TOML file, then add
    ``effects``.

    Args:
        path_or_preset_name: a preset name or the path of a config TOML file.
        effects: effect name -> parameter mapping ({} for the defaults; ``enabled = false``
            to switch one off), or effect objects; these override effects in the file.

    Raises:
        SimConfigError: one line naming the bad key and the fix.
    """
    src = str(path_or_preset_name)
    if src in PRESET_NAMES:
        path = PRESET_DIR / f"{src}.toml"
    else:
        path = Path(src)
        if not path.is_file():
            raise SimConfigError(no_such_config(src))
    try:
        doc = tomllib.loads(path.read_text())
    except (UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        if path.suffix.lower() in FLIGHT_LOG_SUFFIXES:  # the log given where its config goes
            raise SimConfigError(
                f"{path}: a flight log, not a sim config; make a config from it with "
                f"vehicle-sim config-from-log {path} --out my_vehicle.toml"
            ) from None
        if isinstance(exc, UnicodeDecodeError):
            raise SimConfigError(
                f"{path}: a binary file, not a config TOML; use one of "
                f"{', '.join(PRESET_NAMES)} or the path of a TOML file"
            ) from None
        raise SimConfigError(f"{path}: not valid TOML ({exc}); fix the syntax") from None
    try:
        config = config_from_mapping(doc, preset_name=path.stem)
    except SimConfigError as exc:  # say which file: a user may pass several
        raise SimConfigError(f"{src}: {exc}") from None
    if effects is not None:
        config = config.with_effects(effects)
    return config


def config_from_mapping(doc: Mapping[str, Any], preset_name: str) -> SimConfig:
    """Validate a parsed config document (see module docstring) and build the config."""
    sections = ", ".join([*_SCHEMA, "px4_params", "effects"])
    for key, kind in _OTHER_FILE_KINDS.items():
        if key in doc:
            raise SimConfigError(
                f"{kind} ([{key}]), not a simulation config; pass a preset "
                f"({', '.join(PRESET_NAMES)}) or a config TOML with the sections {sections}"
            )
    for section in doc:
        if section not in _SCHEMA and section not in ("effects", "px4_params"):
            raise SimConfigError(f"{section}: unknown section; use {sections}")
    values = {s: _section(doc, s) for s in _SCHEMA}
    veh, rot, bat = values["vehicle"], values["rotors"], values["battery"]
    vehicle = VehicleSpec(
        mass_kg=veh["mass_kg"],
        inertia_kgm2=veh["inertia_kgm2"],
        rotor_max_speed_radps=veh["rotor_max_speed_radps"],
        thrust_coeff_n_per_radps2=veh["thrust_coeff_n_per_radps2"],
        torque_coeff_nm_per_radps2=veh["torque_coeff_nm_per_radps2"],
        motor_time_constant_s=veh["motor_time_constant_s"],
        rotor_positions_frd_m=rot["positions_frd_m"],
        rotor_spin=rot["spin"],
        battery_full_v=bat["full_v"],
        battery_empty_v=bat["empty_v"],
    )
    effects_doc = doc.get("effects", {})
    if not isinstance(effects_doc, Mapping):
        raise SimConfigError("effects: expected tables [effects.<name>]; see presets/iris.toml")
    return SimConfig(
        preset_name=preset_name,
        vehicle=vehicle,
        effects=_build_effects(effects_doc),
        physics_dt_s=values["sim"].get("physics_dt_s", 0.002),
        backend=values["sim"].get("backend", "builtin"),
        px4_params=_px4_params(doc.get("px4_params", {})),
    )


def _px4_params(table: Any) -> tuple[tuple[str, float], ...]:
    """Validate ``[px4_params]``: known PX4 names, finite numbers of the parameter's type within
    PX4's bounds; MPC_THR_HOVER refused."""
    from vehicle_sim.params import PX4_PARAMS

    if not isinstance(table, Mapping):
        raise SimConfigError("px4_params: expected a table of NAME = number")
    out = []
    for name, value in table.items():
        if name == "MPC_THR_HOVER":
            raise SimConfigError(
                "px4_params.MPC_THR_HOVER: follows from vehicle.mass_kg and the rotors; "
                "set the mass instead"
            )
        if name not in PX4_PARAMS:
            near = difflib.get_close_matches(name, list(PX4_PARAMS), n=1)
            hint = f"did you mean {near[0]}? " if near else ""
            raise SimConfigError(f"px4_params.{name}: unknown parameter; {hint}see params.py")
        if (
            isinstance(value, bool)
            or not isinstance(value, (int, float))
            or not math.isfinite(value)
        ):
            raise SimConfigError(f"px4_params.{name}: {value!r} is not a finite number")
        try:
            PX4_PARAMS[name].check(name, float(value))
        except ValueError as exc:
            raise SimConfigError(f"px4_params.{name}: {exc}; set a value PX4 accepts") from None
        out.append((name, float(value)))
    return tuple(sorted(out))


def _build_effects(
    effects: Mapping[str, Mapping[str, Any] | None] | Iterable[Effect],
) -> tuple[Effect, ...]:
    if not isinstance(effects, Mapping):
        out = tuple(effects)
        for e in out:
            if getattr(e, "name", None) not in EFFECT_NAMES:
                raise SimConfigError(
                    f"effects: {e!r} is not an effect; use the classes in vehicle_sim.effects"
                )
        return out
    built = []
    for name, values in effects.items():
        if isinstance(values, Mapping) and "enabled" in values:
            if not isinstance(values["enabled"], bool):
                raise SimConfigError(
                    f"effects.{name}.enabled: expected true or false, got {values['enabled']!r}"
                )
            if not values["enabled"]:
                if name not in EFFECT_NAMES:
                    raise SimConfigError(
                        f"effects.{name}: unknown effect; choose from {', '.join(EFFECT_NAMES)}"
                    )
                continue
        built.append(make_effect(name, values))
    return tuple(built)


def _section(doc: Mapping[str, Any], section: str) -> dict[str, Any]:
    schema = _SCHEMA[section]
    choices = _CHOICES.get(section, {})
    table = doc.get(section, {})
    if not isinstance(table, Mapping):
        raise SimConfigError(f"{section}: expected a table [{section}], got {table!r}")
    known = [*schema, *choices]
    for key in table:
        if key not in known:
            close = difflib.get_close_matches(key, known, n=1, cutoff=0.5)
            hint = f"did you mean {close[0]}? " if close else ""
            raise SimConfigError(
                f"{section}.{key}: unknown key; {hint}keys carry their unit: {', '.join(known)}"
            )
    out: dict[str, Any] = {
        key: _check_choice(f"{section}.{key}", table[key], names)
        for key, names in choices.items()
        if key in table
    }
    for key, (kind, lo, hi, unit, required) in schema.items():
        if key not in table:
            if required:
                raise SimConfigError(
                    f"{section}.{key} is missing; add {key} = <value in {unit}> under [{section}]"
                )
            continue
        out[key] = _check(f"{section}.{key}", table[key], kind, lo, hi, unit)
    return out


def _check_choice(where: str, value: Any, names: tuple[str, ...]) -> str:
    """``value`` if it is one of ``names``; else SimConfigError listing them."""
    if not isinstance(value, str) or value not in names:
        raise SimConfigError(f"{where} = {value!r} is unknown; choose one of {', '.join(names)}")
    return value


def _check(where: str, value: Any, kind: str, lo: float, hi: float, unit: str) -> Any:
    def number(v: Any) -> float:
        if isinstance(v, bool) or not isinstance(v, (int, float)):
            raise SimConfigError(
                f"{where}: expected a number in {unit}, got {type(v).__name__} {v!r}; "
                f"write a plain number like {lo}"
            )
        f = float(v)
        if not (math.isfinite(f) and lo <= f <= hi):
            raise SimConfigError(
                f"{where} = {value!r} is out of range; use a value in [{lo}, {hi}] {unit}"
            )
        return f

    def vec(v: Any, n: int, what: str) -> tuple:
        if not isinstance(v, list) or len(v) != n:
            raise SimConfigError(f"{where}: expected {what} in {unit}, got {value!r}")
        return tuple(v)

    if kind == "float":
        return number(value)
    if kind == "vec3":
        return tuple(number(v) for v in vec(value, 3, "a list of 3 numbers"))
    if kind == "vec3x4":
        rows = vec(value, 4, "4 rotor positions [x, y, z]")
        return tuple(tuple(number(v) for v in vec(r, 3, "[x, y, z] per rotor")) for r in rows)
    spins = vec(value, 4, "4 spin directions (+1 or -1)")
    if any(s not in (1, -1) or isinstance(s, bool) for s in spins):
        raise SimConfigError(f"{where}: each spin must be 1 or -1, got {value!r}")
    return tuple(int(s) for s in spins)
