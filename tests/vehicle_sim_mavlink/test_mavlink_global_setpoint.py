"""SET_POSITION_TARGET_GLOBAL_INT through the dispatcher flies to the point around home
(real simulator in process, simulated time; no sockets)."""

from __future__ import annotations

import numpy as np
from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim import FlightMode, Simulator, load_sim_config
from vehicle_sim.mavlink.dispatcher import Dispatcher
from vehicle_sim.mavlink.scheduler import RateScheduler
from vehicle_sim.mavlink.stats import StatsCounter
from vehicle_sim.mavlink.telemetry import DEFAULT_RATES_HZ, TelemetryContext

POSITION_AND_YAW = 0b100111111000
FACTORY = mavlink2.MAVLink(None, srcSystem=255, srcComponent=190)


def global_setpoint(telemetry: TelemetryContext, target_ned_m, frame: int):
    lat, lon, alt_amsl = telemetry.origin.to_global(target_ned_m)
    alt = alt_amsl - telemetry.origin.alt_amsl_m if frame == 6 else alt_amsl
    return FACTORY.set_position_target_global_int_encode(
        0, 1, 1, frame, POSITION_AND_YAW, round(lat * 1e7), round(lon * 1e7), alt,
        0, 0, 0, 0, 0, 0, 0.0, 0.0,
    )  # fmt: skip


def test_global_int_position_setpoint_is_flown_in_offboard():
    sim = Simulator(load_sim_config("iris"), seed=3)
    telemetry, stats = TelemetryContext(), StatsCounter()
    dispatcher = Dispatcher(sim, telemetry, stats)
    scheduler = RateScheduler(DEFAULT_RATES_HZ)
    target_ned_m = (6.0, -4.0, -5.0)
    for frame in (6, 5):  # relative altitude, then AMSL: the same point
        msg = global_setpoint(telemetry, target_ned_m, frame)
        msg.pack(FACTORY)  # as received: header fields set
        assert dispatcher.handle(msg, scheduler, 0) == []
    assert sim.set_mode(FlightMode.OFFBOARD).accepted and sim.arm().accepted
    for _ in range(300):  # 15 s at a 20 Hz stream
        dispatcher.handle(global_setpoint(telemetry, target_ned_m, 6), scheduler, 0)
        sim.step(0.05)
    assert np.allclose(sim.state.pos_ned_m, target_ned_m, atol=0.3)
    assert stats.snapshot().setpoints_accepted >= 300


def test_global_int_in_a_terrain_frame_is_refused_with_a_statustext():
    sim = Simulator(load_sim_config("iris"), seed=3)
    dispatcher = Dispatcher(sim, TelemetryContext(), StatsCounter())
    msg = global_setpoint(TelemetryContext(), (1.0, 1.0, -3.0), 6)
    msg.coordinate_frame = 11  # GLOBAL_TERRAIN_ALT_INT
    out = dispatcher.handle(msg, RateScheduler(DEFAULT_RATES_HZ), 0)
    assert any(o.notice and "frame 11 unsupported" in o.notice[1] for o in out)
