"""Contact with hand-placed obstacles: a graze and a hit crash the vehicle, a 1 cm miss does
not; the range sensor sees what the geometry says."""

from __future__ import annotations

import copy

import numpy as np
import pytest

from planners.obstacles import Box, Cylinder, ObstacleWorld, Sphere
from tests.vehicle_sim.sim_flying import fly, hovering
from vehicle_sim.world_contact import DEFAULT_VEHICLE_RADIUS_M, RangeSensorSpec

SPEED_MPS = 2.0
PERIOD_S = 0.02


@pytest.fixture(scope="module")
def pass_by():
    """A hovering Iris and the exact path (one row per physics step) it flies north at
    2 m/s for 3 s, without obstacles."""
    start = hovering(settle_s=6.0)
    sim = copy.deepcopy(start)
    sim.set_world(ObstacleWorld([Sphere((500.0, 500.0, -2.5), 0.1)]))  # far: checks on
    path = []
    for _ in range(round(3.0 / PERIOD_S)):
        sim.set_velocity_setpoint(_north())
        for _ in range(round(PERIOD_S / sim.physics_dt_s)):
            sim.step(sim.physics_dt_s)
            path.append(sim.state.pos_ned_m)
    return start, np.array(path)


def _north():
    from vehicle_sim import VelocitySetpoint

    return VelocitySetpoint((SPEED_MPS, 0.0, 0.0))


def _fly_past(start, obstacle) -> object:
    sim = copy.deepcopy(start)
    sim.set_world(ObstacleWorld([obstacle]))
    fly(sim, (SPEED_MPS, 0.0, 0.0), 3.0, period_s=PERIOD_S)
    return sim


def _cylinder_beside(path: np.ndarray, gap_m: float, radius_m: float = 0.3) -> Cylinder:
    """A trunk east of the path whose surface passes ``gap_m`` from the vehicle's surface at
    the closest point of the (obstacle-free) path."""
    k = len(path) // 2
    centre_e = path[k, 1] + DEFAULT_VEHICLE_RADIUS_M + radius_m + gap_m
    # the path wanders by millimetres: move the trunk so its closest approach is exact
    for _ in range(5):
        d = np.hypot(path[:, 0] - path[k, 0], path[:, 1] - centre_e)
        centre_e += DEFAULT_VEHICLE_RADIUS_M + radius_m + gap_m - d.min()
    return Cylinder((float(path[k, 0]), float(centre_e)), radius_m)


def test_a_miss_by_1_cm_is_no_contact(pass_by):
    start, path = pass_by
    sim = _fly_past(start, _cylinder_beside(path, +0.01))
    assert sim.contacts == [] and sim.state.armed
    assert sim.log_row()["crash"] == 0.0


def test_a_graze_by_1_cm_is_a_crash(pass_by):
    start, path = pass_by
    sim = _fly_past(start, _cylinder_beside(path, -0.01))
    assert len(sim.contacts) == 1
    contact = sim.contacts[0]
    # reported when the clearance first drops below the radius, before the deepest point
    assert DEFAULT_VEHICLE_RADIUS_M - 0.011 < contact.clearance_m < DEFAULT_VEHICLE_RADIUS_M
    assert not sim.state.armed
    assert sim.log_row()["crash"] == 1.0
    texts = [text for _severity, text in sim.drain_events()]
    assert any(t.startswith("Crash: contact with an obstacle") for t in texts)


@pytest.mark.parametrize(
    "obstacle",
    [
        Cylinder((4.0, 0.0), 0.2),
        Sphere((4.0, 0.0, -2.5), 0.3),
        Box((4.0, 0.0, -2.5), (0.1, 2.0, 2.0)),
    ],
)
def test_a_hit_at_speed_crashes_once_and_the_vehicle_falls(pass_by, obstacle):
    start, _ = pass_by
    moved = _shift(obstacle, start.state.pos_ned_m)
    sim = _fly_past(start, moved)
    assert len(sim.contacts) == 1, "one crash, not one per step"
    assert sim.contacts[0].speed_mps > 1.5
    front = ObstacleWorld([moved]).clearance_m(np.array(sim.contacts[0].pos_ned_m))[0]
    assert 0.0 < front < DEFAULT_VEHICLE_RADIUS_M
    fly(sim, (0.0, 0.0, 0.0), 2.0)
    assert not sim.state.armed and sim.state.pos_ned_m[2] > -1.0  # motors cut: it fell


def _shift(obstacle, pos):
    n, e = float(pos[0]), float(pos[1])
    if isinstance(obstacle, Cylinder):
        return Cylinder(
            (obstacle.center_ne_m[0] + n, obstacle.center_ne_m[1] + e), obstacle.radius_m
        )
    c = obstacle.center_ned_m
    moved = (c[0] + n, c[1] + e, c[2])
    if isinstance(obstacle, Sphere):
        return Sphere(moved, obstacle.radius_m)
    return Box(moved, obstacle.half_extents_m)


def test_range_scan_matches_the_geometry():
    world = ObstacleWorld([Cylinder((3.0, 0.0), 0.5), Box((0.0, -4.0, -2.0), (1.0, 0.5, 3.0))])
    from vehicle_sim import Simulator, load_sim_config

    sim = Simulator(load_sim_config("iris"))
    sim.set_world(world, range_sensor=RangeSensorSpec(n_sectors=4, max_range_m=5.0))
    scan = sim.range_scan()
    # north: the trunk at 3 - 0.5 m; east: nothing; south: nothing; west: the box at 3.5 m
    np.testing.assert_allclose(scan.distances_m, [2.5, np.inf, np.inf, 3.5])
    np.testing.assert_allclose(scan.hit_points_ned_m()[:, :2], [[2.5, 0.0], [0.0, -3.5]], atol=1e-9)


def test_without_a_world_there_is_no_scan_and_no_crash_column():
    from vehicle_sim import Simulator, load_sim_config

    sim = Simulator(load_sim_config("iris"))
    assert sim.range_scan() is None and "crash" not in sim.log_row()
    with pytest.raises(ValueError, match="vehicle_radius_m"):
        sim.set_world(None, vehicle_radius_m=0.0)


def test_a_truth_log_with_a_world_records_the_crash_column(pass_by):
    from flightlog.schema import FlightLogRecorder

    start, path = pass_by
    sim = _fly_past(start, _cylinder_beside(path, -0.05))
    recorder = FlightLogRecorder(sim.log_metadata())
    recorder.append(sim.log_row())
    assert recorder.to_log()["crash"][0] == 1.0
