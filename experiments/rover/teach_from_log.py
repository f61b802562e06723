"""The teach pass taken from a recorded drive in a PX4 ULog instead of a live one.

A PX4 rover user drove the path last week in MANUAL and has the .ulg: its local position
(vehicle_local_position x, y: north, east of the estimator's origin) is the drive, in the path
frame a live teach records (x north, y west of the local origin; experiments.rover.teach), over
a span of the log: ``start_s`` to ``end_s`` (seconds from the log's start) when given, else the
stretch the vehicle was armed (the one it drove farthest in, when it was armed more than once),
else, when the log has no arming state, the whole log.

What a drive holds that a path cannot ([Ostafew16] 4.1: the path is a chain of vertices the
robot drives along, one way):

- **Stops**: a sample closer than the vertex spacing to the last one kept is left out, so a
  rover standing still, its estimate wandering by centimetres, is one point, not a tangle (a
  stop long enough for the estimate to drift further leaves a kink of that drift). The kept
  samples are about a spacing apart, the path's own resolution: a sharp corner is cut by a
  few centimetres, and the path ends within a spacing of where the drive stopped.
- **Reversals**: where the drive turns back on itself (successive moves, each about a vertex
  spacing long, more than ``REVERSAL_RAD`` apart in direction: backing up, a three-point turn,
  turning in place and driving off the way it came) the vertex sequence would fold back, and
  the repeat drives forward only. Such a span is refused, naming where it reverses and the
  longest one-way stretch as a ``--start-s/--end-s`` that teaches it.
- Samples the estimator marks xy-invalid are left out and counted; a NaN position it calls
  valid is refused, as a live teach refuses one.
- What the estimator says of its own position is passed on: where its horizontal accuracy
  (eph) grows past ``EPH_NOTE_SPACINGS`` vertex spacings in the span, and its resets of the
  horizontal position in the span that shift it by more than ``RESET_NOTE_SPACINGS`` spacings
  (the estimate, and so the path, jumps there), a note each;
  the path is still taught (a rover's own log is what the user has), the notes say how far to
  trust it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from experiments.rover.teach import MIN_TEACH_M, TeachError
from flightlog.ulog_track import ULogTrack
from planners.rover.path import TaughtPath

REVERSAL_RAD = math.radians(120.0)  # a turn between successive moves this sharp folds back
EPH_NOTE_SPACINGS = 2.0  # an eph above this many vertex spacings is said (module docstring)
RESET_NOTE_SPACINGS = 0.2  # a reset shifting the position by more than this many is said


@dataclass(frozen=True)
class LogTeach:
    """A teach pass taken from a log.

    Attributes:
        path: the taught path, resampled to the vertex spacing, in the path frame.
        span_s: (start_s, end_s) of the log used, from its start [s].
        span_from: how the span was chosen ("--start-s/--end-s", "armed", "whole log").
        notes: lines for the user (samples left out, other armed stretches; the log's damage
            is ``track.damage``, said on reading it).
    """

    path: TaughtPath
    span_s: tuple[float, float]
    span_from: str
    notes: list[str]


def teach_from_track(
    track: ULogTrack,
    spacing_m: float = 0.25,
    start_s: float | None = None,
    end_s: float | None = None,
) -> LogTeach:
    """The path ``track`` drove over the chosen span (module docstring).

    Raises:
        TeachError: one line naming what is wrong and the fix: a span outside the log, a log
            never armed, no valid position in the span, a NaN position, too little motion,
            or a reversal.
    """
    notes: list[str] = []
    span, span_from = _span_s(track, spacing_m, start_s, end_s, notes)
    where = f"{track.name} {span[0]:.1f}-{span[1]:.1f} s"
    in_span = (track.t_s >= span[0]) & (track.t_s <= span[1])
    valid = in_span & track.xy_valid
    if not track.xy_valid.any():
        raise TeachError(
            f"{track.name}: the local position is invalid throughout the log (xy_valid false: "
            "no GPS fix or other position source); drive it again with a position estimate"
        )
    if not in_span.any():
        raise TeachError(
            f"{where}: no position sample in the span (the log's {len(track.t_s)} lie from "
            f"{track.t_s[0]:.1f} to {track.t_s[-1]:.1f} s); {_span_fix(track)}"
        )
    if not valid.any():
        t_valid = track.t_s[track.xy_valid]
        raise TeachError(
            f"{where}: no valid local position in the span (xy_valid false); pass "
            f"--start-s/--end-s where it is valid ({t_valid[0]:.1f}-{t_valid[-1]:.1f} s)"
        )
    if int(np.sum(in_span & ~track.xy_valid)):
        notes.append(
            f"{int(np.sum(in_span & ~track.xy_valid))} of {int(in_span.sum())} position samples "
            "in the span have xy_valid false (no position estimate) and were left out"
        )
    notes.extend(_estimator_notes(track, valid, spacing_m))
    t, ne = track.t_s[valid], track.pos_ne_m[valid]
    bad = ~np.all(np.isfinite(ne), axis=1)
    if bad.any():
        fix = "teach a span without them" if not bad.all() else "teach another span"
        raise TeachError(
            f"{where}: the local position is not finite (NaN) in {int(bad.sum())} of {len(t)} "
            f"samples, from t={t[bad][0]:.1f} to {t[bad][-1]:.1f} s, while the estimator calls "
            f"it valid; {fix} (--start-s/--end-s)"
        )
    xy = np.column_stack([ne[:, 0], -ne[:, 1]])  # north, west: the path frame
    keep = _moving_samples(xy, spacing_m)
    t, xy = t[keep], xy[keep]
    steps = np.diff(xy, axis=0)
    driven = float(np.hypot(*steps.T).sum())
    need = max(MIN_TEACH_M, 3 * spacing_m)
    if driven < need or len(xy) < 3:
        raise TeachError(
            f"{where}: the vehicle moved {driven:.2f} m (wandering within the {spacing_m:g} m "
            f"vertex spacing counts as standing); a path needs at least {need:g} m: "
            f"{_span_fix(track)}"
        )
    folds = reversals(steps)
    if folds.size:
        i = int(folds[0])
        turn = math.degrees(_turn_rad(steps[i : i + 2])[0])
        more = f", and {len(folds) - 1} more time{'s' if len(folds) > 2 else ''}"
        a, b, one_way_m = longest_one_way(t, folds, xy)
        fix = f"pass --start-s {a:.1f} --end-s {b:.1f}, its longest one-way stretch ("
        if one_way_m < need or not _teaches(track, spacing_m, a, b):
            fix = "no stretch between its turns gives a path (the longest: "
        raise TeachError(
            f"{where}: the drive turns back on itself at t={t[i + 1]:.1f} s (by {turn:.0f} deg: "
            f"backing up, a three-point turn, a turn in place){more if len(folds) > 1 else ''}; "
            f"a path goes one way: {fix}{one_way_m:.1f} m), or drive it again one way"
        )
    try:
        path = TaughtPath.from_drive(xy, spacing_m)
    except ValueError as exc:
        raise TeachError(f"{where}: the positions give no path: {exc}") from None
    return LogTeach(path, span, span_from, notes)


def _estimator_notes(track: ULogTrack, rows: np.ndarray, spacing_m: float) -> list[str]:
    """Notes on the estimator's own account of the position in the taught ``rows`` (N,) bool:
    its horizontal accuracy past EPH_NOTE_SPACINGS spacings, its resets of the position past
    RESET_NOTE_SPACINGS."""
    notes = []
    eph = np.full(len(track.t_s), np.nan) if track.eph_m is None else track.eph_m
    eph = np.where(rows, eph, np.nan)
    if np.isfinite(eph).any() and np.nanmax(eph) > EPH_NOTE_SPACINGS * spacing_m:
        worst = int(np.nanargmax(eph))
        notes.append(
            f"the estimator's horizontal accuracy (eph) reached {eph[worst]:.2f} m at "
            f"t={track.t_s[worst]:.1f} s (median {np.nanmedian(eph):.2f} m over the span): "
            "the path is no more accurate than that there; a span where eph stays small "
            "teaches a truer one"
        )
    t_rows = track.t_s[rows]
    inside = [
        (t, m)
        for t, m in track.xy_resets
        if t_rows[0] <= t <= t_rows[-1] and m > RESET_NOTE_SPACINGS * spacing_m
    ]
    if inside:
        t_big, m_big = max(inside, key=lambda tm: tm[1])
        notes.append(
            f"the estimator reset its horizontal position {len(inside)} time"
            f"{'s' if len(inside) > 1 else ''} in the span (the largest by {m_big:.2f} m at "
            f"t={t_big:.1f} s): the path jumps with the estimate there"
        )
    return notes


def _teaches(track: ULogTrack, spacing_m: float, start_s: float, end_s: float) -> bool:
    """Whether the span teaches a path: the samples kept from another first one can be
    shorter, or fold where the whole drive's did not."""
    try:
        teach_from_track(track, spacing_m, start_s, end_s)
    except TeachError:
        return False
    return True


def _moving_samples(xy: np.ndarray, spacing_m: float) -> np.ndarray:
    """Indices of the samples at least ``spacing_m`` from the last one kept (the first is
    kept): what the vehicle standing still adds is left out (module docstring)."""
    kept = [0]
    for i in range(1, len(xy)):
        if math.dist(xy[i], xy[kept[-1]]) >= spacing_m:
            kept.append(i)
    return np.array(kept)


def reversals(steps_m: np.ndarray) -> np.ndarray:
    """Indices i where move i+1 turns more than ``REVERSAL_RAD`` from move i; ``steps_m``
    (M, 2) are the moves between kept samples [m]."""
    return np.flatnonzero(_turn_rad(steps_m) > REVERSAL_RAD)


def _turn_rad(steps_m: np.ndarray) -> np.ndarray:
    """|Direction change| from each move of ``steps_m`` (M, 2) to the next, (M-1,) [rad]."""
    heading = np.arctan2(steps_m[:, 1], steps_m[:, 0])
    return np.abs(np.angle(np.exp(1j * np.diff(heading))))


def longest_one_way(
    t_s: np.ndarray, folds: np.ndarray, xy_m: np.ndarray
) -> tuple[float, float, float]:
    """(start_s, end_s, length_m) of the longest stretch between reversals, its times rounded
    inwards to 0.1 s; ``folds`` as :func:`reversals` gives them for the samples ``xy_m`` (K, 2)
    at ``t_s`` (K,)."""
    cuts = [0, *(folds + 1).tolist(), len(t_s) - 1]
    s = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy_m, axis=0).T))])
    a, b = max(zip(cuts[:-1], cuts[1:], strict=True), key=lambda ab: s[ab[1]] - s[ab[0]])
    inside = math.ceil(t_s[a] * 10.0) / 10.0, math.floor(t_s[b] * 10.0) / 10.0  # as printed
    return *inside, float(s[b] - s[a])


def _span_s(
    track: ULogTrack,
    spacing_m: float,
    start_s: float | None,
    end_s: float | None,
    notes: list[str],
) -> tuple[tuple[float, float], str]:
    """The span to teach and how it was chosen; TeachError when it is outside the log."""
    log = f"{track.name} ({track.duration_s:.1f} s of data)"
    if start_s is not None or end_s is not None:
        a = 0.0 if start_s is None else start_s
        b = track.duration_s if end_s is None else end_s
        if a < 0 or a >= track.duration_s:
            raise TeachError(
                f"--start-s {a:g} is outside {log}; pass one from 0 to {track.duration_s:.1f}"
            )
        if b > track.duration_s:
            raise TeachError(
                f"--end-s {b:g} is past the end of {log}; leave --end-s out for the log's end"
            )
        if b <= a and start_s is None:
            raise TeachError(f"--end-s {b:g} is the log's start; pass one after 0")
        if b <= a:
            raise TeachError(f"--end-s {b:g} is not after --start-s {a:g}; swap them")
        return (a, b), "--start-s/--end-s"
    spans = track.armed_spans_s
    if spans is None:
        notes.append(f"{track.name} does not log arming (no vehicle_status): the whole log used")
        return (0.0, track.duration_s), "whole log"
    if not spans:
        raise TeachError(
            f"{log}: the vehicle was never armed; pass --start-s and --end-s to teach a span "
            "of it anyway"
        )
    if len(spans) == 1:
        return spans[0], "armed"
    driven = [_driven_m(track, span, spacing_m) for span in spans]
    best = int(np.argmax(driven))
    listed = ", ".join(f"{a:.1f}-{b:.1f} s" for a, b in spans)
    notes.append(
        f"{track.name}: armed {len(spans)} times ({listed}); taught the one driven farthest; "
        "--start-s/--end-s picks another"
    )
    return spans[best], "armed"


def _driven_m(track: ULogTrack, span: tuple[float, float], spacing_m: float) -> float:
    """Distance between the samples :func:`_moving_samples` keeps in ``span`` [m]."""
    rows = (track.t_s >= span[0]) & (track.t_s <= span[1]) & track.xy_valid
    xy = track.pos_ne_m[rows]
    xy = xy[np.all(np.isfinite(xy), axis=1)]
    if len(xy) < 2:
        return 0.0
    kept = xy[_moving_samples(xy, spacing_m)]
    return float(np.hypot(*np.diff(kept, axis=0).T).sum())


def _span_fix(track: ULogTrack) -> str:
    """The fix for a span without a usable drive: the log's armed stretches, if any."""
    spans = track.armed_spans_s or []
    if not spans:
        return "pass --start-s/--end-s around the drive"
    listed = ", ".join(f"{a:.1f}-{b:.1f} s" for a, b in spans)
    return f"pass --start-s/--end-s around the drive (armed: {listed})"
