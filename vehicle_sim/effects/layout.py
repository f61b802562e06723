"""Index layout of the packed effect-parameter vector the jitted physics reads.

Every effect writes its parameters into one float64 vector of length ``N_EFFECT``; the
physics reads it by these indices, which are defined in :mod:`vehicle_sim.physics` (numba
caches per file) and re-exported here for the effect classes. The neutral vector
(:func:`neutral_effect_vector`) means "no effect": zero drag, wind and gusts, mass ratio 1,
no battery sag, no ground effect, the preset's own motor time constant, no command delay.
"""

from __future__ import annotations

import numpy as np

from vehicle_sim.physics import (
    BATTERY_LOSS,
    BATTERY_TIME,
    BODY_DRAG_C,
    COMMAND_DELAY,
    FIELD_CENTER_NE,
    FIELD_HALF_WIDTH,
    FIELD_HEADING,
    FIELD_VEL_NED,
    GROUND_GAIN,
    GROUND_HEIGHT,
    GROUND_RADIUS,
    GUST_LENGTH,
    GUST_SIGMA,
    ISO_DRAG_K,
    MOTOR_TAU,
    N_EFFECT,
    PAYLOAD_RATIO,
    ROTOR_DRAG_K,
    THRUST_CURVE_GAIN,
    WIND_NED,
)

__all__ = [
    "BATTERY_LOSS", "BATTERY_TIME", "BODY_DRAG_C", "COMMAND_DELAY", "FIELD_CENTER_NE",
    "FIELD_HALF_WIDTH", "FIELD_HEADING", "FIELD_VEL_NED", "GROUND_GAIN",
    "GROUND_HEIGHT", "GROUND_RADIUS", "GUST_LENGTH", "GUST_SIGMA", "ISO_DRAG_K", "MOTOR_TAU",
    "N_EFFECT", "PAYLOAD_RATIO", "ROTOR_DRAG_K", "THRUST_CURVE_GAIN", "WIND_NED",
    "neutral_effect_vector",
]  # fmt: skip


def neutral_effect_vector() -> np.ndarray:
    """The effect vector with every effect off, shape (N_EFFECT,)."""
    ep = np.zeros(N_EFFECT)
    ep[PAYLOAD_RATIO] = 1.0
    ep[GUST_LENGTH] = 1.0
    ep[GROUND_RADIUS] = 0.1
    return ep
