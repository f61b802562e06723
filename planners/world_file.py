"""Obstacle worlds as files (TOML), read by the simulator's CLI and the companion alike.

A world file looks like this (local NED, metres; vertical cylinders stand on the ground and
reach above any flight, as the trees of [Kulathunga23]'s forest)::

    name = "forest_seed3"
    [[cylinder]]
    center_ne_m = [12.0, 4.5]
    radius_m = 0.35
    [[sphere]]
    center_ned_m = [5.0, 0.0, -2.0]
    radius_m = 0.5
    [[box]]
    center_ned_m = [20.0, 0.0, -1.0]
    half_extents_m = [0.5, 3.0, 1.0]

Parsing is pure (``parse_world``); ``load_world`` adds the read and ``save_world`` the atomic
write. Every problem raises :class:`WorldFileError`, one line naming the file and the fix.
"""

from __future__ import annotations

import math
import tomllib
from pathlib import Path

import tomli_w

from flightlog.atomic_output import write_text_atomic
from planners.obstacles import Box, Cylinder, Obstacle, ObstacleWorld, Sphere

_KINDS = {
    "cylinder": (
        {"center_ne_m": 2, "radius_m": 0},
        lambda t: Cylinder(t["center_ne_m"], t["radius_m"]),
    ),
    "sphere": (
        {"center_ned_m": 3, "radius_m": 0},
        lambda t: Sphere(t["center_ned_m"], t["radius_m"]),
    ),
    "box": (
        {"center_ned_m": 3, "half_extents_m": 3},
        lambda t: Box(t["center_ned_m"], t["half_extents_m"]),
    ),
}
_POSITIVE = {"radius_m", "half_extents_m"}


class WorldFileError(ValueError):
    """A world file that cannot be used; one line naming the file and the fix."""


def load_world(path: str | Path) -> ObstacleWorld:
    """Read and validate a world file; WorldFileError (one line) on any problem."""
    path = Path(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise WorldFileError(f"{path}: no such world file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise WorldFileError(f"{path}: cannot read world file ({exc})") from None
    return parse_world(text, source=str(path))


def parse_world(text: str, source: str = "<world>") -> ObstacleWorld:
    """Validate world TOML text (see the module docstring); ``source`` names it in errors."""
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise WorldFileError(f"{source}: not valid TOML ({exc})") from None
    unknown = sorted(set(raw) - {"name", *_KINDS})
    if unknown:
        raise WorldFileError(
            f"{source}: unknown key {unknown[0]!r}; known: name, {', '.join(_KINDS)}"
        )
    obstacles: list[Obstacle] = []
    for kind, (fields, make) in _KINDS.items():
        tables = raw.get(kind, [])
        if not isinstance(tables, list):
            raise WorldFileError(f"{source}: {kind} must be an array of tables ([[{kind}]])")
        for i, table in enumerate(tables):
            obstacles.append(make(_fields(table, fields, f"{source}: {kind}[{i}]")))
    return ObstacleWorld(obstacles)


def _fields(table: object, fields: dict[str, int], where: str) -> dict[str, object]:
    if not isinstance(table, dict) or set(table) != set(fields):
        raise WorldFileError(f"{where} needs exactly the keys {', '.join(fields)}")
    out: dict[str, object] = {}
    for key, size in fields.items():
        value = table[key]
        values = value if size else [value]
        ok = (
            isinstance(values, list)
            and len(values) == max(size, 1)
            and all(isinstance(v, int | float) and not isinstance(v, bool) for v in values)
            and all(math.isfinite(v) for v in values)
        )
        if ok and key in _POSITIVE:
            ok = all(v > 0 for v in values)
        if not ok:
            what = f"{size} finite numbers" if size else "a finite number"
            sign = " (> 0)" if key in _POSITIVE else ""
            raise WorldFileError(f"{where}.{key} = {value!r}; expected {what}{sign}")
        out[key] = tuple(float(v) for v in values) if size else float(value)
    return out


def world_text(world: ObstacleWorld, name: str = "world") -> str:
    """The TOML text of ``world`` (inverse of parse_world)."""
    doc: dict[str, object] = {"name": name}
    for o in world.obstacles:
        if isinstance(o, Cylinder):
            row, kind = {"center_ne_m": list(o.center_ne_m), "radius_m": o.radius_m}, "cylinder"
        elif isinstance(o, Sphere):
            row, kind = {"center_ned_m": list(o.center_ned_m), "radius_m": o.radius_m}, "sphere"
        else:
            row = {"center_ned_m": list(o.center_ned_m), "half_extents_m": list(o.half_extents_m)}
            kind = "box"
        doc.setdefault(kind, []).append(row)  # type: ignore[union-attr]
    return tomli_w.dumps(doc)


def save_world(path: str | Path, world: ObstacleWorld, name: str = "world") -> Path:
    """Write ``world`` to ``path`` atomically; returns the path."""
    return write_text_atomic(path, world_text(world, name))
