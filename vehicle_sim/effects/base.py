"""What every effect is: a frozen dataclass of documented, validated parameters that owns its
physics, its diagnosis search and what it takes to identify it.

An effect class subclasses :class:`Effect` and declares

- ``name`` (from the fixed vocabulary of docs/design.md section 4) and ``VEHICLE``,
- ``PARAMS``: one :class:`ParamSpec` per field, with unit, default and valid range; a spec's
  ``search`` (:class:`Search`) is the range the diagnosis searches, inside the valid range, so
  config validation and the diagnosis read their bounds from the same place; its ``typical``
  the range real vehicles show (hidden effects in the diagnosis' tests are drawn from it),
- ``ROLE``: how the diagnosis treats it (:data:`ROLES`),
- ``NEEDS``: what a log must hold to identify it (:data:`REQUIREMENTS`), ``EXCITE``: what to
  fly to excite it, ``ACTS_THROUGH``/``FIT_WITH``: effects it needs to act at all,
- its physics: ``pack(ep)`` for the jitted simulator (:mod:`.layout`), and the same equations
  in NumPy (``air_velocity_ned``, ``drag_force_body``, ``thrust_factor``, ``mass_ratio_of``) for
  the diagnosis' force model; or ``terrain`` for a rover effect.

Construction from code (``RotorDrag(k_n_per_mps=(0.3, 0.3, 0.1))``) and from a config mapping
(:func:`effect_from_mapping`) run the same validation, so a bad value gives the same one-line
error either way.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any, ClassVar

import numpy as np


class SimConfigError(ValueError):
    """A simulator config that cannot be used; one line naming the key and the fix."""


@dataclass(frozen=True)
class Search:
    """How the diagnosis searches one parameter.

    Attributes:
        lo, hi: search bounds (per component), inside the parameter's valid range.
        start: start value (scalar or per component) of a least-squares fit.
        warm: start from the config's own value when the config has the effect.
        free: leading components searched; the rest are held at 0 (wind: horizontal only).
            None: all.
        grid: > 0 for a replay-searched parameter: the number of grid points tried first.
        geometric: the grid is spaced geometrically (else linearly).
    """

    lo: float
    hi: float
    start: float | tuple[float, ...] = 0.0
    warm: bool = False
    free: int | None = None
    grid: int = 0
    geometric: bool = False

    def grid_values(self) -> np.ndarray:
        """(grid,) the values a replay search tries first."""
        space = np.geomspace if self.geometric else np.linspace
        return space(self.lo, self.hi, self.grid)


@dataclass(frozen=True)
class ParamSpec:
    """One effect parameter.

    Attributes:
        name: field name, with its unit as suffix (``k_n_per_mps``).
        unit: human-readable unit.
        size: 1 for a scalar, 2 or 3 for a vector.
        lo, hi: inclusive valid range (per component).
        doc: what it means.
        search: how the diagnosis searches it (None: not searched).
        typical: (lo, hi) range on real vehicles, one pair for all components or one per
            component; hidden effects in the diagnosis' tests are drawn from it (None: the
            default is kept).
    """

    name: str
    unit: str
    size: int
    lo: float
    hi: float
    doc: str
    search: Search | None = None
    typical: tuple[float, float] | tuple[tuple[float, float], ...] | None = None

    def __post_init__(self) -> None:
        s = self.search
        if s is not None and not self.lo <= s.lo < s.hi <= self.hi:
            raise ValueError(
                f"{self.name}: search range [{s.lo}, {s.hi}] outside [{self.lo}, {self.hi}]"
            )

    def typical_ranges(self) -> tuple[tuple[float, float], ...]:
        """(size,) (lo, hi) pairs of the typical range per component; () without one."""
        t = self.typical
        if t is None:
            return ()
        pairs = t if isinstance(t[0], tuple) else (t,) * self.size
        return tuple((float(lo), float(hi)) for lo, hi in pairs)


ROLES = {
    "force": "fitted to the force residual by the diagnosis' NumPy force model",
    "command": "fitted by replaying the simulator itself (one implementation)",
    "disturbance": "random or position-bound air; not fitted, the diagnosis reports what it leaves",
    "terrain": "a rover's terrain effect (``terrain`` method); no diagnosis yet",
}
# What a log must hold to identify an effect (the multirotor ones are checked by
# diagnosis.identifiability; the rover has no diagnosis yet).
REQUIREMENTS = {
    "thrust": "a total rotor thrust column (the force residual needs it)",
    "speed_span": "horizontal speeds spanning several m/s",
    "crossing_headings": "flight in at least two crossing directions",
    "near_ground": "altitude changes below two rotor radii",
    "voltage_drop": "a battery voltage that falls",
    "setpoint_steps": "sharp velocity setpoint steps",
    "ground_speed_span": "driving at several speeds",
    "turns": "turns of several curvatures",
    "drive_over": "driving over the place it acts, in several headings",
}


class Effect:
    """Base of every effect class (see module docstring); its physics hooks are neutral.

    NumPy hooks (n rows, the same equations as the jitted simulator, :mod:`vehicle_sim.physics`):
    None means "no contribution", so a neutral effect changes no arithmetic.
    """

    name: ClassVar[str]
    PARAMS: ClassVar[tuple[ParamSpec, ...]]
    VEHICLE: ClassVar[str] = "multirotor"
    ROLE: ClassVar[str]
    NEEDS: ClassVar[tuple[str, ...]]
    EXCITE: ClassVar[str]
    ACTS_THROUGH: ClassVar[tuple[str, ...]] = ()
    FIT_WITH: ClassVar[str | None] = None

    def pack(self, ep: np.ndarray) -> None:
        """Write this effect's parameters into the packed vector ``ep`` (shape (N_EFFECT,))."""

    def air_velocity_ned(self, pos_ned_m: np.ndarray) -> np.ndarray | None:
        """(n, 3) air velocity over ground [m/s] this effect adds at positions (n, 3) [m]."""
        return None

    def drag_force_body(self, air_body_mps: np.ndarray) -> np.ndarray | None:
        """(n, 3) body FRD force [N] on the body air-relative velocity (n, 3) [m/s]."""
        return None

    def thrust_factor(self, alt_m: np.ndarray, discharge: np.ndarray) -> np.ndarray | None:
        """(n,) true / nominal rotor thrust at altitude (n,) [m] and battery discharge (n,)."""
        return None

    def mass_ratio_of(self) -> float:
        """True mass / nominal mass this effect makes."""
        return 1.0

    @classmethod
    def draw_typical(cls, rng: np.random.Generator) -> dict[str, float | list[float]]:
        """Parameters drawn uniformly, component by component, from their ``typical`` ranges
        (the others keep their defaults): a hidden effect as a real vehicle might have it."""
        out: dict[str, float | list[float]] = {}
        for spec in cls.PARAMS:
            ranges = spec.typical_ranges()
            if ranges:
                values = [float(rng.uniform(lo, hi)) for lo, hi in ranges]
                out[spec.name] = values[0] if spec.size == 1 else values
        return out


def check_value(spec: ParamSpec, value: Any, where: str) -> float | tuple[float, ...]:
    """Validate one parameter value against its spec; returns it as float or tuple of floats."""
    if spec.size == 1:
        if isinstance(value, bool) or not isinstance(value, (int, float, np.floating)):
            raise SimConfigError(
                f"{where}.{spec.name}: expected a number in {spec.unit}, got "
                f"{type(value).__name__} {value!r}; write e.g. {spec.name} = {spec.lo}"
            )
        items: tuple[float, ...] = (float(value),)
    else:
        ok = isinstance(value, (list, tuple, np.ndarray)) and len(value) == spec.size
        ok = ok and all(
            not isinstance(v, bool) and isinstance(v, (int, float, np.floating)) for v in value
        )
        if not ok:
            raise SimConfigError(
                f"{where}.{spec.name}: expected a list of {spec.size} numbers in {spec.unit}, "
                f"got {value!r}; write e.g. {spec.name} = [{spec.lo}, {spec.lo}, {spec.lo}]"
            )
        items = tuple(float(v) for v in value)
    for v in items:
        if not (math.isfinite(v) and spec.lo <= v <= spec.hi):
            raise SimConfigError(
                f"{where}.{spec.name} = {value!r} is out of range; use values in "
                f"[{spec.lo}, {spec.hi}] {spec.unit} ({spec.doc})"
            )
    return items[0] if spec.size == 1 else items


def validate_effect(effect: Any) -> None:
    """Check every declared parameter of a constructed effect (call from ``__post_init__``)."""
    where = f"effects.{effect.name}"
    for spec in effect.PARAMS:
        value = check_value(spec, getattr(effect, spec.name), where)
        object.__setattr__(effect, spec.name, value)


def effect_from_mapping(cls: type, values: Mapping[str, Any]) -> Any:
    """Build effect ``cls`` from a config mapping; unknown keys and bad values raise."""
    where = f"effects.{cls.name}"
    known = {spec.name: spec for spec in cls.PARAMS}
    kwargs: dict[str, Any] = {}
    for key, value in values.items():
        if key == "enabled":
            continue
        if key not in known:
            raise SimConfigError(
                f"{where}.{key}: unknown parameter; {cls.name} takes "
                f"{', '.join(f'{s.name} [{s.unit}]' for s in cls.PARAMS)}"
            )
        kwargs[key] = check_value(known[key], value, where)
    return cls(**kwargs)


def effect_as_mapping(effect: Any) -> dict[str, float | list[float]]:
    """The effect's parameters as a plain mapping (the inverse of :func:`effect_from_mapping`)."""
    out: dict[str, float | list[float]] = {}
    for f in fields(effect):
        v = getattr(effect, f.name)
        out[f.name] = list(v) if isinstance(v, tuple) else v
    return out
