"""Typed PARAM_SET fuzz in flight: no client input makes the vehicle apply a wrong parameter.

Hovering in HOLD, a client sends, for every parameter, its current value under every other
MAV_PARAM_TYPE (the classic bug: INT32 bits read as a float gain), and under its own type NaN,
+-inf and values just outside PX4's bounds. Nothing may change, the vehicle must hold within
0.2 m, every refusal is answered with the unchanged PARAM_VALUE, and a valid set still works.
"""

from __future__ import annotations

import math
import time

import numpy as np
import pytest
from mavlink_test_client import MAV_RESULT_ACCEPTED, wait_until
from pymavlink.dialects.v20 import common as mavlink2

from vehicle_sim import FlightMode
from vehicle_sim.mavlink import params
from vehicle_sim.params import PX4_PARAMS

ALL_TYPES = range(mavlink2.MAV_PARAM_TYPE_UINT8, mavlink2.MAV_PARAM_TYPE_REAL64 + 1)
WIRE = {"FLOAT": params.PARAM_TYPE_REAL32, "INT32": params.PARAM_TYPE_INT32}


def hostile_sets(values: dict[str, float]) -> list[tuple[str, float, int]]:
    """(name, wire value, wire type) for every parameter: wrong types, then bad values."""
    sets = []
    for name, spec in PX4_PARAMS.items():
        own = WIRE[spec.type]
        for wire_type in ALL_TYPES:
            if wire_type != own:
                sets.append((name, params.int32_as_float(int(values[name])), wire_type))
                sets.append((name, values[name], wire_type))
        bad = [math.nan, math.inf, -math.inf]
        if math.isfinite(spec.lo):
            bad.append(spec.lo - max(1.0, abs(spec.lo)))
        if math.isfinite(spec.hi):
            bad.append(spec.hi + max(1.0, abs(spec.hi)))
        for value in bad:
            if own == params.PARAM_TYPE_INT32 and math.isfinite(value):
                value = params.int32_as_float(int(value))
            sets.append((name, value, own))
    return sets


@pytest.mark.slow
def test_typed_param_set_fuzz_in_flight_changes_nothing_and_the_vehicle_holds(endpoint, client):
    assert client.command(400, 1).result == MAV_RESULT_ACCEPTED
    assert client.command(22, *[math.nan] * 7).result == MAV_RESULT_ACCEPTED
    wait_until(
        lambda: endpoint.state.mode == FlightMode.HOLD and -endpoint.state.pos_ned_m[2] > 2.3,
        30.0,
        "takeoff",
    )
    wait_until(lambda: np.linalg.norm(endpoint.state.vel_ned_mps) < 0.05, 20.0, "settled hover")
    sim = endpoint.sim
    before = {name: sim.get_param(name) for name in sim.param_names()}
    hover_m = endpoint.state.pos_ned_m.copy()
    worst_m = 0.0
    sets = hostile_sets(before)
    assert len(sets) > 10 * len(PX4_PARAMS)
    replies = 0
    for i, (name, value, wire_type) in enumerate(sets):
        with client.send_lock:
            client.mav.param_set_send(1, 1, name.encode(), value, wire_type)
        if i % 25 == 24:  # pace, and count the unchanged echoes
            reply = client.recv("PARAM_VALUE", 3.0, lambda m, n=name: m.param_id == n)
            replies += reply is not None
            worst_m = max(worst_m, float(np.linalg.norm(endpoint.state.pos_ned_m - hover_m)))
    time.sleep(1.0)
    worst_m = max(worst_m, float(np.linalg.norm(endpoint.state.pos_ned_m - hover_m)))
    after = {name: sim.get_param(name) for name in sim.param_names()}
    changed = {n: (before[n], after[n]) for n in before if before[n] != after[n]}
    assert changed == {}
    assert replies >= len(sets) // 25 - 2
    assert endpoint.state.armed and endpoint.state.mode == FlightMode.HOLD
    assert worst_m < 0.2
    assert endpoint.stats.notices_sent + endpoint.stats.notices_suppressed > 0

    # The right type and a value within PX4's bounds is still applied, and echoed.
    reply = client.set_param("MPC_XY_CRUISE", 4.0)
    assert reply is not None and reply.param_value == pytest.approx(4.0)
    assert sim.get_param("MPC_XY_CRUISE") == pytest.approx(4.0)
    with client.send_lock:
        client.mav.param_set_send(1, 1, b"NAV_DLL_ACT", params.int32_as_float(2), 6)
    echo = client.recv("PARAM_VALUE", 3.0, lambda m: m.param_id == "NAV_DLL_ACT")
    assert echo is not None and params.float_as_int32(echo.param_value) == 2
    assert sim.get_param("NAV_DLL_ACT") == 2.0
