"""The ULog mapping on real hardware flights (tests/fixtures/ulog/README.md), checked topic by
topic against the raw ULog: command source in POSCTL, AUTO.MISSION/RTL and OFFBOARD, modes,
validity drops, thrust and rotor speed sources, rates, and what each command does with them."""

from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest
from pyulog import ULog

from flightlog import px4
from flightlog.reader import read_log
from flightlog.ulog import TOPICS
from scripts import diagnose as diagnose_cli
from scripts import fit_gp as fit_gp_cli
from scripts import flightlog_cli, vehicle_sim_cli

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
FLIGHTS = {  # file: (firmware, modes kept)
    "quad_posctl_v1_15.ulg": ("v1.15.1", {"POSCTL"}),
    "quad_offboard_v1_16.ulg": ("v1.16.0", {"OFFBOARD"}),  # its POSCTL is on the ground
    "quad_mission_rtl_v1_9_esc.ulg": ("v1.9.0-beta", {"MISSION", "RTL"}),
}


def raw_topics(path: Path) -> dict[str, dict[str, np.ndarray]]:
    ulog = ULog(str(path), message_name_filter_list=list(TOPICS))
    return {d.name: d.data for d in ulog.data_list if d.multi_id == 0}


def held(topic: dict[str, np.ndarray], field: str, t_us: np.ndarray) -> np.ndarray:
    """The value last published at or before each of ``t_us``."""
    k = np.searchsorted(topic["timestamp"], t_us, side="right") - 1
    return np.asarray(topic[field], float)[k]


def kept_times_us(log, raw) -> np.ndarray:
    """Absolute ULog time of every kept row, recovered from the raw local position."""
    pos = raw["vehicle_local_position"]
    first = np.flatnonzero(
        np.isclose(pos["x"], log["pos_n_m"][0]) & np.isclose(pos["vx"], log["vel_n_mps"][0])
    )[0]
    return np.round(log["t_s"] * 1e6) + float(pos["timestamp"][first])


@pytest.mark.parametrize("name", sorted(FLIGHTS))
def test_command_is_the_velocity_controllers_setpoint_and_modes_come_from_nav_state(name):
    firmware, modes = FLIGHTS[name]
    log, raw = read_log(FIXTURES / name), raw_topics(FIXTURES / name)
    meta = log.metadata
    assert meta["firmware"] == firmware
    assert meta["command_topic"] == "vehicle_local_position_setpoint"
    t_us = kept_times_us(log, raw)
    sp = raw["vehicle_local_position_setpoint"]
    for axis, field in zip("ned", ("vx", "vy", "vz"), strict=True):
        np.testing.assert_allclose(log[f"cmd_vel_{axis}_mps"], held(sp, field, t_us))
    nav = held(raw["vehicle_status"], "nav_state", t_us).astype(int)
    assert list(log["mode"]) == list(px4.mode_names(nav, firmware))
    assert set(log["mode"]) == modes
    assert set(nav) <= px4.position_controlled_nav_states(firmware)
    assert np.all(log["armed"] == 1.0)
    assert log.n_rows == meta["rows_in_log"] - sum(meta["dropped_rows"].values())
    pos = raw["vehicle_local_position"]
    np.testing.assert_allclose(log["vel_e_mps"], np.interp(t_us, pos["timestamp"], pos["vy"]))


def test_v1_9_rotor_speed_from_real_esc_rpm_and_commanded_thrust_from_actuator_controls():
    path = FIXTURES / "quad_mission_rtl_v1_9_esc.ulg"
    log, raw = read_log(path), raw_topics(path)
    t_us = kept_times_us(log, raw)
    esc = raw["esc_status"]
    rpm = np.column_stack(
        [np.interp(t_us, esc["timestamp"], esc[f"esc[{i}].esc_rpm"]) for i in range(4)]
    )
    np.testing.assert_allclose(
        log["rotor_speed_rms_radps"], np.sqrt(np.mean((rpm * np.pi / 30) ** 2, axis=1))
    )
    assert log.metadata["rotor_speed_source"]["rotors"] == 4
    assert log.metadata["thrust_source"] == {"topic": "actuator_controls_0", "kind": "commanded"}
    assert "angular_rate" not in log.metadata["rates_hz"]  # vehicle_angular_velocity is v1.10+
    assert log.metadata["rates_hz"]["local_position"] == pytest.approx(8.0, abs=0.1)


@pytest.mark.parametrize("name", ["quad_posctl_v1_15.ulg", "quad_offboard_v1_16.ulg"])
def test_produced_thrust_from_actuator_motors_and_10_hz_default_profile_rates(name):
    log, raw = read_log(FIXTURES / name), raw_topics(FIXTURES / name)
    meta = log.metadata
    assert meta["thrust_source"]["topic"] == "actuator_motors"
    assert meta["thrust_source"]["kind"] == "produced"
    t_us = kept_times_us(log, raw)
    motors = raw["actuator_motors"]
    fac = meta["px4_params"].get("THR_MDL_FAC", 0.0)
    u = np.column_stack(
        [np.interp(t_us, motors["timestamp"], motors[f"control[{i}]"]) for i in range(4)]
    )
    expected = (fac * u**2 + (1 - fac) * u).mean(axis=1)
    np.testing.assert_allclose(log["thrust_norm"], expected, rtol=1e-9)
    assert meta["rates_hz"]["local_position"] == pytest.approx(10.0, abs=0.1)
    assert meta["rates_hz"]["velocity_command"] == pytest.approx(10.0, abs=0.2)


REFUSED = {  # file: (command, pattern of its one line)
    "octo_altctl_v1_14.ulg": r"no valid motion: of \d+ rows, dropped \d+ not_position_controlled",
    "fixedwing_v1_17rc_status.ulg": r"a fixed wing log \(MAV_TYPE 1\), not a multirotor",
    "quad_mission_rtl_v1_9_esc.ulg": r"needs faster signals: local_position at 7.96 Hz "
    r"\(needs >= 10 Hz\)",
    # flown in STAB without GPS: the line names the mode as well as the estimator
    "quad_stab_nogps_v1_16_1.ulg": r"no valid motion: of \d+ rows, dropped \d+ estimator_invalid; "
    r"flown in STAB; fly a multirotor in a position-controlled mode",
}


@pytest.mark.parametrize("name", sorted(REFUSED))
def test_real_logs_no_command_can_use_refused_in_one_line_exit_2_nothing_written(
    name, tmp_path, capsys
):
    log = str(FIXTURES / name)
    out = tmp_path / "out"
    runs = [
        ("fit-gp", lambda: fit_gp_cli.main([log, "--out", str(out / "model"), "--no-plots"])),
        ("diagnose", lambda: diagnose_cli.main([log, "--sim-config", "iris", "--out", str(out)])),
    ]
    if "v1_9" not in name:  # the 8 Hz log converts fine: only its users need 10 Hz
        runs.append(
            ("flightlog", lambda: flightlog_cli.main(["convert", log, "--out", str(out / "f.csv")]))
        )
    for prog, run in runs:
        assert run() == 2, prog
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(prog), err
        assert re.search(REFUSED[name], err[0]), err[0]
        assert not out.exists()


def test_octocopter_is_a_multirotor_refused_only_for_its_modes(capsys):
    assert flightlog_cli.main(["info", str(FIXTURES / "octo_altctl_v1_14.ulg")]) == 0
    out = capsys.readouterr().out
    assert "vehicle: octorotor" in out and "mode ALTCTL:" in out
    assert "cannot use this log: no valid motion" in out
    assert "config-from-log: from its PX4 parameters only" in out


def test_a_fixed_wing_log_is_not_offered_to_config_from_log(capsys):
    assert flightlog_cli.main(["info", str(FIXTURES / "fixedwing_v1_17rc_status.ulg")]) == 0
    out = capsys.readouterr().out
    assert "not a multirotor" in out and "config-from-log" not in out


@pytest.fixture
def no_airframe_log(tmp_path) -> Path:
    """The real POSCTL flight with SYS_AUTOSTART 0 and MAV_TYPE 0: a board never given an
    airframe."""
    ulog = ULog(str(FIXTURES / "quad_posctl_v1_15.ulg"))
    ulog.initial_parameters.update({"SYS_AUTOSTART": 0, "MAV_TYPE": 0})
    log = tmp_path / "no_airframe.ulg"
    ulog.write_ulog(str(log))
    return log


def test_a_log_of_a_board_with_no_airframe_set_says_so(no_airframe_log, tmp_path, capsys):
    """A board never given an airframe logs SYS_AUTOSTART 0 and MAV_TYPE 0; every command
    called its log 'a generic vehicle log (MAV_TYPE 0), not a multirotor' and asked for a
    quadcopter's log, though the vehicle may be one: the airframe is what is missing."""
    log = no_airframe_log
    said = "no airframe set (SYS_AUTOSTART 0, MAV_TYPE 0): set the airframe"
    assert flightlog_cli.main(["info", str(log)]) == 0
    assert f"cannot use this log: {said}" in capsys.readouterr().out
    out = str(tmp_path / "out")
    runs = [
        ("vehicle-sim", vehicle_sim_cli.main, ["config-from-log", str(log), "--out", out]),
        ("fit-gp", fit_gp_cli.main, [str(log), "--out", out, "--no-plots"]),
    ]
    for prog, main, argv in runs:
        assert main(argv) == 2, prog
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(prog) and said in err[0], err
        assert "not a multirotor" not in err[0] and "generic vehicle" not in err[0]


def test_info_on_a_log_with_no_airframe_set_calls_the_vehicle_unknown(no_airframe_log, capsys):
    """info said 'vehicle: generic vehicle' above its refusal for want of an airframe: MAV_TYPE 0
    is PX4's default there, not a type the log states."""
    assert flightlog_cli.main(["info", str(no_airframe_log)]) == 0
    lines = capsys.readouterr().out.splitlines()
    vehicle = [s for s in lines if s.startswith("vehicle:")]
    assert vehicle == ["vehicle: unknown (no airframe set: SYS_AUTOSTART 0, MAV_TYPE 0)"]
    assert any("cannot use this log: no airframe set" in s for s in lines)


@pytest.mark.parametrize("name", ["quad_posctl_v1_15.ulg", "quad_offboard_v1_16.ulg"])
def test_diagnose_on_a_real_flight_under_its_own_tuning_is_examined_and_never_overconfident(
    name, tmp_path
):
    from diagnosis.diagnosis import diagnose
    from vehicle_sim import load_sim_config
    from vehicle_sim.config_from_log import config_from_log

    log = read_log(FIXTURES / name)
    config_path = tmp_path / "mine.toml"
    config_path.write_text(config_from_log(log).toml)
    d = diagnose([log], load_sim_config(config_path))
    assert np.isfinite(d.baseline.rmse_mps())  # replayed in POSCTL / OFFBOARD
    floor = float(d.noise_floor["replay_rmse_mps"])
    if d.extended.rmse_mps() > 3.0 * floor:
        assert "unexplained" in d.verdict
    assert not set(d.at_bound) & set(d.verdict)
    assert "none" not in d.verdict


@pytest.mark.parametrize("name", ["quad_posctl_v1_15.ulg", "quad_offboard_v1_16.ulg"])
def test_fit_gp_on_a_real_flight_refuses_a_model_worse_than_nominal_unless_forced(
    name, tmp_path, capsys
):
    out = tmp_path / "model.npz"
    code = fit_gp_cli.main([str(FIXTURES / name), "--out", str(out), "--no-plots"])
    err = capsys.readouterr().err
    if code == 3:
        assert "the model is worse than nominal" in err and not out.exists()
        code = fit_gp_cli.main([str(FIXTURES / name), "--out", str(out), "--no-plots", "--force"])
    assert code == 0 and out.exists()


def test_a_closed_loop_that_scores_no_row_says_so_in_the_headline(tmp_path):
    """The real OFFBOARD hover on the iris preset: iris touches down in every flight segment the
    vehicle flew, so closed-loop tracking scores no row. The headline says it was not examined,
    and the report gives no gain for it."""
    from diagnosis.diagnosis import diagnose
    from diagnosis.report import report_document
    from vehicle_sim import load_sim_config

    d = diagnose([read_log(FIXTURES / "quad_offboard_v1_16.ulg")], load_sim_config("iris"))
    cl = d.closed_loop
    assert cl.segments > 0 and cl.scored.sum() == 0
    said = [w for w in d.warnings if w.startswith("closed-loop tracking not examined")]
    assert len(said) == 1 and f"{cl.reanchored} of {cl.segments}" in said[0], d.warnings
    doc = report_document(d)["closed_loop"]
    assert doc["gain"] is None and doc["ground_hold_gain"] is None  # no row: no ratio


def test_a_replay_that_cannot_be_examined_gives_no_gain_and_says_so_in_the_headline(
    tmp_path, capsys
):
    """The EKF-failure flight keeps 4.9 s of POSCTL, too short for a held-out replay window:
    the last line names what was not examined instead of a gain of 1.0x, and report.json
    gives no gain (as for a closed loop that scores no row)."""
    out = tmp_path / "out"
    log = str(FIXTURES / "quad_posctl_ekf_fail_v1_15.ulg")
    assert diagnose_cli.main([log, "--sim-config", "iris", "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert "nan" not in err
    last = err.strip().splitlines()[-1]
    assert "held-out replay not examined" in last and not re.search(r"gain [\d.]+x", last), last
    assert "not examined: " in last and "command_delay" in last, last
    doc = json.loads((out / "report.json").read_text())
    assert doc["baseline"]["replay_vel_rmse_mps"] is None
    assert doc["extended"]["gain"] is None


def test_info_says_when_the_version_is_not_logged_and_counts_the_loggers_dropouts(capsys):
    """pyulog's sample log (AUAV-X2.1, before PX4 logged ver_sw_release), whose logger dropped
    messages four times: info says both, with the dropouts pyulog reads."""
    path = FIXTURES / "quad_manual_dropouts_nover.ulg"
    assert flightlog_cli.main(["info", str(path)]) == 0
    out = capsys.readouterr().out
    assert "firmware: PX4, version not logged (no ver_sw_release), on AUAV_X21" in out
    ms = [d.duration for d in ULog(str(path), message_name_filter_list=[]).dropouts]
    assert len(ms) == 4
    line = f"logger dropouts: 4, {sum(ms) / 1e3:g} s in all, longest {max(ms):g} ms"
    assert line in out
    assert flightlog_cli.main(["info", str(FIXTURES / "quad_posctl_v1_15.ulg")]) == 0
    assert "logger dropouts" not in capsys.readouterr().out
