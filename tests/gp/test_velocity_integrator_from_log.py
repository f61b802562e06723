"""px4_velocity_pi's integrator rebuilt from a flight log is the one the companion held in
flight; fit-gp's pipeline fits the PI structure's residual with the gains recorded with the
log, and refuses in one line a log without them; the structure alone predicts the flight
offset-free (the integrator held as the disturbance it cancels)."""

from __future__ import annotations

import numpy as np
import pytest

from companion.autopilot_gains import velocity_loop_gains, velocity_loop_metadata
from companion.control_loop import Tick
from companion.flight_recorder import FlightRecorder
from companion.inprocess_link import InProcessLink
from companion.mission import Mission
from companion.nmpc_planner import CompanionNmpc, NmpcSettings
from companion.runner import RunnerConfig, fly_mission
from flightlog.schema import FlightLog, write_flight_log
from gp.datasets import DatasetConfig, residual_dataset, split_segments
from gp.errors import DatasetError
from gp.features import feature_definition
from gp.log_signals import model_state
from gp.model_io import read_model_header
from gp.prediction_check import Predictor, horizon_prediction_rmse
from gp.training import TrainingConfig, resolve_features, train_residual_model
from planners.bspline import BSplineReference
from planners.nominal_models import INTEGRATOR_STATES
from scripts.fit_gp import main as fit_gp

SEED = 20261124
PERIOD_S = 0.02


def _fly_pi(seed: int) -> tuple[FlightLog, dict[float, np.ndarray], dict[str, float]]:
    """A short flight of the px4_velocity_pi planner through the wind field (a random path
    near the start), its log (with the gains in its sidecar) and the companion's integrator
    at every OFFBOARD tick."""
    rng = np.random.default_rng(seed)
    link = InProcessLink.from_vehicle("iris_wind_field", seed)
    gains = dict(velocity_loop_gains(link))
    settings = NmpcSettings(
        speed_limit_mps=3.0, time_budget_s=30.0, nominal_model="px4_velocity_pi",
        nominal_params=tuple(gains.items()),
    )  # fmt: skip
    planner = CompanionNmpc(settings)
    steps = rng.uniform(-3.0, 3.0, (3, 3)) * np.array([1.0, 1.0, 0.1])
    points = np.array([0.0, 0.0, -3.0]) + np.vstack([np.zeros(3), np.cumsum(steps, axis=0)])
    reference = BSplineReference(points, 1.5)
    mission = Mission(
        name="integrator", altitude_m=3.0, speed_limit_mps=3.0, reference_kind="bspline",
        points_ned_m=tuple(tuple(float(c) for c in p) for p in points), goal_tolerance_m=0.5,
    )  # fmt: skip
    recorder = FlightRecorder(period_s=PERIOD_S, wall_clock_columns=False)
    held: dict[float, np.ndarray] = {}

    def on_tick(tick: Tick) -> None:
        recorder.record(tick)
        if tick.state.mode == "OFFBOARD":
            held[float(tick.t_s)] = planner.velocity_integrator_mps2

    runner = RunnerConfig(rate_hz=1.0 / PERIOD_S)
    fly_mission(link, planner, reference, mission, runner, on_tick, lambda message: None)
    log = recorder.to_log({"rate_hz": 1.0 / PERIOD_S, **velocity_loop_metadata(link)})
    return log, held, gains


@pytest.fixture(scope="module")
def pi_flight():
    return _fly_pi(SEED)


@pytest.mark.slow
def test_rebuilt_integrator_is_what_the_companion_held(pi_flight):
    log, held, gains = pi_flight
    features = feature_definition("velocity", "px4_velocity_pi", **gains)
    model = features.nominal()
    (segment,) = split_segments(log, DatasetConfig(features, modes=("OFFBOARD",)))
    rebuilt = model_state(model, segment)[
        :, [model.state_names.index(c) for c in INTEGRATOR_STATES]
    ]
    companion = np.array([held[float(t)] for t in segment["t_s"]])
    assert segment.n_rows == len(held)  # the segment is the companion's plans, all of them
    assert np.max(np.abs(companion)) > 0.1  # the wind moved the integrator
    np.testing.assert_allclose(rebuilt, companion, atol=1e-9)


@pytest.mark.slow
def test_pi_residual_is_fitted_with_the_logged_gains(pi_flight):
    log, _, gains = pi_flight
    config = TrainingConfig(
        features="velocity", nominal="px4_velocity_pi", inducing="random", m=10, restarts=1,
        modes=("OFFBOARD",), residual_steps=5, seed=SEED,
    )  # fmt: skip
    result = train_residual_model([log], config)
    assert dict(result.model.features.nominal_params) == pytest.approx(gains)
    retuned = {k: v * 1.5 for k, v in gains.items()}  # the gains are read, not defaulted
    relog = FlightLog(log.columns, {**log.metadata, "velocity_loop_gains": retuned})
    features, _ = resolve_features([relog], config)
    assert dict(features.nominal_params) == pytest.approx(retuned)
    # the PI structure explains the flight better than the kinematic model does
    kinematic = residual_dataset(
        [log],
        DatasetConfig(feature_definition("velocity", residual_dt_s=PERIOD_S), modes=("OFFBOARD",)),
    )
    pi = residual_dataset([log], DatasetConfig(result.model.features, modes=("OFFBOARD",)))
    assert np.sqrt(np.mean(pi.Y**2)) < np.sqrt(np.mean(kinematic.Y**2))

    bare = FlightLog(
        log.columns, {k: v for k, v in log.metadata.items() if k != "velocity_loop_gains"}
    )
    with pytest.raises(DatasetError, match="velocity_loop_gains") as refused:
        train_residual_model([bare], config)
    assert "\n" not in str(refused.value)
    given = TrainingConfig(**{**config.__dict__, "nominal_params": tuple(gains.items())})
    assert train_residual_model([bare], given).model.features.nominal_params


@pytest.mark.slow
def test_fit_gp_cli_fits_the_pi_structure_from_a_log_file(pi_flight, tmp_path):
    log, _, gains = pi_flight
    path = write_flight_log(tmp_path / "pi.csv", log)
    out = tmp_path / "pi_model"
    argv = [str(path), "--out", str(out), "--nominal", "px4_velocity_pi", "--mode", "OFFBOARD"]
    code = fit_gp([*argv, "--m", "10", "--restarts", "1", "--no-plots", "--force"])
    assert code == 0
    doc = read_model_header(tmp_path / "pi_model.npz")
    nominal = doc["feature_definition"]["nominal_model"]
    assert nominal["name"] == "px4_velocity_pi" and nominal["params"] == pytest.approx(gains)


class _IntegratorAsAcceleration(Predictor):
    """The PI structure started from the integrator rebuilt from the log, as if it were an
    acceleration the vehicle has (the rule offset-free planning replaces)."""

    def start_states(self, x: np.ndarray) -> np.ndarray:
        return x


@pytest.mark.slow
def test_offset_free_pi_predicts_the_wind_flight_better_than_reading_the_integrator(pi_flight):
    log, _, gains = pi_flight
    model = feature_definition("velocity", "px4_velocity_pi", **gains).nominal()
    offset_free, _ = horizon_prediction_rmse(Predictor("pi", model), [log], 2.0, ("OFFBOARD",))
    raw, _ = horizon_prediction_rmse(
        _IntegratorAsAcceleration("raw", model), [log], 2.0, ("OFFBOARD",)
    )
    assert offset_free < 0.8 * raw
