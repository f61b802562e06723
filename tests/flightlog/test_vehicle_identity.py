"""Logs of different vehicles or configs are told apart by their metadata, and fit-gp, which
pools every log it is given, says so in one line naming the logs and the field."""

from __future__ import annotations

from pathlib import Path

from flightlog.schema import FlightLog
from flightlog.ulog import read_ulog
from flightlog.vehicle_identity import mixed_vehicle_fields
from scripts import fit_gp as fit_gp_cli

FIXTURES = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
POSCTL = FIXTURES / "quad_posctl_v1_15.ulg"  # airframe 4001 on a PX4_FMU_V6C
OFFBOARD = FIXTURES / "quad_offboard_v1_16.ulg"  # airframe 4003 on a CUAV_7_NANO


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
