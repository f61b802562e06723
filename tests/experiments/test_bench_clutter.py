"""`bench --only clutter` on a small forest: two pairs, every planner, the figures by name."""

from __future__ import annotations

import math

import pytest

from experiments.bench import clutter
from experiments.clutter.table3 import Table3Config
from planners.forest import ForestSpec

FIGURES = (
    "clutter_success_fraction",
    "clutter_mean_cycle_ms",
    "clutter_distance_mean_m",
    "clutter_rrtstar_distance_mean_m",
    "clutter_contacts",
)


@pytest.mark.slow
def test_two_pairs_in_a_small_forest(tmp_path):
    config = Table3Config(
        forest=ForestSpec(seed=3, size_ne_m=(30.0, 30.0), density_per_100m2=3.0),
        n_pairs=2,
        training_flights=2,
        rrt_iterations=2000,
        planners=("proposed", "rrtstar", "rrtstar_online", "pd"),
    )
    plot = tmp_path / "forest.png"
    figures = clutter.run(progress=lambda _m: None, config=config, plot_path=plot)
    assert set(FIGURES) <= set(figures)
    assert all(math.isfinite(figures[name]) for name in FIGURES)
    assert figures["clutter_success_fraction"] == 1.0
    assert figures["clutter_contacts"] == 0.0
    assert figures["clutter_learned_model_flown"] == 1.0
    assert figures["clutter_gp_flown"] in (0.0, 1.0)  # 0: the identified lag flies alone
    assert math.isfinite(figures["clutter_rrtstar_online_mean_cycle_ms"])
    # the PD regulator on the straight reference meets a trunk at least once
    assert figures["clutter_pd_contacts"] >= 1.0
    assert plot.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
