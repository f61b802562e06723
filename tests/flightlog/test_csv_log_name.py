"""A schema-v1 CSV log is never written under a .ulg name: every reader takes a .ulg for a PX4
ULog and would refuse the CSV as a damaged one ('copy the log again from the vehicle'); nor
under a .json one, a sidecar's name, which would move another log's sidecar aside.
(flightlog convert's --out: test_flightlog_cli.)"""

from __future__ import annotations

from pathlib import Path

import pytest

from scripts import companion_cli, vehicle_sim_cli

LINE = Path(__file__).resolve().parents[2] / "missions" / "line_20m.toml"


CLIS = pytest.mark.parametrize(
    ("main", "prog", "argv"),
    [
        (companion_cli.main, "companion", [str(LINE), "--link", "inprocess"]),
        (
            vehicle_sim_cli.main,
            "vehicle-sim",
            ["--duration-s", "0.5", "--offboard-bind-port", "0", "--gcs-bind-port", "0"],
        ),
    ],
    ids=["companion", "vehicle-sim"],
)


@CLIS
def test_a_log_named_ulg_is_refused_in_one_line_before_anything_is_written(
    tmp_path, capsys, main, prog, argv
):
    path = tmp_path / "flight.ulg"
    assert main([*argv, "--log", str(path)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"{prog}: error: --log {path}: a .ulg name for a schema-v1 CSV log, which every "
        "command would then refuse as a damaged ULog; name it .csv"
    ]
    assert list(tmp_path.iterdir()) == []


@CLIS
def test_a_log_named_as_a_sidecar_is_refused_and_that_sidecar_stays(
    tmp_path, capsys, main, prog, argv
):
    sidecar = tmp_path / "earlier.csv.json"
    sidecar.write_text('{"source": "px4_ulog"}')
    assert main([*argv, "--log", str(sidecar)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [
        f"{prog}: error: --log {sidecar}: a .json name for a schema-v1 CSV log, the name of "
        "a log's sidecar (LOG.csv.json); name it .csv"
    ]
    assert list(tmp_path.iterdir()) == [sidecar]
    assert sidecar.read_text() == '{"source": "px4_ulog"}'
