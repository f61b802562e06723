"""The replay and the simulator give the same floats as the recorded reference, bit for bit.

A noisy log of a vehicle with effects its config does not know (wind, rotor drag, gusts, a
command delay) is replayed with the plain config and with one carrying a command delay (the
delayed setpoints in flight), through :func:`replay` and :func:`replay_sse`, its thrust tracked
(:func:`track_thrust`, also with extra velocity noise) and its segments flown in closed loop
(:func:`closed_loop`, plain against delayed); a vehicle is flown through takeoff, hold,
OFFBOARD with a command delay, LAND and the disarm after it, and another through a mission
(takeoff, a speed change, two waypoints, return to launch) in gusts. The reference
(``tests/fixtures/replay_reference.npz``) was recorded with the same code before its per-step
Python was cut down, and the change kept the numbers bit for bit on the machine that recorded
it; the replay's figures were recorded again when its warm-up began to read the integral past
the attitude lag, again when it began to fit the run's start integral by output error
(diagnosis.warm_up), and again when windows began to be scored after their nuisance
(diagnosis.window_nuisance), and the mission's flight when LAND took PX4's descent
profile (MPC_Z_V_AUTO_DN above MPC_LAND_ALT1, MPC_LAND_SPEED below MPC_LAND_ALT2) and when its
NAV_TAKEOFF became the take-off (at MPC_TKO_SPEED up to the item's 4 m, where it had climbed
to MIS_TAKEOFF_ALT's 2.5 m first), the rest unchanged. The test allows a relative 1e-7
(RTOL): NumPy picks its vectorised maths by the CPU's features, so another machine differs in
the last bits (measured on a second machine: the noisy log's velocities by 3e-14 relative),
and the replay's output-error fit of the start integral carries that to its tolerance's scale
(the simulated velocities by up to 1e-9 m/s, the SSE by 1.5e-9 relative, over the 1e-9 this
test first allowed); no change of behaviour hides below 1e-7. Record it again only for an
intended change of the numbers:
``np.savez(REFERENCE, **computed())``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from diagnosis.closed_loop import closed_loop
from diagnosis.replay import replay, replay_sse, windows
from diagnosis.thrust_response import track_thrust
from flightlog.schema import FlightLog
from tests.vehicle_sim.sim_flying import record_offboard
from vehicle_sim import FlightMode, Simulator, VelocitySetpoint, load_sim_config
from vehicle_sim.mission_plan import (
    DO_CHANGE_SPEED,
    NAV_RETURN_TO_LAUNCH,
    NAV_TAKEOFF,
    NAV_WAYPOINT,
    MissionItem,
)
from vehicle_sim.sensor_noise import add_sensor_noise, draw_sensor_noise

REFERENCE = Path(__file__).resolve().parents[1] / "fixtures" / "replay_reference.npz"
HIDDEN = {
    "wind": {"vel_ned_mps": [1.5, -1.0, 0.0]},
    "rotor_drag": {"k_n_per_mps": [0.35, 0.3, 0.1]},
    "gusts": {"intensity_mps": 0.3},
    "command_delay": {"delay_s": 0.08},
}
RATE_HZ = 25.0
RTOL = 1e-7  # relative; absolute floor RTOL too (for values near 0)


def excited_log(duration_s: float = 14.0) -> FlightLog:
    """A log of an Iris with ``HIDDEN`` effects flying OFFBOARD velocity steps and a sine, with
    a yaw rate, recorded at ``RATE_HZ``."""
    sim = Simulator(load_sim_config("iris", HIDDEN), seed=5)
    sim.arm()
    sim.takeoff(4.0)
    while sim.state.mode is not FlightMode.HOLD:
        sim.step(0.5)
    sim.set_velocity_setpoint(VelocitySetpoint((0.0, 0.0, 0.0)))
    sim.step(0.1)
    sim.set_mode(FlightMode.OFFBOARD)

    def command_at(t: float) -> VelocitySetpoint:
        step = 2.0 if (t // 3.0) % 2 else -1.0
        return VelocitySetpoint((step, 1.2 * np.sin(1.3 * t), 0.4 * np.cos(0.9 * t)), 0.3)

    return record_offboard(sim, command_at, duration_s, RATE_HZ)


def flown_states() -> np.ndarray:
    """(m, 24) time, position, velocity, acceleration, quaternion, rates, thrust, motors, mode
    and armed flag of a vehicle with a command delay, every 0.1 s from takeoff to disarm."""
    sim = Simulator(load_sim_config("iris", {"command_delay": {"delay_s": 0.1}}), seed=2)
    rows = []

    def record(seconds: float, cmd: VelocitySetpoint | None = None) -> None:
        for _ in range(round(seconds / 0.1)):
            if cmd is not None:
                sim.set_velocity_setpoint(cmd)
            s = sim.step(0.1)
            rows.append(
                np.r_[
                    s.t_s,
                    s.pos_ned_m,
                    s.vel_ned_mps,
                    s.acc_ned_mps2,
                    s.q_wxyz,
                    s.rates_frd_radps,
                    s.thrust_n,
                    s.motor_speeds_norm,
                    s.mode.value,
                    float(s.armed),
                ]  # fmt: skip
            )

    sim.arm()
    sim.takeoff(3.0)
    record(6.0)
    record(0.2, VelocitySetpoint((0.0, 0.0, 0.0)))
    sim.set_mode(FlightMode.OFFBOARD)
    record(3.0, VelocitySetpoint((1.5, -0.5, -0.3), 0.2))
    sim.set_mode(FlightMode.LAND)
    record(9.0)
    return np.array(rows)


def flown_mission() -> np.ndarray:
    """(900, 14) time, position, velocity, quaternion, thrust, mode and armed flag every 0.1 s
    of a mission flown in gusts with a command delay, from arming to the disarm after its RTL."""
    effects = {"rotor_drag": {}, "gusts": {"intensity_mps": 0.4}, "command_delay": {}}
    sim = Simulator(load_sim_config("iris", effects), seed=3)
    sim.set_param("RTL_RETURN_ALT", 8.0)
    nan3 = (np.nan, np.nan, np.nan)
    sim.set_mission(
        (
            MissionItem(NAV_TAKEOFF, (np.nan, np.nan, -4.0), (0.0, 0.0, 0.0, 0.0)),
            MissionItem(DO_CHANGE_SPEED, nan3, (1.0, 3.0, -1.0, 0.0)),
            MissionItem(NAV_WAYPOINT, (10.0, 5.0, -5.0), (1.0, 0.5, 0.0, 0.0)),
            MissionItem(NAV_WAYPOINT, (0.0, 12.0, -4.0), (0.0, 0.5, 0.0, 0.0)),
            MissionItem(NAV_RETURN_TO_LAUNCH, nan3, (0.0, 0.0, 0.0, 0.0)),
        )
    )
    sim.arm()
    sim.set_mode(FlightMode.MISSION)
    rows = []
    for _ in range(900):
        s = sim.step(0.1)
        rows.append(
            np.r_[s.t_s, s.pos_ned_m, s.vel_ned_mps, s.q_wxyz, s.thrust_n, s.mode.value, s.armed]
        )
    return np.array(rows)


def computed() -> dict[str, np.ndarray]:
    """The figures compared with the reference, by name."""
    noisy = add_sensor_noise(excited_log(), draw_sensor_noise(np.random.default_rng(3)), 3)
    wins = windows([noisy], window_s=1.5)
    out = {}
    plain = load_sim_config("iris")
    delayed = load_sim_config("iris", {"command_delay": {"delay_s": 0.08}})
    for name, config in (("plain", plain), ("delayed", delayed)):
        result = replay(config, [noisy], wins)
        out[f"{name}_t_s"] = result.t_s
        out[f"{name}_sim_vel_ned_mps"] = result.sim_vel_ned_mps
        out[f"{name}_meas_vel_ned_mps"] = result.meas_vel_ned_mps
        out[f"{name}_sse"] = np.array(replay_sse(config, [noisy], wins, np.inf))
    out["thrust_n"] = track_thrust(plain, [noisy], wins).sim_thrust_n
    extra = np.array([0.05, 0.05, 0.02])
    out["thrust_extra_noise_n"] = track_thrust(delayed, [noisy], wins, extra, 1).sim_thrust_n
    loop = closed_loop(plain, delayed, [noisy], wins)
    out["closed_loop_baseline_vel_ned_mps"] = loop.baseline_vel_ned_mps
    out["closed_loop_extended_vel_ned_mps"] = loop.extended_vel_ned_mps
    out["flown_states"] = flown_states()
    out["flown_mission"] = flown_mission()
    return out


def test_replay_and_simulator_give_the_reference_floats():
    reference = np.load(REFERENCE)
    got = computed()
    assert set(got) == set(reference.files)
    assert len(got["plain_t_s"]) > 200  # windows were flown
    assert got["flown_states"][-1, -1] == 0.0  # the flight ended landed and disarmed
    modes = set(got["flown_mission"][:, -2])
    assert {FlightMode.MISSION.value, FlightMode.RTL.value} <= modes, modes
    assert got["flown_mission"][-1, -1] == 0.0  # ... and so did the mission
    for name, value in got.items():
        ref = reference[name]
        assert value.shape == ref.shape, (name, value.shape, ref.shape)
        np.testing.assert_allclose(value, ref, rtol=RTOL, atol=RTOL, err_msg=name)
