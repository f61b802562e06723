"""Without --log each flight's log is a new file, as PX4's SD-card logs: a second flight never
writes over the first; an explicit --log is written where it says, and a log already there is
kept under a numbered name (and put back when nothing is flown)."""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path

from companion.app import CompanionConfig, run_companion
from flightlog.flight_log_files import claim_new_log_path
from flightlog.schema import read_flight_log, sidecar_path
from scripts.companion_cli import main

LINE = Path(__file__).resolve().parents[2] / "missions" / "line_20m.toml"
NOON = datetime(2026, 5, 1, 12, 30, 5, tzinfo=UTC)


def test_names_are_the_utc_time_and_a_taken_one_is_never_reused(tmp_path: Path) -> None:
    (tmp_path / "flight_2026-05-01_12-30-05_2.csv.json").write_text("{}")  # a sidecar only
    first = claim_new_log_path(tmp_path, NOON)
    second = claim_new_log_path(tmp_path, NOON)
    third = claim_new_log_path(tmp_path, NOON.astimezone().replace(microsecond=1))
    assert [first.name, second.name, third.name] == [
        "flight_2026-05-01_12-30-05.csv",
        "flight_2026-05-01_12-30-05_3.csv",
        "flight_2026-05-01_12-30-05_4.csv",
    ]
    assert first.read_bytes() == b"" and not sidecar_path(first).exists()


def test_two_flights_without_log_keep_both_logs(tmp_path, monkeypatch, capsys) -> None:
    monkeypatch.chdir(tmp_path)
    argv = [str(LINE), "--link", "inprocess"]
    assert main(argv) == 0
    first = sorted((tmp_path / "out" / "flights").glob("*.csv"))
    assert len(first) == 1
    kept = first[0].read_bytes()
    assert f"companion: flight log: {first[0].relative_to(tmp_path)} (a new file" in (
        capsys.readouterr().err
    )
    assert main([*argv, "--seed", "1"]) == 0
    logs = sorted((tmp_path / "out" / "flights").glob("*.csv"))
    assert len(logs) == 2 and first[0] in logs and first[0].read_bytes() == kept
    seeds = {read_flight_log(p).metadata.get("seed") for p in logs}
    assert len(seeds) == 2, seeds
    assert not (tmp_path / "out" / "flight.csv").exists()


def test_an_explicit_log_is_written_there_and_the_earlier_one_kept(tmp_path, capsys) -> None:
    log = tmp_path / "nominal.csv"
    argv = [str(LINE), "--link", "inprocess", "--log", str(log)]
    assert main(argv) == 0 and read_flight_log(log).n_rows > 100
    first = (log.read_bytes(), sidecar_path(log).read_bytes())
    assert "kept as" not in capsys.readouterr().err
    assert main([*argv, "--seed", "1"]) == 0
    kept = tmp_path / "nominal.1.csv"
    assert f"flight log: {log} (the log there before is kept as {kept})" in (
        capsys.readouterr().err
    )
    assert (kept.read_bytes(), sidecar_path(kept).read_bytes()) == first
    assert read_flight_log(log).metadata["seed"] == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "nominal.1.csv",
        "nominal.1.csv.json",
        "nominal.csv",
        "nominal.csv.json",
    ]


def test_a_flight_refused_before_take_off_leaves_the_earlier_log_in_place(tmp_path) -> None:
    mission = tmp_path / "long.toml"  # more flight than its battery holds: refused, no row
    mission.write_text(
        LINE.read_text().replace("altitude_m = 2.5", "altitude_m = 2.5\nendurance_s = 5.0")
    )
    log = tmp_path / "nominal.csv"
    log.write_text("an earlier flight\n")
    sidecar_path(log).write_text("{}")
    assert main([str(mission), "--link", "inprocess", "--log", str(log)]) == 2
    assert log.read_text() == "an earlier flight\n" and sidecar_path(log).read_text() == "{}"
    assert sorted(p.name for p in tmp_path.iterdir()) == [
        "long.toml",
        "nominal.csv",
        "nominal.csv.json",
    ]


def test_a_tool_that_owns_its_folder_replaces_its_log(tmp_path) -> None:
    """The demo and the showcase write their folder anew each run: no numbered copies pile up."""
    log = tmp_path / "nominal.csv"
    for seed in (0, 1):
        config = CompanionConfig(LINE, link="inprocess", log_path=log, replace_log=True, seed=seed)
        assert run_companion(config, lambda _: None).outcome.status == "completed"
    assert read_flight_log(log).metadata["seed"] == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["nominal.csv", "nominal.csv.json"]


def test_a_log_at_the_vehicle_config_it_flies_is_refused_not_moved_aside(tmp_path) -> None:
    """--log at an input the flight reads (here --vehicle's TOML) would move that input to a
    numbered name and leave a flight log in its place."""
    vehicle = tmp_path / "quad.toml"
    preset = Path(__file__).resolve().parents[2] / "vehicle_sim" / "presets" / "iris.toml"
    vehicle.write_text(preset.read_text())
    argv = [str(LINE), "--link", "inprocess", "--vehicle", str(vehicle), "--log", str(vehicle)]
    assert main(argv) == 2
    assert vehicle.read_text() == preset.read_text()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["quad.toml"]
