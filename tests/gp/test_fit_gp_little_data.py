"""fit-gp says in one line when a log holds too little flight for the inducing points asked
for, on a short mission flown by the companion on the simulator."""

from __future__ import annotations

import re

from experiments.mission_flights import fly_ordinary_mission
from scripts.fit_gp import main as fit_gp

FAST = ["--mode", "offboard", "--restarts", "1", "--no-plots", "--force"]


def _little_data_lines(capsys) -> list[str]:
    return [line for line in capsys.readouterr().err.splitlines() if "too little" in line]


def test_a_short_log_is_warned_with_the_fix_and_the_fix_quiets_it(tmp_path, capsys):
    """The S-curve mission at 20 Hz: about 17 s in OFFBOARD, 13 s of it for training, under
    the 30 s the default 30 inducing points want; the m the warning names is enough."""
    log = fly_ordinary_mission("s_curve", {}, tmp_path, seed=0).path
    assert fit_gp([str(log), "--out", str(tmp_path / "m30"), *FAST]) == 0
    (line,) = _little_data_lines(capsys)
    found = re.fullmatch(
        r"fit-gp: warning: (\d+\.\d) s of flight in OFFBOARD to train on \(\d+ rows\) for 30 "
        r"inducing points, under 1 s per point: too little to learn the residual from; "
        r"fly/log more, or lower --m \(to (\d+) or fewer\)",
        line,
    )
    assert found, line
    flown_s, most = float(found[1]), int(found[2])
    assert 10.0 < flown_s < 16.0 and most == int(flown_s)
    assert fit_gp([str(log), "--out", str(tmp_path / "fewer"), "--m", str(most), *FAST]) == 0
    assert _little_data_lines(capsys) == []
