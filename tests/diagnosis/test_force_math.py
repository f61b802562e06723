"""The force residual and the candidate fits on arrays with known parameters."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from diagnosis.candidates import fit_jointly, make_candidate
from diagnosis.force_model import (
    BatteryModel,
    flight_time_from_voltage,
    predicted_residual,
)
from diagnosis.forces import (
    ForceData,
    ForceDataError,
    acceleration,
    force_data,
    neighbour_mean,
    rotation_matrices,
)
from flightlog.schema import FlightLog

BATTERY = BatteryModel(full_v=16.8, empty_v=14.0)
MASS_KG = 1.5


def synthetic(n: int = 600, seed: int = 0, alt_m: np.ndarray | None = None) -> ForceData:
    """Rows with random attitude, velocity and acceleration; residual left at zero."""
    rng = np.random.default_rng(seed)
    rot = Rotation.from_euler("xyz", rng.uniform(-0.4, 0.4, (n, 3))).as_matrix()
    t = np.arange(n) * 0.05
    return ForceData(
        t_s=t,
        segment=np.zeros(n, int),
        vel_ned_mps=rng.uniform(-8.0, 8.0, (n, 3)),
        acc_ned_mps2=rng.normal(0.0, 1.0, (n, 3)),
        rot=rot,
        thrust_n=rng.uniform(12.0, 18.0, n),
        alt_m=rng.uniform(0.02, 0.4, n) if alt_m is None else alt_m,
        battery_v=16.8 - 0.004 * t,
        mass_kg=MASS_KG,
        resid_ned_n=np.zeros((n, 3)),
    )


def with_residual(data: ForceData, effects: dict, noise_n: float = 0.0) -> ForceData:
    rng = np.random.default_rng(1)
    r = predicted_residual(effects, data, BATTERY) + noise_n * rng.standard_normal((data.n_rows, 3))
    return ForceData(**{**data.__dict__, "resid_ned_n": r})


def test_rotation_matrices_match_scipy():
    q_xyzw = Rotation.random(50, random_state=3).as_quat()
    q_wxyz = np.column_stack([q_xyzw[:, 3], q_xyzw[:, :3]])
    expected = Rotation.from_quat(q_xyzw).as_matrix()
    np.testing.assert_allclose(rotation_matrices(q_wxyz), expected, atol=1e-12)


def test_neighbour_mean_keeps_the_signal_and_drops_the_rows_own_noise():
    rng = np.random.default_rng(4)
    t = np.arange(4000) * 0.02
    smooth = np.column_stack([np.sin(t), 0.3 * t**2])
    noise = rng.normal(0.0, 0.3, smooth.shape)
    # error (dt^2 / 2) x the second derivative: at most 1 (sine) and 0.6 (parabola)
    np.testing.assert_allclose(
        neighbour_mean(smooth)[1:-1], smooth[1:-1], atol=0.5 * 0.02**2 * 1.01
    )
    mean_noise = neighbour_mean(noise)
    for axis in range(2):
        assert abs(np.corrcoef(mean_noise[:, axis], noise[:, axis])[0, 1]) < 0.05
    assert neighbour_mean(smooth[:1]).shape == (1, 2)


def test_acceleration_is_differentiated_when_not_logged():
    t = np.arange(400) * 0.02
    vel = np.column_stack([np.sin(t), 0.5 * t, np.zeros_like(t)])
    cols = {"t_s": t, "vel_n_mps": vel[:, 0], "vel_e_mps": vel[:, 1], "vel_d_mps": vel[:, 2]}
    acc = acceleration(FlightLog(cols))
    inner = slice(20, -20)
    np.testing.assert_allclose(acc[inner, 0], np.cos(t[inner]), atol=5e-3)
    np.testing.assert_allclose(acc[inner, 1], 0.5, atol=1e-9)


def test_a_log_never_airborne_is_refused_saying_which_condition_failed():
    """A log recorded disarmed on the ground (a v1.8 SITL log kept after its RTL): the refusal
    counts the rows that fail each airborne condition, so the user learns it never flew."""
    n = 50
    cols = {"t_s": np.arange(n) * 0.1, "armed": np.zeros(n), "thrust_n": np.zeros(n)}
    cols |= {k: np.zeros(n) for k in ("vel_n_mps", "vel_e_mps", "vel_d_mps", "pos_n_m", "pos_e_m")}
    cols |= {"pos_d_m": np.full(n, -0.5), "q_w": np.ones(n), "q_x": np.zeros(n)}
    cols |= {"q_y": np.zeros(n), "q_z": np.zeros(n)}
    with pytest.raises(ForceDataError) as err:
        force_data([FlightLog(cols)], mass_kg=1.5)
    assert "of 50 rows, 50 disarmed, 0 not above 1 cm, 50 without thrust" in str(err.value)
    assert str(err.value).endswith("use a log of a flight")


def test_rows_with_nan_thrust_or_altitude_are_counted_as_failing_their_condition():
    """A NaN fails "thrust > 0" and "altitude > 1 cm" (every comparison with NaN is False): the
    refusal must count those rows, not say that 0 rows failed each condition."""
    n = 50
    cols = {"t_s": np.arange(n) * 0.1, "armed": np.ones(n), "thrust_n": np.full(n, np.nan)}
    cols |= {k: np.zeros(n) for k in ("vel_n_mps", "vel_e_mps", "vel_d_mps", "pos_n_m", "pos_e_m")}
    cols |= {"pos_d_m": np.r_[np.full(10, np.nan), np.full(n - 10, -5.0)], "q_w": np.ones(n)}
    cols |= {"q_x": np.zeros(n), "q_y": np.zeros(n), "q_z": np.zeros(n)}
    with pytest.raises(ForceDataError) as err:
        force_data([FlightLog(cols)], mass_kg=1.5)
    assert "of 50 rows, 0 disarmed, 10 not above 1 cm, 50 without thrust" in str(err.value)


def test_rotor_drag_residual_is_linear_in_body_air_velocity():
    data = synthetic()
    k = np.array([0.4, 0.3, 0.1])
    wind = np.array([2.0, -1.0, 0.0])
    effects = {"rotor_drag": {"k_n_per_mps": k}, "wind": {"vel_ned_mps": wind}}
    r = predicted_residual(effects, data, BATTERY)
    for i in (0, 123, 599):
        v_body = data.rot[i].T @ (data.vel_ned_mps[i] - wind)
        np.testing.assert_allclose(r[i], data.rot[i] @ (-k * v_body), atol=1e-12)


def test_isotropic_drag_points_against_the_airspeed():
    data = synthetic()
    wind = np.array([1.0, 2.0, 0.0])
    effects = {"isotropic_drag": {"k_n_per_mps2": 0.05}, "wind": {"vel_ned_mps": wind}}
    r = predicted_residual(effects, data, BATTERY)
    air = data.vel_ned_mps - wind
    np.testing.assert_allclose(r, -0.05 * np.linalg.norm(air, axis=1)[:, None] * air, atol=1e-12)


@pytest.mark.parametrize(
    ("name", "effects", "base"),
    [
        ("rotor_drag", {"rotor_drag": {"k_n_per_mps": (0.45, 0.3, 0.12)}}, {}),
        ("body_drag", {"body_drag": {"c_n_per_mps2": (0.05, 0.03, 0.07)}}, {}),
        ("isotropic_drag", {"isotropic_drag": {"k_n_per_mps2": 0.045}}, {}),
        ("payload", {"payload": {"mass_ratio": 1.3}}, {}),
        ("battery_sag", {"battery_sag": {"max_thrust_loss": 0.3}}, {}),
        (
            "ground_effect",
            {"ground_effect": {"max_gain": 0.3, "rotor_radius_m": 0.14}},
            {},
        ),
        (
            "wind",
            {"rotor_drag": {"k_n_per_mps": (0.35, 0.35, 0.1)}, "wind": {"vel_ned_mps": (3, -2, 0)}},
            {"rotor_drag": {"k_n_per_mps": (0.35, 0.35, 0.1)}},
        ),
    ],
)
def test_candidate_fit_recovers_known_parameters(name, effects, base):
    data = with_residual(synthetic(), effects, noise_n=0.05)
    fit = fit_jointly([make_candidate(name, base)], base, data, BATTERY)
    for key, value in effects[name].items():
        np.testing.assert_allclose(fit.effects[name][key], value, rtol=0.03, atol=0.02)


def test_wind_without_drag_in_config_fits_drag_jointly():
    effects = {"rotor_drag": {"k_n_per_mps": (0.5, 0.4, 0.1)}, "wind": {"vel_ned_mps": (2, 3, 0)}}
    data = with_residual(synthetic(), effects)
    fit = fit_jointly([make_candidate("wind", {})], {}, data, BATTERY)
    np.testing.assert_allclose(fit.effects["wind"]["vel_ned_mps"], (2, 3, 0), atol=1e-3)
    np.testing.assert_allclose(fit.effects["rotor_drag"]["k_n_per_mps"], (0.5, 0.4, 0.1), atol=1e-3)


def test_flight_time_from_voltage_inverts_the_discharge_law():
    data = synthetic(n=2000)
    load = data.thrust_n / (MASS_KG * 9.80665)
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (load[1:] + load[:-1]) * 0.05)])
    volts = 16.8 - (16.8 - 14.0) * integral / 420.0
    data = ForceData(**{**data.__dict__, "battery_v": volts})
    assert flight_time_from_voltage(data, BATTERY) == pytest.approx(420.0, rel=1e-9)
