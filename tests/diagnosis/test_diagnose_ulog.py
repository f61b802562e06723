"""diagnose on PX4 logs: a real ULog gives the same report as its `flightlog convert` CSV, and
a hidden effect flown in the simulator, logged as PX4 topics with EKF2-like noise, stays
findable through the mapping."""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from diagnosis.diagnosis import diagnose
from diagnosis.excitation import schedule_from_mapping
from diagnosis.fly_schedule import fly_schedule
from flightlog.ulog import flight_log_from_topics
from scripts import diagnose as diagnose_cli
from scripts import flightlog_cli
from vehicle_sim import load_sim_config

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "flightlog"))
from px4_topics import topics_of  # noqa: E402

AUTO = Path(__file__).resolve().parents[1] / "fixtures" / "ulog" / "quad_sitl_v1_15_auto.ulg"
POSCTL = AUTO.parent / "quad_posctl_v1_15.ulg"  # a real vehicle
HOVER = schedule_from_mapping(
    {
        "segment": [
            {"kind": "hover", "duration_s": 10.0},
            {"kind": "velocity", "duration_s": 3.0, "speed_mps": 2.0, "heading_deg": 30.0},
            {"kind": "hover", "duration_s": 7.0},
        ]
    }
)


@pytest.mark.slow
@pytest.mark.parametrize("ulog", [AUTO, POSCTL], ids=["sitl_auto", "real_posctl"])
def test_ulog_and_converted_csv_give_the_same_report(ulog, tmp_path):
    csv = tmp_path / "flight.csv"
    assert flightlog_cli.main(["convert", str(ulog), "--out", str(csv)]) == 0
    for name, log in (("a", ulog), ("b", csv)):
        assert (
            diagnose_cli.main([str(log), "--sim-config", "iris", "--out", str(tmp_path / name)])
            == 0
        )
    a = json.loads((tmp_path / "a" / "report.json").read_text())
    b = json.loads((tmp_path / "b" / "report.json").read_text())
    assert a == b


@pytest.mark.slow
def test_hidden_payload_findable_through_px4_topics_with_noise():
    rng = np.random.default_rng(14)
    mass_ratio = float(rng.uniform(1.1, 1.4))
    config = load_sim_config("iris", {"payload": {"mass_ratio": mass_ratio}})
    flight = fly_schedule(config, HOVER, seed=3)
    topics = topics_of(flight, rng=rng)
    max_thrust_n = 4 * config.vehicle.max_rotor_thrust_n
    topics["vehicle_thrust_setpoint"]["xyz[2]"] = -flight["thrust_n"] / max_thrust_n
    mapped = flight_log_from_topics(topics, "synthetic.ulg", {"MAV_TYPE": 2})
    assert "thrust_n" not in mapped.columns and mapped.has("thrust_norm")
    result = diagnose([mapped], load_sim_config("iris"))
    assert "payload" in result.verdict
    found = next(c for c in result.causes if c.name == "payload")
    assert found.params["mass_ratio"] == pytest.approx(mass_ratio, rel=0.05)


def test_real_auto_flight_is_replayed_in_its_position_controlled_modes_and_judged_honestly():
    """The SITL log flies TAKEOFF, HOLD and RTL only (no OFFBOARD): its commands still drive
    the replay, and a vehicle the iris preset does not match is never 'explained'."""
    from flightlog.reader import read_log

    log = read_log(AUTO)
    d = diagnose([log], load_sim_config("iris"))
    assert np.isfinite(d.baseline.rmse_mps())
    floor = float(d.noise_floor["replay_rmse_mps"])
    assert d.extended.rmse_mps() > 10.0 * floor  # an x500 in SITL is not the iris preset
    assert "unexplained" in d.verdict  # never "none" beside an error this large
    assert d.thrust_sources and "ESC rotor speed not used" in d.thrust_sources[0]


def test_replay_runs_end_at_gaps_left_by_dropped_rows():
    from diagnosis.replay import MAX_ROW_GAP_S, airborne_runs
    from flightlog.schema import FlightLog

    flight = fly_schedule(load_sim_config("iris"), HOVER)
    t = flight["t_s"]
    keep = (t < 8.0) | (t > 8.0 + 2 * MAX_ROW_GAP_S)  # rows dropped as estimator-invalid
    cols = {k: v[keep] for k, v in flight.columns.items() if k != "mode"}
    runs = airborne_runs(FlightLog(cols, {"source": "px4_ulog"}))
    assert len(runs) == 2
    (a0, b0), (a1, b1) = runs
    assert cols["t_s"][b0 - 1] < 8.0 < cols["t_s"][a1] and b0 == a1


def test_logs_of_two_airframes_diagnosed_together_are_named_in_the_headline():
    """One diagnosis fits one config to every log it is given: pooling two PX4 airframes (4001
    and 4003, two boards) is said in the headline, with the logs and the differing fields."""
    from flightlog.reader import read_log

    offboard = AUTO.parent / "quad_offboard_v1_16.ulg"
    d = diagnose([read_log(POSCTL), read_log(offboard)], load_sim_config("iris"))
    mixed = [w for w in d.warnings if w.startswith("the logs are from different vehicles")]
    assert len(mixed) == 1
    assert f"4001 in {POSCTL}" in mixed[0] and f"4003 in {offboard}" in mixed[0]


def test_every_progress_line_names_diagnose(tmp_path, capsys):
    """Its progress lines were '[   0.1 s] read 1 log(s)', unlike fit-gp's and the demo's
    'fit-gp [   0.1 s] ...': beside other commands' output, nothing said whose they were."""
    assert diagnose_cli.main([str(AUTO), "--sim-config", "iris", "--out", str(tmp_path)]) == 0
    lines = capsys.readouterr().err.splitlines()
    assert lines and all(line.startswith("diagnose") for line in lines), lines[:3]


def test_the_last_line_names_what_was_not_examined_also_beside_a_gain(tmp_path, capsys):
    """The real POSCTL hover spans 1.1 m/s and no setpoint step: 8 of the causes cannot be
    examined. The last line said 'unexplained; gain 1.0x' and nothing of them (it named them
    only when the replay itself was not examined), as did each --batch line."""
    assert diagnose_cli.main([str(POSCTL), "--sim-config", "iris", "--out", str(tmp_path)]) == 0
    err = capsys.readouterr().err.strip().splitlines()
    last = err[-1]
    doc = json.loads((tmp_path / "report.json").read_text())
    not_examined = doc["not_examined"]
    # the report's warnings are said where the command runs too, as fit-gp says its own
    assert doc["warnings"] and all(f"diagnose: warning: {w}" in err for w in doc["warnings"])
    assert "rotor_drag" in not_examined and "command_delay" in not_examined
    assert "gain 1.0x" in last and f"not examined: {', '.join(not_examined)}" in last, last
    verdict = next(line for line in (tmp_path / "report.md").read_text().splitlines()
                   if line.startswith("- **Verdict:"))  # fmt: skip
    assert verdict.startswith("- **Verdict: `unexplained` (not examined: rotor_drag"), verdict


def test_a_large_replay_error_is_warned_of_beside_an_unexplained_force_residual():
    """PX4 SITL's AUTO flight on iris: the force residual stays (unexplained) and the held-out
    replay error stays about 100x the log's noise floor. The replay error was warned of only
    when nothing else had said unexplained, so the report's warnings kept silent about it."""
    from flightlog.reader import read_log

    d = diagnose([read_log(AUTO)], load_sim_config("iris"))
    assert "rms_force_n" in next(c for c in d.causes if c.name == "unexplained").params
    rmse, floor = d.extended.rmse_mps(), d.noise_floor["replay_rmse_mps"]
    assert rmse > 20 * floor
    said = [w for w in d.warnings if w.startswith("held-out replay velocity RMSE")]
    assert len(said) == 1 and f"{rmse:.3f} m/s" in said[0], d.warnings
    assert d.verdict.count("unexplained") == 1


def test_the_rows_the_mapping_left_out_are_said_in_the_headline():
    """PX4 SITL's AUTO flight: 196 of its 311 rows have no valid position estimate or no
    velocity command. The report said nothing of rows left out (a real v1.17 flight lost 40 %
    of them to dead reckoning without a word); a log that lost under a tenth stays quiet."""
    from flightlog.reader import read_log
    from flightlog.ulog import rows_left_out_note

    d = diagnose([read_log(AUTO)], load_sim_config("iris"))
    said = [w for w in d.warnings if "rows used" in w]
    assert said == [
        "quad_sitl_v1_15_auto.ulg: 115 of its 311 rows used; left out: 96 with the estimator's "
        "position or velocity invalid or dead reckoning, 100 without a velocity command"
    ], d.warnings
    assert rows_left_out_note(read_log(POSCTL)) is None  # 71 of 761 rows


@pytest.mark.parametrize("ulog", [POSCTL, AUTO], ids=["real", "sitl"])
def test_no_cause_explains_less_than_nothing_and_unexplained_says_what_is_left(ulog):
    """PX4's position-control flight against iris: ground_effect's 4.808 -> 4.845 N read
    'explained -100 %', and unexplained's evidence said its residual stayed 'after every
    deterministic candidate' beside a row that had removed most of it. (The real flight's
    replay is left unexplained, SITL's force residual.)"""
    from flightlog.reader import read_log

    d = diagnose([read_log(ulog)], load_sim_config("iris"))
    assert all(0.0 <= c.explained_fraction <= 1.0 for c in d.causes), d.causes
    (left,) = [c for c in d.causes if c.name == "unexplained"]
    assert left.explained_fraction == 0.0 and 0.0 < left.confidence <= 1.0
    named = [c.name for c in d.causes if c.name in d.verdict and c.name != "unexplained"]
    assert ("with no" in left.evidence) == (not named), left.evidence
    if "rms_force_n" in left.params:  # the force residual's; else the replay's
        said = f"{100 * left.confidence:.0f} % of the config's held-out squared error is left"
        assert said in left.evidence, left.evidence
    else:
        assert left.confidence == min((d.extended.rmse_mps() / d.baseline.rmse_mps()) ** 2, 1.0)
