"""An earlier log moved aside (flightlog.flight_log_files) is never lost: a failure half-way
puts it back beside its sidecar."""

from __future__ import annotations

import os

import pytest

from flightlog import flight_log_files
from flightlog.atomic_output import OutputError
from flightlog.flight_log_files import keep_earlier_log, restore_earlier_log
from flightlog.schema import sidecar_path


def test_a_sidecar_that_cannot_be_moved_leaves_the_earlier_log_where_it_was(
    tmp_path, monkeypatch
) -> None:
    log = tmp_path / "nominal.csv"
    log.write_text("an earlier flight\n")
    sidecar_path(log).write_text("{}")
    replace = os.replace

    def sidecar_refused(src, dst):
        if str(src).endswith(".json"):
            raise PermissionError(13, "Permission denied")
        replace(src, dst)

    monkeypatch.setattr(flight_log_files.os, "replace", sidecar_refused)
    with pytest.raises(OutputError, match=r"nominal\.csv\.json: cannot write there"):
        keep_earlier_log(log)
    assert log.read_text() == "an earlier flight\n" and sidecar_path(log).read_text() == "{}"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["nominal.csv", "nominal.csv.json"]


def test_restoring_a_log_without_a_sidecar_removes_the_refused_sessions_one(tmp_path) -> None:
    log = tmp_path / "onboard.csv"
    log.write_text("an earlier flight\n")
    kept = keep_earlier_log(log)
    assert kept is not None and not log.exists()
    log.write_text("t_s\n")  # the refused session's log, streamed with its sidecar
    sidecar_path(log).write_text('{"complete": false}')
    restore_earlier_log(kept, log)
    assert log.read_text() == "an earlier flight\n"
    assert sorted(p.name for p in tmp_path.iterdir()) == ["onboard.csv"]
