"""`diagnose --batch`: one report set per log, the same on a Dask cluster as on local processes."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

from experiments.hidden_effects import draw, fly_hidden
from scripts.diagnose import main


@pytest.mark.slow(expected_s=75)
def test_batch_on_a_dask_cluster_equals_the_local_batch(tmp_path, capsys):
    distributed = pytest.importorskip("distributed")
    rng = np.random.default_rng(5)
    logs = []
    for i in range(2):  # two airframes, each with its own hidden payload; same file name
        truth, _ = draw("payload", rng)
        fly_hidden(truth, tmp_path / f"vehicle{i}", seed=30 + i)
        logs.append(str(tmp_path / f"vehicle{i}" / "flight_0.csv"))
    args = [*logs, "--sim-config", "iris", "--batch"]
    # one local process diagnoses both logs in turn, the cluster's two workers as they come
    assert main([*args, "--out", str(tmp_path / "local"), "--workers", "1"]) == 0
    with distributed.LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    ) as cluster:
        remote = ["--out", str(tmp_path / "dask"), "--scheduler", cluster.scheduler_address]
        assert main([*args, *remote]) == 0
    assert "batch: 2 diagnoses on tcp://" in capsys.readouterr().err
    local = json.loads((tmp_path / "local" / "batch.json").read_text())
    assert [e["report"] for e in local["logs"]] == [
        "000_flight_0/report.json",
        "001_flight_0/report.json",
    ]
    assert all(e["verdict"] == ["payload"] for e in local["logs"])
    assert (tmp_path / "dask" / "batch.json").read_text() == json.dumps(local, indent=2) + "\n"
    for entry in local["logs"]:
        a = (tmp_path / "local" / entry["report"]).read_text()
        assert a == (tmp_path / "dask" / entry["report"]).read_text()
        assert (tmp_path / "dask" / entry["report"]).with_name("extended_config.toml").is_file()


def test_scheduler_without_batch_or_malformed_exits_2(tmp_path, capsys):
    log = tmp_path / "flight_0.csv"
    log.write_text("t_s,pos_n_m\n0,0\n")
    base = [str(log), "--sim-config", "iris", "--out", str(tmp_path / "out")]
    with pytest.raises(SystemExit) as exc:
        main([*base, "--scheduler", "tcp://h:8786"])
    assert exc.value.code == 2 and "add --batch" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exc:
        main([*base, "--batch", "--scheduler", "h:8786"])
    assert exc.value.code == 2 and "tcp://HOST:PORT" in capsys.readouterr().err
    # --workers alone was taken and ignored; beside --scheduler one of them was
    for extra, said in (
        (["--workers", "3"], "--workers runs a --batch diagnosis; add --batch"),
        (["--batch", "--workers", "3", "--scheduler", "tcp://h:8786"], "give one"),
    ):
        with pytest.raises(SystemExit) as exc:
            main([*base, *extra])
        assert exc.value.code == 2 and said in capsys.readouterr().err


def test_batch_summary_names_each_log_by_the_path_given(tmp_path):
    """Two logs of the same file name from two vehicles: batch.json tells which report is
    whose (it gave both as flight_0.csv)."""
    from flightlog.schema import write_flight_log
    from tests.vehicle_sim.sim_flying import hovering, record_offboard
    from vehicle_sim import VelocitySetpoint

    logs = []
    for i in range(2):
        sim = hovering(settle_s=2.0, seed=i)
        log = record_offboard(sim, lambda t: VelocitySetpoint((0.0, 0.0, 0.0)), 8.0, 25.0)
        logs.append(str(write_flight_log(tmp_path / f"vehicle{i}" / "flight_0.csv", log)))
    out = tmp_path / "out"
    assert (
        main([*logs, "--sim-config", "iris", "--batch", "--workers", "1", "--out", str(out)]) == 0
    )
    summary = json.loads((out / "batch.json").read_text())["logs"]
    assert [e["log"] for e in summary] == logs


def test_batch_skips_each_log_it_cannot_diagnose_with_its_reason_and_diagnoses_the_rest(
    tmp_path, capsys
):
    """A folder off an SD card: a MANUAL flight (no velocity command), a log at 8 Hz, one
    recorded on the ground, and one usable offboard flight."""
    from dataclasses import replace

    from flightlog.reader import read_log
    from flightlog.schema import write_flight_log

    fixtures = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
    usable = read_log(fixtures / "quad_offboard_v1_16.ulg")
    grounded = replace(usable, columns={**usable.columns, "pos_d_m": 0.0 * usable["pos_d_m"]})
    logs = [
        str(fixtures / "quad_manual_v1_6.ulg"),
        str(fixtures / "quad_mission_rtl_v1_9_esc.ulg"),
        str(write_flight_log(tmp_path / "grounded.csv", grounded)),
        str(fixtures / "quad_offboard_v1_16.ulg"),
    ]
    out = tmp_path / "out"
    args = [*logs, "--sim-config", "iris", "--batch", "--workers", "1", "--out", str(out)]
    assert main(args) == 0
    err = capsys.readouterr().err
    skips = [line for line in err.splitlines() if line.startswith("diagnose: skipping ")]
    assert [line.split(": ")[1].removeprefix("skipping ") for line in skips] == logs[:3]
    assert all(line.count(log) == 1 for line, log in zip(skips, logs, strict=False))
    assert "no velocity command" in skips[0] and "needs faster signals" in skips[1]
    assert "no airborne rows" in skips[2] and err.count("no airborne rows") == 1  # said once
    # the path once: not "skipping LOG: LOG: ULog lacks ..."
    assert all(line.count(log) == 1 for line, log in zip(skips, logs, strict=False))
    assert "1 report sets in" in err and "3 log(s) skipped (batch.json says why)" in err
    summary = json.loads((out / "batch.json").read_text())["logs"]
    assert [e["log"] for e in summary] == logs
    assert [("skipped" in e) for e in summary] == [True, True, True, False]
    assert not any(e["skipped"].startswith(e["log"]) for e in summary[:3])
    assert (out / summary[3]["report"]).is_file()
    assert main([*logs[:3], *args[4:-1], str(tmp_path / "none")]) == 2
    assert capsys.readouterr().err.splitlines()[-1].startswith("diagnose: none of the 3 logs")
    assert not (tmp_path / "none").exists()


def test_a_flight_too_short_to_hold_out_is_skipped_with_its_reason_not_a_traceback():
    """4 s of a real flight: every airborne row falls in one 4 s training block, so there is no
    held-out row to judge a cause on (the unexplained check stacked an empty list: ValueError,
    a traceback out of diagnose and out of the whole batch)."""
    from dataclasses import replace

    from experiments.batch_diagnose import DiagnosisJob, run_diagnosis_job
    from flightlog.reader import read_log
    from vehicle_sim import load_sim_config

    log = read_log(
        Path(__file__).resolve().parents[1] / "fixtures" / "ulog" / "quad_offboard_v1_16.ulg"
    )
    mid = log.n_rows // 2
    short = replace(log, columns={k: v[mid : mid + 40] for k, v in log.columns.items()})
    outcome = run_diagnosis_job(DiagnosisJob("short", short, load_sim_config("iris")))
    assert outcome.diagnosis is None
    assert outcome.skipped.startswith("too little flight to hold any out: the 40 airborne rows")


def test_a_log_path_that_does_not_exist_is_a_typo_refused_before_any_work(tmp_path, capsys):
    fixtures = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
    logs = [str(fixtures / "quad_offboard_v1_16.ulg"), str(fixtures / "quad_offboard_v1_61.ulg")]
    out = tmp_path / "out"
    args = [*logs, "--sim-config", "iris", "--batch", "--workers", "1", "--out", str(out)]
    assert main(args) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"diagnose: error: no such log: {logs[1]}; check the path"]
    assert not out.exists()


def test_a_damaged_log_in_a_batch_is_said_on_stderr_and_in_the_summary(tmp_path, capsys):
    """A truncated ULog is diagnosed as far as it was read; a batch says so as a single
    diagnosis does (it said it only inside the log's report.md)."""
    fixtures = Path(__file__).resolve().parents[1] / "fixtures" / "ulog"
    whole = (fixtures / "quad_offboard_v1_16.ulg").read_bytes()
    cut = tmp_path / "cut.ulg"
    cut.write_bytes(whole[: int(0.8 * len(whole))])
    logs = [str(fixtures / "quad_offboard_v1_16.ulg"), str(cut)]
    out = tmp_path / "out"
    args = [*logs, "--sim-config", "iris", "--batch", "--workers", "1", "--out", str(out)]
    assert main(args) == 0
    said = [line for line in capsys.readouterr().err.splitlines() if "is truncated" in line]
    assert len(said) == 1 and said[0].startswith(f"diagnose: warning: {cut}: ")
    whole_entry, cut_entry = json.loads((out / "batch.json").read_text())["logs"]
    assert not any("truncated" in w for w in whole_entry["warnings"])
    assert any("is truncated" in w for w in cut_entry["warnings"])
