"""Without --log each flight's log is a new file, as PX4's SD-card logs: a second flight never
writes over the first; an explicit --log is written where it says."""

from __future__ import annotations

from datetime import UTC, datetime
from pathlib import Path

from companion.new_log_path import claim_new_log_path
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


def test_an_explicit_log_is_written_there_and_says_it_replaces_one(tmp_path, capsys) -> None:
    log = tmp_path / "nominal.csv"
    argv = [str(LINE), "--link", "inprocess", "--log", str(log)]
    assert main(argv) == 0 and read_flight_log(log).n_rows > 100
    assert "replaces it" not in capsys.readouterr().err
    assert main(argv) == 0
    assert f"flight log: {log} exists; this flight replaces it" in capsys.readouterr().err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["nominal.csv", "nominal.csv.json"]
