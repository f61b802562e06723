"""Built-in plant: 6-DOF rigid body, four rotors with first-order lag, the effects; RK4.

Pure, jitted (numba) functions on flat float64 arrays, so a whole flight segment runs without
returning to Python. Frames: NED world, FRD body, quaternion (w, x, y, z) body-to-NED.
The kernels here and in :mod:`vehicle_sim.flight_control` use NumPy's error model: a float
division by zero gives inf or NaN instead of raising, which spares a test and a branch at every
division (about 15 % of a step; the numbers are the same). They divide only by validated
positive quantities (mass, inertia, time constants, gains) or behind guards.

State vector ``x`` (shape (N_STATE,)):
    [0:3] position NED [m], [3:6] velocity NED [m/s], [6:10] quaternion, [10:13] body rates
    FRD [rad/s], [13:17] rotor speeds normalised to the maximum [0..1], [17:20] gust velocity
    NED [m/s], [20] battery discharge fraction [0..1].
Plant parameters ``pp`` (shape (N_PLANT,)): see the ``P_*`` indices. Rotor geometry ``rp``
(shape (4, 3), FRD hub positions [m]) and ``spin`` (shape (4,), +1 ccw seen from above).
Effect vector ``ep`` (shape (N_EFFECT,)): the ``E_*`` indices below, filled by the effect classes
(:mod:`vehicle_sim.effects`); all numba-visible constants live in this file so that numba's
per-file cache never goes stale. Each effect class also holds the same physics in NumPy for the
diagnosis; tests/diagnosis/test_effect_registry.py checks the two agree for every effect.
Aux output ``aux`` (shape (N_AUX,)): kinematic acceleration NED at the end of the step, ground
contact flag, nominal and true total thrust [N], and the last motor commands.

Rotor i gives thrust T_i = g_eff * T_max * n_i^2 along -z_body and a reaction torque
spin_i * k_m * T_i about z_body, where n_i is its normalised speed, which follows its command
with time constant tau. g_eff is the effects' thrust factor (battery sag, ground effect). With
the thrust_curve effect (gain g) the speed follows sqrt(n_h^2 + g (n_cmd^2 - n_h^2)) instead of
n_cmd, n_h^2 the nominal hover thrust fraction: thrust changes by g per commanded change.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

POS, VEL, QUAT, RATES, MOTORS, GUST, DISCHARGE = 0, 3, 6, 10, 13, 17, 20
N_DYN = 17  # entries integrated by RK4 (position .. motors)
N_STATE = 21

P_MASS, P_JX, P_JY, P_JZ, P_TMAX, P_KM, P_TAU, P_G = 0, 1, 2, 3, 4, 5, 6, 7
N_PLANT = 8

AUX_ACC, AUX_CONTACT, AUX_THRUST_NOM, AUX_THRUST_TRUE, AUX_CMD = 0, 3, 4, 5, 6
N_AUX = 10

# packed effect vector (neutral values in effects.layout.neutral_effect_vector)
ROTOR_DRAG_K = 0  # (3,) N/(m/s), body FRD axes
BODY_DRAG_C = 3  # (3,) N/(m/s)^2, body FRD axes
WIND_NED = 6  # (3,) m/s
GUST_SIGMA = 9  # m/s, per axis
GUST_LENGTH = 10  # m
PAYLOAD_RATIO = 11  # true mass / nominal mass
BATTERY_TIME = 12  # s of hover-equivalent flight from full to empty; 0 = effect off
BATTERY_LOSS = 13  # fraction of thrust lost when empty
GROUND_GAIN = 14  # fraction of thrust gained with the rotors at the ground
GROUND_RADIUS = 15  # m, rotor radius
GROUND_HEIGHT = 16  # m, rotor plane height above the ground when landed
MOTOR_TAU = 17  # s; 0 = the preset's motor time constant
COMMAND_DELAY = 18  # s (applied by the simulator, not the physics)
FIELD_VEL_NED = 19  # (3,) m/s, peak air velocity of the wind field
FIELD_CENTER_NE = 22  # (2,) m, a point on the field's centre line (north, east)
FIELD_HEADING = 24  # rad, direction of the centre line (0 = north)
FIELD_HALF_WIDTH = 25  # m, 1/e half-width of the field; 0 = effect off
ISO_DRAG_K = 26  # N/(m/s)^2, drag along the airspeed: F = -k |v_air| v_air
THRUST_CURVE_GAIN = 27  # true / assumed thrust change per command change at hover; 0 = off
N_EFFECT = 28

GUST_MIN_SPEED_MPS = 1.0
MOTOR_STOPPED = 1e-9  # normalised rotor speed below which a rotor counts as stopped


@njit(cache=True, error_model="numpy")
def field_weight(x, ep):
    """Share in [0, 1] of the wind field's peak air velocity at the position x[0:2]:
    exp(-(d / half_width)^2), d the horizontal distance [m] from the field's centre line."""
    w = ep[FIELD_HALF_WIDTH]
    if w <= 0.0:
        return 0.0
    h = ep[FIELD_HEADING]
    d = -(x[0] - ep[FIELD_CENTER_NE]) * math.sin(h) + (x[1] - ep[FIELD_CENTER_NE + 1]) * math.cos(h)
    return math.exp(-(d / w) * (d / w))


@njit(cache=True, error_model="numpy")
def derivatives(x, n_cmd, pp, rp, spin, ep, gust, thrust_factor, dx):
    """Time derivative of the first N_DYN state entries into ``dx``; returns true thrust [N]."""
    qw, qx, qy, qz = x[6], x[7], x[8], x[9]
    r00 = 1.0 - 2.0 * (qy * qy + qz * qz)
    r01 = 2.0 * (qx * qy - qw * qz)
    r02 = 2.0 * (qx * qz + qw * qy)
    r10 = 2.0 * (qx * qy + qw * qz)
    r11 = 1.0 - 2.0 * (qx * qx + qz * qz)
    r12 = 2.0 * (qy * qz - qw * qx)
    r20 = 2.0 * (qx * qz - qw * qy)
    r21 = 2.0 * (qy * qz + qw * qx)
    r22 = 1.0 - 2.0 * (qx * qx + qy * qy)
    tmax = pp[P_TMAX] * thrust_factor
    thrust = 0.0
    tx = 0.0
    ty = 0.0
    tz = 0.0
    for i in range(4):
        n = x[MOTORS + i]
        t = tmax * n * n
        thrust += t
        tx -= rp[i, 1] * t
        ty += rp[i, 0] * t
        tz += spin[i] * pp[P_KM] * t
    fw = field_weight(x, ep)
    vax = x[3] - ep[WIND_NED] - fw * ep[FIELD_VEL_NED] - gust[0]
    vay = x[4] - ep[WIND_NED + 1] - fw * ep[FIELD_VEL_NED + 1] - gust[1]
    vaz = x[5] - ep[WIND_NED + 2] - fw * ep[FIELD_VEL_NED + 2] - gust[2]
    vbx = r00 * vax + r10 * vay + r20 * vaz
    vby = r01 * vax + r11 * vay + r21 * vaz
    vbz = r02 * vax + r12 * vay + r22 * vaz
    kiso = ep[ISO_DRAG_K] * math.sqrt(vbx * vbx + vby * vby + vbz * vbz)
    fbx = -ep[ROTOR_DRAG_K] * vbx - ep[BODY_DRAG_C] * vbx * abs(vbx) - kiso * vbx
    fby = -ep[ROTOR_DRAG_K + 1] * vby - ep[BODY_DRAG_C + 1] * vby * abs(vby) - kiso * vby
    fbz = -thrust - ep[ROTOR_DRAG_K + 2] * vbz - ep[BODY_DRAG_C + 2] * vbz * abs(vbz) - kiso * vbz
    m = pp[P_MASS] * ep[PAYLOAD_RATIO]
    dx[0] = x[3]
    dx[1] = x[4]
    dx[2] = x[5]
    dx[3] = (r00 * fbx + r01 * fby + r02 * fbz) / m
    dx[4] = (r10 * fbx + r11 * fby + r12 * fbz) / m
    dx[5] = (r20 * fbx + r21 * fby + r22 * fbz) / m + pp[P_G]
    p, q, r = x[10], x[11], x[12]
    dx[6] = 0.5 * (-qx * p - qy * q - qz * r)
    dx[7] = 0.5 * (qw * p + qy * r - qz * q)
    dx[8] = 0.5 * (qw * q + qz * p - qx * r)
    dx[9] = 0.5 * (qw * r + qx * q - qy * p)
    jx, jy, jz = pp[P_JX], pp[P_JY], pp[P_JZ]
    dx[10] = (tx - (jz - jy) * q * r) / jx
    dx[11] = (ty - (jx - jz) * r * p) / jy
    dx[12] = (tz - (jy - jx) * p * q) / jz
    tau = ep[MOTOR_TAU] if ep[MOTOR_TAU] > 0.0 else pp[P_TAU]
    gain = ep[THRUST_CURVE_GAIN]
    hover = pp[P_MASS] * pp[P_G] / (4.0 * pp[P_TMAX])  # hover n^2 of the nominal vehicle
    for i in range(4):
        target = n_cmd[i]
        if gain > 0.0 and target > 0.0:
            target = math.sqrt(max(hover + gain * (target * target - hover), 0.0))
        dx[MOTORS + i] = (target - x[MOTORS + i]) / tau
    return thrust


@njit(cache=True, error_model="numpy")
def thrust_factor(x, ep):
    """Thrust multiplier of battery sag and ground effect for state ``x``."""
    f = 1.0 - ep[BATTERY_LOSS] * x[DISCHARGE] if ep[BATTERY_TIME] > 0.0 else 1.0
    gain = ep[GROUND_GAIN]
    if gain > 0.0:
        h = max(-x[2], 0.0) + ep[GROUND_HEIGHT]
        h_max = 2.0 * ep[GROUND_RADIUS]
        if h < h_max:
            s = 1.0 - h / h_max
            f *= 1.0 + gain * s * s
    return f


@njit(cache=True, error_model="numpy")
def plant_step(x, n_cmd, pp, rp, spin, ep, noise, k, dt, scratch, aux):
    """Advance ``x`` by one RK4 step of ``dt`` with normalised rotor-speed commands ``n_cmd``.

    Also applies ground contact (the ground is the plane down = 0: the vehicle rests on it,
    never sinks, and sticks until its thrust lifts it), advances gusts with white noise row
    ``noise[k]`` (only read when gusts are on) and battery discharge, and fills ``aux``.
    ``scratch``: (6, N_DYN) work array.
    """
    k1, k2, k3, k4, xt = scratch[0], scratch[1], scratch[2], scratch[3], scratch[4]
    gust = x[GUST : GUST + 3]
    tf = thrust_factor(x, ep)
    derivatives(x, n_cmd, pp, rp, spin, ep, gust, tf, k1)
    for j in range(N_DYN):
        xt[j] = x[j] + 0.5 * dt * k1[j]
    derivatives(xt, n_cmd, pp, rp, spin, ep, gust, tf, k2)
    for j in range(N_DYN):
        xt[j] = x[j] + 0.5 * dt * k2[j]
    derivatives(xt, n_cmd, pp, rp, spin, ep, gust, tf, k3)
    for j in range(N_DYN):
        xt[j] = x[j] + dt * k3[j]
    derivatives(xt, n_cmd, pp, rp, spin, ep, gust, tf, k4)
    for j in range(N_DYN):
        x[j] += dt / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j])
    qn = math.sqrt(x[6] * x[6] + x[7] * x[7] + x[8] * x[8] + x[9] * x[9])
    for j in range(6, 10):
        x[j] /= qn
    for i in range(4):
        n = min(max(x[MOTORS + i], 0.0), 1.0)
        x[MOTORS + i] = n if n > MOTOR_STOPPED else 0.0
    contact = x[2] >= 0.0
    if contact:
        _rest_on_ground(x)
    sigma = ep[GUST_SIGMA]
    if sigma > 0.0:
        vax = x[3] - ep[WIND_NED]
        vay = x[4] - ep[WIND_NED + 1]
        vaz = x[5] - ep[WIND_NED + 2]
        speed = max(math.sqrt(vax * vax + vay * vay + vaz * vaz), GUST_MIN_SPEED_MPS)
        a = math.exp(-dt * speed / ep[GUST_LENGTH])
        b = sigma * math.sqrt(1.0 - a * a)
        for j in range(3):
            x[GUST + j] = a * x[GUST + j] + b * noise[k, j]
    nominal = 0.0
    for i in range(4):
        nominal += pp[P_TMAX] * x[MOTORS + i] * x[MOTORS + i]
    if ep[BATTERY_TIME] > 0.0:
        weight = pp[P_MASS] * pp[P_G]
        x[DISCHARGE] = min(x[DISCHARGE] + dt * nominal / weight / ep[BATTERY_TIME], 1.0)
    dx = scratch[5]
    true_thrust = derivatives(x, n_cmd, pp, rp, spin, ep, gust, thrust_factor(x, ep), dx)
    for j in range(3):
        aux[AUX_ACC + j] = 0.0 if contact else dx[VEL + j]
    aux[AUX_CONTACT] = 1.0 if contact else 0.0
    aux[AUX_THRUST_NOM] = nominal
    aux[AUX_THRUST_TRUE] = true_thrust


@njit(cache=True, error_model="numpy")
def _rest_on_ground(x):
    """Ground reaction: on the plane, at rest, level with the current yaw."""
    x[2] = 0.0
    for j in range(3, 6):
        x[j] = 0.0
    qw, qx, qy, qz = x[6], x[7], x[8], x[9]
    yaw = math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))
    x[6] = math.cos(0.5 * yaw)
    x[7] = 0.0
    x[8] = 0.0
    x[9] = math.sin(0.5 * yaw)
    for j in range(10, 13):
        x[j] = 0.0


@njit(cache=True, error_model="numpy")
def run_plant(n_steps, dt, x, n_cmd, pp, rp, spin, ep, noise, aux):
    """Open loop: ``n_steps`` physics steps with fixed rotor-speed commands ``n_cmd`` (4,)."""
    scratch = np.zeros((6, N_DYN))
    for k in range(n_steps):
        plant_step(x, n_cmd, pp, rp, spin, ep, noise, k, dt, scratch, aux)
        for i in range(4):
            aux[AUX_CMD + i] = n_cmd[i] * n_cmd[i]
