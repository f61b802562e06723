"""The horizontal track a PX4 ULog recorded, of any vehicle: local position and arming.

Where :func:`flightlog.ulog.read_ulog` maps a multirotor flight onto schema v1 (and refuses
other vehicles, or a drive without a velocity command), this reads only what a recorded drive
needs, from any vehicle type (a rover driven in MANUAL, a multirotor's track):
``vehicle_local_position`` timestamp, x, y (NED, metres from the estimator's local origin),
xy_valid, eph (the estimator's horizontal accuracy), xy_reset_counter with delta_xy (where the
estimator shifted its position: [PX4-msgs] vehicle_local_position), ref_lat/ref_lon (the
origin, where xy_global says it is known) and ``vehicle_status`` arming_state. Its times count
from the start `flightlog info` gives a log it does not map, a rover's (the first data of
:data:`flightlog.ulog.TOPICS`): the modes it lists there and a ``--start-s`` agree. Samples
out of time order are left out as :mod:`flightlog.ulog_time` does, and a truncated or corrupt
file is read as far as it goes and says so (:func:`flightlog.ulog.damage_note_of`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from flightlog import px4
from flightlog.schema import FlightLogError
from flightlog.ulog import TOPICS, damage_metadata, damage_note_of, open_ulog
from flightlog.ulog_time import data_span_us

EARTH_RADIUS_M = 6.371e6
# Bounds of a vehicle_local_position sample's numbers ([PX4-msgs]): a local position or reset
# shift within the Earth's radius [m], an origin a latitude and longitude [deg].
PLAUSIBLE_LIMITS = {
    "x": EARTH_RADIUS_M,
    "y": EARTH_RADIUS_M,
    "delta_xy[0]": EARTH_RADIUS_M,
    "delta_xy[1]": EARTH_RADIUS_M,
    "ref_lat": 90.0,
    "ref_lon": 180.0,
}


@dataclass(frozen=True)
class ULogTrack:
    """A ULog's horizontal track.

    Attributes:
        name: the file's name.
        t_s: sample times from the log's start (N,) [s] (the start as `flightlog info` has it:
            the later of the logging start and the first data).
        pos_ne_m: local position north, east (N, 2) [m], as logged (NaN possible).
        xy_valid: the estimator's xy_valid flag (N,) (all True where the log has none).
        duration_s: the log's data span [s].
        armed_spans_s: (start_s, end_s) of each armed stretch; None when the log has no
            vehicle_status (arming not logged).
        origin_deg: (lat, lon) of the local origin, or None when the log does not know it.
        vehicle: the vehicle type in words (MAV_TYPE), "no airframe set" for a board never
            given one (:func:`flightlog.px4.no_airframe_set`: its MAV_TYPE 0 names no type),
            or None when not logged.
        damage: one sentence when the file is truncated, corrupt or had samples out of time
            order left out (:func:`flightlog.ulog.damage_note_of`), else None.
        eph_m: the estimator's horizontal position accuracy per sample (N,) [m] (NaN where
            the log has none; None for a track built without it).
        xy_resets: (t_s, shift_m) of each reset of the horizontal position: when, and by how
            far the estimate jumped (|delta_xy|) [s], [m].
    """

    name: str
    t_s: np.ndarray
    pos_ne_m: np.ndarray
    xy_valid: np.ndarray
    duration_s: float
    armed_spans_s: list[tuple[float, float]] | None
    origin_deg: tuple[float, float] | None
    vehicle: str | None
    damage: str | None
    eph_m: np.ndarray | None = None
    xy_resets: tuple[tuple[float, float], ...] = ()


def read_ulog_track(path: str | Path) -> ULogTrack:
    """The horizontal track of the ULog at ``path`` (module docstring).

    Raises:
        FlightLogError: no such file, not a ULog, unreadable, or no vehicle_local_position (one
            line naming the file and the fix; a damaged file says where it is damaged).
    """
    path = Path(path)
    ulog, damage, topics, out_of_order = open_ulog(path, TOPICS, or_else="")  # all: info's start
    t0_us, t1_us = data_span_us(topics, ulog.start_timestamp)
    duration_s = (t1_us - t0_us) * 1e-6
    meta = {"ulog": path.name, "duration_s": duration_s, **damage_metadata(damage, out_of_order)}
    pos = topics.get("vehicle_local_position")
    if pos is None or len(pos["timestamp"]) == 0:
        raise FlightLogError(
            f"{path}: ULog holds no vehicle_local_position; log the drive with PX4's default "
            "logging profile (SDLOG_PROFILE) and a position estimate (GPS or other)"
        )
    t_s = (np.asarray(pos["timestamp"], float) - t0_us) * 1e-6
    pos_ne = np.column_stack([np.asarray(pos[f], float) for f in ("x", "y")])
    valid = np.asarray(pos["xy_valid"]) > 0 if "xy_valid" in pos else np.ones(len(t_s), bool)
    params = ulog.initial_parameters
    plausible = _plausible(pos, len(t_s))
    mav_type = int(params["MAV_TYPE"]) if "MAV_TYPE" in params else None
    return ULogTrack(
        name=path.name,
        t_s=t_s,
        pos_ne_m=pos_ne,
        xy_valid=valid,
        duration_s=duration_s,
        armed_spans_s=_armed_spans_s(topics.get("vehicle_status"), t0_us, duration_s),
        origin_deg=_origin_deg(pos, plausible),
        vehicle="no airframe set" if px4.no_airframe_set(params) else px4.vehicle_name(mav_type),
        damage=damage_note_of(meta),
        eph_m=np.asarray(pos["eph"], float) if "eph" in pos else np.full(len(t_s), np.nan),
        xy_resets=_xy_resets(pos, t_s, plausible),
    )


def _plausible(pos, n: int) -> np.ndarray:
    """(n,) the samples resets and the origin are read from: those whose numbers a vehicle can
    have. A damaged log's bytes read as a sample gave a reset by 3.7e37 m (and another as its
    counter came back) and an origin at latitude -4.8e240 deg. (Not only valid estimates: a
    reset comes as the estimate becomes valid.)"""
    keep = np.ones(n, bool)
    for field, limit in PLAUSIBLE_LIMITS.items():
        if field in pos:
            with np.errstate(invalid="ignore"):  # NaN: not known (an origin not yet set)
                keep &= ~(np.abs(np.asarray(pos[field], float)) > limit)
    return keep


def _xy_resets(pos, t_s: np.ndarray, keep: np.ndarray) -> tuple[tuple[float, float], ...]:
    """(t_s, |delta_xy| [m]) wherever xy_reset_counter changes between the samples ``keep``
    (n,) holds (none when not logged)."""
    if not all(f in pos for f in ("xy_reset_counter", "delta_xy[0]", "delta_xy[1]")):
        return ()
    rows = np.flatnonzero(keep)
    at = rows[np.flatnonzero(np.diff(np.asarray(pos["xy_reset_counter"], int)[rows])) + 1]
    shift = np.hypot(np.asarray(pos["delta_xy[0]"], float), np.asarray(pos["delta_xy[1]"], float))
    return tuple((float(t_s[i]), float(shift[i])) for i in at)


def _armed_spans_s(status, t0_us: float, duration_s: float) -> list[tuple[float, float]] | None:
    """(start_s, end_s) of each run of armed vehicle_status samples, from the log's start
    (a first sample stamped before it counts from 0; the last run ends at the log's end)."""
    if status is None or len(status["timestamp"]) == 0:
        return None
    t = np.clip((np.asarray(status["timestamp"], float) - t0_us) * 1e-6, 0.0, duration_s)
    armed = np.asarray(status["arming_state"]) == px4.ARMING_STATE_ARMED
    edges = np.flatnonzero(np.diff(np.r_[0, armed.astype(int), 0]))
    ends = np.r_[t, duration_s]
    return [(float(t[a]), float(ends[b])) for a, b in zip(edges[::2], edges[1::2], strict=True)]


def _origin_deg(pos, keep: np.ndarray) -> tuple[float, float] | None:
    """(lat, lon) [deg] of the local origin from the last sample of ``keep`` (n,) whose
    xy_global says it is set, else None (no global reference, or fields not logged)."""
    if not all(f in pos for f in ("xy_global", "ref_lat", "ref_lon")):
        return None
    known = np.flatnonzero((np.asarray(pos["xy_global"]) > 0) & keep)
    if not len(known):
        return None
    i = known[-1]
    return float(pos["ref_lat"][i]), float(pos["ref_lon"][i])
