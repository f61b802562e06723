"""fit-gp on a real PX4 ULog: same result as on its `flightlog convert` CSV; honest refusal
when the model is worse than nominal or a time constant sits on its bound; --mode rules."""

from __future__ import annotations

from pathlib import Path

import pytest
from pyulog import ULog

from flightlog.reader import read_log
from flightlog.schema import FlightLog, write_flight_log
from flightlog.velocity_loop_gains import GRAVITY_MPS2, OLD_TO_ACC
from gp.errors import DatasetError
from gp.model_io import read_model_header
from gp.velocity_integrator import logged_velocity_loop_gains
from scripts import fit_gp as fit_gp_cli
from scripts import fit_gp_run, flightlog_cli

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
AUTO = FIXTURES / "quad_sitl_v1_15_auto.ulg"
POSCTL = FIXTURES / "quad_posctl_v1_15.ulg"  # a real vehicle
V1_9 = FIXTURES / "quad_mission_rtl_v1_9_esc.ulg"  # a real vehicle, gains under pre-v1.11 names
OFFBOARD = FIXTURES / "quad_offboard_v1_16.ulg"  # a real vehicle hovering in OFFBOARD
FAST = ["--no-plots", "--m", "10", "--restarts", "1", "--force"]


@pytest.mark.parametrize("ulog", [AUTO, POSCTL], ids=["sitl_auto", "real_posctl"])
def test_ulog_and_its_converted_csv_give_the_same_model(ulog, tmp_path, capsys):
    csv = tmp_path / "flight.csv"
    assert flightlog_cli.main(["convert", str(ulog), "--out", str(csv)]) == 0
    capsys.readouterr()
    assert fit_gp_cli.main([str(ulog), "--out", str(tmp_path / "a"), *FAST]) == 0
    from_ulog = capsys.readouterr().out
    assert fit_gp_cli.main([str(csv), "--out", str(tmp_path / "b"), *FAST]) == 0
    assert capsys.readouterr().out == from_ulog
    a = read_model_header(tmp_path / "a.npz")
    b = read_model_header(tmp_path / "b.npz")
    assert a["hyperparameters"] == b["hyperparameters"]
    for key in ("n_rows", "residual_mean", "residual_std", "nominal_rmse_mps"):
        assert a["training_data"][key] == b["training_data"][key]


def test_worse_than_nominal_warns_exits_3_and_writes_nothing(tmp_path, capsys):
    code = fit_gp_cli.main([str(AUTO), "--out", str(tmp_path / "m"), *FAST[:-1]])
    err = capsys.readouterr().err
    assert code == fit_gp_cli.EXIT_DOUBTFUL
    assert "the model is worse than nominal" in err and "pass --force" in err
    assert list(tmp_path.iterdir()) == []


def test_a_refused_lag_says_nothing_of_a_file_it_did_not_write(tmp_path, capsys):
    """README's own-vehicle command on a real hover: the GP does not beat the identified lag and
    the lag's tau_d_s sits on its bound, so nothing is written; it said "the file keeps the GP
    to inspect" before "no model written"."""
    args = ["--nominal", "first_order_lag", "--mode", "OFFBOARD", "--check-horizon-s", "2"]
    code = fit_gp_cli.main([str(OFFBOARD), *args, "--out", str(tmp_path / "m"), "--no-plots"])
    err = capsys.readouterr().err
    assert code == fit_gp_cli.EXIT_DOUBTFUL
    assert "does NOT beat first_order_lag alone" in err and "sits on its bound" in err
    assert "the file keeps" not in err
    assert list(tmp_path.iterdir()) == []


def test_time_constant_on_its_bound_is_a_doubt():
    metrics = {"nominal_rmse_mps": [0.3, 0.3, 0.1], "augmented_rmse_mps": [0.1, 0.1, 0.05]}
    assert fit_gp_run.model_doubts(metrics, {"tau_s": 0.4, "tau_d_s": 0.6}) == []
    (doubt,) = fit_gp_run.model_doubts(metrics, {"tau_s": 0.4, "tau_d_s": 10.0})
    assert "tau_d_s=10.000 s sits on its bound" in doubt


def test_mode_filter_on_ulog_and_refused_on_a_log_without_modes(tmp_path, capsys):
    code = fit_gp_cli.main([str(AUTO), "--out", str(tmp_path / "m"), "--mode", "rtl", *FAST])
    assert code == 0
    data = read_model_header(tmp_path / "m.npz")["training_data"]
    assert data["n_rows"] + data["held_out"]["n_rows"] < read_log(AUTO).n_rows - 3
    log = read_log(AUTO)
    bare = FlightLog({k: v for k, v in log.columns.items() if k != "mode"}, {})
    csv = write_flight_log(tmp_path / "bare.csv", bare)
    capsys.readouterr()
    assert fit_gp_cli.main([str(csv), "--out", str(tmp_path / "n"), "--mode", "rtl"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    (line,) = [e for e in err if e.startswith("fit-gp: error")]
    assert "has no mode column; drop --mode" in line
    assert not (tmp_path / "n.npz").exists()
    assert fit_gp_cli.main([str(AUTO), "--out", str(tmp_path / "o"), "--mode", "offboard"]) == 2
    assert "no rows in mode OFFBOARD; the logs hold HOLD, RTL, TAKEOFF" in capsys.readouterr().err


def test_two_hz_log_refused_with_the_rate_needed(tmp_path, capsys):
    log = read_log(AUTO)
    slow = FlightLog({k: v[::5] for k, v in log.columns.items()}, {"source": "csv"})
    csv = write_flight_log(tmp_path / "slow.csv", slow)
    assert fit_gp_cli.main([str(csv), "--out", str(tmp_path / "m"), "--no-plots"]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert (
        "velocity_command at 2 Hz (needs >= 5 Hz)" in line and "log vehicle_local_position" in line
    )
    assert not (tmp_path / "m.npz").exists()


def test_px4_velocity_pi_takes_its_gains_from_the_ulog_parameters(tmp_path, capsys):
    """A PX4 ULog records MPC_*_VEL_*_ACC among its parameters: px4_velocity_pi fits on it
    with those gains (it asked for a sidecar a ULog never has)."""
    out = tmp_path / "pi"
    argv = [str(POSCTL), "--nominal", "px4_velocity_pi", "--out", str(out), *FAST]
    assert fit_gp_cli.main(argv) == 0, capsys.readouterr().err
    header = read_model_header(out)
    params = read_log(POSCTL).metadata["px4_params"]
    nominal = header["feature_definition"]["nominal_model"]["params"]
    assert nominal["vel_p_xy"] == pytest.approx(params["MPC_XY_VEL_P_ACC"])
    assert nominal["vel_i_z"] == pytest.approx(params["MPC_Z_VEL_I_ACC"])


def test_px4_velocity_pi_reads_gains_a_ulog_records_under_their_pre_v1_11_names(tmp_path, capsys):
    """PX4 up to v1.10 logs MPC_XY_VEL_P/I/D and MPC_Z_VEL_P/I/D (normalised thrust per m/s),
    no MPC_*_VEL_*_ACC: fit-gp refused such a log as one without gains. The real POSCTL flight
    with its gains written under the old names (old = new x MPC_THR_HOVER / g) fits with the
    gains it flew."""
    ulog = ULog(str(POSCTL))
    params = ulog.initial_parameters
    hover = params["MPC_THR_HOVER"]
    flown = {new: params.pop(new) for new in OLD_TO_ACC.values()}
    params.update({old: flown[new] * hover / GRAVITY_MPS2 for old, new in OLD_TO_ACC.items()})
    old_names = tmp_path / "posctl_pre_v1_11_names.ulg"
    ulog.write_ulog(str(old_names))
    out = tmp_path / "pi"
    argv = [str(old_names), "--nominal", "px4_velocity_pi", "--out", str(out), *FAST]
    assert fit_gp_cli.main(argv) == 0, capsys.readouterr().err
    assert (
        f"velocity-loop gains of {old_names}: its PX4 parameters MPC_XY_VEL_P, MPC_XY_VEL_I, "
        "MPC_XY_VEL_D, MPC_Z_VEL_P, MPC_Z_VEL_I, MPC_Z_VEL_D (before v1.11, normalised thrust "
        "per m/s) x g / hover thrust 0.580 (MPC_THR_HOVER parameter)"
    ) in capsys.readouterr().err
    nominal = read_model_header(out)["feature_definition"]["nominal_model"]["params"]
    assert nominal["vel_p_xy"] == pytest.approx(flown["MPC_XY_VEL_P_ACC"], rel=1e-6)
    assert nominal["vel_i_z"] == pytest.approx(flown["MPC_Z_VEL_I_ACC"], rel=1e-6)


def test_the_real_v1_9_gains_are_read_at_its_mpc_thr_hover_or_refused_saying_why():
    """The real v1.9 flight: MPC_XY_VEL_P 0.12, MPC_Z_VEL_I 0.05 at MPC_THR_HOVER 0.5. Without
    MPC_THR_HOVER and with no produced thrust (it logs the commanded one) nothing gives the
    scale: one line says so instead of a guess."""
    log = read_log(V1_9)
    gains = logged_velocity_loop_gains([log])
    assert gains["vel_p_xy"] == pytest.approx(0.12 * GRAVITY_MPS2 / 0.5, rel=1e-6)
    assert gains["vel_i_z"] == pytest.approx(0.05 * GRAVITY_MPS2 / 0.5, rel=1e-6)
    params = {k: v for k, v in log.metadata["px4_params"].items() if k != "MPC_THR_HOVER"}
    no_hover = FlightLog(log.columns, {**log.metadata, "px4_params": params}, V1_9)
    with pytest.raises(DatasetError) as err:
        logged_velocity_loop_gains([no_hover])
    assert str(err.value).startswith(
        f"{V1_9}: it records MPC_XY_VEL_P, MPC_XY_VEL_I, MPC_XY_VEL_D, MPC_Z_VEL_P, "
        "MPC_Z_VEL_I, MPC_Z_VEL_D under their names before PX4 v1.11 (normalised thrust per "
        "m/s) and no hover thrust to scale them by (no MPC_THR_HOVER parameter in (0, 1], no "
        "produced thrust while hovering); px4_velocity_pi needs"
    )
    assert "\n" not in str(err.value)


def test_a_model_from_a_10_hz_ulog_says_the_companion_rate_it_flies_at(tmp_path, capsys):
    """PX4 logs at 10 Hz: a kinematic-model residual fitted there was written without a word
    and then refused by the companion at its default 50 Hz, found only at take-off."""
    assert fit_gp_cli.main([str(POSCTL), "--out", str(tmp_path / "m"), *FAST]) == 0
    err = capsys.readouterr().err
    assert (
        "fit-gp: warning: the companion's NMPC will refuse this model at its default 50 Hz "
        "(the residual is measured over the logs' 0.0992 s steps): fly it with companion "
        "--rate-hz 10.1, or fit logs flown at 50 Hz"
    ) in err


def test_the_rows_the_mapping_left_out_are_warned_of(tmp_path, capsys):
    """PX4 SITL's AUTO flight: 196 of its 311 rows have no valid position estimate or no
    velocity command; fit-gp named only the rows it used, as diagnose did."""
    assert fit_gp_cli.main([str(AUTO), "--out", str(tmp_path / "m"), *FAST]) == 0
    err = capsys.readouterr().err
    assert "fit-gp: warning: quad_sitl_v1_15_auto.ulg: 115 of its 311 rows used; left out:" in err
