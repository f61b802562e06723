"""Force residual from a flight log: what the nominal rigid body with rotor thrust leaves over.

    r = m_nom * (a - g_ned) - R(q) @ [0, 0, -T]        [N], NED, per row

with m_nom the nominal mass, a the kinematic acceleration (the ``acc_*`` columns, or the
velocity differentiated with a Savitzky-Golay filter), g_ned = (0, 0, 9.80665) and T the
logged total rotor thrust ``thrust_n`` (the thrust the vehicle's own rotor model attributes to
its motor speeds). Drag, wind, a payload, ground effect and battery sag all show up in r; it does
not depend on which controller flew the vehicle.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import savgol_filter

from flightlog.schema import GRAVITY_MPS2, FlightLog

MIN_AIRBORNE_ALT_M = 0.01  # rows lower than this count as on the ground
SAVGOL_WINDOW_S = 0.25  # differentiation window when no acceleration is logged [s]


class ForceDataError(ValueError):
    """A log from which no force residual can be computed; the message says what is missing."""


@dataclass(frozen=True)
class ForceData:
    """Airborne rows of one or more logs, with the force residual.

    Attributes (n = number of airborne rows):
        t_s: (n,) time since the start of the log [s].
        segment: (n,) index of the log (and gap-free piece) each row came from.
        vel_ned_mps: (n, 3) velocity over ground.
        acc_ned_mps2: (n, 3) kinematic acceleration.
        rot: (n, 3, 3) body FRD to NED rotation matrices.
        thrust_n: (n,) logged total rotor thrust.
        alt_m: (n,) altitude above the take-off point (-pos_d).
        battery_v: (n,) battery voltage, NaN when not logged.
        mass_kg: nominal mass used for the residual.
        resid_ned_n: (n, 3) the force residual r defined in the module docstring.
        pos_ned_m: (n, 3) position NED [m] (None when not known: then an effect whose air is
            bound to a place, wind_field, predicts NaN).
        acc_regressor_ned_mps2, thrust_regressor_n: (n, 3) and (n,) acceleration and thrust as
            the effects' force models take them (:func:`neighbour_mean`); None: as measured.
    """

    t_s: np.ndarray
    segment: np.ndarray
    vel_ned_mps: np.ndarray
    acc_ned_mps2: np.ndarray
    rot: np.ndarray
    thrust_n: np.ndarray
    alt_m: np.ndarray
    battery_v: np.ndarray
    mass_kg: float
    resid_ned_n: np.ndarray
    pos_ned_m: np.ndarray | None = None
    acc_regressor_ned_mps2: np.ndarray | None = None
    thrust_regressor_n: np.ndarray | None = None

    @property
    def n_rows(self) -> int:
        return len(self.t_s)

    def take(self, rows: np.ndarray) -> ForceData:
        """The subset of rows ``rows`` (boolean mask or indices)."""
        optional = {
            k: None if getattr(self, k) is None else getattr(self, k)[rows]
            for k in _OPTIONAL_ROW_FIELDS
        }
        return ForceData(
            **{k: getattr(self, k)[rows] for k in _ROW_FIELDS}, mass_kg=self.mass_kg, **optional
        )

    def acc_regressor(self) -> np.ndarray:
        """(n, 3) acceleration the force models take [m/s^2]."""
        return (
            self.acc_ned_mps2
            if self.acc_regressor_ned_mps2 is None
            else self.acc_regressor_ned_mps2
        )

    def thrust_regressor(self) -> np.ndarray:
        """(n,) total rotor thrust the force models take [N]."""
        return self.thrust_n if self.thrust_regressor_n is None else self.thrust_regressor_n

    def positions(self) -> np.ndarray:
        """(n, 3) position NED [m]; NaN where not known."""
        if self.pos_ned_m is None:
            return np.full((self.n_rows, 3), np.nan)
        return self.pos_ned_m

    def thrust_axis_ned(self) -> np.ndarray:
        """(n, 3) unit thrust direction in NED (body -z)."""
        return -self.rot[:, :, 2]


_ROW_FIELDS = (
    "t_s", "segment", "vel_ned_mps", "acc_ned_mps2", "rot", "thrust_n", "alt_m", "battery_v",
    "resid_ned_n",
)  # fmt: skip
_OPTIONAL_ROW_FIELDS = ("pos_ned_m", "acc_regressor_ned_mps2", "thrust_regressor_n")


def neighbour_mean(x: np.ndarray) -> np.ndarray:
    """(n, ...) mean of each row's two neighbours (the one neighbour at either end).

    The force residual holds the measured acceleration and thrust, white noise included; an
    effect's force model that took the same noisy values as regressors would correlate with
    that noise, and a least-squares fit of it is biased (errors in variables: a payload and a
    battery sag, nearly collinear, are pushed apart by a few per cent of the weight on a log
    with 0.3 m/s^2 of IMU noise and 3 % of thrust noise). The neighbours' mean carries the same
    smooth signal (to (dt^2 / 2) x its second derivative) and none of the row's own white
    noise: an instrumental variable [Soderstrom89].
    """
    x = np.asarray(x, float)
    if len(x) < 2:
        return x.copy()
    out = np.empty_like(x)
    out[1:-1] = 0.5 * (x[:-2] + x[2:])
    out[0], out[-1] = x[1], x[-2]
    return out


def rotation_matrices(q_wxyz: np.ndarray) -> np.ndarray:
    """(n, 3, 3) body-to-NED rotation matrices of unit quaternions ``q_wxyz`` (n, 4)."""
    q = q_wxyz / np.linalg.norm(q_wxyz, axis=1, keepdims=True)
    w, x, y, z = q.T
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=1,
    )


def acceleration(log: FlightLog) -> np.ndarray:
    """(n, 3) kinematic acceleration NED [m/s^2]: logged, or differentiated velocity."""
    if log.has("acc_n_mps2", "acc_e_mps2", "acc_d_mps2"):
        return log.stack("acc_n_mps2", "acc_e_mps2", "acc_d_mps2")
    t = log["t_s"]
    vel = log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps")
    dt = float(np.median(np.diff(t))) if len(t) > 1 else 1.0
    window = max(5, 2 * round(SAVGOL_WINDOW_S / dt / 2) + 1)
    if len(t) < window:
        raise ForceDataError(f"log too short ({len(t)} rows) to differentiate its velocity")
    return savgol_filter(vel, window, 2, deriv=1, delta=dt, axis=0)


HOVER_THRUST_TOLERANCE = (0.75, 1.33)  # accepted thrust / weight in steady hover


def with_thrust_n(
    log: FlightLog,
    max_total_thrust_n: float,
    thrust_coeff_n_per_radps2: float,
    n_rotors: int,
    mass_kg: float,
) -> tuple[FlightLog, str]:
    """``log`` with a ``thrust_n`` column [N] from the best source it holds, and which one.

    1. ``thrust_n`` as logged.
    2. ``rotor_speed_rms_radps`` (ESC telemetry): n_rotors * k_T * rms^2, used only if its
       steady-hover median lies within :data:`HOVER_THRUST_TOLERANCE` of the weight (a wrong
       thrust coefficient or ESC pole count would otherwise pass for a payload).
    3. ``thrust_norm`` * ``max_total_thrust_n`` (PX4's thrust setpoint or motor outputs;
       assumes thrust linear in the command, as the simulator's mixer does).
    Without any of them the log is returned unchanged with source ``"none"``.
    """
    if log.has("thrust_n"):
        return log, "thrust_n as logged"
    note = ""
    if log.has("rotor_speed_rms_radps"):
        thrust = n_rotors * thrust_coeff_n_per_radps2 * log["rotor_speed_rms_radps"] ** 2
        ratio = _hover_thrust_ratio(log, thrust, mass_kg)
        lo, hi = HOVER_THRUST_TOLERANCE
        if ratio is not None and lo <= ratio <= hi:
            cols = {**log.columns, "thrust_n": thrust}
            source = (
                f"ESC rotor speed x the config's thrust coefficient (hover {ratio:.2f} x weight)"
            )
            return FlightLog(cols, log.metadata, log.path), source
        why = (
            "cannot be checked against the weight (no steady hover)"
            if ratio is None
            else f"is {ratio:.2f} x the weight (thrust coefficient or ESC pole count wrong?)"
        )
        note = f"; ESC rotor speed not used: its hover thrust {why}"
    if log.has("thrust_norm"):
        cols = {**log.columns, "thrust_n": log["thrust_norm"] * max_total_thrust_n}
        return FlightLog(cols, log.metadata, log.path), "normalised thrust x max thrust" + note
    return log, "none" + note


def _hover_thrust_ratio(log: FlightLog, thrust_n: np.ndarray, mass_kg: float) -> float | None:
    """Median thrust / weight over steady airborne rows (speed and acceleration < 0.3), or None
    when fewer than 20 such rows exist."""
    vel = log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps")
    acc = acceleration(log)
    steady = (np.linalg.norm(vel, axis=1) < 0.3) & (np.linalg.norm(acc, axis=1) < 0.3)
    steady &= -log["pos_d_m"] > MIN_AIRBORNE_ALT_M
    if log.has("landed"):
        steady &= log["landed"] < 0.5
    if log.has("armed"):
        steady &= log["armed"] > 0.5
    if np.sum(steady) < 20:
        return None
    return float(np.median(thrust_n[steady]) / (mass_kg * GRAVITY_MPS2))


def force_data(logs: list[FlightLog], mass_kg: float) -> ForceData:
    """Stack the airborne rows of ``logs`` and compute their force residual.

    Raises:
        ForceDataError: no ``thrust_n`` column (force-based causes need it) or no airborne row.
    """
    parts = []
    rows = disarmed = low = no_thrust = 0
    for i, log in enumerate(logs):
        if not log.has("thrust_n"):
            raise ForceDataError(
                f"log {i + 1} has no thrust_n column: force-based causes are not identifiable; "
                "log the total rotor thrust (from motor RPM and the thrust coefficient)"
            )
        alt = -log["pos_d_m"]
        armed = log["armed"] > 0.5 if log.has("armed") else np.ones(log.n_rows, bool)
        air = (alt > MIN_AIRBORNE_ALT_M) & armed & (log["thrust_n"] > 0.0)
        rows += log.n_rows  # each count fails its condition of ``air`` (a NaN fails it too)
        disarmed += int(np.sum(~armed))
        low += int(np.sum(~(alt > MIN_AIRBORNE_ALT_M)))
        no_thrust += int(np.sum(~(log["thrust_n"] > 0.0)))
        battery = log["battery_v"] if log.has("battery_v") else np.full(log.n_rows, np.nan)
        q = log.stack("q_w", "q_x", "q_y", "q_z")
        acc = acceleration(log)
        cols = {
            "t_s": log["t_s"] - log["t_s"][0],
            "segment": np.full(log.n_rows, i),
            "vel_ned_mps": log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps"),
            "acc_ned_mps2": acc,
            "rot": rotation_matrices(q),
            "thrust_n": log["thrust_n"],
            "alt_m": alt,
            "battery_v": battery,
            "pos_ned_m": log.stack("pos_n_m", "pos_e_m", "pos_d_m"),
            "acc_regressor_ned_mps2": neighbour_mean(acc),
            "thrust_regressor_n": neighbour_mean(log["thrust_n"]),
        }
        parts.append({k: v[air] for k, v in cols.items()})
    if not any(len(p["t_s"]) for p in parts):
        raise ForceDataError(
            f"no airborne rows (altitude > 1 cm, armed, thrust > 0) in the logs: of {rows} rows, "
            f"{disarmed} disarmed, {low} not above 1 cm, {no_thrust} without thrust (NaN counts "
            "as failing); use a log of a flight"
        )
    cols = {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}
    g = np.array([0.0, 0.0, GRAVITY_MPS2])
    thrust_force = -cols["rot"][:, :, 2] * cols["thrust_n"][:, None]
    resid = mass_kg * (cols["acc_ned_mps2"] - g) - thrust_force
    return ForceData(**cols, mass_kg=mass_kg, resid_ned_n=resid)
