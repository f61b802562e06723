"""A replay window's error is taken after what an error in its run's start integral and in its
anchor's measured velocity explain, and only that: a command-path difference stays in it."""

from __future__ import annotations

import dataclasses

import numpy as np
import pytest

from diagnosis import sim_anchor
from diagnosis.replay import replay, windows
from diagnosis.window_nuisance import RunNuisance
from tests.vehicle_sim.sim_flying import hovering, record_offboard
from vehicle_sim import AnchorState, VelocitySetpoint, load_sim_config
from vehicle_sim.sensor_noise import SensorNoise, add_sensor_noise

WINDOWS = 6


def _rows(rng: np.random.Generator, window_s: float = 2.0) -> np.ndarray:
    """Row times since the anchor [s], 18-26 ms apart (a jittered 45 Hz log)."""
    return np.cumsum(rng.uniform(0.018, 0.026, int(window_s / 0.018)))


def _fly(config, tau_s, setpoint_at, dv0=None, integral=None) -> np.ndarray:
    """(m, 3) velocity NED at ``tau_s`` of a hovering vehicle of ``config`` flown free from a
    start-velocity error ``dv0`` and an integral offset (3,), on ``setpoint_at(t)``."""
    sim = sim_anchor.fresh_copy(sim_anchor.hovering_template(config))
    hover = sim.state
    if dv0 is not None:
        sim.anchor(
            AnchorState(hover.pos_ned_m, hover.vel_ned_mps + dv0, hover.q_wxyz,
                        hover.rates_frd_radps)
        )  # fmt: skip
    if integral is not None:
        sim.set_velocity_integral(sim.velocity_integral_mps2 + integral)
    out, t = [], 0.0
    for tau in tau_s:
        sim.set_velocity_setpoint(setpoint_at(t))
        sim.advance(tau - t)
        t = tau
        out.append(sim.vel_ned_mps)
    return np.array(out)


def _fitted(config, taus, simulated, measured) -> list[np.ndarray]:
    nuisance = RunNuisance(config)
    for tau, sim, meas in zip(taus, simulated, measured, strict=True):
        nuisance.add(tau, sim, meas)
    return nuisance.fitted()


def _rms(parts: list[np.ndarray]) -> float:
    x = np.vstack(parts)
    return float(np.sqrt(np.mean(np.sum(x * x, axis=1))))


def _ramp(speed_mps: float):
    def setpoint_at(t: float) -> VelocitySetpoint:
        return VelocitySetpoint((min(1.5 * t, speed_mps), 0.5 * min(t, 1.0), -0.3 * (t > 1.0)))

    return setpoint_at


@pytest.mark.parametrize("seed", [1, 2, 3])
def test_a_runs_integral_offset_and_each_anchors_velocity_error_are_removed(seed):
    rng = np.random.default_rng(seed)
    config = load_sim_config("iris")
    integral = rng.uniform(-0.1, 0.1, 3)  # one for the run
    taus, measured, simulated = [], [], []
    for _ in range(WINDOWS):
        tau, ramp, dv0 = (
            _rows(rng),
            _ramp(float(rng.uniform(0.5, 3.0))),
            rng.uniform(-0.15, 0.15, 3),
        )
        taus.append(tau)
        measured.append(_fly(config, tau, ramp, dv0, integral))
        simulated.append(_fly(config, tau, ramp))
    fitted = _fitted(config, taus, simulated, measured)
    raw = _rms([s - m for s, m in zip(simulated, measured, strict=True)])
    left = _rms([f - m for f, m in zip(fitted, measured, strict=True)])
    assert raw > 0.03
    assert left < 0.05 * raw  # responses about hover serve windows that accelerate


def test_windows_longer_than_the_responses_horizon_get_responses_as_long():
    """Windows of 4 s (DiagnosisConfig.window_s): their rows reach 4 s past the anchor, beyond
    the 2.5 s the responses were flown for by default; those rows were given the responses'
    last slope, extrapolated, and 7.6 % of the raw error was left (2.4 % with responses flown
    as long)."""
    rng = np.random.default_rng(1)
    config = load_sim_config("iris")
    integral = rng.uniform(-0.1, 0.1, 3)
    taus, measured, simulated = [], [], []
    for _ in range(WINDOWS):
        tau, ramp = _rows(rng, window_s=4.0), _ramp(float(rng.uniform(0.5, 3.0)))
        dv0 = rng.uniform(-0.15, 0.15, 3)
        taus.append(tau)
        measured.append(_fly(config, tau, ramp, dv0, integral))
        simulated.append(_fly(config, tau, ramp))
    assert max(tau[-1] for tau in taus) > 3.5
    fitted = _fitted(config, taus, simulated, measured)
    raw = _rms([s - m for s, m in zip(simulated, measured, strict=True)])
    left = _rms([f - m for f, m in zip(fitted, measured, strict=True)])
    assert left < 0.03 * raw


@pytest.mark.parametrize("seed", [4, 5])
def test_a_command_delay_stays_in_the_runs_error(seed):
    rng = np.random.default_rng(seed)
    delay_s = float(rng.uniform(0.05, 0.15))
    nominal = load_sim_config("iris")
    delayed = load_sim_config("iris", {"command_delay": {"delay_s": delay_s}})
    taus, measured, simulated = [], [], []
    for _ in range(WINDOWS):
        tau, at_s = _rows(rng), float(rng.uniform(0.1, 1.2))
        speed = rng.uniform(-2.0, 2.0, 3) * (1.0, 1.0, 0.5)

        def step(t: float, at_s=at_s, speed=speed) -> VelocitySetpoint:
            return VelocitySetpoint(tuple(speed * (t >= at_s)))

        taus.append(tau)
        measured.append(_fly(delayed, tau, step))
        simulated.append(_fly(nominal, tau, step))
    fitted = _fitted(nominal, taus, simulated, measured)
    raw = _rms([s - m for s, m in zip(simulated, measured, strict=True)])
    left = _rms([f - m for f, m in zip(fitted, measured, strict=True)])
    assert raw > 0.02
    assert left > 0.8 * raw  # six windows: the run's one offset takes up 4-18 %, no more


def test_the_error_left_only_grows_as_windows_are_added():
    """What a search's early stop relies on (diagnosis.replay.replay_sse): the squared error
    left after the run's nuisance never falls as windows are added, and at the end it is the
    fitted windows' own."""
    rng = np.random.default_rng(7)
    config = load_sim_config("iris")
    delayed = load_sim_config("iris", {"command_delay": {"delay_s": 0.1}})
    nuisance, left, windows_added = RunNuisance(config), [], []
    for _ in range(WINDOWS):
        tau, ramp = _rows(rng), _ramp(float(rng.uniform(0.5, 3.0)))
        meas, sim = _fly(delayed, tau, ramp), _fly(config, tau, ramp)
        nuisance.add(tau, sim, meas)
        windows_added.append(meas)
        left.append(nuisance.sse())
    assert np.all(np.diff(left) >= -1e-12) and left[-1] > 0.0
    pairs = zip(nuisance.fitted(), windows_added, strict=True)
    own = sum(float(np.sum((f - m) ** 2)) for f, m in pairs)
    assert left[-1] == pytest.approx(own, rel=1e-9)


@pytest.mark.parametrize(("rate_hz", "bound_mps"), [(50.0, 0.010), (25.0, 0.016)])
def test_a_thinned_log_that_lost_its_opening_step_replays_with_its_own_config(rate_hz, bound_mps):
    # a companion's stream, logged at 250 Hz and thinned: the step that opened OFFBOARD falls
    # between two kept rows, the start integral is fitted on a command that never flew, and
    # that stays for the whole run (held-out replay 0.018 and 0.036 m/s before the run's
    # offset was fitted; what is left is the commands the thinning lost inside the windows)
    def command_at(t: float) -> VelocitySetpoint:
        if t < 0.003:
            return VelocitySetpoint((0.0, 0.0, 0.0))
        return VelocitySetpoint((min(1.0 + t, 2.5), 0.3 * np.sin(t), -0.2 * np.sin(0.7 * t)))

    log = record_offboard(hovering(settle_s=2.0), command_at, 9.0, 250.0)
    thinned = add_sensor_noise(log, dataclasses.replace(SensorNoise.none(), log_rate_hz=rate_hz), 0)
    assert replay(load_sim_config("iris"), [thinned], windows([thinned])).rmse_mps() < bound_mps
