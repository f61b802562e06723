"""What a flight log holds, as lines a user reads (the core of ``flightlog info``)."""

from __future__ import annotations

import numpy as np

from flightlog import px4
from flightlog.battery_pack import CELL_RANGE_V, PackReading, counts_in_words
from flightlog.reader import NEEDS_HZ, log_rates_hz, rate_shortfalls
from flightlog.schema import FlightLog
from flightlog.ulog import damage_note, parameters_give_a_config


def mode_spans(log: FlightLog) -> list[tuple[str, float, float]]:
    """(mode, start_s, end_s) for each contiguous run of one mode; [] without a mode column."""
    if not log.has("mode"):
        return []
    mode, t = log["mode"], log["t_s"]
    cuts = [0, *(np.flatnonzero(mode[1:] != mode[:-1]) + 1).tolist(), len(mode)]
    return [
        (str(mode[a]), float(t[a]), float(t[b - 1]))
        for a, b in zip(cuts[:-1], cuts[1:], strict=True)
        if b > a
    ]


def describe_log(log: FlightLog) -> list[str]:
    """Lines: vehicle, firmware, duration, rates, modes, validity, thrust, what commands can do."""
    meta = log.metadata
    t = log["t_s"]
    lines = [f"file: {log.where}", f"source: {meta.get('source', 'csv')}"]
    vehicle = meta.get("vehicle")
    if isinstance(vehicle, dict):
        vtol = " (VTOL)" if vehicle.get("is_vtol") else ""
        lines.append(f"vehicle: {vehicle.get('type')}{vtol}")
    if meta.get("source") == "px4_ulog":
        lines += _firmware_and_dropouts(meta)
    if "duration_s" in meta:
        lines.append(f"log duration: {meta['duration_s']:.1f} s")
    damaged = damage_note(log)
    if damaged:
        kind = "truncated" if meta.get("truncated_at_byte") else "corrupt"
        lines.append(f"{kind}: {damaged}")
    lines.append(f"usable rows: {log.n_rows} over {t[-1] - t[0]:.1f} s")
    for name, hz in log_rates_hz(log).items():
        lines.append(f"rate {name}: {hz:g} Hz")
    if meta.get("command_topic"):
        lines.append(f"velocity command from: {meta['command_topic']}")
    spans = mode_spans(log)
    for mode, a, b in spans:
        lines.append(f"mode {mode}: {a:.1f} s to {b:.1f} s")
    if not spans:
        lines.append("modes: not recorded (--mode filters cannot be used)")
    dropped = meta.get("dropped_rows")
    if isinstance(dropped, dict):
        total = meta.get("rows_in_log")
        for why, n in dropped.items():
            lines.append(f"dropped {why.replace('_', ' ')}: {n} of {total} rows")
    for seg in meta.get("vtol_multicopter_segments_s", []) or []:
        lines.append(f"VTOL multicopter phase: {seg[0]:.1f} s to {seg[1]:.1f} s")
    thrust = meta.get("thrust_source")
    if isinstance(thrust, dict):
        lines.append(f"thrust: {thrust.get('kind')} from {thrust.get('topic')}")
    elif log.has("thrust_n") or log.has("thrust_norm"):
        lines.append("thrust: " + ("thrust_n" if log.has("thrust_n") else "thrust_norm"))
    else:
        lines.append("thrust: none")
    if log.has("battery_v"):
        lines.append(_battery_line(log["battery_v"]))
    rotor = meta.get("rotor_speed_source")
    if isinstance(rotor, dict):
        lines.append(
            f"rotor speed: produced, from {rotor.get('topic')} ({rotor.get('detail')}); diagnose "
            "prefers it when the config's thrust coefficient matches the hover"
        )
    grounded: dict[str, str] = {}  # command: why the log's rows give it nothing to use
    if log.has("armed"):
        armed = log["armed"] > 0.5
        flying = armed & (log["landed"] < 0.5) if log.has("landed") else armed
        lines.append(f"armed: {int(armed.sum())} of {log.n_rows} rows ({int(flying.sum())} flying)")
        if not armed.any():
            why = "no armed row (the vehicle never flew)"
            grounded = {"fit-gp": why, "diagnose": why}
        elif not flying.any():
            grounded = {"diagnose": "no airborne row (armed on the ground only)"}
    for command in NEEDS_HZ:
        short = rate_shortfalls(log, command)
        verdict = "too slow: " + "; ".join(short) if short else "rates sufficient"
        if command in grounded:
            verdict = f"cannot use this log: {grounded[command]}"
        lines.append(f"{command}: {verdict}")
    has_thrust = log.has("thrust_n") or log.has("thrust_norm") or log.has("rotor_speed_rms_radps")
    if not has_thrust:
        lines.append(
            "diagnose: no thrust: the causes read from the force residual (drags, wind, "
            "payload, battery sag, ground effect) cannot be examined, only those read from the "
            "replay (command delay, motor lag, thrust curve, flight control)"
        )
        if meta.get("source") == "companion":
            lines.append(
                "diagnose: this is the companion's log (MAVLink carries no thrust or "
                "acceleration); diagnose the vehicle's onboard log instead: its PX4 .ulg, or "
                "vehicle-sim --log"
            )
    return lines


def _battery_line(volts: np.ndarray) -> str:
    """What the logged voltage (n,) [V] says of the pack (:mod:`.battery_pack`)."""
    pack = PackReading.of([volts])
    if pack is None:
        return "battery: battery_v holds no finite value"
    if not pack.is_pack():
        return (
            f"battery: median {pack.median_v:.2f} V is no pack voltage (below one cell's "
            f"{CELL_RANGE_V[0]:.1f} V: no power module?); diagnose cannot examine battery sag"
        )
    return (
        f"battery: {pack.least_v:.1f}-{pack.most_v:.1f} V, a pack of "
        f"{counts_in_words(pack.cells())} cells"
    )


def describe_unusable_ulog(summary: dict, reason: str) -> list[str]:
    """Lines for a ULog the mapping refuses: what it holds (``ulog.summarise_ulog``), why no
    command can use its flight, and, for a multirotor, that config-from-log can use its
    parameters."""
    lines = ["source: px4_ulog"]
    if px4.no_airframe_set(summary["px4_params"]):
        lines.append("vehicle: unknown (no airframe set: SYS_AUTOSTART 0, MAV_TYPE 0)")
    elif summary.get("vehicle"):
        lines.append(f"vehicle: {summary['vehicle']}")
    lines += _firmware_and_dropouts(summary)
    lines.append(f"log duration: {summary['duration_s']:.1f} s")
    for name, hz in summary["rates_hz"].items():
        count = summary["messages"][name]
        lines.append(f"topic {name}: {hz:g} Hz" if count > 1 else f"topic {name}: {count} message")
    for mode, a, b in summary["modes"]:
        lines.append(f"mode {mode}: {a:.1f} s to {b:.1f} s")
    if not summary["modes"]:
        lines.append("modes: not recorded")
    lines.append(f"fit-gp, diagnose, convert: cannot use this log: {reason}")
    if parameters_give_a_config(summary):
        lines.append(
            "config-from-log: from its PX4 parameters only (hover thrust: the MPC_THR_HOVER "
            "parameter, not measured)"
        )
    return lines


def _firmware_and_dropouts(meta: dict) -> list[str]:
    """A ULog's firmware line (also when the log records no version) and, if its logger dropped
    messages, how many and for how long."""
    hardware = meta.get("hardware")
    board = f"on {hardware}" if hardware else "on a board not logged (no ver_hw)"
    if meta.get("firmware"):
        lines = [f"firmware: PX4 {meta['firmware']} {board}"]
    else:
        lines = [
            f"firmware: PX4, version not logged (no ver_sw_release), {board}; "
            "flight modes read with the numbering before v1.15"
        ]
    count, total_s, longest_s = meta.get("logger_dropouts") or (0, 0.0, 0.0)
    if count:
        lines.append(
            f"logger dropouts: {count:g}, {total_s:g} s in all, longest {longest_s * 1e3:g} ms "
            "(no topic has data in them)"
        )
    return lines
