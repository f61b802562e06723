"""Mission files: what to fly, as TOML.

A mission file looks like this (units in the names; NED, so altitude is -down)::

    name = "line_20m"
    altitude_m = 2.5           # takeoff altitude above the origin [m]
    speed_limit_mps = 2.0      # reference speed and horizontal command limit [m/s]
    command_limit_mps = 3.0    # optional: a higher horizontal command limit [m/s], headroom
                               # for a planner that leads a lagging vehicle
    repeats = 1                # how many times the reference is flown (optional, default 1)
    goal_tolerance_m = 0.3     # "arrived" radius at the goal (optional, default 0.3)
    endurance_s = 900.0        # optional: the vehicle's hover time on a full battery [s];
                               # a mission longer than it allows is refused before take-off
    obstacles_world = "w.toml" # optional obstacle world (planners/world_file.py), relative
                               # to the mission file; flown only by a planner that honours
                               # obstacles (nmpc_clutter), refused otherwise

    [reference]
    kind = "waypoints"         # "waypoints" (straight legs) or "bspline" (spline through them)
    points_ned_m = [[0.0, 0.0, -2.5], [20.0, 0.0, -2.5]]

Parsing is pure (`parse_mission` takes the text); `load_mission` adds the file read. Every
problem raises `MissionError` with one line naming the file and the fix.
"""

from __future__ import annotations

import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Literal, get_args

ReferenceKind = Literal["waypoints", "bspline"]
REFERENCE_KINDS: tuple[str, ...] = get_args(ReferenceKind)

_TOP_KEYS = {
    "name", "altitude_m", "speed_limit_mps", "command_limit_mps", "repeats", "goal_tolerance_m",
    "endurance_s",
    "obstacles_world", "reference",
}  # fmt: skip
_REFERENCE_KEYS = {"kind", "points_ned_m"}


class MissionError(ValueError):
    """A mission file that cannot be flown; the message is one line naming the file."""


@dataclass(frozen=True)
class Mission:
    """A validated mission.

    Attributes:
        name: mission name (for logs).
        altitude_m: takeoff altitude above the origin [m], > 0.
        speed_limit_mps: reference speed and horizontal command limit [m/s], > 0.
        reference_kind: "waypoints" (straight legs at constant speed) or "bspline" (cubic
            B-spline through the points, starting and ending at rest).
        points_ned_m: (N, 3) points the reference passes through, local NED [m], repeats
            already unrolled.
        goal_tolerance_m: radius around the goal counted as arrived [m].
        obstacles_world: obstacle world file, or None.
        repeats: how many times the points were repeated.
        command_limit_mps: horizontal command limit [m/s] if above the reference speed, else
            None (the reference speed is the limit). A vehicle lags its velocity command, so a
            planner commanding exactly the reference speed falls behind a reference moving at
            it; the headroom lets a planner that knows the lag (a learned model) lead.
        endurance_s: the vehicle's hover time on a full battery [s], if the user gives it.
    """

    name: str
    altitude_m: float
    speed_limit_mps: float
    reference_kind: ReferenceKind
    points_ned_m: tuple[tuple[float, float, float], ...]
    goal_tolerance_m: float = 0.3
    obstacles_world: Path | None = None
    repeats: int = 1
    command_limit_mps: float | None = None
    endurance_s: float | None = None

    @property
    def horizontal_command_limit_mps(self) -> float:
        """The horizontal command limit [m/s]: command_limit_mps, else speed_limit_mps."""
        return self.speed_limit_mps if self.command_limit_mps is None else self.command_limit_mps

    @property
    def goal_ned_m(self) -> tuple[float, float, float]:
        """The last point: where the vehicle should end up."""
        return self.points_ned_m[-1]


def load_mission(path: str | Path) -> Mission:
    """Read and validate a mission file; raises MissionError (one line) on any problem."""
    path = Path(path)
    try:
        text = path.read_text()
    except FileNotFoundError:
        raise MissionError(f"{path}: no such mission file") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise MissionError(f"{path}: cannot read mission file ({exc})") from None
    return parse_mission(text, source=path)


def parse_mission(text: str, source: Path | str = "<mission>") -> Mission:
    """Validate mission TOML text; ``source`` names it in errors and anchors relative paths."""
    where = str(source)
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise MissionError(f"{where}: not valid TOML ({exc})") from None
    if "segment" in raw and "reference" not in raw:
        raise MissionError(
            f"{where}: an excitation schedule ([[segment]] tables), not a companion mission: the "
            "diagnosis flies it (diagnosis.fly_schedule in process, experiments."
            "mavlink_excitation over MAVLink); on a real vehicle fly its shapes in OFFBOARD "
            "(diagnosis/README.md)"
        )
    _no_unknown_keys(raw, _TOP_KEYS, where, "")
    ref = raw.get("reference")
    if not isinstance(ref, dict):
        raise MissionError(f"{where}: missing [reference] table with kind and points_ned_m")
    _no_unknown_keys(ref, _REFERENCE_KEYS, where, "reference.")
    kind = ref.get("kind", "waypoints")
    if kind not in REFERENCE_KINDS:
        raise MissionError(
            f"{where}: reference.kind {kind!r} is not known; choose one of "
            f"{', '.join(REFERENCE_KINDS)}"
        )
    repeats = _positive_int(raw.get("repeats", 1), where, "repeats")
    points = _points(ref.get("points_ned_m"), where, minimum=2)
    obstacles = raw.get("obstacles_world")
    if obstacles is not None and not isinstance(obstacles, str):
        raise MissionError(f"{where}: obstacles_world must be a file name string")
    base = Path(source).parent if isinstance(source, Path) else Path(".")
    speed = _positive(raw.get("speed_limit_mps"), where, "speed_limit_mps")
    command_limit = raw.get("command_limit_mps")
    if command_limit is not None:
        command_limit = _positive(command_limit, where, "command_limit_mps")
        if command_limit < speed:
            raise MissionError(
                f"{where}: command_limit_mps {command_limit:g} is below speed_limit_mps "
                f"{speed:g}; raise it or leave it out"
            )
    return Mission(
        name=_text(raw.get("name", Path(where).stem), where, "name"),
        altitude_m=_positive(raw.get("altitude_m"), where, "altitude_m"),
        speed_limit_mps=speed,
        reference_kind=kind,
        points_ned_m=points * repeats,
        goal_tolerance_m=_positive(raw.get("goal_tolerance_m", 0.3), where, "goal_tolerance_m"),
        obstacles_world=None if obstacles is None else base / obstacles,
        repeats=repeats,
        command_limit_mps=command_limit,
        endurance_s=(
            None
            if raw.get("endurance_s") is None
            else _positive(raw["endurance_s"], where, "endurance_s")
        ),
    )


def _no_unknown_keys(table: dict, known: set[str], where: str, prefix: str) -> None:
    unknown = sorted(set(table) - known)
    if unknown:
        raise MissionError(
            f"{where}: unknown key {prefix}{unknown[0]}; known keys: "
            f"{', '.join(prefix + k for k in sorted(known))}"
        )


def _positive(value: object, where: str, key: str) -> float:
    if value is None:
        raise MissionError(f"{where}: missing {key} (a positive number)")
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise MissionError(f"{where}: {key} must be a positive number, got {value!r}")
    if not math.isfinite(value) or value <= 0.0:
        raise MissionError(f"{where}: {key} must be a positive number, got {value!r}")
    return float(value)


def _positive_int(value: object, where: str, key: str) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise MissionError(f"{where}: {key} must be an integer >= 1, got {value!r}")
    return value


def _text(value: object, where: str, key: str) -> str:
    if not isinstance(value, str) or not value:
        raise MissionError(f"{where}: {key} must be a non-empty string, got {value!r}")
    return value


def _points(value: object, where: str, minimum: int) -> tuple[tuple[float, float, float], ...]:
    hint = "a list of [north, east, down] triples in metres"
    if not isinstance(value, list) or len(value) < minimum:
        raise MissionError(
            f"{where}: reference.points_ned_m must be {hint}, at least {minimum} of them"
        )
    points = []
    for i, p in enumerate(value):
        ok = (
            isinstance(p, list)
            and len(p) == 3
            and all(isinstance(c, int | float) and not isinstance(c, bool) for c in p)
            and all(math.isfinite(c) for c in p)
        )
        if not ok:
            raise MissionError(f"{where}: reference.points_ned_m[{i}] = {p!r}; expected {hint}")
        if p[2] >= 0.0:
            raise MissionError(
                f"{where}: reference.points_ned_m[{i}] has down = {p[2]} m, at or below the "
                "ground; use a negative down (altitude 3 m is down = -3)"
            )
        points.append((float(p[0]), float(p[1]), float(p[2])))
    return tuple(points)
