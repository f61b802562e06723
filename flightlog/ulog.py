"""PX4 ULog files mapped onto flight-log schema v1 (read with pyulog).

Topics: ``vehicle_local_position`` (time base: x, y, z, vx, vy, vz, ax, ay, az),
``vehicle_attitude`` (q[0..3], body FRD to NED), ``trajectory_setpoint`` (velocity[0..2] or
vx/vy/vz, yawspeed), optional ``vehicle_angular_velocity`` (xyz[0..2]), ``battery_status``
(voltage_v) and ``vehicle_thrust_setpoint`` (xyz[2], normalised, up negative -> ``thrust_norm``).
Continuous signals are interpolated onto the local-position times, setpoints held (zero-order),
quaternions renormalised. Rows before every required topic has a sample are dropped.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np
from pyulog import ULog

from flightlog.schema import FlightLog, FlightLogError, validate_flight_log

Topics = Mapping[str, Mapping[str, np.ndarray]]
TOPICS = (
    "vehicle_local_position", "vehicle_attitude", "trajectory_setpoint",
    "vehicle_angular_velocity", "battery_status", "vehicle_thrust_setpoint",
)  # fmt: skip
REQUIRED_TOPICS = TOPICS[:3]


def read_ulog(path: str | Path) -> FlightLog:
    """Read a PX4 ULog file as a schema-v1 log.

    Raises:
        FlightLogError: unreadable file or a required topic missing (one line).
    """
    path = Path(path)
    try:
        ulog = ULog(str(path), message_name_filter_list=list(TOPICS))
    except Exception as exc:  # pyulog raises several types for corrupt files
        raise FlightLogError(f"{path}: not a readable ULog file ({exc})") from None
    topics = {d.name: d.data for d in ulog.data_list if d.multi_id == 0}
    log = flight_log_from_topics(topics, str(path))
    return FlightLog(log.columns, {**log.metadata, "ulog": path.name}, path)


def flight_log_from_topics(topics: Topics, where: str = "ulog") -> FlightLog:
    """Map ULog topics (name -> field -> array, ``timestamp`` in us) onto schema v1."""
    missing = [t for t in REQUIRED_TOPICS if t not in topics]
    if missing:
        raise FlightLogError(f"{where}: ULog lacks topic(s) {', '.join(missing)}")
    pos = topics["vehicle_local_position"]
    att = topics["vehicle_attitude"]
    sp = topics["trajectory_setpoint"]
    t_us = np.asarray(pos["timestamp"], dtype=float)
    start = max(float(att["timestamp"][0]), float(sp["timestamp"][0]))
    rows = t_us >= start
    t_us = t_us[rows]
    if len(t_us) < 2:
        raise FlightLogError(
            f"{where}: fewer than 2 rows where position, attitude and setpoint overlap"
        )
    cols: dict[str, np.ndarray] = {"t_s": (t_us - t_us[0]) * 1e-6}
    for name, field in zip(("pos_n_m", "pos_e_m", "pos_d_m"), "xyz", strict=True):
        cols[name] = np.asarray(pos[field], dtype=float)[rows]
    for axis, field in zip("ned", ("vx", "vy", "vz"), strict=True):
        cols[f"vel_{axis}_mps"] = np.asarray(pos[field], dtype=float)[rows]
    if all(f in pos for f in ("ax", "ay", "az")):
        for axis, field in zip("ned", ("ax", "ay", "az"), strict=True):
            cols[f"acc_{axis}_mps2"] = np.asarray(pos[field], dtype=float)[rows]
    q = np.column_stack([_interp(att, f"q[{i}]", t_us) for i in range(4)])
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    for i, name in enumerate(("q_w", "q_x", "q_y", "q_z")):
        cols[name] = q[:, i]
    fields = ("velocity[0]", "velocity[1]", "velocity[2]")
    if not all(f in sp for f in fields):
        fields = ("vx", "vy", "vz")
    for axis, field in zip("ned", fields, strict=True):
        cols[f"cmd_vel_{axis}_mps"] = np.nan_to_num(_hold(sp, field, t_us))
    cols["cmd_yaw_rate_radps"] = np.nan_to_num(_hold(sp, "yawspeed", t_us))
    rates = topics.get("vehicle_angular_velocity")
    if rates is not None:
        for axis, i in zip("xyz", range(3), strict=True):
            cols[f"rate_{axis}_radps"] = _interp(rates, f"xyz[{i}]", t_us)
    if "battery_status" in topics:
        cols["battery_v"] = _interp(topics["battery_status"], "voltage_v", t_us)
    if "vehicle_thrust_setpoint" in topics:
        cols["thrust_norm"] = -_hold(topics["vehicle_thrust_setpoint"], "xyz[2]", t_us)
    log = FlightLog(cols, {"source": "px4_ulog"})
    validate_flight_log(log)
    return log


def _interp(topic: Mapping[str, np.ndarray], field: str, t_us: np.ndarray) -> np.ndarray:
    return np.interp(t_us, np.asarray(topic["timestamp"], float), np.asarray(topic[field], float))


def _hold(topic: Mapping[str, np.ndarray], field: str, t_us: np.ndarray) -> np.ndarray:
    times = np.asarray(topic["timestamp"], float)
    k = np.clip(np.searchsorted(times, t_us, side="right") - 1, 0, len(times) - 1)
    return np.asarray(topic[field], float)[k]
