"""Logs of different vehicles or configs are told apart by their metadata, and fit-gp, which
pools every log it is given, says so in one line naming the logs and the field."""

from __future__ import annotations

from pathlib import Path

from pymavlink.dialects.v20 import common as mavlink2

from companion.autopilot_gains import velocity_loop_metadata
from companion.inprocess_link import InProcessLink
from flightlog.schema import FlightLog
from flightlog.ulog import read_ulog
from flightlog.vehicle_identity import airframe_mismatch, mixed_vehicle_fields
from flightlog.velocity_loop_gains import (
    GAINS_METADATA_KEY,
    GRAVITY_MPS2,
    OLD_TO_ACC,
    VELOCITY_LOOP_PARAMS,
)
from scripts import fit_gp as fit_gp_cli
from vehicle_sim import Simulator, load_sim_config
from vehicle_sim.mavlink.params import param_value_msg

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
POSCTL = FIXTURES / "quad_posctl_v1_15.ulg"  # airframe 4001 on a PX4_FMU_V6C
OFFBOARD = FIXTURES / "quad_offboard_v1_16.ulg"  # airframe 4003 on a CUAV_7_NANO
V1_9 = FIXTURES / "quad_mission_rtl_v1_9_esc.ulg"  # gains under their pre-v1.11 names


def with_metadata(log: FlightLog, name: str, **metadata: object) -> FlightLog:
    """The rows of ``log`` as a log named ``name`` whose sidecar holds only ``metadata``."""
    return FlightLog(log.columns, dict(metadata), Path(name))


def test_companion_logs_of_two_presets_are_named_with_their_values() -> None:
    rows = read_ulog(POSCTL)
    logs = [
        with_metadata(rows, "a.csv", vehicle_preset="iris", mass_kg=1.5),
        with_metadata(rows, "b.csv", vehicle_preset="iris_study", mass_kg=1.5),
        with_metadata(rows, "c.csv", vehicle_preset="iris", mass_kg=1.5 * (1 + 1e-6)),
    ]
    assert mixed_vehicle_fields(logs) == [
        "vehicle preset iris in a.csv and c.csv, iris_study in b.csv"
    ]


def test_a_field_only_one_log_records_is_not_a_difference() -> None:
    rows = read_ulog(POSCTL)
    logs = [
        with_metadata(rows, "sim.csv", vehicle="iris", backend="builtin", mass_kg=1.5),
        with_metadata(rows, "companion.csv", vehicle_preset="iris"),
    ]
    assert mixed_vehicle_fields(logs) == []
    heavier = with_metadata(rows, "heavy.csv", vehicle="iris", mass_kg=1.8)
    assert mixed_vehicle_fields([*logs, heavier]) == ["mass_kg 1.5 in sim.csv, 1.8 in heavy.csv"]


def test_fit_gp_warns_when_ulogs_of_two_airframes_are_pooled(tmp_path, capsys) -> None:
    argv = ["--m", "5", "--restarts", "1", "--no-plots"]
    out = tmp_path / "model"
    assert fit_gp_cli.main([str(POSCTL), str(OFFBOARD), "--out", str(out), *argv]) == 0
    warnings = [
        line for line in capsys.readouterr().err.splitlines() if "different vehicles" in line
    ]
    assert len(warnings) == 1, warnings
    assert warnings[0].startswith("fit-gp: warning: the logs are from different vehicles")
    assert f"airframe (SYS_AUTOSTART) 4001 in {POSCTL}, 4003 in {OFFBOARD}" in warnings[0]
    assert "hardware PX4_FMU_V6C" in warnings[0]
    assert out.with_suffix(".npz").is_file()  # pooled as asked: a warning, not a refusal
    fit_gp_cli.main([str(POSCTL), "--out", str(tmp_path / "one"), *argv])  # one vehicle
    assert "different vehicles" not in capsys.readouterr().err


def _over_mavlink(sim: Simulator, name: str) -> float:
    """A parameter as the companion reads it from vehicle-sim: PARAM_VALUE on the wire."""
    wire = param_value_msg(sim, name).pack(mavlink2.MAVLink(None))
    return mavlink2.MAVLink(None).decode(bytearray(wire)).param_value


def test_the_same_gains_read_in_process_and_over_mavlink_are_the_same_vehicle() -> None:
    """In process MPC_XY_VEL_P_ACC is 1.8; over MAVLink a float32, 1.7999999523: one vehicle."""
    rows = read_ulog(POSCTL)
    sim = Simulator(load_sim_config("iris"), seed=0)
    in_process = velocity_loop_metadata(InProcessLink(sim, {}))[GAINS_METADATA_KEY]
    wire = {n: _over_mavlink(sim, p) for n, p in VELOCITY_LOOP_PARAMS.items()}
    assert wire != in_process  # float32 on the wire
    logs = [
        with_metadata(rows, "inprocess.csv", vehicle_preset="iris", velocity_loop_gains=in_process),
        with_metadata(rows, "mavlink.csv", velocity_loop_gains=wire),
    ]
    assert mixed_vehicle_fields(logs) == []
    retuned = with_metadata(rows, "retuned.csv", velocity_loop_gains={**wire, "vel_p_xy": 1.9})
    assert [c.split(" ")[0] for c in mixed_vehicle_fields([*logs, retuned])] == [
        "velocity_loop_gains"
    ]


def test_unreadable_identity_values_are_left_out_not_a_crash() -> None:
    rows = read_ulog(POSCTL)
    logs = [
        with_metadata(rows, "a.csv", px4_params={"SYS_AUTOSTART": "quad"}, mass_kg=float("nan")),
        with_metadata(rows, "b.csv", px4_params={"SYS_AUTOSTART": 4001}, mass_kg=True),
        with_metadata(rows, "c.csv", velocity_loop_gains={"vel_p_xy": "fast"}),
    ]
    assert mixed_vehicle_fields(logs) == []


def test_gains_logged_under_their_pre_v1_11_names_are_compared_in_todays_units() -> None:
    """The real v1.9 flight logs MPC_XY_VEL_P 0.12 ... (normalised thrust per m/s): a log of
    another tuning passed as the same vehicle (only a sidecar's gains were compared), while
    the same loop logged under the v1.11 names (x g / MPC_THR_HOVER 0.5) is the same vehicle."""
    rows = read_ulog(V1_9)
    params = rows.metadata["px4_params"]
    today = {k: v for k, v in params.items() if k not in OLD_TO_ACC}
    today |= {new: params[old] * GRAVITY_MPS2 / 0.5 for old, new in OLD_TO_ACC.items()}
    renamed = with_metadata(rows, "v1_11.ulg", px4_params=today)
    assert mixed_vehicle_fields([rows, renamed]) == []
    retuned = with_metadata(rows, "retuned.ulg", px4_params={**params, "MPC_XY_VEL_P": 0.2})
    clauses = mixed_vehicle_fields([rows, renamed, retuned])
    assert len(clauses) == 1 and clauses[0].startswith("velocity_loop_gains ["), clauses
    assert clauses[0].endswith(
        f"[MPC_XY_VEL_P_ACC 2.354] in {V1_9} and v1_11.ulg, [MPC_XY_VEL_P_ACC 3.923] in retuned.ulg"
    )


def test_two_vehicles_gains_are_named_as_px4_names_them_to_a_readable_precision() -> None:
    """The two real vehicles' gains, float32 parameters, were printed as a Python dict of
    px4_velocity_pi's names ({'vel_p_xy': 1.600000023841858, ...}); a PX4 engineer reads
    the parameters that differ, under PX4's names."""
    clauses = mixed_vehicle_fields([read_ulog(POSCTL), read_ulog(OFFBOARD)])
    (gains,) = [c for c in clauses if c.startswith("velocity_loop_gains")]
    assert gains == (
        "velocity_loop_gains [MPC_XY_VEL_P_ACC 1.6, MPC_Z_VEL_P_ACC 2.5, MPC_Z_VEL_I_ACC 1, "
        f"MPC_Z_VEL_D_ACC 0.0075] in {POSCTL}, [MPC_XY_VEL_P_ACC 1.8, MPC_Z_VEL_P_ACC 4, "
        f"MPC_Z_VEL_I_ACC 2, MPC_Z_VEL_D_ACC 0] in {OFFBOARD}"
    )


def test_a_config_built_for_another_airframe_is_named_with_the_logs_that_flew_another() -> None:
    """A config from ``config-from-log`` of the offboard log (airframe 4003) diagnosing the
    position-control log (4001) gave a confident battery_sag without a word on the vehicle."""
    built_for = {"SYS_AUTOSTART": 4003.0, "MPC_XY_VEL_P_ACC": 1.8}
    posctl, offboard = read_ulog(POSCTL), read_ulog(OFFBOARD)
    said = airframe_mismatch(built_for, [offboard, posctl])
    assert said.startswith(
        f"the config was built for airframe (SYS_AUTOSTART) 4003, the log(s) flew 4001 in {POSCTL}:"
    )
    assert str(OFFBOARD) not in said and "vehicle-sim config-from-log" in said
    assert airframe_mismatch(built_for, [offboard]) == ""
    assert airframe_mismatch({"MPC_XY_VEL_P_ACC": 1.8}, [posctl]) == ""  # a preset: no airframe
    assert airframe_mismatch(built_for, [with_metadata(posctl, "a.csv")]) == ""  # log silent
