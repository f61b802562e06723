"""Cubic uniform B-spline references through waypoints, timed under speed/accel limits.

The spline interpolates the waypoints at its knots and starts and ends at rest (zero
velocity). All segments last the same time (a uniform B-spline in time), the shortest that
keeps |velocity| <= max_speed_mps and |acceleration| <= max_acc_mps2 everywhere. Before t = 0
and after the end the reference holds its end points at rest. Yaw is held constant.

Jerk-limited ends (``ramp_jerk_mps3``). The spline starts and ends at rest but with a step in
acceleration (its second derivative at the end knots is not zero; up to the acceleration limit
on fast references): a multirotor has to tilt before it accelerates, so no vehicle follows that
step. PX4's own setpoint generators limit the jerk (MPC_JERK_AUTO, 4 m/s^3 by default in auto
modes; MPC_JERK_MAX, 8 m/s^3, in position mode; [PX4-params]). With ``ramp_jerk_mps3`` set,
time is reparametrised over a ramp at each end: the knot parameter's rate rises from 0 to its
cruise value as r(x) = 2x - x^2 over the ramp (x from 0 to 1), and falls symmetrically at the
end. The path is unchanged (the same control points); velocity and acceleration start and end
at 0 and are continuous, and the jerk is bounded (it steps where a ramp meets the cruise).
The ramps' length is the one whose peak jerk is ``ramp_jerk_mps3`` (four fixed-point steps,
within about 1 %; in the spline's own near-quadratic start the peak is about
2.04 |a_plain(0)| / ramp length, one length for both ends, fitted to the larger step).
Between the ramps the reference is the plain one delayed by a third of a ramp: the segment time
stays the plain one unless the warped timing needs more to keep the speed and acceleration
limits (the warp's C'(u) u'' term adds up to 11 % to the acceleration within a ramp). Each
ramp adds a third of its length to the duration. Without it (the default) the reference is
the plain spline, bit for bit.
"""

from __future__ import annotations

import numpy as np

from planners.reference import ReferenceSample, SampledReference

# Rows: coefficients of 1, s, s^2, s^3 for the 4 control points of one segment.
_BASIS = np.array([[1, 4, 1, 0], [-3, 0, 3, 0], [3, -6, 3, 0], [-1, 3, -3, 1]]) / 6.0
_LIMIT_SAMPLES_PER_SEGMENT = 64
_LIMIT_MARGIN = 1.001
# The ramps (module docstring): samples per ramp for their limits and jerk (on top of the
# plain check's: a ramp's acceleration peaks within a fraction of a segment), the
# fixed-point steps fitting their length to the jerk, and the longest ramp in segments (the
# two ramps meet in the middle at 3/4 of the knot range each).
_RAMP_SAMPLES = 512
_RAMP_ITERATIONS = 4
_RAMP_MAX = 0.75
_RAMP_PEAK_JERK = 2.04  # peak of d/dx (r^2 + R r'), r = 2x - x^2, R its integral


class BSplineReference(SampledReference):
    """Cubic uniform B-spline through ``waypoints_ned_m`` (M+1, 3), M >= 1.

    Attributes:
        waypoints_ned_m: the waypoints, shape (M+1, 3) [m].
        control_points_ned_m: control points, shape (M+3, 3) [m].
        segment_duration_s: time per spline segment [s].
        duration_s: total time, M * segment_duration_s [s], plus 2/3 * ramp_s with ramps.
        yaw_rad: constant yaw of the reference [rad].
        ramp_jerk_mps3: the peak jerk of the ramps at each end [m/s^3] (module docstring);
            None: no ramps.
        ramp_s: each ramp's length [s]; 0 without ramps.
    """

    def __init__(
        self,
        waypoints_ned_m: np.ndarray,
        max_speed_mps: float = 1.5,
        max_acc_mps2: float = 1.0,
        yaw_rad: float = 0.0,
        ramp_jerk_mps3: float | None = None,
    ) -> None:
        wp = np.asarray(waypoints_ned_m, dtype=float)
        if wp.ndim != 2 or wp.shape[1] != 3 or wp.shape[0] < 2:
            raise ValueError(f"waypoints_ned_m must have shape (M+1, 3), M >= 1; got {wp.shape}")
        if not np.all(np.isfinite(wp)):
            raise ValueError("waypoints_ned_m must be finite")
        if not (max_speed_mps > 0 and max_acc_mps2 > 0):
            raise ValueError(
                f"limits must be > 0, got max_speed_mps={max_speed_mps}, "
                f"max_acc_mps2={max_acc_mps2}"
            )
        if ramp_jerk_mps3 is not None and not 0 < ramp_jerk_mps3 < np.inf:
            raise ValueError(
                f"ramp_jerk_mps3 must be finite and > 0 (None: no ramps), got {ramp_jerk_mps3}"
            )
        self.waypoints_ned_m = wp
        self.yaw_rad = float(yaw_rad)
        self.control_points_ned_m = _interpolating_control_points(wp)
        self._n_seg = wp.shape[0] - 1
        cp = self.control_points_ned_m
        segments = np.stack([cp[:-3], cp[1:-2], cp[2:-1], cp[3:]], axis=1)  # (M, 4, 3)
        self._coef = np.einsum("kj,njd->nkd", _BASIS, segments)  # each segment's polynomial
        s = np.linspace(0.0, self._n_seg, self._n_seg * _LIMIT_SAMPLES_PER_SEGMENT + 1)
        _, d1, d2 = self._param_derivatives(s)
        speed = np.max(np.linalg.norm(d1, axis=1))
        acc = np.max(np.linalg.norm(d2, axis=1))
        seg = max(speed / max_speed_mps, np.sqrt(acc / max_acc_mps2), 1e-6)
        self.segment_duration_s = float(seg * _LIMIT_MARGIN)
        self.duration_s = self.segment_duration_s * self._n_seg
        self._ramp = 0.0  # each ramp's length in segment times
        self.ramp_s = 0.0
        if ramp_jerk_mps3 is not None:
            self._fit_ramps(ramp_jerk_mps3, max_speed_mps, max_acc_mps2)

    def _fit_ramps(self, jerk_mps3: float, max_speed_mps: float, max_acc_mps2: float) -> None:
        """Set the ramps' length so that their peak jerk is ``jerk_mps3`` [m/s^3], and the
        segment time so that the warped timing keeps the limits (never below the plain one)."""
        plain_s = self.segment_duration_s
        acc_ends = np.linalg.norm(self._param_derivatives(np.array([0.0, self._n_seg]))[2], axis=1)
        if not np.max(acc_ends) > 0:
            return  # no step in acceleration at either end: nothing to ramp
        ramp_s = _RAMP_PEAK_JERK * float(np.max(acc_ends)) / plain_s**2 / jerk_mps3
        for _ in range(_RAMP_ITERATIONS):
            self._ramp = min(ramp_s / self.segment_duration_s, _RAMP_MAX * self._n_seg)
            span = self._span()
            ramps = np.linspace(0.0, self._ramp, _RAMP_SAMPLES + 1)
            whole = np.linspace(0.0, span, self._n_seg * _LIMIT_SAMPLES_PER_SEGMENT + 1)
            tau = np.concatenate([whole, ramps, span - ramps])
            _, d1, d2 = self._warped_derivatives(tau)
            speed = np.max(np.linalg.norm(d1, axis=1))
            acc = np.max(np.linalg.norm(d2, axis=1))
            seg = max(speed / max_speed_mps, np.sqrt(acc / max_acc_mps2))
            self.segment_duration_s = max(plain_s, float(seg * _LIMIT_MARGIN))
            ramp_d2 = d2[whole.size :].reshape(2, -1, 3)  # start, end ramp
            jerk = np.linalg.norm(np.diff(ramp_d2, axis=1), axis=2) / (ramps[1] - ramps[0])
            peak_mps3 = float(np.max(jerk)) / self.segment_duration_s**3
            ramp_s = self._ramp * self.segment_duration_s * peak_mps3 / jerk_mps3
        self.ramp_s = self._ramp * self.segment_duration_s
        self.duration_s = self.segment_duration_s * self._span()

    def _span(self) -> float:
        """The duration in segment times: the knot range plus a third of each ramp."""
        return self._n_seg + 2.0 * self._ramp / 3.0

    def _warp(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Knot parameter u at times ``tau`` (n,) [segment times], du/dtau and d2u/dtau2.

        du/dtau is r(x) = 2x - x^2 of x = tau / ramp in the start ramp, 1 between the ramps,
        r of the time left over the ramp in the end ramp; u integrates it (r's integral
        x^2 - x^3 / 3 is 2/3 at x = 1: a ramp advances u by two thirds of its length).
        """
        k, span = self._ramp, self._span()
        tau = np.minimum(np.maximum(tau, 0.0), span)  # np.clip's result, a third of its cost
        x0 = np.minimum(np.maximum(tau / k, 0.0), 1.0)
        x1 = np.minimum(np.maximum((span - tau) / k, 0.0), 1.0)
        start, end = tau < k, tau > span - k
        u = np.where(start, k * (x0**2 - x0**3 / 3), tau - k / 3)
        u = np.where(end, self._n_seg - k * (x1**2 - x1**3 / 3), u)
        du = np.where(start, 2 * x0 - x0**2, np.where(end, 2 * x1 - x1**2, 1.0))
        ddu = np.where(start, (2 - 2 * x0) / k, np.where(end, -(2 - 2 * x1) / k, 0.0))
        return u, du, ddu

    def _warped_derivatives(self, tau: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position and its first two derivatives w.r.t. tau [segment times], each (n, 3)."""
        u, du, ddu = self._warp(tau)
        pos, d1, d2 = self._param_derivatives(u)
        return pos, d1 * du[:, None], d2 * du[:, None] ** 2 + d1 * ddu[:, None]

    def _param_derivatives(self, u: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Position and its first two derivatives w.r.t. the knot parameter u, each (n, 3)."""
        # (np.minimum/np.maximum: np.clip's same result at a third of its cost on 21 values)
        i = np.minimum(np.maximum(np.floor(u).astype(int), 0), self._n_seg - 1)
        s = (u - i)[:, None]
        s2, s3 = s**2, s**3
        coef = self._coef[i]  # (n, 4 powers, 3)
        pos = coef[:, 0] + s * coef[:, 1] + s2 * coef[:, 2] + s3 * coef[:, 3]
        d1 = coef[:, 1] + 2 * s * coef[:, 2] + 3 * s2 * coef[:, 3]
        d2 = 2 * coef[:, 2] + 6 * s * coef[:, 3]
        return pos, d1, d2

    def sample(self, t_s: np.ndarray | float) -> ReferenceSample:
        """Reference at times ``t_s`` [s] (scalar or (n,)); arrays of leading size n."""
        t = np.atleast_1d(np.asarray(t_s, dtype=float))
        inside = (t > 0.0) & (t < self.duration_s)
        if self._ramp > 0:
            pos, d1, d2 = self._warped_derivatives(t / self.segment_duration_s)
        else:
            u = np.minimum(np.maximum(t / self.segment_duration_s, 0.0), self._n_seg)
            pos, d1, d2 = self._param_derivatives(u)
        if inside.all():  # (np.where's result without its two temporaries)
            vel, acc = d1 / self.segment_duration_s, d2 / self.segment_duration_s**2
        else:
            vel = np.where(inside[:, None], d1 / self.segment_duration_s, 0.0)
            acc = np.where(inside[:, None], d2 / self.segment_duration_s**2, 0.0)
        yaw = np.full(t.shape, self.yaw_rad)
        return ReferenceSample(pos, vel, acc, yaw, np.zeros(t.shape))

    def length_m(self) -> float:
        """Arc length [m] (dense polyline approximation)."""
        s = np.linspace(0.0, self._n_seg, self._n_seg * _LIMIT_SAMPLES_PER_SEGMENT + 1)
        pos, _, _ = self._param_derivatives(s)
        return float(np.sum(np.linalg.norm(np.diff(pos, axis=0), axis=1)))


def spline_points(waypoints_ned_m: np.ndarray, samples_per_segment: int) -> np.ndarray:
    """Points (M * samples_per_segment + 1, 3) [m] along the cubic B-spline through the
    waypoints (M+1, 3), evenly in the knot parameter: the geometry of a
    :class:`BSplineReference` through them, without its timing."""
    wp = np.asarray(waypoints_ned_m, dtype=float)
    cp = _interpolating_control_points(wp)
    n_seg = wp.shape[0] - 1
    u = np.linspace(0.0, n_seg, n_seg * samples_per_segment + 1)
    i = np.clip(np.floor(u).astype(int), 0, n_seg - 1)
    s = u - i
    powers = np.column_stack([np.ones_like(s), s, s**2, s**3])  # (n, 4)
    weights = powers @ _BASIS  # (n, 4): weight of control points i..i+3
    return sum(weights[:, k : k + 1] * cp[i + k] for k in range(4))


def _interpolating_control_points(wp: np.ndarray) -> np.ndarray:
    """Control points P_-1..P_M+1 with C(i) = W_i and C'(0) = C'(M) = 0."""
    m = wp.shape[0] - 1
    n = m + 3
    a = np.zeros((n, n))
    b = np.zeros((n, 3))
    for i in range(m + 1):
        a[i, i : i + 3] = (1 / 6, 4 / 6, 1 / 6)
        b[i] = wp[i]
    a[m + 1, [0, 2]] = (-1.0, 1.0)  # (P_1 - P_-1) / 2 = 0
    a[m + 2, [m, m + 2]] = (-1.0, 1.0)
    return np.linalg.solve(a, b)
