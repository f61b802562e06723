"""The built-in preset "f450" describes the same vehicle as JSBSim's F450 model."""

import numpy as np
import pytest

from tests.jsbsim_backend.jsbsim_helpers import HOVER_CMD
from vehicle_sim.config import load_sim_config
from vehicle_sim.jsbsim_backend import JsbsimF450Plant
from vehicle_sim.jsbsim_backend.f450 import ENGINE_INDEX_OF_MOTOR
from vehicle_sim.jsbsim_backend.units import KG_PER_SLUG, M_PER_FT, M_PER_IN


@pytest.fixture(scope="module")
def both():
    plant = JsbsimF450Plant()
    return load_sim_config("f450").vehicle, plant._fdm


def test_mass_and_inertia_match(both):
    spec, fdm = both
    assert spec.mass_kg == pytest.approx(fdm["inertia/mass-slugs"] * KG_PER_SLUG, rel=1e-6)
    jsb_inertia = [fdm[f"inertia/i{a}{a}-slugs_ft2"] * KG_PER_SLUG * M_PER_FT**2 for a in "xyz"]
    np.testing.assert_allclose(spec.inertia_kgm2, jsb_inertia, rtol=1e-4)  # JSBSim rounds units


def test_rotor_positions_and_spins_match_in_our_motor_order(both):
    """JSBSim's structural frame is x aft, y right, z up (inches): FRD = (-x, y, -z) from the CG."""
    spec, fdm = both
    cg_in = np.array([fdm[f"inertia/cg-{a}-in"] for a in "xyz"])
    for motor, engine in enumerate(ENGINE_INDEX_OF_MOTOR):
        struct_in = np.array([fdm[f"propulsion/engine[{engine}]/{a}-position"] for a in "xyz"])
        frd_m = (struct_in - cg_in) * np.array([-1.0, 1.0, -1.0]) * M_PER_IN
        np.testing.assert_allclose(spec.rotor_positions_frd_m[motor], frd_m, atol=1e-6)
        assert spec.rotor_spin[motor] == fdm[f"propulsion/engine[{engine}]/propeller-sense"]


def test_hover_command_matches(both):
    """Our mixer's thrust command u maps to rotor speed sqrt(u); at hover that is JSBSim's."""
    spec, _ = both
    assert np.sqrt(spec.hover_thrust_norm) == pytest.approx(HOVER_CMD, abs=2e-3)
