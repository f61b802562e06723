"""`make showcase` end to end: four real in-process flights, a table and a plot."""

from __future__ import annotations

import pytest

from experiments import showcase


@pytest.mark.slow
def test_showcase_flies_every_planner_in_calm_and_wind_and_plots(tmp_path, capsys):
    assert showcase.main(["--out", str(tmp_path)]) == 0
    table = capsys.readouterr().out
    rows = {
        line.split("|")[1].strip(): float(line.split("|")[2])
        for line in table.splitlines()
        if line.startswith("| pd") or line.startswith("| nmpc")
    }
    assert set(rows) == {"pd, calm", "pd, wind", "nmpc, calm", "nmpc, wind"}
    assert rows["nmpc, calm"] < rows["pd, calm"]
    assert rows["pd, wind"] > rows["pd, calm"]
    assert (tmp_path / "square.png").stat().st_size > 10_000
    assert len(list(tmp_path.glob("square_*.csv"))) == 4
