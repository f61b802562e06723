"""The forest plot's legend names what the learned rows flew: 'NMPC+GP' only when the GP
flew (bench --only clutter printed clutter_gp_flown 0 beside a legend saying NMPC+GP)."""

from __future__ import annotations

import pytest

from experiments.clutter.plot import legend_labels

LEARNED_ROWS = ("proposed", "gp_no_regeneration", "rrtstar_online", "rrtstar")


@pytest.mark.parametrize(
    ("learned_flown", "gp_flown", "flew"),
    [
        (True, True, "NMPC+GP"),
        (True, False, "NMPC+identified lag"),
        (False, False, "NMPC+kinematic"),
    ],
)
def test_the_learned_rows_say_what_flew(learned_flown, gp_flown, flew):
    labels = legend_labels(learned_flown, gp_flown)
    assert all(flew in labels[kind] for kind in LEARNED_ROWS), labels
    assert "GP" not in labels["nominal"] and "GP" not in labels["no_regeneration"]
    if not gp_flown:
        assert not any("GP" in label for label in labels.values()), labels
