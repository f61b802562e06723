"""Mission files: the shipped ones load, bad ones fail with one line naming the problem."""

from __future__ import annotations

from pathlib import Path

import pytest

from companion.mission import MissionError, load_mission, parse_mission

REPO = Path(__file__).resolve().parents[2]

GOOD = """
name = "t"
altitude_m = 2.0
speed_limit_mps = 1.5
repeats = 2

[reference]
kind = "waypoints"
points_ned_m = [[0.0, 0.0, -2.0], [4.0, 0.0, -2.0]]
"""


def test_shipped_missions_load() -> None:
    line = load_mission(REPO / "missions" / "line_20m.toml")
    assert line.goal_ned_m == (20.0, 0.0, -2.5)
    assert line.altitude_m == 2.5
    square = load_mission(REPO / "missions" / "square.toml")
    assert square.repeats == 2
    assert len(square.points_ned_m) == 10
    assert square.goal_ned_m == (0.0, 0.0, -3.0)
    assert load_mission(REPO / "missions" / "s_curve.toml").reference_kind == "bspline"


def test_repeats_unroll_points_and_defaults_apply() -> None:
    m = parse_mission(GOOD)
    assert m.points_ned_m == ((0.0, 0.0, -2.0), (4.0, 0.0, -2.0)) * 2
    assert m.goal_tolerance_m == 0.3
    assert m.obstacles_world is None
    assert m.reference_kind == "waypoints"


def test_command_limit_defaults_to_the_reference_speed_and_may_give_headroom() -> None:
    assert parse_mission(GOOD).horizontal_command_limit_mps == 1.5
    faster = parse_mission(GOOD.replace("repeats = 2", "command_limit_mps = 2.5"))
    assert faster.speed_limit_mps == 1.5 and faster.horizontal_command_limit_mps == 2.5
    demo = load_mission(REPO / "missions" / "demo_bspline.toml")
    assert demo.horizontal_command_limit_mps > demo.speed_limit_mps


def test_obstacles_world_is_relative_to_the_mission_file(tmp_path: Path) -> None:
    f = tmp_path / "m.toml"
    f.write_text('obstacles_world = "w.toml"\n' + GOOD)
    assert load_mission(f).obstacles_world == tmp_path / "w.toml"


@pytest.mark.parametrize(
    ("text", "match"),
    [
        ("name = ", "not valid TOML"),
        (GOOD.replace("altitude_m = 2.0\n", ""), "missing altitude_m"),
        (GOOD.replace("altitude_m = 2.0", "altitude_m = -1.0"), "altitude_m must be a positive"),
        (GOOD.replace("speed_limit_mps = 1.5", "speed_limit_mps = 'fast'"), "speed_limit_mps"),
        (GOOD.replace('kind = "waypoints"', 'kind = "spiral"'), "choose one of waypoints, bspline"),
        (GOOD.replace("repeats = 2", "repeats = 0"), "repeats must be an integer >= 1"),
        (GOOD.replace("repeats = 2", "speed = 2"), "unknown key speed"),
        (GOOD.replace("repeats = 2", "command_limit_mps = 1.0"), "below speed_limit_mps 1.5"),
        (GOOD.replace("[[0.0, 0.0, -2.0], ", "[[0.0, 0.0], "), r"points_ned_m\[0\]"),
        (GOOD.replace("[4.0, 0.0, -2.0]", "[4.0, 0.0, 1.0]"), "at or below the ground"),
        (GOOD.replace("[[0.0, 0.0, -2.0], ", "["), "at least 2 of them"),
        (GOOD.split("[reference]")[0], r"missing \[reference\]"),
    ],
)
def test_bad_missions_fail_with_one_line(text: str, match: str) -> None:
    with pytest.raises(MissionError, match=match) as info:
        parse_mission(text, source="bad.toml")
    message = str(info.value)
    assert "\n" not in message
    assert message.startswith("bad.toml: ")


def test_missing_file_is_one_line(tmp_path: Path) -> None:
    with pytest.raises(MissionError, match="no such mission file"):
        load_mission(tmp_path / "nope.toml")


def test_a_mission_with_obstacles_is_refused_before_take_off(tmp_path: Path) -> None:
    from companion.app import CompanionConfig, CompanionInputError, run_companion

    f = tmp_path / "m.toml"
    f.write_text('obstacles_world = "w.toml"\n' + GOOD)
    log = tmp_path / "f.csv"
    config = CompanionConfig(mission_path=f, link="inprocess", log_path=log)
    with pytest.raises(CompanionInputError, match="would fly through them") as info:
        run_companion(config, lambda _m: None)
    assert "\n" not in str(info.value) and not log.exists()


def test_an_excitation_schedule_is_named_as_such_not_as_a_bad_mission() -> None:
    schedule = Path(__file__).resolve().parents[2] / "missions" / "excite_full.toml"
    with pytest.raises(MissionError, match="excitation schedule.*not a companion mission") as err:
        load_mission(schedule)
    assert "\n" not in str(err.value)
