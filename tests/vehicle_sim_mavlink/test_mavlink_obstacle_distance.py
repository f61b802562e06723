"""vehicle-sim --world: the endpoint streams its range sensor as OBSTACLE_DISTANCE, which the
companion's pymavlink side decodes into the scan the simulator took."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from mavlink_test_client import Client, make_endpoint

from companion.obstacle_distance_wire import obstacle_distances_of
from planners.obstacles import Cylinder, ObstacleWorld
from scripts.vehicle_sim_cli import build_endpoint, main, parse_args

REPO = Path(__file__).resolve().parents[2]


def test_the_endpoint_streams_obstacle_distance_in_a_world():
    ep = make_endpoint(speed=3.0)
    ep.sim.set_world(ObstacleWorld([Cylinder((2.0, 0.0), 0.5)]))
    ep.start()
    client = Client(ep.local_port)
    try:
        client.hello()
        msg = client.recv("OBSTACLE_DISTANCE", 5.0)
        assert msg is not None, "no OBSTACLE_DISTANCE within 5 s"
        scan = obstacle_distances_of(msg, np.zeros(3), 0.0)
        north = int(np.argmin(np.abs(scan.angles_rad)))
        assert abs(scan.distances_m[north] - 1.5) < 0.02  # the trunk 2 m north, radius 0.5
        assert np.isinf(scan.distances_m[36])  # nothing south
    finally:
        client.close()
        ep.stop()


def test_world_flag_loads_the_world_and_a_bad_one_is_one_line(tmp_path, capsys):
    config = parse_args(["--world", str(REPO / "missions" / "forest_short_world.toml")])
    assert build_endpoint(config).sim.world is not None
    bad = tmp_path / "w.toml"
    bad.write_text("[[sphere]]\ncenter_ned_m = [0, 0]\nradius_m = 1\n")
    assert main(["--world", str(bad), "--duration-s", "1"]) == 2
    err = capsys.readouterr().err.strip()
    assert err.count("\n") == 0 and "center_ned_m" in err
