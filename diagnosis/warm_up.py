"""The autopilot's velocity integral at the end of a replay's warm-up, read past the attitude lag.

During a replay's warm-up (the first ``LEAD_IN_S`` of an airborne run) the integral is read off
each row's measured thrust vector by inverting the velocity loop
(``Simulator.anchor``'s ``integral="match_thrust"``), which assumes the attitude is the one the
loop commands. While the commanded acceleration changes, the attitude lags it, and the
inversion returns that lag as an integral: matched minus true is about -lag x the rate of
change of the acceleration (the jerk). A companion mission starts moving as OFFBOARD starts: on
the project's square mission, flown in process and diagnosed against the very config that flew
it, the plain mean over the warm-up gave an integral 0.3-0.4 m/s^2 off, kept for the whole run:
held-out replay error 0.336 m/s, 4168x the noise floor, verdict "unexplained" (the S-curve and
the demo B-spline, flown by the PD regulator, were called unexplained too).

So per row j of the warm-up the follower (re-anchored at every row, its integral carried by the
loop's own integration from the run's start) gives d_j = matched_j - carried_j, and

    d_j = c - lag jerk_j + noise          (c (3,) per axis, lag [s] shared by north and east)

is fitted by least squares; the integral at the end of the warm-up is the carried one plus c.
The lag is the tilt's, so it is fitted and applied on the horizontal axes only: vertically the
thrust follows through the motors alone, and there a config of the wrong mass leaves a
mismatch between matched and carried that a vertical lag term would take up (a payload of 1.35
was then also read as a thrust curve).
The jerk is the measured acceleration's, smoothed over ``SMOOTH_S``. With no jerk to speak of
(a hover) the fit is the mean of d_j ([Kulathunga23]-style logs, and the earlier rule: one noisy
row's integral would otherwise stay in every window of the run); noise in the jerk only pulls
the lag towards 0, and the lag is kept within [0, ``MAX_LAG_S``].
"""

from __future__ import annotations

import numpy as np

LEAD_IN_S = 1.0
SMOOTH_S = 0.2
MAX_LAG_S = 0.5


def smoothed_jerk(t_s: np.ndarray, acc_mps2: np.ndarray) -> np.ndarray:
    """(n, 3) rate of change [m/s^3] of the acceleration (n, 3) [m/s^2] logged at times t_s (n,)
    [s]: a centred moving average over ``SMOOTH_S``, then its centred difference over the same
    span (rows near the ends use what they have)."""
    n = len(t_s)
    lo = np.searchsorted(t_s, t_s - 0.5 * SMOOTH_S)
    hi = np.searchsorted(t_s, t_s + 0.5 * SMOOTH_S, side="right")
    csum = np.vstack([np.zeros((1, 3)), np.cumsum(acc_mps2, axis=0)])
    smooth = (csum[hi] - csum[lo]) / np.maximum(hi - lo, 1)[:, None]
    ahead = np.minimum(np.searchsorted(t_s, t_s + 0.5 * SMOOTH_S), n - 1)
    span = np.maximum(t_s[ahead] - t_s[lo], 1e-9)[:, None]
    return (smooth[ahead] - smooth[lo]) / span


def integral_offset(diffs: np.ndarray, jerks: np.ndarray) -> tuple[np.ndarray, float]:
    """(c (3,) [m/s^2], lag [s]) of the fit in the module docstring.

    Args:
        diffs: (n, 3) matched minus carried integral per warm-up row, NED [m/s^2], n >= 1.
        jerks: (n, 3) the rows' smoothed jerk, NED [m/s^3] (the down axis is not used).
    """
    d = diffs[:, :2] - diffs[:, :2].mean(axis=0)
    j = jerks[:, :2] - jerks[:, :2].mean(axis=0)
    den = float(np.sum(j * j))
    lag = 0.0 if den <= 1e-12 else float(np.clip(-np.sum(d * j) / den, 0.0, MAX_LAG_S))
    offset = diffs.mean(axis=0)
    offset[:2] += lag * jerks[:, :2].mean(axis=0)
    return offset, lag
