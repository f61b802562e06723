"""The history GP's experience bins keep the local GP at constant size; section 3.4's example;
a short experiment 1 learns (max lateral error lower on trial 4 than on trial 1)."""

import numpy as np
import pytest

from experiments.rover import learner
from experiments.rover.illustrative import run, tracking_rms
from experiments.rover.localisation import LocalisationError, LocalisationErrorConfig
from experiments.rover.scenarios import scenario
from experiments.rover.trial import run_trials


def test_local_gp_uses_a_bounded_number_of_experiences_however_many_trials() -> None:
    rng = np.random.default_rng(3)
    gp = learner.make_history_gp()
    assert gp.config.max_local_points == 11 * 3 * 4
    sizes = []
    for _trial in range(12):
        for vertex in range(60):
            for _ in range(6):  # ~6 control steps per vertex at 0.4 m/s and 10 Hz
                speed = rng.uniform(0.3, 0.6)
                gp.add(vertex, speed, rng.normal(size=8), rng.normal(size=3))
        sizes.append(gp.local_data(30, 0.45)[0].shape[0])
    assert len(gp) == 60 * 2 * 4  # two speed bins (0.25-0.5, 0.5-0.75) of 4 per vertex
    assert set(sizes[4:]) == {11 * 2 * 4}  # full bins: the local GP stops growing
    assert max(sizes) <= gp.config.max_local_points


def test_observed_disturbance_is_zero_for_a_unicycle_move() -> None:
    p0 = np.array([1.0, 2.0, 0.3])
    p1 = p0 + 0.1 * np.array([0.5 * np.cos(0.3), 0.5 * np.sin(0.3), 0.2])
    assert learner.observed_disturbance(p0, p1, 0.5, 0.2, 0.1) == pytest.approx(np.zeros(3))


@pytest.mark.parametrize("heading", [0.0, np.pi / 2])
def test_observed_disturbance_is_in_the_robot_frame_left_positive(heading: float) -> None:
    """Commanded 0.5 m/s straight on, the robot moved in 0.1 s 0.04 m ahead and 0.02 m to
    its left and turned 0.01 rad: it went 0.1 m/s slower than commanded, drifted 0.2 m/s to its
    left and turned at 0.1 rad/s, at heading 0 (left is +y) as at pi/2 (left is -x)."""
    c, s = np.cos(heading), np.sin(heading)
    p0 = np.array([1.0, 2.0, heading])
    p1 = p0 + np.array([0.04 * c - 0.02 * s, 0.04 * s + 0.02 * c, 0.01])
    g = learner.observed_disturbance(p0, p1, 0.5, 0.0, 0.1)
    assert g == pytest.approx([-0.1, 0.2, 0.1])


def test_an_experience_query_holds_the_step_as_it_happened() -> None:
    """a_k = (s, e_L, e_H, v_act_{k-1}, omega_act_{k-1}, v_cmd_k, omega_cmd_k, omega_cmd_{k-1}):
    from consecutive poses 0.05 m apart (3-4-5) and 0.02 rad turned in 0.1 s, the velocity
    state is 0.5 m/s and 0.2 rad/s; the commands go in as given, now then before."""
    a = learner.experience_query(
        3.0, 0.1, -0.05, np.array([0.0, 0.0, 0.0]), np.array([0.03, 0.04, 0.02]),
        0.6, 0.3, -0.2, 0.1,
    )  # fmt: skip
    assert a == pytest.approx([3.0, 0.1, -0.05, 0.5, 0.2, 0.6, 0.3, -0.2])


def test_localisation_white_noise_alone_is_uncorrelated_frame_to_frame() -> None:
    """With no wander (bias_std 0), the error is white noise of std white_std per axis, mean
    0: consecutive draws do not repeat (a constant offset would not be noise)."""
    cfg = LocalisationErrorConfig(bias_std=(0.0, 0.0, 0.0), white_std=(0.01, 0.02, 0.005))
    err = LocalisationError(cfg, 0.1, np.random.default_rng(3))
    e = np.array([err.draw() for _ in range(20000)])
    assert np.std(e, axis=0) == pytest.approx([0.01, 0.02, 0.005], rel=0.05)
    assert np.all(np.abs(np.mean(e, axis=0)) < 0.05 * np.array([0.01, 0.02, 0.005]))
    lag1 = np.mean(e[1:, 0] * e[:-1, 0]) / np.var(e[:, 0])
    assert abs(lag1) < 0.05


def test_a_pass_keeps_its_speed_bins_apart_and_stores_the_mean_of_each() -> None:
    """Steps at one vertex at 0.3 and 0.4 m/s (bin 0.25-0.5 m/s) and at 0.6 m/s (bin 0.5-0.75
    m/s) make two experiences: the first the mean of its two steps (query 1 and 3 -> 2,
    disturbance 0.5 and 0.1 -> 0.3, whichever came last), the second the 0.6 m/s step."""
    gp = learner.make_history_gp()
    one = np.ones(8)
    learner.store_pass(
        gp, [(4, 0.3, one, np.full(3, 0.5)), (4, 0.6, 5 * one, np.full(3, -1.0)),
             (4, 0.4, 3 * one, np.full(3, 0.1))],
    )  # fmt: skip
    stored = {b: (a, g) for _, b, a, g in gp.stored()}
    assert sorted(stored) == [1, 2]
    assert stored[1][0] == pytest.approx(2 * one) and stored[1][1] == pytest.approx([0.3] * 3)
    assert stored[2][0] == pytest.approx(5 * one) and stored[2][1] == pytest.approx([-1.0] * 3)


@pytest.mark.slow
def test_illustrative_example_ranks_feedback_mpc_lbnmpc() -> None:
    rms = {name: tracking_rms(run(name)) for name in ("feedback", "mpc", "lbnmpc")}
    assert rms["lbnmpc"] < 0.6 * rms["mpc"] < 0.6 * rms["feedback"]


@pytest.mark.slow
def test_the_example_figure_names_the_controllers_as_its_title_does() -> None:
    """The legend says feedback, MPC and LB-NMPC, as the title and the paper, not the code's
    "mpc" and "lbnmpc"."""
    import matplotlib.pyplot as plt

    from experiments.rover.illustrative import figure

    fig, _runs = figure()
    plt.close(fig)  # a pyplot figure left open is another test's leak
    labels = [t.get_text() for t in fig.axes[0].get_legend().get_texts()]
    assert [label.split(" (")[0] for label in labels] == [
        "desired z_d", "feedback", "MPC", "LB-NMPC",
    ]  # fmt: skip
    assert "feedback vs MPC vs LB-NMPC" in fig.texts[0].get_text()


def test_local_gp_mean_and_jacobian_match_the_gp_and_finite_differences() -> None:
    rng = np.random.default_rng(5)
    gp = learner.make_history_gp()
    for i in range(40):
        gp.add(i // 4, 0.4, rng.normal(0, 0.5, 8), rng.normal(0, 0.2, 3))
    model = learner.LocalDisturbance(gp, 5, 0.4)
    assert model.n_experiences == gp.local_data(5, 0.4)[0].shape[0] == 40
    q = rng.normal(0, 0.3, 8)
    mean, jac = model.mean_and_jacobian(q)
    assert mean == pytest.approx(gp.predict(5, 0.4, q[None, :])[0][0], abs=1e-9)
    eye = 1e-6 * np.eye(8)
    num = np.array(
        [
            (model.mean_and_jacobian(q + e)[0] - model.mean_and_jacobian(q - e)[0]) / 2e-6
            for e in eye
        ]
    ).T
    assert jac == pytest.approx(num, abs=1e-7)


def test_a_pass_adds_one_experience_per_bin_the_mean_of_its_steps_there() -> None:
    gp = learner.make_history_gp()
    a, g = np.zeros(8), np.zeros(3)
    for trial in range(6):
        experiences = [(7, 0.4, a + trial + d, g + d) for d in (0.1, 0.02, 0.06)]
        experiences.append((8, 0.4, a - trial, g - 1.0))
        learner.store_pass(gp, experiences)
    X, Y = gp.local_data(7, 0.4)
    assert len(gp) == 8  # c_bin passes in each of the two bins, newest kept
    own = X[:, 0] > 0
    assert sorted(X[own, 0]) == pytest.approx([2.06, 3.06, 4.06, 5.06])
    assert Y[own, 0] == pytest.approx(np.full(4, 0.06))
    assert Y[~own, 0] == pytest.approx(np.full(4, -1.0))


@pytest.mark.slow
def test_short_experiment_1_learns_from_past_trials_with_a_bounded_local_gp() -> None:
    records = run_trials(scenario("rover_exp1").with_trials(4))
    assert all(r.completed for r in records)
    assert records[0].n_local.max() == 0  # the first trial has no experience
    assert records[3].max_e_lat_m < records[0].max_e_lat_m
    sizes = [int(r.n_local.max()) for r in records[1:]]
    assert 0 < max(sizes) <= 132


def test_localisation_error_wanders_slowly_with_small_frame_to_frame_noise() -> None:
    cfg = LocalisationErrorConfig(bias_std=(0.01, 0.01, 0.005), bias_tau_s=3.0)
    err = LocalisationError(cfg, 0.1, np.random.default_rng(7))
    e = np.array([err.draw() for _ in range(20000)])
    assert np.std(e[:, 0]) == pytest.approx(0.01, rel=0.15)
    step = np.diff(e[:, 0])  # what a velocity from consecutive fixes sees, x dt
    assert np.std(step) < 0.3 * np.std(e[:, 0])
    with pytest.raises(ValueError, match="bias_tau_s"):
        LocalisationErrorConfig(bias_tau_s=0.0)


def _chains(cfg: LocalisationErrorConfig, seed: int, n: int = 6000) -> np.ndarray:
    """(8, n, 3) errors of independent chains (each starts stationary), 10 Hz."""
    out = []
    for k in range(8):
        err = LocalisationError(cfg, 0.1, np.random.default_rng([seed, k]))
        out.append(np.array([err.draw() for _ in range(n)]))
    return np.stack(out)


@pytest.mark.parametrize("seed", [11, 12])
def test_localisation_wander_has_the_std_and_correlation_time_it_is_given(seed) -> None:
    rng = np.random.default_rng(seed)
    sigma, tau = rng.uniform(0.005, 0.015), rng.uniform(2.0, 4.0)
    e = _chains(LocalisationErrorConfig((sigma, sigma, 0.005), tau, (0.0, 0.0, 0.0)), seed)
    assert np.std(e[:, :, :2]) == pytest.approx(sigma, rel=0.15)
    assert np.std(e[:, 0, :2]) == pytest.approx(sigma, rel=0.4)  # stationary from the start
    x = e[:, :, 0] - e[:, :, 0].mean()
    acf = [np.mean(x[:, lag:] * x[:, : x.shape[1] - lag]) for lag in range(int(12 * tau / 0.1))]
    assert 0.1 * (np.sum(acf) - 0.5 * acf[0]) / acf[0] == pytest.approx(tau, rel=0.25)


@pytest.mark.parametrize("seed", [21, 22])
def test_scenario_localisation_wander_keeps_the_vo_bound_between_nearby_fixes(seed) -> None:
    """[Stenning13]'s "less than 4 cm/m" (quoted by [Ostafew16] 5.1) between fixes d metres
    apart at experiment 1's 0.4 m/s and 10 Hz, d from one frame (4 cm) to 4 m: the wander of the
    scenarios' stand-in (its white per-frame noise left out)."""
    cfg = LocalisationErrorConfig(white_std=(0.0, 0.0, 0.0))
    e = _chains(cfg, seed)
    for lag in (1, 2, 5, 10, 25, 50, 100):
        rel = np.sqrt(np.mean(np.sum((e[:, lag:, :2] - e[:, :-lag, :2]) ** 2, axis=2)))
        assert rel < 0.04 * (0.4 * 0.1 * lag), (lag, rel)


@pytest.mark.slow
def test_illustrative_figure_compares_the_learned_g_with_what_it_learns() -> None:
    """g learns the nominal model's whole miss (the disturbance and the a, b model error), not
    d_k alone: the figure draws that miss beside g, labels both axes, and its legend carries
    each controller's RMS tracking error as the command prints it."""
    import matplotlib.pyplot as plt

    from experiments.rover.illustrative import figure

    fig, runs = figure()
    try:
        states, disturbances = fig.axes
        assert states.get_ylabel() and disturbances.get_ylabel() and disturbances.get_xlabel()
        labels = [line.get_label() for line in disturbances.get_lines()]
        assert any("model error" in label for label in labels), labels
        lb = runs["lbnmpc"]
        # the learned g follows what the nominal model misses (median over the trial, as the
        # steps of z_d make spikes) far better than it follows dt d_k
        miss_err = np.median(np.abs(lb["g"] - lb["resid"]))
        d_err = np.median(np.abs(lb["g"] - 0.1 * lb["d"]))
        assert miss_err < 0.3 * d_err
        legend = [t.get_text() for t in states.get_legend().get_texts()]
        assert any(f"{tracking_rms(runs['lbnmpc']):.3f}" in t for t in legend), legend
    finally:
        plt.close(fig)
