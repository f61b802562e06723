"""PX4-like multicopter flight control as pure jitted functions.

The cascade follows PX4's mc_pos_control / mc_att_control / mc_rate_control:
position P -> velocity PID with anti-windup -> acceleration -> thrust vector with hover thrust
and tilt limit (vertical thrust has priority) -> quaternion attitude P (reduced attitude first,
yaw weighted) -> body-rate PID -> mixer with saturation (roll/pitch before yaw) -> normalised
motor thrust commands. It maps (state, setpoint, controller state, parameters) to motor commands
and knows nothing of the physics, so any plant that provides the state layout of
:mod:`vehicle_sim.physics` can be flown by it. Its kernels use NumPy's error model, as the
physics' do (see there).

Arrays (all float64):
    setpoint ``sp`` (N_SP,): position NED [m] (NaN per axis = not controlled), velocity NED
        feed-forward [m/s] (NaN = 0), yaw [rad] (NaN = integrate the yaw rate), yaw rate
        [rad/s], velocity limits horizontal / up / down [m/s], tilt limit [rad], ground-idle
        flag (motors at idle, integrators reset), armed flag, acceleration limit [m/s^2] of the
        velocity setpoint (auto modes: the setpoint is slewed at this rate and the slew is fed
        forward as acceleration, like PX4's trajectory generator; 0 = steps pass unchanged),
        acceleration feed-forward NED [m/s^2] (NaN = 0; e.g. an orbit's centripetal one).
    controller state ``cs`` (N_CTRL,): velocity integral [m/s^2], rate integral, previous
        rates [rad/s], yaw setpoint [rad], last velocity setpoint [m/s], last thrust vector
        (normalised, NED).
    parameters ``cp`` (N_CP,): PX4 gains, see ``C_*`` indices and :mod:`vehicle_sim.params`.
    mixer ``mix`` (4, 4): per motor, the normalised thrust per unit of roll, pitch, yaw torque
        command and collective thrust.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from vehicle_sim.compile_notice import announce_compiles
from vehicle_sim.physics import POS, QUAT, RATES, VEL

SP_POS, SP_VEL, SP_YAW, SP_YAW_RATE = 0, 3, 6, 7
SP_VMAX_XY, SP_VMAX_UP, SP_VMAX_DN, SP_TILT = 8, 9, 10, 11
SP_IDLE, SP_ARMED, SP_ACC_MAX, SP_ACC_FF = 12, 13, 14, 15
N_SP = 18

CS_VEL_INT, CS_RATE_INT, CS_PREV_RATES, CS_YAW_SP, CS_VEL_SP, CS_THR_SP = 0, 3, 6, 9, 10, 13
N_CTRL = 16

(
    C_VEL_P_XY,
    C_VEL_I_XY,
    C_VEL_D_XY,
    C_VEL_P_Z,
    C_VEL_I_Z,
    C_VEL_D_Z,
    C_POS_P_XY,
    C_POS_P_Z,
    C_THR_HOVER,
    C_THR_MIN,
    C_THR_MAX,
    C_ATT_P,
    C_YAW_WEIGHT,
    C_RATE_P,
    C_RATE_I,
    C_RATE_D,
    C_RATE_INT_LIM,
    C_RATE_MAX,
    C_IDLE,
    C_G,
) = (0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11, 14, 15, 18, 21, 24, 27, 30, 31)
N_CP = 32

# Work arrays for the temporaries of a control step (velocity setpoint, feed-forward, error,
# acceleration setpoint; then thrust vector, rate setpoint, torque), so a loop of steps
# allocates none (``control_step_in``).
N_VELOCITY_WORK = 12
N_CONTROL_WORK = 9 + N_VELOCITY_WORK


@njit(cache=True, error_model="numpy")
def quat_mul(a0, a1, a2, a3, b0, b1, b2, b3):
    """Hamilton product a * b of two quaternions given as (w, x, y, z) scalars."""
    return (
        a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3,
        a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2,
        a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1,
        a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0,
    )


@njit(cache=True, error_model="numpy")
def yaw_of(x):
    """Yaw [rad] of the attitude in state ``x``."""
    qw, qx, qy, qz = x[QUAT], x[QUAT + 1], x[QUAT + 2], x[QUAT + 3]
    return math.atan2(2.0 * (qw * qz + qx * qy), 1.0 - 2.0 * (qy * qy + qz * qz))


@njit(cache=True, error_model="numpy")
def _wrap_pi(a):
    return (a + math.pi) % (2.0 * math.pi) - math.pi


@njit(cache=True, error_model="numpy")
def reset_controller(x, cs):
    """Clear integrators and align the yaw setpoint with the current yaw."""
    for j in range(9):
        cs[j] = 0.0
    for j in range(3):
        cs[CS_PREV_RATES + j] = x[RATES + j]
        cs[CS_VEL_SP + j] = 0.0
        cs[CS_THR_SP + j] = 0.0
    cs[CS_YAW_SP] = yaw_of(x)


@njit(cache=True, error_model="numpy")
def velocity_control(x, acc, sp, cs, cp, dt, thr):
    """Position/velocity cascade: writes the normalised thrust vector (NED) into ``thr``."""
    velocity_control_in(x, acc, sp, cs, cp, dt, thr, np.empty(N_VELOCITY_WORK))


@njit(cache=True, error_model="numpy")
def velocity_control_in(x, acc, sp, cs, cp, dt, thr, work):
    """:func:`velocity_control` with its temporaries in ``work`` (N_VELOCITY_WORK,)."""
    vsp, acc_ff, err, acc_sp = work[0:3], work[3:6], work[6:9], work[9:12]
    for i in range(3):
        v = sp[SP_VEL + i]
        vsp[i] = v if math.isfinite(v) else 0.0
        if math.isfinite(sp[SP_POS + i]):
            kp = cp[C_POS_P_Z] if i == 2 else cp[C_POS_P_XY]
            vsp[i] += kp * (sp[SP_POS + i] - x[POS + i])
    vxy = math.sqrt(vsp[0] * vsp[0] + vsp[1] * vsp[1])
    if vxy > sp[SP_VMAX_XY]:
        vsp[0] *= sp[SP_VMAX_XY] / vxy
        vsp[1] *= sp[SP_VMAX_XY] / vxy
    vsp[2] = min(max(vsp[2], -sp[SP_VMAX_UP]), sp[SP_VMAX_DN])
    for i in range(3):
        acc_ff[i] = 0.0
    a_max = sp[SP_ACC_MAX]
    if a_max > 0.0:
        d0 = vsp[0] - cs[CS_VEL_SP]
        d1 = vsp[1] - cs[CS_VEL_SP + 1]
        d2 = vsp[2] - cs[CS_VEL_SP + 2]
        dn = math.sqrt(d0 * d0 + d1 * d1 + d2 * d2)
        s = min(1.0, a_max * dt / dn) if dn > 0.0 else 1.0
        vsp[0] = cs[CS_VEL_SP] + s * d0
        vsp[1] = cs[CS_VEL_SP + 1] + s * d1
        vsp[2] = cs[CS_VEL_SP + 2] + s * d2
        acc_ff[0], acc_ff[1], acc_ff[2] = s * d0 / dt, s * d1 / dt, s * d2 / dt
    for i in range(3):
        a_ff = sp[SP_ACC_FF + i]
        if math.isfinite(a_ff):
            acc_ff[i] += a_ff
    g = cp[C_G]
    hover = cp[C_THR_HOVER]
    for i in range(3):
        cs[CS_VEL_SP + i] = vsp[i]
        err[i] = vsp[i] - x[VEL + i]
        kp = cp[C_VEL_P_Z] if i == 2 else cp[C_VEL_P_XY]
        kd = cp[C_VEL_D_Z] if i == 2 else cp[C_VEL_D_XY]
        acc_sp[i] = kp * err[i] + cs[CS_VEL_INT + i] - kd * acc[i] + acc_ff[i]
    # acceleration -> thrust direction with tilt limit, collective from hover thrust
    bz0, bz1, bz2 = -acc_sp[0], -acc_sp[1], g
    nrm = math.sqrt(bz0 * bz0 + bz1 * bz1 + bz2 * bz2)
    bz0, bz1, bz2 = bz0 / nrm, bz1 / nrm, bz2 / nrm
    tilt = sp[SP_TILT]
    if bz2 < math.cos(tilt):
        hxy = math.sqrt(bz0 * bz0 + bz1 * bz1)
        bz0, bz1, bz2 = bz0 / hxy * math.sin(tilt), bz1 / hxy * math.sin(tilt), math.cos(tilt)
    coll = (acc_sp[2] * hover / g - hover) / bz2
    coll = min(coll, -cp[C_THR_MIN])
    thr[0], thr[1], thr[2] = bz0 * coll, bz1 * coll, bz2 * coll
    # vertical anti-windup
    if (thr[2] >= -cp[C_THR_MIN] and err[2] >= 0.0) or (thr[2] <= -cp[C_THR_MAX] and err[2] <= 0.0):
        err[2] = 0.0
    # vertical priority: saturate vertical, give the horizontal what is left
    thr[2] = max(thr[2], -cp[C_THR_MAX])
    left = cp[C_THR_MAX] ** 2 - thr[2] * thr[2]
    thr_xy_max = math.sqrt(left) if left > 0.0 else 0.0
    txy = math.sqrt(thr[0] * thr[0] + thr[1] * thr[1])
    if txy > thr_xy_max:
        thr[0] *= thr_xy_max / txy
        thr[1] *= thr_xy_max / txy
    # horizontal tracking anti-windup: feed back what could not be produced
    ax_prod = thr[0] * g / hover
    ay_prod = thr[1] * g / hover
    if acc_sp[0] ** 2 + acc_sp[1] ** 2 > ax_prod**2 + ay_prod**2:
        arw = 2.0 / cp[C_VEL_P_XY]
        err[0] -= arw * (acc_sp[0] - ax_prod)
        err[1] -= arw * (acc_sp[1] - ay_prod)
    for i in range(3):
        ki = cp[C_VEL_I_Z] if i == 2 else cp[C_VEL_I_XY]
        cs[CS_VEL_INT + i] += ki * err[i] * dt
        cs[CS_THR_SP + i] = thr[i]


@njit(cache=True, error_model="numpy")
def attitude_rate_setpoint(x, thr, sp, cs, cp, dt, rsp):
    """Thrust vector + yaw setpoint -> body-rate setpoint ``rsp`` (3,) [rad/s]."""
    use_rate = not math.isfinite(sp[SP_YAW])
    if use_rate:
        cs[CS_YAW_SP] = _wrap_pi(cs[CS_YAW_SP] + sp[SP_YAW_RATE] * dt)
    else:
        cs[CS_YAW_SP] = sp[SP_YAW]
    yaw = cs[CS_YAW_SP]
    tn = math.sqrt(thr[0] * thr[0] + thr[1] * thr[1] + thr[2] * thr[2])
    if tn > 1e-6:
        bz0, bz1, bz2 = -thr[0] / tn, -thr[1] / tn, -thr[2] / tn
    else:
        bz0, bz1, bz2 = 0.0, 0.0, 1.0
    yc0, yc1 = -math.sin(yaw), math.cos(yaw)
    bx0, bx1, bx2 = yc1 * bz2, -yc0 * bz2, yc0 * bz1 - yc1 * bz0
    n = math.sqrt(bx0 * bx0 + bx1 * bx1 + bx2 * bx2)
    bx0, bx1, bx2 = bx0 / n, bx1 / n, bx2 / n
    by0, by1, by2 = bz1 * bx2 - bz2 * bx1, bz2 * bx0 - bz0 * bx2, bz0 * bx1 - bz1 * bx0
    d0, d1, d2, d3 = _quat_from_columns(bx0, bx1, bx2, by0, by1, by2, bz0, bz1, bz2)
    qw, qx, qy, qz = x[QUAT], x[QUAT + 1], x[QUAT + 2], x[QUAT + 3]
    # current body z axis in NED
    ez0 = 2.0 * (qx * qz + qw * qy)
    ez1 = 2.0 * (qy * qz - qw * qx)
    ez2 = 1.0 - 2.0 * (qx * qx + qy * qy)
    # reduced attitude: shortest rotation of the thrust axis, applied in the world frame
    dot = ez0 * bz0 + ez1 * bz1 + ez2 * bz2
    if dot > -0.99:
        c0, c1, c2 = ez1 * bz2 - ez2 * bz1, ez2 * bz0 - ez0 * bz2, ez0 * bz1 - ez1 * bz0
        rw = 1.0 + dot
        rn = math.sqrt(rw * rw + c0 * c0 + c1 * c1 + c2 * c2)
        r0, r1, r2, r3 = quat_mul(rw / rn, c0 / rn, c1 / rn, c2 / rn, qw, qx, qy, qz)
    else:
        r0, r1, r2, r3 = d0, d1, d2, d3
    # mix in only a fraction of the yaw error (PX4 MC_YAW_WEIGHT)
    m0, m1, m2, m3 = quat_mul(r0, -r1, -r2, -r3, d0, d1, d2, d3)
    if m0 < 0.0:
        m0, m3 = -m0, -m3
    m0 = min(max(m0, -1.0), 1.0)
    m3 = min(max(m3, -1.0), 1.0)
    w = cp[C_YAW_WEIGHT]
    a = math.cos(w * math.acos(m0))
    b = math.sin(w * math.asin(m3))
    f0, f1, f2, f3 = quat_mul(r0, r1, r2, r3, a, 0.0, 0.0, b)
    e0, e1, e2, e3 = quat_mul(qw, -qx, -qy, -qz, f0, f1, f2, f3)
    if e0 < 0.0:
        e1, e2, e3 = -e1, -e2, -e3
    rsp[0] = 2.0 * e1 * cp[C_ATT_P]
    rsp[1] = 2.0 * e2 * cp[C_ATT_P + 1]
    rsp[2] = 2.0 * e3 * cp[C_ATT_P + 2] / max(w, 1e-4)
    if use_rate:
        # yaw-rate feed-forward about the world z axis, expressed in body axes
        rsp[0] += 2.0 * (qx * qz - qw * qy) * sp[SP_YAW_RATE]
        rsp[1] += 2.0 * (qy * qz + qw * qx) * sp[SP_YAW_RATE]
        rsp[2] += ez2 * sp[SP_YAW_RATE]
    for i in range(3):
        lim = cp[C_RATE_MAX + i]
        rsp[i] = min(max(rsp[i], -lim), lim)


@njit(cache=True, error_model="numpy")
def _quat_from_columns(a0, a1, a2, b0, b1, b2, c0, c1, c2):
    """Quaternion (w, x, y, z) of the rotation matrix with columns a, b, c."""
    # matrix R[i][j]: column a = R[:, 0], b = R[:, 1], c = R[:, 2]
    tr = a0 + b1 + c2
    if tr > 0.0:
        s = 2.0 * math.sqrt(tr + 1.0)
        return 0.25 * s, (b2 - c1) / s, (c0 - a2) / s, (a1 - b0) / s
    if a0 > b1 and a0 > c2:
        s = 2.0 * math.sqrt(1.0 + a0 - b1 - c2)
        return (b2 - c1) / s, 0.25 * s, (b0 + a1) / s, (c0 + a2) / s
    if b1 > c2:
        s = 2.0 * math.sqrt(1.0 + b1 - a0 - c2)
        return (c0 - a2) / s, (b0 + a1) / s, 0.25 * s, (c1 + b2) / s
    s = 2.0 * math.sqrt(1.0 + c2 - a0 - b1)
    return (a1 - b0) / s, (c0 + a2) / s, (c1 + b2) / s, 0.25 * s


@njit(cache=True, error_model="numpy")
def rate_control(x, rsp, cs, cp, dt, torque):
    """Body-rate PID (D on the measured rate) -> normalised torque commands ``torque`` (3,)."""
    for i in range(3):
        rate = x[RATES + i]
        err = rsp[i] - rate
        d_rate = (rate - cs[CS_PREV_RATES + i]) / dt
        cs[CS_PREV_RATES + i] = rate
        torque[i] = cp[C_RATE_P + i] * err + cs[CS_RATE_INT + i] - cp[C_RATE_D + i] * d_rate
        # integrate less for large errors (PX4), keep within the integrator limit
        i_factor = max(0.0, 1.0 - (err / math.radians(400.0)) ** 2)
        lim = cp[C_RATE_INT_LIM + i]
        integ = cs[CS_RATE_INT + i] + i_factor * cp[C_RATE_I + i] * err * dt
        cs[CS_RATE_INT + i] = min(max(integ, -lim), lim)


@njit(cache=True, error_model="numpy")
def mix_motors(torque, thrust, mix, u):
    """Mixer with saturation: roll/pitch first (shifting thrust), then as much yaw as fits."""
    lo = 1e9
    hi = -1e9
    for i in range(4):
        rp = mix[i, 0] * torque[0] + mix[i, 1] * torque[1]
        u[i] = rp
        lo = min(lo, rp)
        hi = max(hi, rp)
    scale = 1.0
    if hi - lo > 1.0:
        scale = 1.0 / (hi - lo)
        lo *= scale
        hi *= scale
    t = min(max(thrust, -lo), 1.0 - hi)
    for i in range(4):
        u[i] = u[i] * scale + t * mix[i, 3]
    k_yaw = 1.0
    for i in range(4):
        y = mix[i, 2] * torque[2]
        if u[i] + y > 1.0 and y > 0.0:
            k_yaw = min(k_yaw, max(1.0 - u[i], 0.0) / y)
        elif u[i] + y < 0.0 and y < 0.0:
            k_yaw = min(k_yaw, max(u[i], 0.0) / -y)
    for i in range(4):
        u[i] = min(max(u[i] + k_yaw * mix[i, 2] * torque[2], 0.0), 1.0)


@njit(cache=True, error_model="numpy")
def control_step(x, acc, sp, cs, cp, mix, dt, u):
    """One flight-control step: state ``x``, acceleration ``acc`` (3,) -> motor thrusts ``u``.

    ``u`` (4,): normalised motor thrust commands in [0, 1] (rotor speed command = sqrt(u)).
    """
    control_step_in(x, acc, sp, cs, cp, mix, dt, u, np.empty(N_CONTROL_WORK))


# A plant of its own (JSBSim's) calls it from Python: its compile, about 6 s, is said.
announce_compiles(control_step, "the simulator's compiled flight control", 6.0)


@njit(cache=True, error_model="numpy")
def control_step_in(x, acc, sp, cs, cp, mix, dt, u, work):
    """:func:`control_step` with its temporaries in ``work`` (N_CONTROL_WORK,): a loop of
    steps allocates it once, where seven small arrays a step took about 8 % of a physics step."""
    if sp[SP_ARMED] < 0.5:
        reset_controller(x, cs)
        for i in range(4):
            u[i] = 0.0
        return
    if sp[SP_IDLE] > 0.5:
        reset_controller(x, cs)
        if math.isfinite(sp[SP_YAW]):
            cs[CS_YAW_SP] = sp[SP_YAW]
        for i in range(4):
            u[i] = cp[C_IDLE]
        return
    thr, rsp, torque = work[0:3], work[3:6], work[6:9]
    velocity_control_in(x, acc, sp, cs, cp, dt, thr, work[9:])
    attitude_rate_setpoint(x, thr, sp, cs, cp, dt, rsp)
    rate_control(x, rsp, cs, cp, dt, torque)
    collective = math.sqrt(thr[0] * thr[0] + thr[1] * thr[1] + thr[2] * thr[2])
    mix_motors(torque, collective, mix, u)


def mixer_matrix(
    rotor_positions_frd_m: np.ndarray, rotor_spin: np.ndarray, yaw_torque_per_thrust_m: float
) -> np.ndarray:
    """PX4-style normalised mixer (4, 4) from rotor geometry.

    Columns: roll, pitch, yaw, thrust. The pseudo-inverse of the effectiveness matrix,
    normalised as PX4's control allocator does: roll and pitch share one scale (the weaker axis
    swings half the motors by +-1/sqrt(2) per unit command, quad X), yaw is scaled so the
    largest swing is 1, thrust so a unit command is full thrust on every motor.
    """
    pos = np.asarray(rotor_positions_frd_m, dtype=float)
    spin = np.asarray(rotor_spin, dtype=float)
    eff = np.vstack([-pos[:, 1], pos[:, 0], spin * yaw_torque_per_thrust_m, np.ones(len(spin))])
    mix = np.linalg.pinv(eff)
    scales = []
    for j in (0, 1):
        col = mix[:, j]
        nz = np.count_nonzero(np.abs(col) > 1e-9)
        scales.append(np.sqrt(np.sum(col**2) / (nz / 2.0)))
    mix[:, 0:2] /= max(scales)
    mix[:, 2] /= np.max(np.abs(mix[:, 2]))
    mix[:, 3] /= np.mean(mix[:, 3])
    return np.ascontiguousarray(mix)
