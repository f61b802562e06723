"""The CasADi export equals the NumPy posterior and has the right Jacobian."""

import casadi as ca
import numpy as np

from gp.casadi_export import BufferedCall, posterior_function


def test_export_equals_numpy_prediction(small_model):
    f = posterior_function(small_model.posterior_)
    assert f.name_in() == ["z"] and f.name_out() == ["mean", "var"]
    X = 2.0 * np.random.default_rng(1).normal(size=(50, 3))
    mean, std = small_model.predict(X)
    out_mean, out_var = f.map(X.shape[0])(X.T)
    np.testing.assert_allclose(np.array(out_mean).T, mean, rtol=0, atol=1e-9)
    np.testing.assert_allclose(np.array(out_var).T, std**2, rtol=0, atol=1e-9)


def test_export_jacobian_matches_finite_differences_of_numpy(small_model):
    f = posterior_function(small_model.posterior_, include_variance=False)
    z = ca.MX.sym("z", 3)
    jac = ca.Function("mean_jacobian", [z], [ca.jacobian(f(z), z)])
    h = 1e-4  # central differences: truncation ~h^2, round-off ~1e-13 / h

    def mean_at(x):
        return small_model.predict(x[None])[0][0]

    for x in 1.5 * np.random.default_rng(2).normal(size=(5, 3)):
        numeric = np.column_stack(
            [(mean_at(x + h * e) - mean_at(x - h * e)) / (2 * h) for e in np.eye(3)]
        )
        np.testing.assert_allclose(np.array(jac(x)), numeric, atol=1e-6)


def test_expanded_sx_function_and_buffered_call_agree(small_model):
    f = posterior_function(small_model.posterior_)
    x = np.array([0.3, -1.2, 0.4])
    mean, std = small_model.predict(x[None])
    np.testing.assert_allclose(np.array(f.expand()(x)[0]).ravel(), mean[0], atol=1e-9)
    call = BufferedCall(f)
    got_mean, got_var = call(x)
    np.testing.assert_allclose(got_mean, mean[0], atol=1e-9)
    np.testing.assert_allclose(got_var, std[0] ** 2, atol=1e-9)


def test_export_plugs_into_the_nmpc_residual_term_with_sx_inputs(small_model):
    from planners.nominal_models import kinematic_4dof
    from planners.residual import ResidualTerm

    term = ResidualTerm.of_velocity(posterior_function(small_model.posterior_), kinematic_4dof())
    x, u = ca.SX.sym("x", 4), ca.SX.sym("u", 4)
    g = ca.Function("g", [x, u], [term(x, u)])
    cmd = np.array([0.5, -0.2, 0.1, 0.0])
    np.testing.assert_allclose(
        np.array(g(np.zeros(4), cmd)).ravel(), small_model.predict(cmd[None, :3])[0][0], atol=1e-9
    )
