"""`bench`: parts run through the runner, figures come out as JSON or a table, bad parts fail."""

from __future__ import annotations

import json
import math

import pytest

from scripts import bench


def test_quick_sim_part_gives_a_finite_positive_factor_as_json(capsys):
    assert bench.main(["--only", "sim", "--quick", "--json"]) == 0
    figures = json.loads(capsys.readouterr().out)
    assert set(figures) == {"sim_realtime_factor"}
    assert math.isfinite(figures["sim_realtime_factor"]) and figures["sim_realtime_factor"] > 0


def test_table_lists_every_figure():
    table = bench.format_table({"a_ms": 1.5, "b": 2e-7})
    assert table.splitlines()[2:] == ["| `a_ms` | 1.5 |", "| `b` | 2e-07 |"]


def test_unknown_part_is_a_one_line_error(capsys):
    with pytest.raises(SystemExit) as exc:
        bench.main(["--only", "gpu"])
    assert exc.value.code == 2
    assert "unknown part 'gpu'; choose from sim, jsbsim" in capsys.readouterr().err


def test_json_gives_a_figure_not_measured_as_null_not_nan():
    """A part that could not measure a figure (acados not installed) reports NaN; --json must
    stay standard JSON (NaN is not JSON: strict parsers refuse the whole object)."""

    def refuse(constant: str) -> None:
        raise ValueError(f"{constant} is not JSON")

    figures = json.loads(bench.format_json({"a_ms": float("nan"), "b": 2.0}), parse_constant=refuse)
    assert figures == {"a_ms": None, "b": 2.0}
