"""What every effect is: a frozen dataclass of documented, validated parameters.

An effect class declares ``name`` (from the fixed vocabulary of docs/design.md section 4),
``PARAMS`` (one :class:`ParamSpec` per field, with unit, default and valid range) and
``pack(ep)``, which writes its parameters into the packed vector of :mod:`.layout`.
Construction from code (``RotorDrag(k_n_per_mps=(0.3, 0.3, 0.1))``) and from a config mapping
(:func:`effect_from_mapping`) run the same validation, so a bad value gives the same one-line
error either way.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass, fields
from typing import Any, ClassVar, Protocol

import numpy as np


class SimConfigError(ValueError):
    """A simulator config that cannot be used; one line naming the key and the fix."""


@dataclass(frozen=True)
class ParamSpec:
    """One effect parameter.

    Attributes:
        name: field name, with its unit as suffix (``k_n_per_mps``).
        unit: human-readable unit.
        size: 1 for a scalar, 3 for a per-axis vector.
        lo, hi: inclusive valid range (per component).
        doc: what it means.
    """

    name: str
    unit: str
    size: int
    lo: float
    hi: float
    doc: str


class Effect(Protocol):
    """The role every effect plays (see module docstring)."""

    name: ClassVar[str]
    PARAMS: ClassVar[tuple[ParamSpec, ...]]

    def pack(self, ep: np.ndarray) -> None:
        """Write this effect's parameters into the packed vector ``ep`` (shape (N_EFFECT,))."""


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
