"""The companion arms and takes off only multicopters: given a PX4 ground rover on its link
(another vehicle answering on the port, a wrong --url), it refuses in one line before arming."""

from __future__ import annotations

import pytest

from companion.inprocess_rover_link import InProcessRoverLink
from companion.link import vehicle_kind
from companion.runner import not_a_multicopter
from scripts.companion_cli import main
from tests.companion.test_companion_mission_on_every_link import free_udp_port
from vehicle_sim.rover import RoverSim, rover_preset
from vehicle_sim.rover.mavlink_rover import RoverMavlinkEndpoint


@pytest.mark.parametrize(
    ("mav_type", "kind"),
    [(2, "multirotor"), (13, "multirotor"), (43, "multirotor"), (22, "VTOL"), (1, "fixed wing"),
     (10, "rover"), (11, "boat"), (0, "other"), (6, "other")],
)  # fmt: skip
def test_each_mav_type_names_its_kind(mav_type, kind):
    assert vehicle_kind(mav_type) == kind


def test_a_rover_is_not_a_multicopter_in_process():
    link = InProcessRoverLink(RoverSim(rover_preset("husky_50kg")))
    problem = not_a_multicopter(link)
    assert "is a rover" in problem and "rover-path" in problem


@pytest.mark.parametrize("link", ["pymavlink", "mavsdk"])
def test_the_companion_refuses_a_ground_rover_on_its_mavlink_link_and_never_arms_it(
    tmp_path, capsys, link
):
    port = free_udp_port()
    rover = RoverMavlinkEndpoint(RoverSim(rover_preset("husky_50kg")), port, mode="udpout")
    rover.start()
    try:
        code = main(
            ["missions/line_20m.toml", "--link", link, "--url", f"udpin://127.0.0.1:{port}"]
            + ["--planner", "pd", "--log", str(tmp_path / "flight.csv")]
        )
        armed = rover.sim.armed
    finally:
        rover.close()
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2
    assert err[-1].startswith(f"companion: error: the vehicle on the {link} link is a rover")
    assert not armed
