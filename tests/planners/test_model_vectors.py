import numpy as np
import pytest

from planners.bspline import BSplineReference
from planners.model_vectors import angle_indices, reference_vectors, state_vector
from planners.nominal_models import NominalModel, first_order_lag, kinematic_4dof, unicycle
from planners.reference import PlannerState

STATE = PlannerState(np.array([1.0, 2.0, -3.0]), np.array([0.4, -0.3, 0.1]), 0.5)


@pytest.mark.parametrize(
    "model, expected",
    [
        (kinematic_4dof(), [1.0, 2.0, -3.0, 0.5]),
        (first_order_lag(), [1.0, 2.0, -3.0, 0.4, -0.3, 0.1, 0.5]),
        (unicycle(), [1.0, 2.0, 0.5]),
    ],
)
def test_state_vector_by_names(model, expected):
    np.testing.assert_allclose(state_vector(model, STATE), expected)


def test_reference_vectors_for_unicycle():
    ref = BSplineReference(np.array([[0.0, 0.0, -2.0], [3.0, 4.0, -2.0], [6.0, 0.0, -2.0]]))
    t = np.array([0.5, 2.0])
    x_ref, u_ref = reference_vectors(unicycle(), ref.sample(t))
    smp = ref.sample(t)
    np.testing.assert_allclose(x_ref[:, :2], smp.pos_ned_m[:, :2])
    np.testing.assert_allclose(u_ref[:, 0], np.linalg.norm(smp.vel_ned_mps[:, :2], axis=1))
    assert angle_indices(unicycle()) == [2]


def test_feedforward_input_keeps_a_first_order_lag_on_the_reference():
    """u = v + tau a: the lag model driven by it has the reference's acceleration; the
    kinematic model (no lead) and feedforward off keep u = v."""
    rng = np.random.default_rng(11)
    points = np.column_stack(
        [np.cumsum(rng.uniform(2, 5, 5)), rng.uniform(-3, 3, 5), -3 * np.ones(5)]
    )
    ref = BSplineReference(points, 4.0)
    smp = ref.sample(np.linspace(0.5, ref.duration_s - 0.5, 7))
    tau, tau_d = rng.uniform(0.2, 0.9), rng.uniform(0.2, 0.9)
    model = first_order_lag(tau, tau_d)
    x_ref, u_ref = reference_vectors(model, smp, feedforward=True)
    x_dot = np.array([np.asarray(model.f(x, u)).ravel() for x, u in zip(x_ref, u_ref, strict=True)])
    np.testing.assert_allclose(x_dot[:, 3:6], smp.acc_ned_mps2, atol=1e-12)
    assert np.abs(smp.acc_ned_mps2).max() > 0.1
    _, u_plain = reference_vectors(model, smp)
    np.testing.assert_allclose(u_plain[:, :3], smp.vel_ned_mps)
    _, u_kin = reference_vectors(kinematic_4dof(), smp, feedforward=True)
    np.testing.assert_allclose(u_kin[:, :3], smp.vel_ned_mps)


def test_unknown_element_name_raises():
    base = kinematic_4dof()
    odd = NominalModel(
        "odd",
        ("pos_n_m", "battery_v"),
        base.input_names,
        base.f,
        np.zeros((2, 3)),
        base.velocity_of,
    )
    with pytest.raises(ValueError, match="no mapping for model element 'battery_v'"):
        state_vector(odd, STATE)
