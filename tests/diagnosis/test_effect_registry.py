"""The effect registry is the one home of every effect: for each registered effect the
simulator's jitted physics and the diagnosis' NumPy force model agree on random states and
parameters, its specs carry units and bounds, config validation and the diagnosis search read
the same bounds, and it says what it needs to be identified and what to fly to excite it."""

from __future__ import annotations

from dataclasses import fields

import numpy as np
import pytest

from diagnosis.candidates import FORCE_CAUSES, make_candidate
from diagnosis.command_path import COMMAND_CAUSES, FLIGHT_CONTROL, search_grid, with_cause
from diagnosis.force_model import MODELLED_ROLES, BatteryModel, predicted_residual
from diagnosis.forces import GRAVITY_MPS2, ForceData, rotation_matrices
from diagnosis.identifiability import CHECKS, FLIGHT_FOR
from vehicle_sim import load_sim_config
from vehicle_sim import physics as ph
from vehicle_sim.builtin_plant import BuiltinPlant
from vehicle_sim.effects import (
    EFFECT_CLASSES,
    REGISTRY,
    ROVER_EFFECTS,
    Effect,
    make_effect,
    make_rover_effect,
    parameter_table,
)
from vehicle_sim.effects.base import (
    REQUIREMENTS,
    ROLES,
    SimConfigError,
    effect_as_mapping,
    effect_from_mapping,
)

N_ROWS = 200
MODELLED = [n for n, c in EFFECT_CLASSES.items() if c.ROLE in MODELLED_ROLES]
HOOKS = ("air_velocity_ned", "drag_force_body", "thrust_factor", "mass_ratio_of")


def has_physics(cls: type) -> bool:
    """Whether an effect class overrides any NumPy physics hook of :class:`Effect`."""
    return any(getattr(cls, h) is not getattr(Effect, h) for h in HOOKS)


def draw_params(cls: type, rng: np.random.Generator) -> dict:
    """Parameters drawn uniformly within the specs' valid ranges (wide ranges: within the
    search range, or +-20 where a range spans the world)."""
    out = {}
    for spec in cls.PARAMS:
        lo, hi = (spec.search.lo, spec.search.hi) if spec.search else (spec.lo, spec.hi)
        lo, hi = max(lo, -20.0), min(hi, 20.0)
        v = rng.uniform(lo, hi, spec.size)
        out[spec.name] = float(v[0]) if spec.size == 1 else v.tolist()
    return out


def random_states(rng: np.random.Generator, n: int) -> np.ndarray:
    """(n, N_STATE) states: near the ground or up to 20 m, moving, tilted, rotors spinning,
    battery partly discharged, no gust."""
    x = np.zeros((n, ph.N_STATE))
    x[:, ph.POS : ph.POS + 2] = rng.uniform(-20.0, 20.0, (n, 2))
    x[:, ph.POS + 2] = -np.where(rng.random(n) < 0.5, rng.uniform(0.0, 0.4, n), 20 * rng.random(n))
    x[:, ph.VEL : ph.VEL + 3] = rng.uniform(-8.0, 8.0, (n, 3))
    q = np.column_stack([np.ones(n), rng.uniform(-0.3, 0.3, (n, 3))])
    x[:, ph.QUAT : ph.QUAT + 4] = q / np.linalg.norm(q, axis=1, keepdims=True)
    x[:, ph.RATES : ph.RATES + 3] = rng.uniform(-1.0, 1.0, (n, 3))
    x[:, ph.MOTORS : ph.MOTORS + 4] = rng.uniform(0.3, 0.9, (n, 4))
    x[:, ph.DISCHARGE] = rng.uniform(0.0, 1.0, n)
    return x


def simulated_force_data(effects: dict, rng: np.random.Generator) -> tuple[ForceData, BatteryModel]:
    """The force residual the simulator's own derivatives give on random states, as the
    diagnosis would form it from a log (nominal thrust from the rotor speeds)."""
    config = load_sim_config("iris", effects)
    plant = BuiltinPlant(config)
    v = config.vehicle
    battery = BatteryModel(v.battery_full_v, v.battery_empty_v)
    x = random_states(rng, N_ROWS)
    acc = np.zeros((N_ROWS, 3))
    thrust = np.zeros(N_ROWS)
    dx = np.zeros(ph.N_DYN)
    for i, xi in enumerate(x):
        motors = xi[ph.MOTORS : ph.MOTORS + 4]
        tf = ph.thrust_factor(xi, plant.ep)
        ph.derivatives(xi, motors, plant.pp, plant.rp, plant.spin, plant.ep, np.zeros(3), tf, dx)
        acc[i] = dx[ph.VEL : ph.VEL + 3]
        thrust[i] = plant.pp[ph.P_TMAX] * float(np.sum(motors * motors))
    rot = rotation_matrices(x[:, ph.QUAT : ph.QUAT + 4])
    g = np.array([0.0, 0.0, GRAVITY_MPS2])
    resid = config.mass_kg * (acc - g) + rot[:, :, 2] * thrust[:, None]
    data = ForceData(
        t_s=np.arange(N_ROWS) * 0.05,
        segment=np.zeros(N_ROWS, int),
        vel_ned_mps=x[:, ph.VEL : ph.VEL + 3],
        acc_ned_mps2=acc,
        rot=rot,
        thrust_n=thrust,
        alt_m=-x[:, ph.POS + 2],
        battery_v=v.battery_full_v - x[:, ph.DISCHARGE] * (v.battery_full_v - v.battery_empty_v),
        mass_kg=config.mass_kg,
        resid_ned_n=resid,
        pos_ned_m=x[:, ph.POS : ph.POS + 3],
    )
    return data, battery


@pytest.mark.parametrize("name", MODELLED)
@pytest.mark.parametrize("seed", [0, 1])
def test_simulator_and_diagnosis_physics_agree(name, seed):
    rng = np.random.default_rng(seed)
    cls = EFFECT_CLASSES[name]
    effects = {name: draw_params(cls, rng)}
    for through in cls.ACTS_THROUGH:  # the drags it acts through, at random strengths
        effects[through] = draw_params(EFFECT_CLASSES[through], rng)
    data, battery = simulated_force_data(effects, rng)
    predicted = predicted_residual(effects, data, battery)
    scale = float(np.max(np.abs(data.resid_ned_n)))
    np.testing.assert_allclose(predicted, data.resid_ned_n, rtol=0.0, atol=1e-9 * scale)
    if has_physics(cls):  # and the effect matters, or a wrong model could pass unseen
        without = {k: v for k, v in effects.items() if k != name}
        moved = np.abs(predicted - predicted_residual(without, data, battery)).max()
        assert moved > 1e-3 * scale, name
    else:  # zero-mean random air: nothing to model, the diagnosis reports what it leaves
        assert cls.ROLE == "disturbance", name


def test_every_effect_has_units_bounds_defaults_and_typical_values_in_range():
    rng = np.random.default_rng(5)
    for name, cls in REGISTRY.items():
        assert cls.name == name and cls.PARAMS, name
        assert [s.name for s in cls.PARAMS] == [f.name for f in fields(cls)], name
        default = effect_as_mapping(cls())
        for spec in cls.PARAMS:
            assert spec.unit and spec.doc and spec.lo < spec.hi, (name, spec)
            values = np.atleast_1d(default[spec.name])
            assert len(values) == spec.size, (name, spec.name)
            assert np.all((spec.lo <= values) & (values <= spec.hi)), (name, spec.name)
            if spec.search is not None:
                assert spec.lo <= spec.search.lo < spec.search.hi <= spec.hi, (name, spec.name)
            inner = spec.search or spec  # a typical value lies where the diagnosis searches
            for lo, hi in spec.typical_ranges():
                assert inner.lo <= lo < hi <= inner.hi, (name, spec.name)
        drawn = effect_as_mapping(effect_from_mapping(cls, cls.draw_typical(rng)))
        assert set(drawn) == {s.name for s in cls.PARAMS}, name


@pytest.mark.parametrize("name", FORCE_CAUSES)
def test_force_search_bounds_are_the_specs_and_pass_config_validation(name):
    cand = make_candidate(name, {})
    lower, upper = [], []
    for n in cand.to_effects(cand.x0):  # the effect, and the one it is fitted with
        for spec in EFFECT_CLASSES[n].PARAMS:
            if spec.search is not None:
                k = spec.size if spec.search.free is None else spec.search.free
                lower += [spec.search.lo] * k
                upper += [spec.search.hi] * k
    np.testing.assert_array_equal(cand.lower, lower)
    np.testing.assert_array_equal(cand.upper, upper)
    for theta in (cand.lower, cand.upper):  # the search's corners are valid configs
        for n, params in cand.to_effects(theta).items():
            make_effect(n, params)
    spec = EFFECT_CLASSES[name].PARAMS[0]
    beyond = spec.hi + 1.0
    with pytest.raises(SimConfigError, match=f"effects.{name}.{spec.name}"):
        make_effect(name, {spec.name: beyond if spec.size == 1 else [beyond] * spec.size})


@pytest.mark.parametrize("name", [n for n in COMMAND_CAUSES if n != FLIGHT_CONTROL])
def test_command_search_grid_is_the_specs_and_replays_the_simulators_own_effect(name):
    param, grid = search_grid(name)
    spec = next(s for s in EFFECT_CLASSES[name].PARAMS if s.name == param)
    assert grid[0] == pytest.approx(spec.search.lo) and grid[-1] == pytest.approx(spec.search.hi)
    assert len(grid) == spec.search.grid
    config = with_cause(load_sim_config("iris"), name, float(grid[-1]))
    assert getattr(config.effect(name), param) == pytest.approx(grid[-1])


def test_every_effect_declares_role_needs_and_excitation():
    for name, cls in REGISTRY.items():
        assert cls.ROLE in ROLES, name
        assert cls.NEEDS and set(cls.NEEDS) <= set(REQUIREMENTS), name
        assert len(cls.EXCITE) > 10, name
        assert set(cls.ACTS_THROUGH) <= set(REGISTRY), name
        assert cls.FIT_WITH is None or cls.FIT_WITH in cls.ACTS_THROUGH, name
        if cls.ROLE in ("force", "command"):  # the diagnosis checks what it needs
            assert set(cls.NEEDS) <= set(CHECKS), name
            assert FLIGHT_FOR[name] == cls.EXCITE
    assert set(FORCE_CAUSES) | set(COMMAND_CAUSES) == set(FLIGHT_FOR)


def test_rover_terrain_effects_share_the_registry_and_its_validation():
    assert set(ROVER_EFFECTS) == {"slope", "wheel_slip", "surface_patch", "rover_payload"}
    assert not set(ROVER_EFFECTS) & set(EFFECT_CLASSES)
    for name, cls in ROVER_EFFECTS.items():
        assert REGISTRY[name] is cls and cls.ROLE == "terrain"
        effect = make_rover_effect(name, draw_params(cls, np.random.default_rng(3)))
        out = effect.terrain(0.0, 0.0, 0.3, 0.5, 0.2)
        assert 0.0 < out.speed_scale <= 1.0 and 0.0 < out.yaw_scale <= 1.0
    with pytest.raises(SimConfigError, match="unknown effect"):
        make_effect("slope", {})


def test_parameter_table_lists_every_parameter_with_both_ranges():
    lines = parameter_table().splitlines()
    assert len(lines) == 1 + sum(len(c.PARAMS) for c in REGISTRY.values())
    for name, cls in REGISTRY.items():
        for spec in cls.PARAMS:
            row = next(r.split() for r in lines if r.split()[:2] == [name, spec.name])
            search = "-" if spec.search is None else f"{spec.search.lo:g}..{spec.search.hi:g}"
            assert row[-2:] == [f"{spec.lo:g}..{spec.hi:g}", search], row
