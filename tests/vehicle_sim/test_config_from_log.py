"""vehicle-sim config-from-log on a real PX4 ULog: the log's tuning and hover thrust in the sim,
the rest assumed and listed; bad logs one line, exit 2, nothing written."""

from __future__ import annotations

import tomllib
from pathlib import Path

import numpy as np
import pytest

from flightlog.reader import read_log
from scripts import vehicle_sim_cli
from tests.vehicle_sim.sim_flying import fly, hovering
from vehicle_sim import SimConfigError, Simulator, load_sim_config
from vehicle_sim.config import GRAVITY_MPS2, config_from_mapping

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
AUTO = FIXTURES / "quad_sitl_v1_15_auto.ulg"


def test_config_uses_the_logs_tuning_and_hovers_at_its_hover_thrust(tmp_path, capsys):
    out = tmp_path / "my_vehicle.toml"
    assert vehicle_sim_cli.main(["config-from-log", str(AUTO), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "assumed: inertia_kgm2, rotor geometry" in err and "from preset 'iris'" in err
    text = out.read_text()
    assert "# Assumed (the log cannot tell):" in text
    config = load_sim_config(out)
    params = read_log(AUTO).metadata["px4_params"]
    sim = Simulator(config)
    assert sim.get_param("COM_OF_LOSS_T") == params["COM_OF_LOSS_T"] == 5.0  # not PX4's default 1.0
    assert sim.get_param("MPC_XY_VEL_P_ACC") == pytest.approx(params["MPC_XY_VEL_P_ACC"], rel=1e-6)
    log = read_log(AUTO)
    speed = np.linalg.norm(log.stack("vel_n_mps", "vel_e_mps", "vel_d_mps"), axis=1)
    measured = float(np.median(log["thrust_norm"][(speed < 0.3) & (log["landed"] == 0)]))
    assert config.vehicle.hover_thrust_norm == pytest.approx(measured, rel=0.02)
    assert sim.get_param("MPC_THR_HOVER") == pytest.approx(measured, rel=0.02)
    cells, full, empty = (params[n] for n in ("BAT1_N_CELLS", "BAT1_V_CHARGED", "BAT1_V_EMPTY"))
    assert config.vehicle.battery_full_v == pytest.approx(cells * full)
    assert config.vehicle.battery_empty_v == pytest.approx(cells * empty)
    assert "battery voltages" not in err


def test_bad_log_one_line_exit_2_nothing_written(tmp_path, capsys):
    out = tmp_path / "v.toml"
    log = FIXTURES / "vtol_manual_v1_11.ulg"
    assert vehicle_sim_cli.main(["config-from-log", str(log), "--out", str(out)]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "no velocity command" in line
    assert not out.exists()


def test_multirotor_log_whose_flight_is_unusable_gives_a_config_from_its_parameters(
    tmp_path, capsys
):
    """A real v1.12 quadrotor armed on the ground in STAB: no velocity command, so no command
    reads its flight, but its parameters are the vehicle's tuning; the config says it was built
    from them alone and that the hover thrust is PX4's default, not measured."""
    log = FIXTURES / "quad_stab_ground_v1_12.ulg"
    out = tmp_path / "v.toml"
    assert vehicle_sim_cli.main(["config-from-log", str(log), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    note = (
        "parameters only: its flight cannot be read (ULog lacks topic(s) "
        "vehicle_local_position_setpoint or trajectory_setpoint (no velocity command; flown in "
        "STAB)), so the hover thrust is the MPC_THR_HOVER parameter, not measured"
    )
    default = "MPC_THR_HOVER = 0.5 is PX4's default: it may never have been set for this vehicle"
    assert note in err and note in out.read_text()
    assert default in err and default in out.read_text()
    config = load_sim_config(out)
    assert config.vehicle.hover_thrust_norm == pytest.approx(0.5, rel=0.02)
    assert config.vehicle.battery_full_v == pytest.approx(4 * 4.05)  # BAT1_N_CELLS 4


def test_truncated_log_names_its_damage_without_the_fly_hint(tmp_path, capsys):
    """The mapping's refusal of a truncated ULog ends with the damage after the hint to fly
    otherwise; the parameters-only note keeps the reason and the damage, not the hint."""
    out = tmp_path / "v.toml"
    log = FIXTURES / "truncated.ulg"
    assert vehicle_sim_cli.main(["config-from-log", str(log), "--out", str(out)]) == 0
    (note,) = [s for s in capsys.readouterr().err.splitlines() if "parameters only" in s]
    assert (
        "flown in HOLD; the file is truncated (at byte" in note and "fly a multirotor" not in note
    )


@pytest.mark.parametrize(
    "name",
    [
        "fixedwing_v1_17rc_status.ulg",
        "octo_altctl_v1_14.ulg",
        "quad_manual_v1_6.ulg",
        "quad_stab_ground_v1_12.ulg",
        "vtol_manual_v1_11.ulg",
    ],
)
def test_info_offers_config_from_log_exactly_when_it_builds_one(name, tmp_path, capsys):
    """On a ULog whose flight no command reads, `flightlog info` and config-from-log decide by
    the same rule (flightlog.ulog.parameters_give_a_config) whether its parameters make a
    config: info's offer is never refused, nor a config built that info did not offer."""
    from scripts import flightlog_cli

    assert flightlog_cli.main(["info", str(FIXTURES / name)]) == 0
    info = capsys.readouterr().out
    assert "cannot use this log" in info
    offered = "config-from-log: from its PX4 parameters only" in info
    out = tmp_path / "v.toml"
    code = vehicle_sim_cli.main(["config-from-log", str(FIXTURES / name), "--out", str(out)])
    assert (code, out.exists()) == ((0, True) if offered else (2, False)), capsys.readouterr()


def test_px4_params_section_is_validated():
    base = {
        "vehicle": {
            "mass_kg": 1.5, "inertia_kgm2": [0.03, 0.03, 0.05], "rotor_max_speed_radps": 1100.0,
            "thrust_coeff_n_per_radps2": 5.84e-6, "torque_coeff_nm_per_radps2": 3.5e-7,
            "motor_time_constant_s": 0.02,
        },
        "rotors": {
            "positions_frd_m": [[0.1, 0.1, 0], [-0.1, -0.1, 0], [0.1, -0.1, 0], [-0.1, 0.1, 0]],
            "spin": [1, 1, -1, -1],
        },
        "battery": {"full_v": 16.8, "empty_v": 14.0},
    }  # fmt: skip
    with pytest.raises(SimConfigError, match="MPC_XY_VEL_P_AC: unknown parameter; did you mean"):
        config_from_mapping({**base, "px4_params": {"MPC_XY_VEL_P_AC": 2.0}}, "t")
    with pytest.raises(SimConfigError, match="MPC_THR_HOVER: follows from vehicle.mass_kg"):
        config_from_mapping({**base, "px4_params": {"MPC_THR_HOVER": 0.4}}, "t")
    with pytest.raises(SimConfigError, match=r"MPC_XY_CRUISE: .*outside PX4's range \[3, 20\]"):
        config_from_mapping({**base, "px4_params": {"MPC_XY_CRUISE": 1.0}}, "t")


def test_real_vehicles_out_of_range_value_is_clamped_and_said(tmp_path, capsys):
    """PX4 stores what it is sent: this real v1.16 vehicle flew with MPC_XY_CRUISE = 1, below
    PX4's documented minimum of 3, which the simulator refuses."""
    log = FIXTURES / "quad_offboard_v1_16.ulg"
    assert read_log(log).metadata["px4_params"]["MPC_XY_CRUISE"] == 1.0
    out = tmp_path / "v.toml"
    assert vehicle_sim_cli.main(["config-from-log", str(log), "--out", str(out)]) == 0
    note = "MPC_XY_CRUISE = 1 is outside PX4's documented range [3, 20]: clamped to 3"
    assert note in capsys.readouterr().err and note in out.read_text()
    assert Simulator(load_sim_config(out)).get_param("MPC_XY_CRUISE") == 3.0


def test_log_without_thrust_or_parameters_refused(tmp_path, capsys):
    from flightlog.schema import FlightLog, write_flight_log

    log = read_log(AUTO)
    cols = {k: v for k, v in log.columns.items() if k != "thrust_norm"}
    csv = write_flight_log(tmp_path / "bare.csv", FlightLog(cols, {"source": "csv"}))
    out = tmp_path / "v.toml"
    assert vehicle_sim_cli.main(["config-from-log", str(csv), "--out", str(out)]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert (
        "no MPC_THR_HOVER parameter in (0, 1] and no produced thrust" in line
        and "log actuator_motors" in line
    )
    assert not out.exists()


@pytest.mark.parametrize("where", ["folder", "under_a_file"])
def test_unwritable_out_one_line_exit_2_nothing_left(where, tmp_path, capsys):
    """An --out that is a folder, or lies under a file: one line naming it, exit 2, no
    traceback and no temporary file left beside it."""
    (tmp_path / "taken").mkdir()
    (tmp_path / "plain").write_text("")
    out = tmp_path / ("taken" if where == "folder" else "plain/my.toml")
    before = sorted(p.name for p in tmp_path.rglob("*"))
    assert vehicle_sim_cli.main(["config-from-log", str(AUTO), "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(out) in err[0], err
    assert sorted(p.name for p in tmp_path.rglob("*")) == before


def test_help_describes_the_whole_command(capsys):
    assert vehicle_sim_cli.main(["config-from-log", "--help"]) == 0
    help_text = " ".join(capsys.readouterr().out.split())
    assert "whose mass agrees with its hover thrust" in help_text


def test_out_onto_the_log_is_refused_and_the_log_kept(tmp_path, capsys):
    log = tmp_path / "flight.ulg"
    log.write_bytes(AUTO.read_bytes())
    assert vehicle_sim_cli.main(["config-from-log", str(log), "--out", str(log)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "is an input being read" in err[0], err
    assert log.read_bytes() == AUTO.read_bytes()


def test_a_vehicle_that_is_no_quadrotor_is_said_to_fly_as_the_presets_rotors(tmp_path, capsys):
    """The real coaxial octocopter: its config flies iris's 4 rotors. That was only inside
    'rotor geometry ... from preset iris', which reads the same for a quadrotor's log."""
    out = tmp_path / "octo.toml"
    log = FIXTURES / "octo_altctl_v1_14.ulg"
    assert vehicle_sim_cli.main(["config-from-log", str(log), "--out", str(out)]) == 0
    said = "rotors: the log's vehicle (octorotor) flies as the 4 rotors of preset 'iris'"
    assert said in capsys.readouterr().err and said in out.read_text()
    assert vehicle_sim_cli.main(["config-from-log", str(AUTO), "--out", str(out)]) == 0
    assert "rotors: the log's vehicle" not in capsys.readouterr().err  # a quadrotor's


def test_a_config_from_parameters_needs_a_multirotor_and_its_hover_thrust():
    """From parameters alone the mass follows from MPC_THR_HOVER: without it, no config."""
    from flightlog.ulog import parameters_give_a_config

    hover = {"MPC_THR_HOVER": 0.4}
    assert parameters_give_a_config({"mav_type": 2, "px4_params": hover})
    assert not parameters_give_a_config({"mav_type": 2, "px4_params": {"MAV_TYPE": 2.0}})
    assert not parameters_give_a_config({"mav_type": 1, "px4_params": hover})  # fixed wing
    zero = {"MPC_THR_HOVER": 0.0}  # no hover thrust: it made a massless vehicle
    assert not parameters_give_a_config({"mav_type": 2, "px4_params": zero})


def test_velocity_gains_logged_under_their_pre_v1_11_names_are_carried_over(tmp_path, capsys):
    """The real v1.9 flight logs MPC_XY_VEL_P 0.12 and MPC_Z_VEL_P 0.25 (normalised thrust per
    m/s, PX4's defaults then 0.09 and 0.2); its config said 'assumed: PX4 defaults' for the
    MPC_*_VEL_*_ACC gains and flew PX4's current default loop instead of the vehicle's."""
    log, out = FIXTURES / "quad_mission_rtl_v1_9_esc.ulg", tmp_path / "v19.toml"
    assert vehicle_sim_cli.main(["config-from-log", str(log), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    params = tomllib.loads(out.read_text())["px4_params"]
    scale = GRAVITY_MPS2 / 0.5  # its hover thrust: MPC_THR_HOVER, not measured (8 Hz log)
    assert params["MPC_XY_VEL_P_ACC"] == pytest.approx(0.12 * scale, rel=1e-6)
    assert params["MPC_Z_VEL_P_ACC"] == pytest.approx(0.25 * scale, rel=1e-6)
    assert params["MPC_XY_VEL_I_ACC"] == pytest.approx(0.05 * scale, rel=1e-6)
    assumed = next(line for line in err.splitlines() if line.startswith("assumed: PX4 defaults"))
    assert "VEL_P_ACC" not in assumed and "VEL_I_ACC" not in assumed
    assert "logged as MPC_*_VEL_P/I/D (PX4 before v1.11" in err
    assert dict(load_sim_config(out).px4_params)["MPC_XY_VEL_P_ACC"] == params["MPC_XY_VEL_P_ACC"]
    # why a log with thrust gave its hover thrust by parameter, and what the mass stands for
    said = "the log's thrust is commanded (actuator_controls_0), not produced: not read as"
    assert said in err and said in out.read_text()
    assert "what the preset's rotors (maximum thrust 28.27 N) hover at the log's hover" in err


def test_a_log_whose_mpc_thr_hover_is_0_is_refused_as_without_one(tmp_path, capsys):
    """MPC_THR_HOVER 0 and no produced thrust: refused in one line as a log without a hover
    thrust; it made a massless vehicle, or a ZeroDivisionError with pre-v1.11 gains."""
    from flightlog.schema import FlightLog, write_flight_log

    log = read_log(AUTO)
    cols = {k: v for k, v in log.columns.items() if k != "thrust_norm"}
    params = {"MPC_THR_HOVER": 0.0, "MPC_XY_VEL_P": 0.1}
    meta = {"source": "csv", "px4_params": params}
    csv = write_flight_log(tmp_path / "zero.csv", FlightLog(cols, meta))
    out = tmp_path / "v.toml"
    assert vehicle_sim_cli.main(["config-from-log", str(csv), "--out", str(out)]) == 2
    (line,) = capsys.readouterr().err.strip().splitlines()
    assert "no MPC_THR_HOVER parameter in (0, 1] and no produced thrust" in line
    assert not out.exists()


def test_rate_loop_gains_stay_the_presets_as_its_airframe_does(tmp_path, capsys):
    """PX4's rate gains act in normalised torque, so they fit only the airframe they were tuned
    on. This real v1.16 vehicle's (roll P 0.039, yaw P 0.14) on iris' torque and inertia made
    the simulated vehicle swing about its velocity command while yawing (north velocity std
    0.13 m/s once settled; its held-out replay 4.5x worse than plain iris'); with the preset's
    gains, as its airframe is, it settles as iris does."""
    log = FIXTURES / "quad_offboard_v1_16.ulg"
    out = tmp_path / "v.toml"
    assert vehicle_sim_cli.main(["config-from-log", str(log), "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert read_log(log).metadata["px4_params"]["MC_ROLLRATE_P"] == pytest.approx(0.0387, 1e-3)
    assert "MC_ROLLRATE_P" not in tomllib.loads(out.read_text())["px4_params"]
    assert "rate-loop gains MC_ROLLRATE_P" in err and "from preset 'iris'" in err
    sim = hovering(preset=str(out))
    states = fly(sim, (0.7, 0.7, 0.4), 4.0, yaw_rate_radps=0.5)
    vel_n_mps = np.array([s.vel_ned_mps[0] for s in states[-40:]])
    assert vel_n_mps.std() < 0.02
