"""End to end: an effect hidden from the config is named first, fitted within 15 % and the
extended config replays held-out data, and tracks the logged setpoints in closed loop, at least
3x better. The same flight with realistic sensor noise (levels drawn at random) still names the
effect first with its main parameter within 15 %; clean flights with noise name nothing."""

from __future__ import annotations

import numpy as np
import pytest

from diagnosis.diagnosis import diagnose
from diagnosis.fly_schedule import fly_schedule
from experiments.hidden_effects import (
    HIDDEN_EFFECTS,
    draw,
    fly_hidden,
    main_parameter_errors,
    schedule,
)
from flightlog.schema import FlightLog, read_flight_log, write_flight_log
from vehicle_sim import load_sim_config
from vehicle_sim.params import PX4_PARAMS
from vehicle_sim.sensor_noise import add_sensor_noise, draw_sensor_noise

CLOSED_LOOP_FLOOR_MPS = 0.02  # closed-loop errors below this leave no gain worth a figure


@pytest.fixture(scope="module", params=HIDDEN_EFFECTS)
def hidden_flight(request, tmp_path_factory):
    """(name, seed, truth, base effects, logs): one flight per hidden effect, drawn at random
    (seeded), shared by the exact and the noisy diagnosis of it (each its own test, so the two
    run side by side on two workers)."""
    name = request.param
    seed = HIDDEN_EFFECTS.index(name)
    truth, base = draw(name, np.random.default_rng(100 + seed))
    logs = read_only(fly_hidden(truth, tmp_path_factory.mktemp(name), seed))
    return name, seed, truth, base, logs


@pytest.fixture(scope="module")
def clean_flight(tmp_path_factory):
    """The excitation mission flown with no hidden effect (seed 11), shared by the tests that
    diagnose it exact or with noise drawn on top."""
    return read_only(fly_hidden({}, tmp_path_factory.mktemp("clean"), 11))


def read_only(logs: list[FlightLog]) -> list[FlightLog]:
    """``logs`` with their columns made read-only, so no test sharing them can change them."""
    for log in logs:
        for column in log.columns.values():
            column.setflags(write=False)
    return logs


@pytest.mark.slow
def test_hidden_effect_is_named_fitted_and_gains(hidden_flight):
    name, _, truth, base, logs = hidden_flight
    result = diagnose(logs, load_sim_config("iris", base))
    assert result.verdict and result.verdict[0] == name, result.verdict
    assert result.causes[0].name == name
    errors = main_parameter_errors(name, truth, result.causes[0].params)
    assert max(errors.values()) < 0.15, errors
    assert name in result.added_effects
    assert result.gain >= 3.0, (result.baseline.rmse_mps(), result.extended.rmse_mps())
    cl = result.closed_loop
    info = (cl.baseline_rmse_mps(), cl.extended_rmse_mps(), cl.reanchored_baseline)
    info += (cl.reanchored_extended, cl.segments)
    if name == "ground_effect":  # acts near the ground only: in the ground holds, scored apart
        more_whole = cl.reanchored_baseline > cl.reanchored_extended
        assert more_whole or cl.ground_hold_gain() >= 3.0, info
    elif cl.baseline_rmse_mps() > CLOSED_LOOP_FLOOR_MPS:  # slow effects the integrator hides
        assert cl.scored.any() and cl.gain() >= 3.0, info


@pytest.mark.slow
def test_hidden_effect_is_named_and_fitted_on_a_noisy_log(hidden_flight):
    name, seed, truth, base, logs = hidden_flight
    noise = draw_sensor_noise(np.random.default_rng(200 + seed))
    noisy = diagnose(
        [add_sensor_noise(log, noise, seed) for log in logs], load_sim_config("iris", base)
    )
    assert noisy.verdict and noisy.verdict[0] == name, (noise, noisy.verdict)
    errors = main_parameter_errors(name, truth, noisy.causes[0].params)
    assert max(errors.values()) < 0.15, (noise, errors)
    assert noisy.gain > 0.95  # slow thrust effects barely move a noisy replay


@pytest.mark.slow
@pytest.mark.parametrize("pair", [("rotor_drag", "payload"), ("ground_effect", "command_delay")])
def test_two_hidden_effects_are_both_named(pair, tmp_path):
    rng = np.random.default_rng(7)
    truth = {}
    for name in pair:
        truth.update(draw(name, rng)[0])
    result = diagnose(fly_hidden(truth, tmp_path, 7), load_sim_config("iris"))
    assert set(result.verdict) == set(pair)
    named = {c.name: c.params for c in result.causes[:2]}
    for name in pair:
        errors = main_parameter_errors(name, truth, named[name])
        assert max(errors.values()) < 0.15, (name, errors)


@pytest.mark.slow
def test_clean_log_gives_empty_verdict(clean_flight):
    result = diagnose(clean_flight, load_sim_config("iris"))
    assert result.verdict == ()
    assert result.causes[0].name == "none"
    assert result.added_effects == {}
    assert result.gain == 1.0
    assert result.closed_loop.baseline_rmse_mps() < 0.01


@pytest.mark.slow
def test_a_thrust_telemetry_scale_is_not_a_payload(tmp_path):
    rng = np.random.default_rng(41)
    factor = float(rng.choice([rng.uniform(0.75, 0.9), rng.uniform(1.1, 1.3)]))
    (log,) = fly_hidden({}, tmp_path, 41)
    cols = dict(log.columns)
    cols["thrust_n"] = cols["thrust_n"] * factor
    scaled = FlightLog(cols, log.metadata)
    result = diagnose([scaled], load_sim_config("iris"))
    assert result.verdict and result.verdict[0] == "thrust_scale", result.verdict
    assert "payload" not in result.verdict and "payload" not in result.added_effects
    assert abs(result.causes[0].params["logged_over_true"] / factor - 1.0) < 0.15


@pytest.mark.slow
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_clean_noisy_logs_name_nothing(seed, clean_flight):
    """Three noise draws here (each about 20 s); the 20-seed rate is `bench --only diagnose`."""
    noise = draw_sensor_noise(np.random.default_rng(300 + seed))
    logs = [add_sensor_noise(log, noise, seed) for log in clean_flight]
    result = diagnose(logs, load_sim_config("iris"))
    assert result.verdict == (), (noise, result.verdict, result.warnings)
    assert result.causes[0].name == "none"
    floor = result.noise_floor["vel_mps"]
    assert all(0.5 * noise.vel_mps < v < 1.5 * noise.vel_mps for v in floor), (noise, floor)


@pytest.mark.slow
def test_gusts_are_reported_as_unexplained_disturbance(tmp_path):
    truth, base = draw("gusts", np.random.default_rng(12))
    result = diagnose(fly_hidden(truth, tmp_path, 12), load_sim_config("iris", base))
    assert result.verdict == ("unexplained",)
    assert result.added_effects == {}
    unexplained = result.causes[0]
    assert unexplained.name == "unexplained"
    ratio = unexplained.params["gust_intensity_mps"] / truth["gusts"]["intensity_mps"]
    assert 0.5 < ratio < 2.0


@pytest.mark.slow
@pytest.mark.parametrize("seed", [51, 53])  # horizontal gains faster (51), slower (53)
def test_another_controller_is_named_flight_control_with_its_gains(seed, tmp_path):
    """The truth flies other horizontal velocity gains than the config (and body drag): the
    diagnosis names ``flight_control`` with the gains within 20 % and still finds the drag."""
    rng = np.random.default_rng(seed)
    # Within PX4's bounds (the simulator refuses others), slower or faster than the defaults.
    factor = rng.uniform(0.72, 0.8) if rng.uniform() < 0.5 else rng.uniform(1.4, 1.9)
    gains = {"MPC_XY_VEL_P_ACC": 1.8 * factor, "MPC_XY_VEL_I_ACC": rng.uniform(1.2, 2.8)}
    truth, _ = draw("body_drag", rng)
    log = fly_schedule(load_sim_config("iris", truth), schedule(), seed=seed, params=gains)
    path = write_flight_log(tmp_path / "flight_0.csv", log)
    result = diagnose([read_flight_log(path)], load_sim_config("iris"))
    assert "flight_control" in result.verdict and "body_drag" in result.verdict, result.causes[:3]
    (named,) = [c for c in result.causes if c.name == "flight_control"]
    for name, value in gains.items():
        assert named.params[name] == pytest.approx(value, rel=0.2), (name, named.params)
    (drag,) = [c for c in result.causes if c.name == "body_drag"]
    fitted = [drag.params[f"c_n_per_mps2_{a}"] for a in "xy"]
    assert fitted == pytest.approx(truth["body_drag"]["c_n_per_mps2"][:2], rel=0.15)


@pytest.mark.slow
# Four of the six draws measured (BENCHMARKS.md, issue 18, session 6), for the suite's time:
# an I pinned within 20 % (55), unpinned with the truth in its interval (51; 53, whose horizontal
# gains are slower than the config's: the other three draw faster ones), on the bound (56).
@pytest.mark.parametrize("seed", [51, 53, 55, 56])
def test_other_horizontal_and_vertical_gains_on_a_noisy_log(seed, tmp_path):
    """The truth flies other horizontal and vertical velocity gains than the config (and body
    drag), logged with realistic sensor noise (levels drawn): ``flight_control`` is named with
    the horizontal gains and the vertical P within 20 % and the drag is still found. The
    vertical I is within 20 % where the cause claims it; where the log does not pin it (noisy
    thrust telemetry against the integrator's few centimetres of swing, BENCHMARKS.md, issue 18,
    session 6) the cause says so, with a 95 % interval that holds the truth and is wider than
    +-20 %."""
    rng = np.random.default_rng(seed)
    factor = rng.uniform(0.72, 0.8) if rng.uniform() < 0.5 else rng.uniform(1.4, 1.9)
    # Vertical P slower or faster than the config's 4.0, away from PX4's lower bound 2.0;
    # vertical I below the config's 2.0.
    z_factor = rng.uniform(0.7, 0.8) if rng.uniform() < 0.5 else rng.uniform(1.4, 2.0)
    gains = {
        "MPC_XY_VEL_P_ACC": 1.8 * factor,
        "MPC_XY_VEL_I_ACC": rng.uniform(1.2, 2.8),
        "MPC_Z_VEL_P_ACC": 4.0 * z_factor,
        "MPC_Z_VEL_I_ACC": rng.uniform(0.6, 1.4),
    }
    truth, _ = draw("body_drag", rng)
    log = fly_schedule(load_sim_config("iris", truth), schedule(), seed=seed, params=gains)
    noise = draw_sensor_noise(np.random.default_rng(seed + 500))
    noisy = add_sensor_noise(log, noise, seed)
    result = diagnose([noisy], load_sim_config("iris"))
    assert "flight_control" in result.verdict and "body_drag" in result.verdict, (
        noise,
        result.causes[:3],
    )
    (named,) = [c for c in result.causes if c.name == "flight_control"]
    assert set(result.added_effects["flight_control"]) == set(gains)
    z_i = "MPC_Z_VEL_I_ACC"
    for name, value in gains.items():
        if name != z_i:
            assert named.params[name] == pytest.approx(value, rel=0.2), (name, named.params)
    assert set(named.unpinned) <= {z_i}, named.unpinned
    if z_i in named.unpinned:
        low, high = named.unpinned[z_i]
        assert low <= gains[z_i] <= high, (named.unpinned, gains[z_i])
        spec = PX4_PARAMS[z_i]
        wide = high - low > 2 * 0.2 * named.params[z_i] or low <= spec.lo or high >= spec.hi
        assert wide, named.unpinned
        assert "not pinned" in named.evidence
    else:
        assert named.params[z_i] == pytest.approx(gains[z_i], rel=0.2), named.params
