"""Excitation flights: a mission file of segments -> velocity setpoints over time.

A flight that reveals the effects of the vocabulary needs speed sweeps in several headings
(drag, wind), altitude steps close to the ground (ground effect), long hover (battery sag,
payload), yaw changes and sharp setpoint steps (command delay, motor lag). A mission file
(``missions/excite_*.toml``) lists segments, flown one after the other::

    name = "excite_full"
    takeoff_alt_m = 2.5

    [[segment]]
    kind = "velocity"        # constant NED velocity setpoint
    duration_s = 3.0
    speed_mps = 4.0          # horizontal speed
    heading_deg = 90.0       # direction of travel, clockwise from north
    climb_mps = 0.0          # vertical speed, up positive
    yaw_rate_degps = 0.0

    [[segment]]
    kind = "altitude"        # go to and hold an altitude above the ground (P control)
    duration_s = 4.0
    alt_m = 0.08

``hover`` segments hold zero velocity (only ``duration_s``).
"""

from __future__ import annotations

import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

SegmentKind = Literal["hover", "velocity", "altitude"]
SEGMENT_KINDS: tuple[str, ...] = ("hover", "velocity", "altitude")
ALT_GAIN_PER_S = 1.0  # altitude P gain [1/s] of ``altitude`` segments
ALT_MAX_SPEED_MPS = 0.6  # vertical speed limit of ``altitude`` segments


class ExcitationError(ValueError):
    """An excitation mission that cannot be flown; one line naming the key and the fix."""


@dataclass(frozen=True)
class Segment:
    """One part of an excitation flight (see module docstring for the meaning of fields)."""

    kind: SegmentKind
    duration_s: float
    speed_mps: float = 0.0
    heading_deg: float = 0.0
    climb_mps: float = 0.0
    yaw_rate_degps: float = 0.0
    alt_m: float = 0.0


@dataclass(frozen=True)
class ExcitationSchedule:
    """A whole excitation flight: take off to ``takeoff_alt_m`` [m], then fly ``segments``."""

    name: str
    takeoff_alt_m: float
    segments: tuple[Segment, ...]

    @property
    def duration_s(self) -> float:
        """Time in OFFBOARD [s]."""
        return sum(s.duration_s for s in self.segments)

    def setpoint(self, t_s: float, alt_m: float) -> tuple[tuple[float, float, float], float]:
        """(velocity NED [m/s], yaw rate [rad/s]) at ``t_s`` after the start, given the
        measured altitude ``alt_m`` [m] (used by ``altitude`` segments)."""
        seg = self.segments[-1]
        start = 0.0
        for s in self.segments:
            if t_s < start + s.duration_s:
                seg = s
                break
            start += s.duration_s
        if seg.kind == "altitude":
            climb = ALT_GAIN_PER_S * (seg.alt_m - alt_m)
            climb = min(max(climb, -ALT_MAX_SPEED_MPS), ALT_MAX_SPEED_MPS)
            return (0.0, 0.0, -climb), 0.0
        heading = math.radians(seg.heading_deg)
        vel = (seg.speed_mps * math.cos(heading), seg.speed_mps * math.sin(heading), -seg.climb_mps)
        return vel, math.radians(seg.yaw_rate_degps)


def schedule_from_mapping(doc: Mapping[str, Any], where: str = "mission") -> ExcitationSchedule:
    """Validate a parsed excitation mission (see module docstring)."""
    segments = doc.get("segment")
    if not isinstance(segments, list) or not segments:
        raise ExcitationError(f"{where}: no [[segment]] tables; add at least one segment")
    out = []
    for i, raw in enumerate(segments):
        at = f"{where}: segment {i + 1}"
        if not isinstance(raw, Mapping):
            raise ExcitationError(f"{at}: expected a table, got {raw!r}")
        kind = raw.get("kind")
        if kind not in SEGMENT_KINDS:
            raise ExcitationError(f"{at}: kind {kind!r} unknown; use one of {SEGMENT_KINDS}")
        unknown = set(raw) - {"kind", *Segment.__dataclass_fields__}
        if unknown:
            raise ExcitationError(f"{at}: unknown keys {sorted(unknown)}")
        values = {k: _number(raw[k], f"{at}.{k}") for k in raw if k != "kind"}
        if values.get("duration_s", 0.0) <= 0.0:
            raise ExcitationError(f"{at}: duration_s must be given and > 0")
        if values.get("alt_m", 0.0) < 0.0:
            raise ExcitationError(f"{at}: alt_m must be >= 0 (height above the ground)")
        out.append(Segment(kind=kind, **values))
    alt = _number(doc.get("takeoff_alt_m", 2.5), f"{where}: takeoff_alt_m")
    if not 0.5 <= alt <= 50.0:
        raise ExcitationError(f"{where}: takeoff_alt_m = {alt} outside [0.5, 50] m")
    return ExcitationSchedule(str(doc.get("name", where)), alt, tuple(out))


def load_schedule(path: str | Path) -> ExcitationSchedule:
    """Read an excitation mission file (TOML)."""
    path = Path(path)
    try:
        doc = tomllib.loads(path.read_text())
    except (OSError, tomllib.TOMLDecodeError) as exc:
        raise ExcitationError(f"{path}: cannot read excitation mission ({exc})") from None
    return schedule_from_mapping(doc, str(path))


def _number(value: Any, where: str) -> float:
    if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
        raise ExcitationError(f"{where}: expected a finite number, got {value!r}")
    return float(value)
