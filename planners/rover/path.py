"""A taught path and localisation relative to its nearest vertex ([Ostafew16] sections 4.1-4.2).

The path is a sequence of vertices (x_m, y_m, heading_rad) about ``spacing_m`` apart, as VT&R
keeps them. It is built from a recorded drive (:meth:`TaughtPath.from_drive`), from segments
(:meth:`TaughtPath.from_segments`: straight runs and arcs), or from a CSV file of ``x_m,y_m``
rows (:meth:`TaughtPath.from_csv_text`). Errors follow [Ostafew16] section 4.2: with x_d the
nearest vertex pose, (e_L, e_H) = [[0,1,0],[0,0,1]] (x_d - x) in the vertex frame, i.e. e_L is
minus the robot's left offset and e_H the heading of the path minus the robot's.
[Ostafew16] records them "when passing the ith vertex" (section 4.2; Figs. 9, 10), where the
robot's projection on the path is the vertex itself; :meth:`TaughtPath.localise_on_path` gives
that measure at every step, against the path pose interpolated at the projection. Against the
nearest vertex alone, e_H carries up to curvature * spacing / 2 of the vertex spacing (0.125 rad
on a 1 1/m turn with 0.25 m vertices) that is no tracking error.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np


def wrap_angle(a: np.ndarray | float) -> np.ndarray | float:
    """Wrap to (-pi, pi]."""
    return np.arctan2(np.sin(a), np.cos(a))


@dataclass(frozen=True)
class PathFix:
    """Localisation of the robot against the path.

    Attributes:
        vertex: index of the nearest vertex (Euclidean).
        s_m: arc length of that vertex plus the along-track offset [m].
        e_lat_m: [Ostafew16]'s e_L [m] (positive when the robot is right of the path).
        e_head_rad: [Ostafew16]'s e_H [rad] (path heading minus robot heading).
    """

    vertex: int
    s_m: float
    e_lat_m: float
    e_head_rad: float


class TaughtPath:
    """Vertices (N, 3) = (x_m, y_m, heading_rad) with arc length s_m (N,)."""

    def __init__(self, xy_m: np.ndarray, spacing_m: float = 0.25) -> None:
        xy = np.asarray(xy_m, dtype=float)
        if xy.ndim != 2 or xy.shape[1] != 2 or xy.shape[0] < 3 or not np.all(np.isfinite(xy)):
            raise ValueError(f"a path needs >= 3 finite (x_m, y_m) rows, got shape {xy.shape}")
        if not spacing_m > 0:
            raise ValueError(f"spacing_m must be > 0, got {spacing_m}")
        seg = np.hypot(*np.diff(xy, axis=0).T)
        keep = np.concatenate([[True], seg > 1e-9])
        xy = xy[keep]
        if xy.shape[0] < 2:
            raise ValueError("a path of zero length (every row the same point) has no heading")
        s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
        n = max(3, int(round(s[-1] / spacing_m)) + 1)
        s_new = np.linspace(0.0, s[-1], n)
        self.xy_m = np.column_stack([np.interp(s_new, s, xy[:, 0]), np.interp(s_new, s, xy[:, 1])])
        d = np.gradient(self.xy_m, axis=0)
        self.heading_rad = np.arctan2(d[:, 1], d[:, 0])
        self._heading_unwrapped = np.unwrap(self.heading_rad)  # for ref_at
        self.s_m = s_new
        self.spacing_m = float(s_new[1] - s_new[0])

    def __len__(self) -> int:
        return self.xy_m.shape[0]

    @property
    def length_m(self) -> float:
        return float(self.s_m[-1])

    def curvature_1pm(self) -> np.ndarray:
        """Curvature at each vertex [1/m], (N,)."""
        dth = np.gradient(np.unwrap(self.heading_rad))
        return dth / self.spacing_m

    @classmethod
    def from_drive(cls, xy_m: np.ndarray, spacing_m: float = 0.25) -> TaughtPath:
        """Teach pass: a recorded drive (positions in time order), resampled by arc length."""
        return cls(xy_m, spacing_m)

    @classmethod
    def from_csv_text(cls, text: str, spacing_m: float = 0.25) -> TaughtPath:
        """Rows ``x_m,y_m`` (a first line of names, e.g. ``x_m,y_m``, is skipped); a malformed
        or non-finite row raises ValueError naming its line."""
        rows = []
        header_allowed = True
        for n, line in enumerate(text.splitlines(), 1):
            if not line.strip():
                continue
            try:
                x, y = (float(v) for v in line.split(",")[:2])
            except ValueError:
                if header_allowed and line.strip()[0].isalpha():
                    header_allowed = False
                    continue
                raise ValueError(f"path line {n}: expected 'x_m,y_m', got {line!r}") from None
            header_allowed = False
            if not (math.isfinite(x) and math.isfinite(y)):
                raise ValueError(f"path line {n}: {line.strip()!r} is not finite")
            rows.append((x, y))
        return cls(np.array(rows), spacing_m)

    @classmethod
    def from_segments(
        cls,
        segments: Sequence[tuple[float, float]],
        start: tuple[float, float, float] = (0.0, 0.0, 0.0),
        spacing_m: float = 0.25,
    ) -> TaughtPath:
        """Segments (length_m, curvature_1pm): curvature 0 is straight, > 0 turns left."""
        x, y, th = start
        pts = [(x, y)]
        step = spacing_m / 4
        for length, curv in segments:
            for _ in range(max(1, int(round(length / step)))):
                x += step * math.cos(th + 0.5 * step * curv)
                y += step * math.sin(th + 0.5 * step * curv)
                th += step * curv
                pts.append((x, y))
        return cls(np.array(pts), spacing_m)

    def pose(self, vertex: int) -> tuple[float, float, float]:
        i = int(np.clip(vertex, 0, len(self) - 1))
        return float(self.xy_m[i, 0]), float(self.xy_m[i, 1]), float(self.heading_rad[i])

    def nearest(self, x_m: float, y_m: float, hint: int = 0, window: int = 40) -> int:
        """Nearest vertex by Euclidean distance, searched in hint-window/4 .. hint+window."""
        lo = max(0, hint - window // 4)
        hi = min(len(self), hint + window + 1)
        d2 = np.sum((self.xy_m[lo:hi] - (x_m, y_m)) ** 2, axis=1)
        return lo + int(np.argmin(d2))

    def localise(
        self, x_m: float, y_m: float, heading_rad: float, hint: int = 0, window: int = 40
    ) -> PathFix:
        """Errors against the nearest vertex (see module docstring), searched as
        :meth:`nearest` does (a loop's end is outside the window of its start when the window
        is less than the loop's vertices)."""
        i = self.nearest(x_m, y_m, hint, window)
        xd, yd, thd = self.pose(i)
        c, s = math.cos(thd), math.sin(thd)
        dx, dy = xd - x_m, yd - y_m
        along = -(c * dx + s * dy)
        e_lat = -s * dx + c * dy
        return PathFix(i, float(self.s_m[i] + along), e_lat, float(wrap_angle(thd - heading_rad)))

    def localise_on_path(
        self, x_m: float, y_m: float, heading_rad: float, hint: int = 0, window: int = 40
    ) -> PathFix:
        """Errors against the path pose at the robot's projection (module docstring).

        ``vertex`` is still the nearest vertex; ``s_m`` is the projection's arc length, refined
        once along the interpolated tangent.
        """
        fix = self.localise(x_m, y_m, heading_rad, hint, window)
        s_m = fix.s_m
        for _ in range(2):
            xr, yr, thr = self.ref_at(np.array([s_m]))[0]
            c, s = math.cos(thr), math.sin(thr)
            dx, dy = xr - x_m, yr - y_m
            s_m = float(np.clip(s_m - (c * dx + s * dy), 0.0, self.length_m))
        e_lat = -s * dx + c * dy
        return PathFix(fix.vertex, s_m, float(e_lat), float(wrap_angle(thr - heading_rad)))

    def ref_at(self, s_m: np.ndarray) -> np.ndarray:
        """Reference poses (n, 3) at arc lengths s_m (n,), clamped to the path."""
        s = np.clip(s_m, 0.0, self.s_m[-1])
        th = self._heading_unwrapped
        return np.column_stack(
            [
                np.interp(s, self.s_m, self.xy_m[:, 0]),
                np.interp(s, self.s_m, self.xy_m[:, 1]),
                wrap_angle(np.interp(s, self.s_m, th)),
            ]
        )


@dataclass(frozen=True)
class LocalisationQuality:
    """Stand-in for VT&R's matched-feature count ([Ostafew16] section 4.2).

    count = max_features * lighting(vertex) * exp(-(e_L/lat_scale)^2 - (e_H/head_scale)^2)
            / (1 + (speed / blur_speed)^2)
    Path-tracking errors change the perspective, speed blurs, dark sections have few features.

    Attributes:
        max_features: count in good light, on the path, at rest.
        lat_scale_m, head_scale_rad: error scales of the perspective loss.
        blur_speed_mps: speed at which motion blur halves the count.
    """

    max_features: float = 120.0
    lat_scale_m: float = 0.5
    head_scale_rad: float = 0.35
    blur_speed_mps: float = 1.5

    def count(self, lighting: float, e_lat_m: float, e_head_rad: float, speed_mps: float) -> float:
        persp = math.exp(
            -((e_lat_m / self.lat_scale_m) ** 2) - (e_head_rad / self.head_scale_rad) ** 2
        )
        blur = 1.0 / (1.0 + (speed_mps / self.blur_speed_mps) ** 2)
        return self.max_features * lighting * persp * blur


def project_arc_length(
    path: TaughtPath, xy_m: np.ndarray, hint: int, window: int = 60
) -> np.ndarray:
    """Arc length (n,) of the nearest vertex plus along-track offset for points (n, 2)."""
    lo = max(0, hint - 5)
    hi = min(len(path), hint + window + 1)
    seg = path.xy_m[lo:hi]
    d2 = np.sum((xy_m[:, None, :] - seg[None, :, :]) ** 2, axis=2)
    idx = lo + np.argmin(d2, axis=1)
    th = path.heading_rad[idx]
    delta = xy_m - path.xy_m[idx]
    return path.s_m[idx] + np.cos(th) * delta[:, 0] + np.sin(th) * delta[:, 1]
