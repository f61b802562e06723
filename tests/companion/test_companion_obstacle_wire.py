"""Range scans over MAVLink: the simulator's OBSTACLE_DISTANCE decodes to the same scan, and
the obstacle-aware planner brakes when scans stop coming."""

from __future__ import annotations

import numpy as np
import pytest
from pymavlink.dialects.v20 import common as mavlink2

from companion.clutter_planner import ClutterNmpc
from companion.link import ObstacleDistances
from companion.nmpc_planner import CompanionNmpc, NmpcSettings
from companion.obstacle_distance_wire import obstacle_distances_of
from planners.bspline import BSplineReference
from planners.obstacles import Box, Cylinder, ObstacleWorld
from planners.reference import PlannerState
from vehicle_sim.mavlink.obstacle_distance import obstacle_distance_message
from vehicle_sim.world_contact import RangeSensorSpec, scan_world


def _over_the_wire(msg):
    sender = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    data = msg.pack(sender)
    return mavlink2.MAVLink(None).parse_char(bytearray(data))


def test_a_scan_survives_the_wire_to_the_centimetre():
    world = ObstacleWorld([Cylinder((3.0, 1.0), 0.4), Box((-2.0, -2.0, -2.0), (0.5, 0.5, 3.0))])
    spec = RangeSensorSpec()
    origin = np.array([0.5, 0.2, -2.5])
    scan = scan_world(world, spec, 12.3, origin)
    got = obstacle_distances_of(_over_the_wire(obstacle_distance_message(scan, 0.2)), origin, 7.0)
    np.testing.assert_allclose(got.angles_rad, scan.angles_rad, atol=1e-6)
    seen = np.isfinite(scan.distances_m)
    assert seen.sum() >= 4 and np.array_equal(np.isfinite(got.distances_m), seen)
    np.testing.assert_allclose(got.distances_m[seen], scan.distances_m[seen], atol=0.005)
    assert got.max_range_m == spec.max_range_m and got.t_s == 7.0


def test_unused_sectors_and_body_frame_are_handled():
    factory = mavlink2.MAVLink(None)
    distances = [65535] * 72
    distances[:4] = [150, 501, 10, 300]  # 1.5 m, nothing (> max), below min, 3 m
    msg = factory.obstacle_distance_encode(
        0, 0, distances, 90, 20, 500, 90.0, 0.0, mavlink2.MAV_FRAME_BODY_FRD
    )
    got = obstacle_distances_of(_over_the_wire(msg), np.zeros(3), 0.0, yaw_rad=np.pi / 2)
    np.testing.assert_allclose(got.angles_rad, [np.pi / 2, np.pi, 0.0])
    np.testing.assert_allclose(got.distances_m, [1.5, np.inf, 3.0])


def test_without_fresh_scans_the_planner_brakes():
    nmpc = CompanionNmpc(NmpcSettings(speed_limit_mps=1.5, period_s=0.05, n_obstacles=4))
    planner = ClutterNmpc(nmpc)
    ref = BSplineReference(np.array([[0.0, 0.0, -2.5], [10.0, 0.0, -2.5]]))
    state = PlannerState(np.array([0.0, 0.0, -2.5]), np.zeros(3), 0.0)
    blind = planner.plan(state, ref, 0.0)
    assert not blind.ok and "no range scan (last never)" in blind.reason
    scan = ObstacleDistances(0.0, np.zeros(3), np.zeros(1), np.array([np.inf]), 5.0)
    planner.observe_obstacles(scan)
    assert planner.plan(state, ref, 0.05).ok
    assert planner.plan(state, ref, 0.5).ok  # 0.5 s old: still fresh enough
    stale = planner.plan(state, ref, 0.6)
    assert not stale.ok and "flying blind" in stale.reason
    np.testing.assert_array_equal(stale.command, 0.0)


@pytest.mark.parametrize("n", [0, 73])
def test_the_message_refuses_impossible_sector_counts(n):
    from vehicle_sim.world_contact import RangeScan

    scan = RangeScan(0.0, np.zeros(3), np.zeros(n), np.zeros(n), 5.0)
    with pytest.raises(ValueError, match="1..72 sectors"):
        obstacle_distance_message(scan, 0.2)


@pytest.mark.parametrize(("offset_m", "regenerated"), [(1.8, False), (2.3, True)])
def test_the_planner_regenerates_its_reference_when_the_vehicle_is_far_from_it(
    offset_m, regenerated
):
    nmpc = CompanionNmpc(NmpcSettings(speed_limit_mps=1.5, period_s=0.05, n_obstacles=4))
    planner = ClutterNmpc(nmpc)
    ref = BSplineReference(np.array([[0.0, 0.0, -2.5], [10.0, 0.0, -2.5]]))
    scan = ObstacleDistances(0.0, np.zeros(3), np.zeros(1), np.array([np.inf]), 5.0)
    planner.observe_obstacles(scan)
    planner.plan(PlannerState(np.array([0.0, 0.0, -2.5]), np.zeros(3), 0.0), ref, 0.0)
    aside = np.array([0.0, offset_m, -2.5])  # beside the reference's start, at rest
    planner.plan(PlannerState(aside, np.zeros(3), 0.0), ref, 0.05)
    assert planner.regenerations == int(regenerated)
    start = planner.path.points_ned_m[0]
    np.testing.assert_allclose(start[:2], aside[:2] if regenerated else [0.0, 0.0], atol=1e-6)
    np.testing.assert_allclose(planner.path.points_ned_m[-1], [10.0, 0.0, -2.5], atol=1e-6)
