"""Excitation missions: parsing, setpoints, and that the shipped missions fly."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from diagnosis.excitation import ExcitationError, load_schedule, schedule_from_mapping

MISSIONS = sorted((Path(__file__).resolve().parents[2] / "missions").glob("excite_*.toml"))


def test_velocity_segment_points_along_heading_and_climbs_up():
    s = schedule_from_mapping(
        {
            "segment": [
                {
                    "kind": "velocity",
                    "duration_s": 2.0,
                    "speed_mps": 4.0,
                    "heading_deg": 90.0,
                    "climb_mps": 1.0,
                    "yaw_rate_degps": 30.0,
                },
            ]
        }
    )
    (vn, ve, vd), yaw_rate = s.setpoint(1.0, alt_m=2.0)
    assert vn == pytest.approx(0.0, abs=1e-12) and ve == pytest.approx(4.0)
    assert vd == -1.0 and yaw_rate == pytest.approx(math.radians(30.0))


def test_altitude_segment_steers_towards_its_altitude_with_a_speed_limit():
    """P control at 1 /s towards the segment's altitude (drawn), down positive, capped at
    0.6 m/s either way; no horizontal motion and no yaw."""
    rng = np.random.default_rng(6)
    target_m = rng.uniform(0.05, 0.3)
    s = schedule_from_mapping(
        {"segment": [{"kind": "altitude", "duration_s": 5.0, "alt_m": target_m}]}
    )
    for error_m in rng.uniform(-0.5, 0.5, 5):  # within the cap: proportional
        (vn, ve, vd), yaw_rate = s.setpoint(1.0, alt_m=target_m + error_m)
        assert vd == pytest.approx(1.0 * error_m) and (vn, ve, yaw_rate) == (0.0, 0.0, 0.0)
    assert s.setpoint(0.0, alt_m=target_m + 10.0)[0][2] == pytest.approx(0.6)
    assert s.setpoint(0.0, alt_m=target_m - 2.0)[0][2] == pytest.approx(-0.6)


def test_segments_follow_each_other_and_the_last_one_holds():
    s = schedule_from_mapping(
        {
            "segment": [
                {"kind": "velocity", "duration_s": 1.0, "speed_mps": 1.0},
                {"kind": "velocity", "duration_s": 1.0, "speed_mps": 2.0},
            ]
        }
    )
    assert [s.setpoint(t, 2.0)[0][0] for t in (0.5, 1.5, 5.0)] == [1.0, 2.0, 2.0]
    assert s.duration_s == 2.0


@pytest.mark.parametrize(
    ("doc", "match"),
    [
        ({}, "no \\[\\[segment\\]\\]"),
        ({"segment": [{"kind": "loop", "duration_s": 1.0}]}, "kind 'loop' unknown"),
        ({"segment": [{"kind": "hover"}]}, "duration_s must be given"),
        ({"segment": [{"kind": "hover", "duration_s": 1.0, "speed": 2}]}, "unknown keys"),
        ({"segment": [{"kind": "altitude", "duration_s": 1.0, "alt_m": -1.0}]}, "alt_m"),
        ({"segment": [{"kind": "hover", "duration_s": "long"}]}, "finite number"),
    ],
)
def test_bad_missions_are_rejected_with_the_key(doc, match):
    with pytest.raises(ExcitationError, match=match):
        schedule_from_mapping(doc)


@pytest.mark.parametrize("path", MISSIONS, ids=lambda p: p.stem)
def test_shipped_missions_load(path):
    s = load_schedule(path)
    assert s.duration_s > 20.0
