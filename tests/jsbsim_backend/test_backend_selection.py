"""The simulator picks its physics backend by name (or takes a backend object as is)."""

import pytest

from tests.jsbsim_backend.jsbsim_helpers import f450_config
from vehicle_sim.backends import BACKEND_NAMES, make_backend
from vehicle_sim.builtin_plant import BuiltinPlant
from vehicle_sim.jsbsim_backend import JsbsimBackend


@pytest.mark.parametrize(
    ("backend", "cls"), [(None, BuiltinPlant), ("builtin", BuiltinPlant), ("jsbsim", JsbsimBackend)]
)
def test_names_select_the_plant(backend, cls):
    assert type(make_backend(backend, f450_config())) is cls


def test_a_backend_object_is_used_as_is():
    plant = JsbsimBackend(f450_config())
    assert make_backend(plant, f450_config()) is plant


def test_unknown_names_are_refused_with_the_valid_ones():
    assert BACKEND_NAMES == ("builtin", "jsbsim")
    with pytest.raises(ValueError, match="unknown backend 'JSBSim'; choose one of builtin, jsbsim"):
        make_backend("JSBSim", f450_config())
