"""A mission with obstacles is flown without contact by a planner that honours them, or
refused before take-off; never flown through."""

from __future__ import annotations

import json
import tomllib
from pathlib import Path

import numpy as np
import pytest

from companion.app import CompanionConfig, CompanionInputError, run_companion
from companion.inprocess_link import InProcessLink
from companion.runner import RunnerConfig
from flightlog.schema import read_flight_log
from planners.world_file import load_world
from vehicle_sim.world_contact import DEFAULT_VEHICLE_RADIUS_M

REPO = Path(__file__).resolve().parents[2]
FOREST = REPO / "missions" / "forest_short.toml"


@pytest.mark.slow
def test_the_forest_mission_is_flown_around_the_trunks(tmp_path):
    world = load_world(REPO / "missions" / "forest_short_world.toml")
    line = np.linspace([0.0, 0.0, -2.5], [20.0, 18.0, -2.5], 400)
    assert world.clearance_m(line).min() < 0.0, "the straight line must go through a trunk"
    log_path = tmp_path / "forest.csv"
    config = CompanionConfig(
        mission_path=FOREST,
        link="inprocess",
        planner="nmpc_clutter",
        log_path=log_path,
        runner=RunnerConfig(rate_hz=20.0),
    )
    result = run_companion(config, lambda _m: None)
    assert result.outcome.status == "completed", result.outcome.detail
    sidecar = json.loads(Path(str(log_path) + ".json").read_text())
    assert sidecar["contacts"] == 0
    log = read_flight_log(log_path)
    flown = np.column_stack([log["pos_n_m"], log["pos_e_m"], log["pos_d_m"]])
    assert world.clearance_m(flown).min() > DEFAULT_VEHICLE_RADIUS_M
    assert np.hypot(*(flown[-1, :2] - [20.0, 18.0])) < 0.6


@pytest.mark.parametrize(
    ("planner", "link", "message"),
    [
        ("pd", "inprocess", "planner 'pd' ignores obstacles and would fly through them"),
        ("nmpc", "inprocess", "planner 'nmpc' ignores obstacles"),
        ("nmpc_clutter", "mavsdk", "brings no range scans"),
    ],
)
def test_a_mission_whose_obstacles_cannot_be_honoured_is_refused(tmp_path, planner, link, message):
    log = tmp_path / "f.csv"
    config = CompanionConfig(mission_path=FOREST, link=link, planner=planner, log_path=log)
    with pytest.raises(CompanionInputError, match=message) as info:
        run_companion(config, lambda _m: None)
    assert "\n" not in str(info.value) and not log.exists()


def test_a_bad_world_file_is_refused_in_one_line(tmp_path):
    (tmp_path / "w.toml").write_text("[[cylinder]]\nradius_m = 1.0\n")
    mission = tmp_path / "m.toml"
    mission.write_text(FOREST.read_text().replace("forest_short_world.toml", "w.toml"))
    config = CompanionConfig(mission_path=mission, link="inprocess", planner="nmpc_clutter")
    with pytest.raises(CompanionInputError, match="cylinder\\[0\\] needs exactly the keys"):
        run_companion(config, lambda _m: None)


def _ray_to_trunks_m(origin_ne_m: np.ndarray, angles_rad: np.ndarray, world_file: Path):
    """Naive reference: per beam (angle from north towards east), the distance [m] from the
    origin to the nearest trunk surface along the ray (the smaller root of
    |o + t d - c|^2 = r^2 for each cylinder of the TOML file), inf where no ray meets one."""
    cylinders = tomllib.loads(world_file.read_text())["cylinder"]
    out = np.full(angles_rad.shape, np.inf)
    for k, angle in enumerate(angles_rad):
        d = np.array([np.cos(angle), np.sin(angle)])
        for cyl in cylinders:
            rel = origin_ne_m - np.asarray(cyl["center_ne_m"])
            b, c = rel @ d, rel @ rel - cyl["radius_m"] ** 2
            if b * b - c >= 0.0 and -b - np.sqrt(b * b - c) > 0.0:
                out[k] = min(out[k], -b - np.sqrt(b * b - c))
    return out


def test_range_scans_reach_the_companion_through_the_link_at_the_sensor_rate(tmp_path):
    # trunks drawn round the start, some within the sensor's range, in a world file
    rng = np.random.default_rng(11)
    bearings, ranges = rng.uniform(0.0, 2 * np.pi, 6), rng.uniform(1.5, 8.0, 6)
    world_file = tmp_path / "trunks.toml"
    world_file.write_text(
        'name = "drawn"\n'
        + "".join(
            f"[[cylinder]]\ncenter_ne_m = [{float(r * np.cos(b))!r}, {float(r * np.sin(b))!r}]\n"
            f"radius_m = {float(rng.uniform(0.15, 0.5))!r}\n"
            for b, r in zip(bearings, ranges, strict=True)
        )
    )
    link = InProcessLink.from_vehicle("iris", 0, load_world(world_file))
    first = link.read_state().obstacle_distances
    assert first is not None and first.angles_rad.shape == (72,)
    # the distances are the world's: each beam against a ray-circle reference from the file
    expected = _ray_to_trunks_m(first.origin_ned_m[:2], first.angles_rad, world_file)
    expected[expected > first.max_range_m] = np.inf
    assert np.isfinite(expected).sum() >= 3, "the start must see some trunks for this test"
    np.testing.assert_allclose(first.distances_m, expected, atol=0.02)
    assert link.read_state().obstacle_distances is first  # no new scan within 0.1 s
    link.clock.sleep_until(0.1)
    assert link.read_state().obstacle_distances.t_s == pytest.approx(0.1)
    assert InProcessLink.from_vehicle("iris", 0).read_state().obstacle_distances is None
