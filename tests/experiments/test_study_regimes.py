"""The study's regimes are StudyConfig overrides with a name."""

import pytest

from experiments.study.config import StudyConfig
from experiments.study.regimes import REGIMES, with_regime
from gp.feature_sets import FEATURE_SETS


def test_agile_raises_speeds_and_the_command_limit_and_keeps_the_rest():
    base = StudyConfig(n_trajectories=3)
    agile = with_regime(base, "agile")
    assert agile.regime == "agile" and agile.n_trajectories == 3
    assert agile.max_speed_mps > 3.0 and agile.nmpc.speed_limit_mps > agile.max_speed_mps
    assert agile.nmpc.period_s == base.nmpc.period_s
    assert agile.ramp_jerk_mps3 == 4.0  # a jerk-limited start, PX4's MPC_JERK_AUTO
    assert base.ramp_jerk_mps3 is None and with_regime(base, "wind_field").ramp_jerk_mps3 is None


def test_wind_field_flies_the_wind_field_vehicle_with_position_features():
    from vehicle_sim import load_sim_config

    wind = with_regime(StudyConfig(), "wind_field")
    assert "wind_field" in load_sim_config(wind.vehicle).effect_names
    assert wind.features == "position_velocity"  # position, not the command (regimes.py)
    assert wind.refit_rounds == 1 and "pos_n_m" in dict(FEATURE_SETS[wind.features])


def test_an_unknown_regime_is_refused_with_the_valid_names():
    with pytest.raises(ValueError, match=", ".join(REGIMES)):
        with_regime(StudyConfig(), "fast")


@pytest.mark.parametrize("regime", list(REGIMES))
def test_every_regime_checks_its_learned_model_in_closed_loop_unless_told_not_to(regime, tmp_path):
    """On by default (the open-loop check alone passed a GP that flew worse than nominal on
    JSBSim's F450); `--no-closed-loop-check` is the one way off."""
    from scripts.study import parse_args

    out = ["--out", str(tmp_path), "--regime", regime]
    assert with_regime(StudyConfig(), regime).closed_loop_check
    assert parse_args(out).closed_loop_check
    assert not parse_args([*out, "--no-closed-loop-check"]).closed_loop_check
