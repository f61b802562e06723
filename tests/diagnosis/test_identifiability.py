"""What the data cannot support is said, not guessed."""

from __future__ import annotations

import numpy as np
import pytest

from diagnosis.diagnosis import diagnose
from diagnosis.excitation import schedule_from_mapping
from diagnosis.fly_schedule import fly_schedule
from diagnosis.force_model import BatteryModel
from diagnosis.identifiability import FLIGHT_FOR, check_identifiability
from diagnosis.replay import windows
from experiments.hidden_effects import draw, fly_hidden
from flightlog.schema import REQUIRED_COLUMNS, FlightLog
from vehicle_sim import load_sim_config

HOVER = schedule_from_mapping({"segment": [{"kind": "hover", "duration_s": 30.0}]})
HOVER_AND_MOVE = schedule_from_mapping(
    {
        "segment": [
            {"kind": "hover", "duration_s": 8.0},
            {"kind": "velocity", "duration_s": 4.0, "speed_mps": 3.0, "heading_deg": 60.0},
            {"kind": "velocity", "duration_s": 4.0, "climb_mps": 1.0},
            {"kind": "hover", "duration_s": 8.0},
        ]
    }
)


def without(log: FlightLog, *names: str) -> FlightLog:
    return FlightLog({k: v for k, v in log.columns.items() if k not in names}, log.metadata)


def test_hover_only_log_cannot_identify_drag_wind_ground_or_command_path():
    log = fly_schedule(load_sim_config("iris"), HOVER)
    missing = {n.name: n for n in check_identifiability([log])}
    expected = {
        "rotor_drag", "body_drag", "isotropic_drag", "wind", "ground_effect", "battery_sag",
        "command_delay", "motor_lag", "thrust_curve", "flight_control",
    }  # fmt: skip
    assert set(missing) == expected
    assert "speed sweeps" in missing["rotor_drag"].flight
    assert "altitude holds" in missing["ground_effect"].flight


@pytest.mark.slow
def test_payload_is_found_in_hover_and_the_rest_is_reported_not_identifiable():
    truth, _ = draw("payload", np.random.default_rng(13))
    log = fly_schedule(load_sim_config("iris", truth), HOVER)
    result = diagnose([log], load_sim_config("iris"))
    assert result.verdict == ("payload",)
    assert result.causes[0].params["mass_ratio"] == pytest.approx(
        truth["payload"]["mass_ratio"], rel=0.02
    )
    listed = {c.name: c for c in result.causes}
    assert listed["ground_effect"].confidence == 0.0
    assert "not identifiable" in listed["ground_effect"].evidence


@pytest.mark.slow
def test_without_thrust_force_causes_are_not_identifiable_but_command_delay_is(tmp_path):
    truth, _ = draw("command_delay", np.random.default_rng(4))
    logs = fly_hidden(truth, tmp_path, seed=4)
    result = diagnose([without(logs[0], "thrust_n")], load_sim_config("iris"))
    assert result.verdict == ("command_delay",)
    assert result.causes[0].params["delay_s"] == pytest.approx(
        truth["command_delay"]["delay_s"], rel=0.1
    )
    evidence = {c.name: c.evidence for c in result.causes}
    assert "no thrust_n column" in evidence["payload"]
    assert result.force is None


def test_sensor_noise_neither_hides_rotor_drag_nor_counts_as_disturbance(tmp_path):
    """White IMU noise of 0.2-0.4 m/s^2 and thrust noise of 1-3 % (levels drawn) on a log of a
    drawn rotor drag: the drag is still named and fitted, and the noise is no disturbance."""
    rng = np.random.default_rng(9)
    truth, _ = draw("rotor_drag", rng)
    acc_std_mps2, thrust_std = rng.uniform(0.2, 0.4), rng.uniform(0.01, 0.03)
    logs = fly_hidden(truth, tmp_path, seed=9)
    cols = dict(logs[0].columns)
    for c in ("acc_n_mps2", "acc_e_mps2", "acc_d_mps2"):
        cols[c] = cols[c] + rng.normal(0.0, acc_std_mps2, len(cols[c]))
    thrust_noise = rng.normal(0.0, thrust_std, len(cols["thrust_n"]))
    cols["thrust_n"] = cols["thrust_n"] * (1.0 + thrust_noise)
    noisy = FlightLog(cols, logs[0].metadata)
    result = diagnose([noisy], load_sim_config("iris"))
    assert result.verdict == ("rotor_drag",), (acc_std_mps2, thrust_std, result.causes[:2])
    k_true = truth["rotor_drag"]["k_n_per_mps"]
    for i, axis in enumerate("xy"):
        fitted = result.causes[0].params[f"k_n_per_mps_{axis}"]
        assert fitted == pytest.approx(k_true[i], rel=0.15), (axis, acc_std_mps2, thrust_std)


@pytest.mark.slow
def test_several_logs_are_diagnosed_together_and_non_offboard_rows_are_not_replayed():
    truth, _ = draw("payload", np.random.default_rng(35))
    config = load_sim_config("iris", truth)
    first = fly_schedule(config, HOVER_AND_MOVE, seed=1)
    second = fly_schedule(config, HOVER_AND_MOVE, seed=2)
    cols = dict(second.columns)
    cols["mode"] = np.where(cols["t_s"] < 5.0, "POSCTL", cols["mode"])
    second = FlightLog(cols, second.metadata)
    result = diagnose([first, second], load_sim_config("iris"))
    assert result.verdict == ("payload",)
    fitted = result.causes[0].params["mass_ratio"]
    assert fitted == pytest.approx(truth["payload"]["mass_ratio"], rel=0.01)
    assert set(np.unique(result.force.segment)) == {0, 1}
    anchors = [w.t_anchor_s for w in windows([first, second]) if w.log_index == 1]
    assert min(anchors) >= 5.0 + 1.0  # OFFBOARD from 5 s, then the lead-in
    assert result.gain >= 3.0


def synthetic(n: int = 100, **cols: np.ndarray) -> FlightLog:
    """A log of ``n`` rows: hovering at 2 m with thrust and a steady battery, except ``cols``."""
    columns = {name: np.zeros(n) for name in REQUIRED_COLUMNS}
    columns.update(t_s=np.arange(n) * 0.05, q_w=np.ones(n), pos_d_m=np.full(n, -2.0))
    columns.update(thrust_n=np.full(n, 15.0), battery_v=np.full(n, 16.0))
    columns.update(cols)
    return FlightLog(columns)


def unidentifiable(logs: list[FlightLog], known: tuple[str, ...] = ()) -> dict[str, object]:
    return {n.name: n for n in check_identifiability(logs, known)}


def test_a_speed_sweep_of_exactly_the_least_span_identifies_drag():
    assert "rotor_drag" not in unidentifiable([synthetic(vel_n_mps=np.linspace(0.0, 3.0, 100))])
    short = unidentifiable([synthetic(vel_n_mps=np.linspace(0.0, 2.0, 100))])
    assert short["rotor_drag"].reason == "horizontal speed spans only 2.0 m/s"


def test_wind_needs_two_crossing_headings_flown_faster_than_a_drift():
    """North at 2 m/s and a 0.5 m/s drift east: one heading. North and east at 2 m/s: two."""
    north = np.r_[np.full(50, 2.0), np.zeros(50)]
    east_drift = np.r_[np.zeros(50), np.full(50, 0.5)]
    one = unidentifiable([synthetic(vel_n_mps=north, vel_e_mps=east_drift)], known=("rotor_drag",))
    assert one["wind"].reason == "flight directions do not cover two crossing headings"
    assert "wind" not in unidentifiable(
        [synthetic(vel_n_mps=north, vel_e_mps=4.0 * east_drift)], known=("rotor_drag",)
    )


def test_sitting_on_the_ground_is_no_altitude_change_near_it():
    """Altitude noise around 0 m while landed (down to -6 cm) is not a hold within two rotor
    radii; holds from 5 to 25 cm are."""
    landed = np.r_[np.zeros(20), np.full(20, 0.06), np.full(60, -2.0)]  # pos_d: alt 0, -6 cm
    assert "ground_effect" in unidentifiable([synthetic(pos_d_m=landed)])
    low = np.r_[-np.linspace(0.05, 0.25, 40), np.full(60, -2.0)]
    assert "ground_effect" not in unidentifiable([synthetic(pos_d_m=low)])


def test_battery_sag_says_whether_the_voltage_is_missing_or_flat():
    no_column = synthetic()
    no_column = FlightLog({k: v for k, v in no_column.columns.items() if k != "battery_v"})
    assert unidentifiable([no_column])["battery_sag"].reason == "no battery_v column"
    flat = unidentifiable([synthetic()])["battery_sag"]
    assert flat.reason == "battery voltage does not change"
    sagging = synthetic(battery_v=np.linspace(16.0, 15.9, 100))
    assert "battery_sag" not in unidentifiable([sagging])


def test_battery_sag_is_not_read_from_a_voltage_that_is_no_pack_or_another_pack():
    """Two real PX4 logs' batteries: a flight controller without a power module (0.0-0.13 V)
    and a 6S pack (20.5-22.7 V) read against a 4S config (14.0-16.8 V). Either would have
    been taken as a discharge (clipped to empty, or to full on every row)."""
    iris = BatteryModel(full_v=16.8, empty_v=14.0)
    none = synthetic(battery_v=np.linspace(0.13, 0.0, 100))
    reason = unidentifiable([none])["battery_sag"]
    assert reason.reason == "battery_v is no pack voltage (median 0.07 V, below one cell's 3.0 V)"
    assert "power module" in reason.flight
    six_s = [synthetic(battery_v=np.linspace(22.7, 20.5, 100))]
    assert "battery_sag" not in unidentifiable(six_s)  # no battery given: not read against one
    other = {n.name: n for n in check_identifiability(six_s, battery=iris)}
    assert other["battery_sag"].reason == (
        "battery_v 20.6-22.6 V is a pack of 6 cells, the config's battery (14.0-16.8 V) one of 4"
    )
    assert "BAT1_N_CELLS" in other["battery_sag"].flight
    # a 4S pack charged to 4.2 V a cell against a config-from-log's 4 x BAT1_V_CHARGED 4.05 V,
    # and a sag to 3.0 V a cell in one row out of fifty: the same pack
    low_full = BatteryModel(full_v=16.2, empty_v=14.4)
    charged = np.linspace(16.8, 16.3, 100)
    charged[::50] = 12.0
    assert "battery_sag" not in {
        n.name for n in check_identifiability([synthetic(battery_v=charged)], (), low_full)
    }
    # a config modelling a pack below one cell reads its own logs
    toy = BatteryModel(full_v=2.0, empty_v=1.5)
    own = [synthetic(battery_v=np.linspace(2.0, 1.8, 100))]
    assert "battery_sag" not in {n.name for n in check_identifiability(own, (), toy)}


def test_a_battery_column_of_nan_is_said_so():
    blank = unidentifiable([synthetic(battery_v=np.full(100, np.nan))])["battery_sag"]
    assert blank.reason == "battery_v holds no finite value"
    some = np.linspace(16.0, 15.9, 100)
    some[::3] = np.nan
    assert "battery_sag" not in unidentifiable([synthetic(battery_v=some)])


def test_setpoint_steps_are_counted_over_every_log():
    """Two logs with two 1 m/s steps each: four steps, the least that identifies the command
    path."""
    steps = np.r_[np.zeros(25), np.ones(25), np.zeros(50)]
    missing = unidentifiable([synthetic(cmd_vel_n_mps=steps), synthetic(cmd_vel_e_mps=steps)])
    assert not {"command_delay", "flight_control"} & set(missing)
    one = unidentifiable([synthetic(cmd_vel_n_mps=steps)])["command_delay"]
    assert one.reason == "only 2 setpoint steps larger than 0.5 m/s"


def test_one_log_without_thrust_leaves_force_causes_unidentifiable():
    thrustless = FlightLog({k: v for k, v in synthetic().columns.items() if k != "thrust_n"})
    missing = unidentifiable([synthetic(), thrustless])
    assert missing["payload"].reason.startswith("no thrust_n column")


def test_a_cause_is_listed_with_the_first_requirement_it_misses():
    """No thrust and no speed span: drag is reported for the thrust, which is checked first."""
    thrustless = FlightLog({k: v for k, v in synthetic().columns.items() if k != "thrust_n"})
    assert unidentifiable([thrustless])["rotor_drag"].reason.startswith("no thrust_n column")


def test_wind_without_identifiable_drag_is_listed_unless_a_drag_is_known():
    """Crossing headings at one speed (2 m/s north, then east): no speed span for drag, so
    wind would carry the drag fit, and both flights are asked for; a configured drag lifts it."""
    north = np.r_[np.full(50, 2.0), np.zeros(50)]
    east = np.r_[np.zeros(50), np.full(50, 2.0)]
    log = synthetic(vel_n_mps=north, vel_e_mps=east)
    wind = unidentifiable([log])["wind"]
    assert wind.reason == "wind acts through drag, which this flight cannot identify"
    assert wind.flight == f"{FLIGHT_FOR['rotor_drag']}; {FLIGHT_FOR['wind']}"
    assert "wind" not in unidentifiable([log], known=("body_drag",))
