"""PX4 ULog files mapped onto flight-log schema v1 (read with pyulog), knowing PX4.

Topics and fields per firmware version ([PX4-msgs] msg/*.msg read at each release tag v1.9.0 to
v1.16.0, tabulated in docs/px4_ulog_fields.md; the layouts are also checked on the real logs in
tests/fixtures/ulog, v1.6 to v1.17, by tests/flightlog/test_ulog_versions.py). The mapping picks
fields by presence, so every layout below is read:

- ``vehicle_local_position`` (all versions): the time base. x, y, z, vx, vy, vz, ax, ay, az;
  validity flags xy_valid, z_valid, v_xy_valid, v_z_valid (all); dead_reckoning (v1.14+, absent
  in v1.11; used when present). Rows the estimator marks invalid are dropped and counted.
- ``vehicle_attitude`` (all): q[0..3], body FRD to NED; interpolated and renormalised.
- Velocity command: ``vehicle_local_position_setpoint`` vx, vy, vz, yawspeed (all versions;
  acc_x.. up to v1.9, acceleration[0..2] from v1.14) is what PX4's velocity controller was
  given in every position-controlled mode (POSCTL, AUTO.*, OFFBOARD); ``trajectory_setpoint``
  (flat vx, vy, vz up to v1.13, velocity[0..2] from v1.14) is used only when the former is absent
  (then it is what reached the controller, e.g. OFFBOARD logs). Rows outside position-controlled
  modes, or whose command is NaN (position-only), are dropped.
- ``vehicle_status`` (all): nav_state -> ``mode`` (values per version in flightlog/px4.py),
  arming_state -> ``armed``; is_vtol and in_transition_mode (all); for the VTOL phase
  vehicle_type (v1.10+) or is_rotary_wing (up to v1.9). Rows before its
  first sample (a log started in the air) have no known mode and are dropped and counted.
- ``vehicle_land_detected`` (all): landed -> ``landed``.
- Thrust, best source first (see :func:`_thrust`), recorded in ``metadata['thrust_source']``;
  ``esc_status`` (all) RPM kept apart as ``rotor_speed_rms_radps`` (:func:`_rotor_speed_rms`).
- ``vehicle_angular_velocity`` xyz[0..2] (v1.10+), ``battery_status`` voltage_v (all).

Continuous signals are interpolated onto the local-position times, setpoints and states held
(zero-order), after each topic's samples older than those before them (older data a damaged
file holds after its damage) are left out and counted (:mod:`flightlog.ulog_time`). Initial
parameters go to ``metadata['px4_params']``, rates per signal to ``metadata['rates_hz']``,
dropped-row counts to ``metadata['dropped_rows']``.
"""

from __future__ import annotations

import contextlib
import io
from collections.abc import Mapping, Sequence
from pathlib import Path

import numpy as np

from flightlog import px4
from flightlog.schema import FlightLog, FlightLogError, validate_flight_log
from flightlog.ulog_integrity import ULogDamage, find_damage
from flightlog.ulog_time import data_span_us, in_time_order
from flightlog.velocity_loop_gains import is_hover_thrust

Topics = Mapping[str, Mapping[str, np.ndarray]]
ULOG_MAGIC = b"ULog\x01\x12\x35"
TOPICS = (
    "vehicle_local_position", "vehicle_attitude", "vehicle_local_position_setpoint",
    "trajectory_setpoint", "vehicle_status", "vehicle_land_detected",
    "vehicle_angular_velocity", "battery_status", "vehicle_thrust_setpoint",
    "actuator_controls_0", "actuator_motors", "actuator_outputs", "esc_status",
)  # fmt: skip
COMMAND_TOPICS = ("vehicle_local_position_setpoint", "trajectory_setpoint")
MOTOR_COUNT = {2: 4, 13: 6, 14: 8, 15: 3, 3: 2}  # MAV_TYPE -> motors (actuator_outputs)
FLY_HINT = (
    "fly a multirotor in a position-controlled mode (POSCTL, AUTO.MISSION/LOITER, OFFBOARD) "
    "with the default logging profile"
)


def is_ulog(path: str | Path) -> bool:
    """True if the file starts with the ULog magic bytes (whatever its extension)."""
    try:
        with Path(path).open("rb") as fh:
            return fh.read(len(ULOG_MAGIC)) == ULOG_MAGIC
    except OSError:
        return False


def parse_ulog(path: Path, topics: Sequence[str] = TOPICS):
    """pyulog's ULog of ``path`` read for ``topics``, with what pyulog prints about a corrupt
    file (a line per unknown message id, on stdout) kept off the user's terminal: the caller
    says what is wrong in one line."""
    from pyulog import ULog  # imported here: the CSV path needs no pyulog

    with contextlib.redirect_stdout(io.StringIO()):
        return ULog(str(path), message_name_filter_list=list(topics))


def damage_note(log: FlightLog) -> str | None:
    """One sentence for a report's headline when ``log`` was read from a truncated or a corrupt
    ULog (:mod:`flightlog.ulog_integrity`), or had samples out of time order left out
    (:mod:`flightlog.ulog_time`), else None."""
    return damage_note_of(log.metadata)


def damage_metadata(damage: ULogDamage | None, out_of_order: int) -> dict[str, object]:
    """The metadata keys :func:`damage_note_of` reads, for a file with ``damage`` (or None)
    and ``out_of_order`` samples out of time order left out."""
    meta: dict[str, object] = {}
    if out_of_order:
        meta["samples_out_of_time_order"] = out_of_order
    if damage is not None and damage.kind == "truncated":
        meta["truncated_at_byte"] = [damage.at_byte, damage.file_bytes]
    elif damage is not None:
        meta["corrupt_at_byte"] = [damage.at_byte, damage.file_bytes]
        meta["corrupt_header"] = damage.detail
    return meta


def damage_note_of(metadata: Mapping[str, object]) -> str | None:
    """:func:`damage_note` from a log's metadata (``ulog``, ``duration_s`` and
    :func:`damage_metadata`'s keys), for a reader that maps no FlightLog."""
    name = metadata.get("ulog", "the ULog")
    duration = f"{metadata.get('duration_s', float('nan')):.1f} s"
    stale = _out_of_order_clause(int(metadata.get("samples_out_of_time_order", 0)))
    cut = metadata.get("truncated_at_byte")
    if cut:
        return (
            f"{name} is truncated (last message incomplete at byte {cut[0]} of {cut[1]}: logging "
            f"stopped mid-message, as a crash or power loss leaves it); its complete part, "
            f"{duration}, was read{stale}"
        )
    bad = metadata.get("corrupt_at_byte")
    if bad:
        return (
            f"{name} is corrupt at byte {bad[0]} of {bad[1]} "
            f"({metadata.get('corrupt_header', 'an invalid message header')}: the file was "
            f"damaged, e.g. by the SD card or the copy, not cut short); {duration} of data were "
            f"read{stale}; messages after the damage may be missing; copy the .ulg again from "
            "the vehicle"
        )
    if stale:
        return f"{name}{stale}; copy the .ulg again from the vehicle"
    return None


# Why the mapping left rows out (``metadata['dropped_rows']`` keys), for a report's headline.
LEFT_OUT_WHY = {
    "estimator_invalid": "with the estimator's position or velocity invalid or dead reckoning",
    "mode_unknown": "before the first vehicle_status (mode unknown)",
    "not_multicopter_phase": "outside the multicopter phase",
    "not_position_controlled": "outside position-controlled modes",
    "no_velocity_command": "without a velocity command",
}
LEFT_OUT_NOTE_FRACTION = 0.1  # of a log's rows: fewer left out go unsaid


def rows_left_out_note(log: FlightLog) -> str | None:
    """One sentence for a report's headline when the mapping left out more than a tenth of a
    ULog's rows (how many, and why: ``metadata['dropped_rows']``), else None: a flight that
    lost its position fix for a while is diagnosed on what is left, and says so."""
    dropped = log.metadata.get("dropped_rows")
    total = log.metadata.get("rows_in_log")
    if not isinstance(dropped, Mapping) or not total:
        return None
    if sum(dropped.values()) <= LEFT_OUT_NOTE_FRACTION * total:
        return None
    why = ", ".join(f"{n} {LEFT_OUT_WHY.get(k, k)}" for k, n in dropped.items() if n)
    name = log.metadata.get("ulog", "the ULog")
    return f"{name}: {log.n_rows} of its {total} rows used; left out: {why}"


def _out_of_order_clause(samples: int) -> str:
    """What a damage note adds when ``samples`` samples out of time order were left out."""
    if not samples:
        return ""
    return (
        f"; {samples} samples out of time order (older than the data before them: blocks of "
        "older data read after damage, e.g. left on the card; or a lone timestamp out of line, "
        "a bit flipped) were left out"
    )


def _damage_clause(damage: ULogDamage, duration_s: float, out_of_order: int = 0) -> str:
    """What a mapping error on a damaged file adds: where, and how much could be read."""
    stale = _out_of_order_clause(out_of_order)
    if damage.kind == "truncated":
        where = f"truncated (at byte {damage.at_byte} of {damage.file_bytes})"
        return f"the file is {where}: only its first {duration_s:.1f} s could be read{stale}"
    where = f"corrupt (at byte {damage.at_byte} of {damage.file_bytes}: {damage.detail})"
    return f"the file is {where}: {duration_s:.1f} s of data could be read{stale}"


def open_ulog(path: Path, topics: Sequence[str] = TOPICS, or_else: str = "a schema-v1 CSV"):
    """pyulog's ULog of ``path`` read for ``topics``, the file's damage (or None), and the first
    instance of each topic in time order with the number of samples that were not
    (:func:`flightlog.ulog_time.in_time_order`); ``or_else`` is what else the user could pass.

    Raises:
        FlightLogError: no such file, a folder, no read access, not a ULog, unreadable, or
            damaged before any local position (one line naming the file and the fix).
    """
    alternative = f" or {or_else}" if or_else else ""
    if path.is_dir():
        raise FlightLogError(f"{path}: a folder, not a flight log; pass a PX4 .ulg in it")
    if not path.is_file():
        raise FlightLogError(f"{path}: no such file; pass a PX4 .ulg{alternative}")
    try:
        path.open("rb").close()
    except OSError as exc:  # is_ulog would call it no ULog
        raise FlightLogError(
            f"{path}: cannot read it ({exc.strerror or exc}); make it readable to you "
            "(chown or chmod, with sudo for a file root copied) and pass it again"
        ) from None
    if not is_ulog(path):
        raise FlightLogError(
            f"{path}: not a ULog file (it does not start with the ULog magic bytes); "
            f"copy the .ulg again from the vehicle{alternative.replace(' or', ', or pass')}"
        )
    damage = find_damage(path)  # a crash, a power loss or a failing card leaves such a file
    try:
        ulog = parse_ulog(path, topics)
    except Exception as exc:  # pyulog raises several types for corrupt files
        raise FlightLogError(
            f"{path}: not a readable ULog file ({type(exc).__name__}: {exc}); "
            "copy the .ulg again from the vehicle's SD card"
        ) from None
    in_order, out_of_order = in_time_order(
        {d.name: d.data for d in ulog.data_list if d.multi_id == 0}
    )
    if "vehicle_local_position" not in in_order and (damage or ulog.file_corruption):
        what = f"{damage.kind} at byte {damage.at_byte}" if damage else "corrupt"
        raise FlightLogError(
            f"{path}: ULog is {what} and holds no local position; copy the .ulg again from the "
            "vehicle"
        )
    return ulog, damage, in_order, out_of_order


def read_ulog(path: str | Path) -> FlightLog:
    """Read a PX4 ULog file as a schema-v1 log.

    Raises:
        FlightLogError: unreadable file, not a multirotor, no valid motion (one line naming
            what is wrong and what to fly or log instead). A truncated file (the vehicle stopped
            logging mid-message: a crash, a power loss) is read up to its last complete message
            and says so in ``truncated_at_byte``; a corrupt one (an invalid message header before
            the end) is read as far as pyulog can and says so in ``corrupt_at_byte`` and
            ``corrupt_header`` (:func:`damage_note`).
    """
    path = Path(path)
    ulog, damage, topics, out_of_order = open_ulog(path)
    params = {k: float(v) for k, v in ulog.initial_parameters.items()}
    info = ulog.msg_info_dict
    meta = {
        "ulog": path.name,
        "firmware": px4.firmware_version(info.get("ver_sw_release")),
        "sys_name": info.get("sys_name"),
        "hardware": info.get("ver_hw"),
        "duration_s": round(
            float(np.diff(data_span_us(topics, ulog.start_timestamp))[0]) * 1e-6, 3
        ),
        "logger_dropouts": logger_dropouts(ulog),
        **damage_metadata(damage, out_of_order),
    }
    where = str(path)
    if not topics:
        raise FlightLogError(
            f"{path}: ULog holds no data messages (truncated after its header?); "
            "copy the complete .ulg from the vehicle"
        )
    try:
        log = flight_log_from_topics(topics, where, params, meta["firmware"])
    except FlightLogError as exc:
        if damage is None:
            raise
        clause = _damage_clause(damage, meta["duration_s"], out_of_order)
        raise FlightLogError(f"{exc}; {clause}") from None
    return FlightLog(log.columns, {**log.metadata, **meta}, path)


def summarise_ulog(path: str | Path) -> dict[str, object]:
    """What a ULog holds, read without mapping it (for ``flightlog info`` on a log the mapping
    refuses): firmware, hardware, vehicle type (name and MAV_TYPE), duration [s], the mapped
    topics present with their rates [Hz], the modes flown as (name, start_s, end_s) from the
    log's start, the initial PX4 parameters (``px4_params``) and the logger's dropouts
    (:func:`logger_dropouts`).

    Raises:
        FlightLogError: not a ULog, or pyulog cannot read even its header.
    """
    path = Path(path)
    if not is_ulog(path):
        raise FlightLogError(f"{path}: not a ULog file (no ULog magic bytes)")
    try:
        ulog = parse_ulog(path)
    except Exception as exc:  # pyulog raises several types for corrupt files
        raise FlightLogError(f"{path}: not a readable ULog file ({type(exc).__name__})") from None
    firmware = px4.firmware_version(ulog.msg_info_dict.get("ver_sw_release"))
    topics, out_of_order = in_time_order(
        {d.name: d.data for d in ulog.data_list if d.multi_id == 0}
    )
    t0, t1 = data_span_us(topics, ulog.start_timestamp)
    params = ulog.initial_parameters
    mav_type = int(params["MAV_TYPE"]) if "MAV_TYPE" in params else None
    span = np.array([t0, t1], dtype=float)
    modes: list[tuple[str, float, float]] = []
    status = topics.get("vehicle_status")
    if status is not None:
        t = np.asarray(status["timestamp"], float)
        nav = np.asarray(status["nav_state"], int)
        cuts = [0, *(np.flatnonzero(nav[1:] != nav[:-1]) + 1).tolist(), len(nav)]
        for a, b in zip(cuts[:-1], cuts[1:], strict=True):
            end = t[b] if b < len(t) else t1
            modes.append((str(px4.mode_names(nav[a : a + 1], firmware)[0]),
                          max(t[a] - t0, 0.0) * 1e-6, (end - t0) * 1e-6))  # fmt: skip
    return {
        "firmware": firmware,
        "hardware": ulog.msg_info_dict.get("ver_hw"),
        "vehicle": px4.vehicle_name(mav_type),
        "mav_type": mav_type,
        "duration_s": (t1 - t0) * 1e-6,
        "rates_hz": {name: _rate(topic, span) for name, topic in sorted(topics.items())},
        "messages": {name: len(topic["timestamp"]) for name, topic in sorted(topics.items())},
        "modes": modes,
        "px4_params": {k: float(v) for k, v in params.items()},
        "logger_dropouts": logger_dropouts(ulog),
        "samples_out_of_time_order": out_of_order,
    }


def parameters_give_a_config(summary: Mapping[str, object]) -> bool:
    """Whether a ULog the mapping refuses still gives a sim config from its PX4 parameters
    alone (vehicle-sim config-from-log): a multirotor by MAV_TYPE that logged MPC_THR_HOVER,
    a hover thrust (:func:`flightlog.velocity_loop_gains.is_hover_thrust`: 0 would make a
    massless vehicle). ``summary`` is :func:`summarise_ulog`'s."""
    params = summary.get("px4_params") or {}
    hover = params.get("MPC_THR_HOVER")
    return (
        summary.get("mav_type") in px4.MAV_TYPE_MULTIROTOR
        and hover is not None
        and is_hover_thrust(float(hover))
    )


def logger_dropouts(ulog) -> list[float]:
    """[count, total s, longest s] of the gaps PX4's logger recorded in pyulog's ``ulog``
    (messages it could not write, e.g. to a slow SD card: no topic has data in them)."""
    ms = [float(d.duration) for d in ulog.dropouts]
    return [len(ms), round(sum(ms) * 1e-3, 3), round(max(ms, default=0.0) * 1e-3, 3)]


def flight_log_from_topics(
    topics: Topics,
    where: str = "ulog",
    params: Mapping[str, float] | None = None,
    firmware: str | None = None,
) -> FlightLog:
    """Map ULog topics (name -> field -> array, ``timestamp`` in us) onto schema v1.

    Args:
        topics: first instance of each topic.
        where: file name for error messages.
        params: PX4 parameters (MAV_TYPE, THR_MDL_FAC, PWM_MIN/MAX, ...); may be empty.
        firmware: 'vA.B.C[-type]' (px4.firmware_version; nav_state values differ by version;
            None: before v1.15).
    """
    params = dict(params or {})
    vehicle = _vehicle(topics, params, where)
    for name in ("vehicle_local_position", "vehicle_attitude"):
        if name not in topics:
            raise FlightLogError(f"{where}: ULog lacks topic {name}; {FLY_HINT}")
    cmd_name = next((n for n in COMMAND_TOPICS if n in topics), None)
    if cmd_name is None:
        flown = _modes_flown(topics, firmware)
        raise FlightLogError(
            f"{where}: ULog lacks topic(s) vehicle_local_position_setpoint or "
            f"trajectory_setpoint (no velocity command{flown}); {FLY_HINT}"
        )
    pos, att, sp = topics["vehicle_local_position"], topics["vehicle_attitude"], topics[cmd_name]
    t_us = np.asarray(pos["timestamp"], dtype=float)
    rows = t_us >= max(float(att["timestamp"][0]), float(sp["timestamp"][0]))
    t_all = t_us[rows]
    cols: dict[str, np.ndarray] = {"t_s": t_all}
    for name, field in zip(("pos_n_m", "pos_e_m", "pos_d_m"), "xyz", strict=True):
        cols[name] = np.asarray(pos[field], dtype=float)[rows]
    for axis, field in zip("ned", ("vx", "vy", "vz"), strict=True):
        cols[f"vel_{axis}_mps"] = np.asarray(pos[field], dtype=float)[rows]
    if all(f in pos for f in ("ax", "ay", "az")):
        for axis, field in zip("ned", ("ax", "ay", "az"), strict=True):
            cols[f"acc_{axis}_mps2"] = np.asarray(pos[field], dtype=float)[rows]
    q = np.column_stack([_interp(att, f"q[{i}]", t_all) for i in range(4)])
    q /= np.linalg.norm(q, axis=1, keepdims=True)
    for i, name in enumerate(("q_w", "q_x", "q_y", "q_z")):
        cols[name] = q[:, i]
    fields = ("velocity[0]", "velocity[1]", "velocity[2]")
    if not all(f in sp for f in fields):
        fields = ("vx", "vy", "vz")  # vehicle_local_position_setpoint; trajectory_setpoint <1.13
    for axis, field in zip("ned", fields, strict=True):
        cols[f"cmd_vel_{axis}_mps"] = _hold(sp, field, t_all)
    cols["cmd_yaw_rate_radps"] = np.nan_to_num(_hold(sp, "yawspeed", t_all))
    rates_topic = topics.get("vehicle_angular_velocity")
    if rates_topic is not None:
        for axis, i in zip("xyz", range(3), strict=True):
            cols[f"rate_{axis}_radps"] = _interp(rates_topic, f"xyz[{i}]", t_all)
    if "battery_status" in topics:
        cols["battery_v"] = _interp(topics["battery_status"], "voltage_v", t_all)
    thrust, thrust_source = _thrust(topics, params, t_all)
    if thrust is not None:
        cols["thrust_norm"] = thrust
    rotor_speed, rotor_source = _rotor_speed_rms(topics, params, t_all)
    if rotor_speed is not None:
        cols["rotor_speed_rms_radps"] = rotor_speed
    keep, dropped, segments = _keep_rows(topics, pos, rows, cols, t_all, vehicle, firmware)
    if keep.sum() < 2:
        counts = ", ".join(f"{n} {why}" for why, n in dropped.items() if n) or "none usable"
        raise FlightLogError(
            f"{where}: no valid motion: of {len(t_all)} rows, dropped {counts}"
            f"{_modes_flown(topics, firmware)}; {FLY_HINT}"
        )
    cols = {k: v[keep] for k, v in cols.items()}
    t0 = cols["t_s"][0]
    rates_hz = {
        "local_position": _rate(pos, t_all),
        "attitude": _rate(att, t_all),
        "velocity_command": _rate(sp, t_all),
    }
    for key, name in (("angular_rate", "vehicle_angular_velocity"), ("battery", "battery_status")):
        if name in topics:
            rates_hz[key] = _rate(topics[name], t_all)
    if thrust_source:
        rates_hz["thrust"] = _rate(topics[thrust_source["topic"]], t_all)
    cols["t_s"] = (cols["t_s"] - t0) * 1e-6
    meta: dict[str, object] = {
        "source": "px4_ulog",
        "vehicle": vehicle,
        "command_topic": cmd_name,
        "rates_hz": rates_hz,
        "dropped_rows": dropped,
        "rows_in_log": int(len(t_all)),
        "thrust_source": thrust_source or {"topic": None, "kind": "none"},
        "px4_params": params,
    }
    if rotor_source:
        meta["rotor_speed_source"] = rotor_source
        rates_hz["rotor_speed"] = _rate(topics["esc_status"], t_all)
    if segments:
        meta["vtol_multicopter_segments_s"] = [
            [round((a - t0) * 1e-6, 3), round((b - t0) * 1e-6, 3)] for a, b in segments
        ]
    log = FlightLog(cols, meta)
    validate_flight_log(log)
    return log


def _vehicle(topics: Topics, params: Mapping[str, float], where: str) -> dict[str, object]:
    """Vehicle type from MAV_TYPE and vehicle_status; refuses non-multirotors in one line, and
    a board with no airframe set (SYS_AUTOSTART 0, MAV_TYPE 0) saying so."""
    status = topics.get("vehicle_status", {})
    is_vtol = bool("is_vtol" in status and np.any(np.asarray(status["is_vtol"]) > 0))
    mav_type = int(params["MAV_TYPE"]) if "MAV_TYPE" in params else None
    if mav_type is not None and mav_type in px4.MAV_TYPE_VTOL:
        is_vtol = True
    name = px4.vehicle_name(mav_type)
    refuse = mav_type is not None and not is_vtol and mav_type not in px4.MAV_TYPE_MULTIROTOR
    if not is_vtol and "vehicle_type" in status:
        vt = np.asarray(status["vehicle_type"])
        for kind, kind_name in ((px4.VEHICLE_TYPE_FIXED_WING, "fixed wing"),
                                (px4.VEHICLE_TYPE_ROVER, "ground rover")):  # fmt: skip
            if np.all(vt == kind):
                refuse, name = True, name or kind_name
    if refuse and px4.no_airframe_set(params):
        raise FlightLogError(
            f"{where}: no airframe set (SYS_AUTOSTART 0, MAV_TYPE 0): set the airframe "
            "(QGroundControl: Vehicle Setup > Airframe) and log again"
        )
    if refuse:
        known = f" (MAV_TYPE {mav_type})" if mav_type is not None else ""
        rover = mav_type == px4.MAV_TYPE_GROUND_ROVER or name == "ground rover"
        raise FlightLogError(
            f"{where}: a {name} log{known}, not a multirotor; these tools model multirotors: "
            + (
                "a PX4 rover's ULog is not read here (the ground rovers are learned only on "
                "the simulated ones: python -m scripts.rover --help); its drive gives a taught "
                "path: rover-path teach --from-log LOG --out PATH.csv"
                if rover
                else "use a log of a quad/hexa/octocopter (or a VTOL in multicopter phase)"
            )
        )
    return {
        "mav_type": mav_type,
        "type": name or "multirotor (MAV_TYPE not logged)",
        "is_vtol": is_vtol,
    }


def _keep_rows(topics, pos, rows, cols, t_all, vehicle, firmware):
    """Rows to keep and why the others were dropped; VTOL multicopter segments (us)."""
    n = len(t_all)
    valid = np.ones(n, dtype=bool)
    for flag in ("xy_valid", "z_valid", "v_xy_valid", "v_z_valid"):
        if flag in pos:
            valid &= np.asarray(pos[flag])[rows] > 0
    if "dead_reckoning" in pos:  # newer versions only (see module docstring)
        valid &= np.asarray(pos["dead_reckoning"])[rows] == 0
    cmd = np.column_stack([cols[f"cmd_vel_{a}_mps"] for a in "ned"])
    has_cmd = np.all(np.isfinite(cmd), axis=1)
    pos_ctrl = np.ones(n, dtype=bool)
    rotary = np.ones(n, dtype=bool)
    known = np.ones(n, dtype=bool)
    status = topics.get("vehicle_status")
    if status is not None:
        known = t_all >= float(np.asarray(status["timestamp"])[0])  # mode unknown before
        nav = _hold(status, "nav_state", t_all).astype(int)
        cols["mode"] = px4.mode_names(nav, firmware)
        cols["armed"] = (_hold(status, "arming_state", t_all) == px4.ARMING_STATE_ARMED) * 1.0
        pos_ctrl = np.isin(nav, list(px4.position_controlled_nav_states(firmware)))
        if vehicle["is_vtol"]:
            if "vehicle_type" in status:  # v1.10+
                rotary = _hold(status, "vehicle_type", t_all) == px4.VEHICLE_TYPE_ROTARY_WING
            elif "is_rotary_wing" in status:  # up to v1.9
                rotary = _hold(status, "is_rotary_wing", t_all) > 0
            if "in_transition_mode" in status:
                rotary &= _hold(status, "in_transition_mode", t_all) == 0
    if "vehicle_land_detected" in topics:
        cols["landed"] = (_hold(topics["vehicle_land_detected"], "landed", t_all) > 0) * 1.0
    valid_known = valid & known
    dropped = {
        "estimator_invalid": int(np.sum(~valid)),
        "mode_unknown": int(np.sum(valid & ~known)),
        "not_multicopter_phase": int(np.sum(valid_known & ~rotary)),
        "not_position_controlled": int(np.sum(valid_known & rotary & ~pos_ctrl)),
        "no_velocity_command": int(np.sum(valid_known & rotary & pos_ctrl & ~has_cmd)),
    }
    keep = valid_known & rotary & pos_ctrl & has_cmd
    segments = []
    if vehicle["is_vtol"]:
        edges = np.flatnonzero(np.diff(np.r_[0, rotary.astype(int), 0]))
        segments = [(t_all[a], t_all[b - 1]) for a, b in zip(edges[::2], edges[1::2], strict=True)]
    return keep, dropped, segments


def _thrust(topics: Topics, params: Mapping[str, float], t_us: np.ndarray):
    """Total thrust as a fraction of the maximum, from the best source present.

    1. ``actuator_motors`` control[i] (v1.13 with SYS_CTRL_ALLOC = 1, v1.14+), produced: each
       motor through PX4's thrust curve THR_MDL_FAC, averaged over CA_ROTOR_COUNT motors.
    2. ``actuator_outputs`` output[i] PWM (all versions), produced: normalised with PWM_MIN/MAX
       (seen in v1.6 and v1.11; UAVCAN vehicles have none) or PWM_MAIN_MIN/MAX where a log
       holds them, then the thrust curve; motors counted from MAV_TYPE.
    3. ``vehicle_thrust_setpoint`` -xyz[2] (v1.12+; published by the multicopter rate
       controller from v1.13) or ``actuator_controls_0`` control[3] (up to v1.13): commanded,
       not produced, thrust (kind ``commanded``).
    ``esc_status`` RPM is kept apart (:func:`_rotor_speed_rms`): turning it into thrust needs
    the vehicle's thrust coefficient, which a log does not hold.
    """
    fac = float(params.get("THR_MDL_FAC", 0.0))
    motors = topics.get("actuator_motors")
    n_rot = int(params.get("CA_ROTOR_COUNT", 0))
    if motors is not None and n_rot > 0:
        u = np.column_stack([_interp(motors, f"control[{i}]", t_us) for i in range(n_rot)])
        if np.all(np.isfinite(u)):
            detail = f"{n_rot} motors through THR_MDL_FAC={fac:g}"
            thrust = px4.motor_thrust_fraction(u, fac).mean(axis=1)
            return thrust, {"topic": "actuator_motors", "kind": "produced", "detail": detail}
    outputs = topics.get("actuator_outputs")
    n_mot = MOTOR_COUNT.get(int(params.get("MAV_TYPE", -1)), 0)
    lo = params.get("PWM_MAIN_MIN", params.get("PWM_MIN"))
    hi = params.get("PWM_MAIN_MAX", params.get("PWM_MAX"))
    if outputs is not None and n_mot and lo is not None and hi is not None and hi > lo:
        pwm = np.column_stack([_interp(outputs, f"output[{i}]", t_us) for i in range(n_mot)])
        u = (pwm - lo) / (hi - lo)
        detail = f"{n_mot} PWM outputs in [{lo:g}, {hi:g}] us through THR_MDL_FAC={fac:g}"
        thrust = px4.motor_thrust_fraction(u, fac).mean(axis=1)
        return thrust, {"topic": "actuator_outputs", "kind": "produced", "detail": detail}
    if "vehicle_thrust_setpoint" in topics:
        thrust = -_hold(topics["vehicle_thrust_setpoint"], "xyz[2]", t_us)
        return thrust, {"topic": "vehicle_thrust_setpoint", "kind": "commanded"}
    if "actuator_controls_0" in topics:
        thrust = _hold(topics["actuator_controls_0"], "control[3]", t_us)
        return thrust, {"topic": "actuator_controls_0", "kind": "commanded"}
    return None, None


def _rotor_speed_rms(topics: Topics, params: Mapping[str, float], t_us: np.ndarray):
    """Root mean square of the rotor speeds [rad/s] from ESC telemetry, and its description.

    ``esc_status`` carries ``esc_count`` and ``esc[i].esc_rpm`` (int32 revolutions per minute,
    every version v1.9 to v1.16; [PX4-msgs] esc_status.msg, esc_report.msg). The rotors are the
    first CA_ROTOR_COUNT (v1.14+) or MAV_TYPE's motor count of the ESCs; an ESC count below
    that, or RPM that never leaves zero (ESCs without telemetry), gives None. The total thrust
    is then n * k_T * rms^2 with the configuration's thrust coefficient k_T [N/(rad/s)^2].
    """
    esc = topics.get("esc_status")
    n_rotors = int(params.get("CA_ROTOR_COUNT", 0)) or MOTOR_COUNT.get(
        int(params.get("MAV_TYPE", -1)), 0
    )
    if esc is None or n_rotors == 0 or not all(f"esc[{i}].esc_rpm" in esc for i in range(n_rotors)):
        return None, None
    if int(np.max(np.asarray(esc.get("esc_count", [n_rotors])))) < n_rotors:
        return None, None
    rpm = np.column_stack([_interp(esc, f"esc[{i}].esc_rpm", t_us) for i in range(n_rotors)])
    if not np.any(np.abs(rpm) > 0):
        return None, None
    radps = np.abs(rpm) * (2.0 * np.pi / 60.0)
    rms = np.sqrt(np.mean(radps**2, axis=1))
    detail = f"{n_rotors} ESC RPM; thrust = {n_rotors} x thrust coefficient x rms^2"
    return rms, {"topic": "esc_status", "kind": "produced", "rotors": n_rotors, "detail": detail}


def _modes_flown(topics: Topics, firmware: str | None) -> str:
    status = topics.get("vehicle_status")
    if status is None:
        return ""
    names = list(dict.fromkeys(px4.mode_names(np.asarray(status["nav_state"]), firmware)))
    return f"; flown in {', '.join(names)}"


def _rate(topic: Mapping[str, np.ndarray], t_span_us: np.ndarray) -> float:
    """Samples per second of a topic over the span of the time base [Hz]."""
    t = np.asarray(topic["timestamp"], float)
    t = t[(t >= t_span_us[0]) & (t <= t_span_us[-1])]
    if len(t) < 2:
        return 0.0
    return round((len(t) - 1) / ((t[-1] - t[0]) * 1e-6), 2)


def _interp(topic: Mapping[str, np.ndarray], field: str, t_us: np.ndarray) -> np.ndarray:
    return np.interp(t_us, np.asarray(topic["timestamp"], float), np.asarray(topic[field], float))


def _hold(topic: Mapping[str, np.ndarray], field: str, t_us: np.ndarray) -> np.ndarray:
    times = np.asarray(topic["timestamp"], float)
    k = np.clip(np.searchsorted(times, t_us, side="right") - 1, 0, len(times) - 1)
    return np.asarray(topic[field], float)[k]
