"""Rover physics and PX4-like control: straight line, yaw-rate limit, slip on a patch, skid."""

import math

import pytest

from vehicle_sim.effects import RoverPayload, WheelSlip
from vehicle_sim.effects.base import SimConfigError
from vehicle_sim.rover import RoverSim, Slope, SurfacePatch, make_rover_effect, rover_preset


def test_straight_line_reaches_commanded_speed_and_stays_on_the_x_axis() -> None:
    sim = RoverSim(rover_preset("husky_50kg"))
    sim.arm()
    sim.set_setpoint(0.5, 0.0)
    st = sim.step(10.0)
    assert st.speed_mps == pytest.approx(0.5, abs=0.01)
    assert st.y_m == pytest.approx(0.0, abs=1e-9)
    assert st.heading_rad == pytest.approx(0.0, abs=1e-9)
    assert 4.0 < st.x_m < 5.0  # 10 s at 0.5 m/s minus the spin-up


@pytest.mark.parametrize("mass_ratio", [1.0, 2.0])
def test_a_payload_divides_the_acceleration_limit_by_its_mass_ratio(mass_ratio: float) -> None:
    """The husky's drive accelerates at most 1.0 m/s^2; twice the mass halves that to 0.5
    m/s^2, and a full-speed step from rest reaches the limit."""
    payload = RoverPayload(mass_ratio=mass_ratio)
    sim = RoverSim(rover_preset("husky_50kg"), effects=(payload,))
    sim.arm()
    sim.set_setpoint(1.0, 0.0)
    speeds = [sim.step(0.01).speed_mps for _ in range(200)]
    accel = max(b - a for a, b in zip([0.0, *speeds], speeds, strict=False)) / 0.01
    assert accel == pytest.approx(1.0 / mass_ratio, rel=1e-6)


def test_turn_command_above_the_limit_turns_at_the_yaw_rate_limit() -> None:
    preset = rover_preset("husky_50kg")
    sim = RoverSim(preset)
    sim.arm()
    sim.set_setpoint(0.3, 5.0)  # far above max_yaw_rate_radps
    st = sim.step(6.0)
    assert st.yaw_rate_radps == pytest.approx(preset.max_yaw_rate_radps, rel=1e-3)


def test_ackermann_turn_rate_follows_the_bicycle_model() -> None:
    preset = rover_preset("dmrv_600kg")
    sim = RoverSim(preset)
    sim.arm()
    sim.set_setpoint(1.0, 0.2)
    st = sim.step(30.0)
    assert st.yaw_rate_radps == pytest.approx(0.2, abs=0.01)
    assert st.yaw_rate_radps == pytest.approx(
        st.speed_mps * math.tan(st.steer_rad) / preset.wheelbase_m, rel=1e-6
    )


def test_an_ackermann_rover_reversing_turns_the_way_its_yaw_rate_setpoint_says() -> None:
    """Backwards (PX4's forward speed < 0) the same yaw rate needs the wheels the other way:
    delta = atan(L omega / v) with v < 0, so at -0.5 m/s and +0.1 rad/s the steering angle is
    atan(2.0 * 0.1 / -0.5) = -0.381 rad and the heading turns counter-clockwise."""
    preset = rover_preset("dmrv_600kg")
    sim = RoverSim(preset)
    sim.arm()
    sim.set_setpoint(-0.5, 0.1)
    st = sim.step(30.0)
    assert st.speed_mps == pytest.approx(-0.5, abs=0.01)
    assert st.yaw_rate_radps == pytest.approx(0.1, abs=0.005)
    assert st.steer_rad == pytest.approx(math.atan(2.0 * 0.1 / -0.5), abs=0.02)


@pytest.mark.parametrize("speed_mps", [0.3, 0.6])
def test_sideways_slip_on_a_patch_matches_the_hand_calculation(speed_mps: float) -> None:
    # Straight through a 2 m wide patch with full traction: ruts that slip the robot 0.2 m per
    # metre driven leave it 2 m * 0.2 = 0.4 m to the left, however fast it drives.
    patch = SurfacePatch(centre_m=(10.0, 0.0), radius_m=1.0, traction=1.0, yaw_efficiency=1.0,
                         lat_slip=0.2)  # fmt: skip
    sim = RoverSim(rover_preset("husky_50kg"), effects=(patch,))
    sim.arm()
    sim.set_setpoint(speed_mps, 0.0)
    sim.step(16.0 / speed_mps)
    assert sim.state.x_m > 15.0
    assert sim.state.y_m == pytest.approx(0.4, abs=0.02)


@pytest.mark.parametrize("speed_mps", [0.35, 1.2])
def test_a_side_slope_slips_the_robot_at_an_angle_not_a_rate(speed_mps: float) -> None:
    # Across a side grade of 0.25 (14 deg) with side_slip_per_grade 0.4, tan(beta) = 0.1: the
    # robot slides downhill (-y) at 0.1 m per metre driven at any speed, so crossing the 4 m
    # wide disc on its diameter costs 0.4 m, and the sideways speed is a tenth of the forward.
    slope = Slope(centre_m=(10.0, 0.0), radius_m=2.0, grade=(0.0, 0.25),
                  uphill_loss_per_grade=0.0, side_slip_per_grade=0.4)  # fmt: skip
    sim = RoverSim(rover_preset("roc6_150kg"), effects=(slope,))
    sim.arm()
    sim.set_setpoint(speed_mps, 0.0)
    while sim.state.x_m < 10.0:
        sim.step(0.1)
    assert sim.state.lat_speed_mps == pytest.approx(-0.1 * sim.state.speed_mps, rel=1e-3)
    sim.step(20.0 / speed_mps)
    assert sim.state.y_m == pytest.approx(-0.4, abs=0.02)


def test_an_ackermann_robot_steers_no_further_than_its_limit() -> None:
    """The DMRV steers at most 0.6 rad on a 2 m wheelbase: asked for 1 rad/s at 1 m/s it turns
    at 1 m/s * tan(0.6) / 2 m = 0.342 rad/s, its tightest turn, with the wheels at 0.6 rad."""
    sim = RoverSim(rover_preset("dmrv_600kg"))
    sim.arm()
    sim.set_setpoint(1.0, 1.0)
    st = sim.step(30.0)
    assert st.steer_rad == pytest.approx(0.6, abs=1e-6)
    assert st.yaw_rate_radps == pytest.approx(1.0 * math.tan(0.6) / 2.0, rel=0.01)


def test_an_ackermann_robot_braking_turns_no_faster_than_commanded() -> None:
    """[Ostafew16] eq. 32 inverted, delta = atan(L omega / v), on the speed the wheels still
    have: braking from 1 m/s to a stop with 0.1 rad/s commanded, the DMRV never turns faster
    than 0.1 rad/s (steering for the commanded stop speed would steer as if at the 0.2 m/s
    floor, five times too hard)."""
    sim = RoverSim(rover_preset("dmrv_600kg"))
    sim.arm()
    sim.set_setpoint(1.0, 0.0)
    sim.step(20.0)
    sim.set_setpoint(0.0, 0.1)
    rates = [sim.step(0.01).yaw_rate_radps for _ in range(400)]
    assert 0.0 < max(rates) <= 0.1


def test_terrain_effects_by_hand() -> None:
    """Each effect's formula at hand-picked states.

    Slope (grade 0.2 along +x, uphill loss 0.5 per grade): heading uphill keeps 1 - 0.5 * 0.2
    = 0.9 of the speed, downhill all of it. Surface patch (lat_slip 0.2 along world +y) at
    1 m/s: 0.2 m/s to the left heading along +x, none heading along +y (the slip is straight
    ahead), 0.2 m/s to the right heading along -x. Wheel slip (0.15 per m/s, 0.2 per 1/m,
    curvature |omega| / max(|v|, 0.1) capped at 2 1/m): at 0.5 m/s and 0.5 rad/s (1 1/m) the
    yaw efficiency is 1 - 0.075 - 0.2 = 0.725; at 0.2 m/s and 1 rad/s (5 1/m, capped) it is
    1 - 0.03 - 0.4 = 0.57.
    """
    slope = Slope(centre_m=(0.0, 0.0), radius_m=5.0, grade=(0.2, 0.0), uphill_loss_per_grade=0.5,
                  side_slip_per_grade=0.0)  # fmt: skip
    assert slope.terrain(0.0, 0.0, 0.0, 1.0, 0.0).speed_scale == pytest.approx(0.9)
    assert slope.terrain(0.0, 0.0, math.pi, 1.0, 0.0).speed_scale == pytest.approx(1.0)
    patch = SurfacePatch(centre_m=(0.0, 0.0), radius_m=5.0, traction=1.0, yaw_efficiency=1.0,
                         lat_slip=0.2)  # fmt: skip
    drift = [patch.terrain(0.0, 0.0, h, 1.0, 0.0).lat_drift_mps for h in (0, math.pi / 2, math.pi)]
    assert drift == pytest.approx([0.2, 0.0, -0.2], abs=1e-12)
    slip = WheelSlip(yaw_loss_per_mps=0.15, yaw_loss_per_curv_m=0.2, lat_slip_s=0.0)
    assert slip.terrain(0.0, 0.0, 0.0, 0.5, 0.5).yaw_scale == pytest.approx(0.725)
    assert slip.terrain(0.0, 0.0, 0.0, 0.2, 1.0).yaw_scale == pytest.approx(0.57)


def test_skid_steer_turn_loses_yaw_rate_the_gyro_loop_makes_up() -> None:
    # ROC6 at 1 m/s, 0.5 rad/s (curvature 0.5 1/m): yaw efficiency 1 - (0.2 * 1 + 0.3 * 0.5)
    # = 0.65, outward slide 0.2 s * 1 m/s * 0.5 rad/s = 0.1 m/s. The yaw-rate loop closes on
    # the measured (ground) yaw rate, so its integrator makes the shortfall up (time constant
    # (1 + 0.65 * 0.3) / (0.65 * 0.1) = 18 s; 150 s is 8 of them).
    slip = WheelSlip(yaw_loss_per_mps=0.2, yaw_loss_per_curv_m=0.3, lat_slip_s=0.2)
    sim = RoverSim(rover_preset("roc6_150kg"), effects=(slip,))
    sim.arm()
    sim.set_setpoint(1.0, 0.5)
    st = sim.step(150.0)
    assert st.speed_mps == pytest.approx(1.0, abs=0.01)
    assert st.yaw_rate_radps == pytest.approx(0.5, abs=0.005)
    assert sim.terrain_at(st).yaw_scale == pytest.approx(0.65, abs=0.005)
    assert st.lat_speed_mps == pytest.approx(-0.1, abs=0.002)


def test_traction_loss_on_mud_is_made_up_by_the_speed_loop() -> None:
    patch = SurfacePatch(centre_m=(0.0, 0.0), radius_m=100.0, traction=0.6, yaw_efficiency=1.0)
    sim = RoverSim(rover_preset("husky_50kg"), effects=(patch,))
    sim.arm()
    sim.set_setpoint(0.4, 0.0)
    sim.step(3.0)
    early = sim.state.speed_mps
    sim.step(60.0)
    assert early < 0.4 * 0.95  # the wheels spin faster than the ground moves
    assert sim.state.speed_mps == pytest.approx(0.4, abs=0.02)  # the integrator catches up


def test_bad_effect_parameters_give_one_line_naming_the_key() -> None:
    with pytest.raises(SimConfigError, match="effects.surface_patch.traction"):
        make_rover_effect("surface_patch", {"traction": 3.0})
    with pytest.raises(SimConfigError, match="unknown rover effect"):
        make_rover_effect("lava", {})
