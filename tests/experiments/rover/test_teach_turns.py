"""A scripted teach drive tighter than the rover can steer is said, with the turn it drove."""

from __future__ import annotations

from pathlib import Path

import pytest

from experiments.rover.teach import turns_not_driven
from planners.rover.path import TaughtPath
from scripts.rover_path import main

PATTERN = [(3.0, 0.0), (4.7, 0.67), (2.0, 0.0)]


def test_an_arc_driven_as_asked_is_not_named() -> None:
    assert turns_not_driven(PATTERN, TaughtPath.from_segments(PATTERN)) == []


@pytest.mark.parametrize("driven", [0.3, -0.67, 0.0])
def test_a_wider_or_wrong_way_arc_is_named_with_what_was_driven(driven: float) -> None:
    path = TaughtPath.from_segments([(3.0, 0.0), (4.7, driven), (2.0, 0.0)])
    (line,) = turns_not_driven(PATTERN, path)
    assert line.startswith(f"segment 2 asked for +0.67 1/m and the rover turned {driven:+.2f}")


def test_a_pattern_past_the_taught_path_names_nothing_it_cannot_see() -> None:
    path = TaughtPath.from_segments([(3.0, 0.0)])
    assert turns_not_driven(PATTERN, path) == []


@pytest.mark.parametrize(("vehicle", "warned"), [("dmrv_600kg", True), ("husky_50kg", False)])
def test_teach_warns_when_the_rover_cannot_steer_the_pattern(
    tmp_path: Path, capsys, vehicle: str, warned: bool
) -> None:
    """The 600 kg Ackermann robot steers at most tan(0.6 rad) / 2 m = 0.34 1/m; the pattern's
    0.67 1/m arc is said to be wider in the taught path. The Husky turns it."""
    out = tmp_path / "p.csv"
    drive = ",".join(f"{length:g}:{curvature:g}" for length, curvature in PATTERN)
    argv = ["teach", "--link", "inprocess", "--vehicle", vehicle, "--drive", drive]
    assert main([*argv, "--out", str(out)]) == 0
    err = capsys.readouterr().err
    assert out.exists()
    assert ("warning: segment 2 asked for +0.67 1/m" in err) is warned, err
