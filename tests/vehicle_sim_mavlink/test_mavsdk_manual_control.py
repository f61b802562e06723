"""MAVSDK's manual_control example flow against vehicle-sim, as against PX4 SITL: set a centred
input, arm, take off, set the input again, start position control, then stream stick inputs at
10 Hz (MAVSDK sends one MANUAL_CONTROL per set_manual_control_input). The one input before
arming is lost during the takeoff, and PX4's failsafe (COM_RCL_EXCEPT 0: TAKEOFF is not exempt)
ends the climb in its hold, as it would on PX4; the streamed sticks then take the vehicle into
POSCTL and fly it; altitude control is entered the same way; when the inputs stop, the
manual-control-loss failsafe runs again (NAV_RCL_ACT, here land)."""

from __future__ import annotations

import threading
import time
from collections.abc import Iterator

import pytest
from mavsdk.plugins.manual_control import ManualControl
from mavsdk.plugins.telemetry import FlightMode as MavsdkFlightMode
from test_mavsdk_example_flows import Drone, take_off, wait

from vehicle_sim import FlightMode

pytestmark = pytest.mark.slow

INPUT_RATE_HZ = 10.0


class StickStream:
    """Calls MAVSDK's set_manual_control_input at INPUT_RATE_HZ from a thread until stopped."""

    def __init__(self, manual: ManualControl) -> None:
        self.manual = manual
        self.inputs = (0.0, 0.0, 0.5, 0.0)  # x forward, y right, z throttle, r yaw
        self._running = threading.Event()
        self._running.set()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while self._running.is_set():
            self.manual.set_manual_control_input(*self.inputs)
            time.sleep(1.0 / INPUT_RATE_HZ)

    def stop(self) -> None:
        self._running.clear()
        self._thread.join(2.0)


@pytest.fixture
def drone() -> Iterator[Drone]:
    d = Drone()
    yield d
    d.close()


def test_manual_control_example_flow(drone: Drone) -> None:
    manual = ManualControl(drone.mavsdk.first_autopilot(5.0))
    drone.param.set_param_int("NAV_RCL_ACT", 3)  # land when the sticks stop
    # a stick thread starved on a busy computer must not lose the sticks before the test does
    # (PX4's 0.5 s is five of its 10 Hz inputs; as test_mavlink_manual_control's)
    drone.param.set_param_float("COM_RC_LOSS_T", 2.0)
    manual.set_manual_control_input(0.0, 0.0, 0.5, 0.0)
    take_off(drone)
    sticks = StickStream(manual)
    try:
        manual.start_position_control()
        wait(lambda: drone.state.mode is FlightMode.POSCTL, 5.0, "POSCTL")
        start = drone.state.pos_ned_m.copy()
        sticks.inputs = (1.0, 0.0, 0.5, 0.0)  # full forward (heading north)
        wait(lambda: drone.state.pos_ned_m[0] > start[0] + 8.0, 20.0, "8 m forward")
        sticks.inputs = (0.0, 0.0, 1.0, 0.0)  # full throttle: climb
        wait(lambda: drone.state.pos_ned_m[2] < start[2] - 3.0, 20.0, "3 m climb")
        sticks.inputs = (0.0, 0.0, 0.5, 1.0)  # full yaw right
        wait(lambda: drone.state.rates_frd_radps[2] > 1.5, 10.0, "yawing right")
        sticks.inputs = (0.0, 0.0, 0.5, 0.0)
        manual.start_altitude_control()
        wait(lambda: drone.state.mode is FlightMode.ALTCTL, 5.0, "ALTCTL")
        wait(
            lambda: drone.telemetry.flight_mode() == MavsdkFlightMode.ALTCTL,
            5.0,
            "MAVSDK reporting ALTCTL",
        )
    finally:
        sticks.stop()
    wait(lambda: drone.state.mode is FlightMode.HOLD, 5.0, "the manual-control-loss hold")
    wait(lambda: drone.state.mode is FlightMode.LAND, 10.0, "NAV_RCL_ACT 3: land")
    wait(lambda: not drone.state.armed, 60.0, "landing and disarm")
    assert drone.endpoint.stats.manual_control_accepted > 30  # 10 Hz while the sticks fly
    assert drone.endpoint.stats.handler_errors == 0
