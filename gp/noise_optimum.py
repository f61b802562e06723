"""A GP fit that explains nothing but noise: the all-noise optimum, told in one line.

Maximising the marginal likelihood (or the SGPR bound) has a well-known optimum where all of
the targets' variance is called noise: the kernel's signal variance shrinks towards its lower
bound and the posterior mean is about 0 everywhere ([Rasmussen06] section 5.4.1, Fig. 5.5: a
local optimum with a long lengthscale and a high noise level). It is right when nothing is
left to learn; it is also where the optimiser ends when it cannot resolve the function, for
instance when an input spans a much wider range than the rest (a few outlying rows, a feature
in other units), so that the lengthscale bounds and the inducing points, both set from the
inputs' spread, are too coarse. The fit report says so rather than leave a GP that predicts 0
looking like a learned model.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

SIGNAL_TO_NOISE_FLOOR = 1e-2  # signal variance below 1 % of the noise variance: all noise


def all_noise_outputs(signal_variances: np.ndarray, noise_variances: np.ndarray) -> list[int]:
    """Indices of the outputs whose signal variance (n_out,) is below SIGNAL_TO_NOISE_FLOOR
    times their noise variance (n_out,), both in output units squared."""
    signal = np.asarray(signal_variances, dtype=float)
    noise = np.asarray(noise_variances, dtype=float)
    return [int(i) for i in np.flatnonzero(signal < SIGNAL_TO_NOISE_FLOOR * noise)]


def all_noise_note(
    names: Sequence[str], signal_variances: np.ndarray, noise_variances: np.ndarray
) -> str | None:
    """One line naming the outputs at the all-noise optimum with their variances, what it
    means and what to try; None when every output's signal stands above the floor."""
    found = all_noise_outputs(signal_variances, noise_variances)
    if not found:
        return None
    each = ", ".join(
        f"{names[i]} {signal_variances[i]:.2g} against {noise_variances[i]:.2g}" for i in found
    )
    return (
        f"the GP explains nothing but noise on {', '.join(names[i] for i in found)} (signal "
        f"variance under {SIGNAL_TO_NOISE_FLOOR:.0%} of the noise variance: {each}), so it "
        "predicts about 0 there: either nothing is left to learn, or the fit missed it (an "
        "input spanning a much wider range than the rest, outliers in it, too little flight, "
        "or too few inducing points: check the features' ranges; with enough flight (fit-gp "
        "warns when there is too little for --m, and then log more first), try a larger --m "
        "or --inducing random)"
    )
