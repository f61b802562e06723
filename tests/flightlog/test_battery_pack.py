"""A logged battery voltage read as a pack: the cell counts it can have, and a voltage that is
no pack at all; `flightlog info` says which, as the diagnosis reads it."""

from __future__ import annotations

import numpy as np

from flightlog.battery_pack import PackReading, cell_counts, counts_in_words
from flightlog.info import describe_log
from flightlog.reader import read_log
from tests.flightlog.ulog_damage import FIXTURES, POSCTL


def test_cell_counts_are_those_a_lithium_pack_reading_so_can_have():
    assert list(cell_counts(14.0, 16.8)) == [4]  # iris' 4S
    assert list(cell_counts(19.8, 26.7)) == [6]  # a 6S of high-voltage cells
    assert list(cell_counts(15.9, 16.8)) == [4, 5]  # a charged pack that says little
    assert list(cell_counts(9.0, 16.8)) == []  # no lithium pack reads both
    assert [counts_in_words(cell_counts(*r)) for r in ((14, 16.8), (15.9, 16.8), (9, 16.8))] == [
        "4",
        "4-5",
        "no whole number of",
    ]


def test_a_reading_leaves_out_the_sags_and_what_was_not_logged():
    volts = np.linspace(16.8, 15.0, 200)
    volts[::40] = 9.0  # a sag under a burst of thrust in one row of forty
    volts[5] = np.nan
    pack = PackReading.of([volts])
    assert pack is not None and pack.least_v > 15.0 and pack.most_v < 16.8
    assert 4 in pack.cells() and pack.is_pack()
    assert PackReading.of([np.full(10, np.nan)]) is None and PackReading.of([]) is None
    assert not PackReading.of([np.linspace(0.13, 0.0, 50)]).is_pack()


def test_info_says_what_the_real_logs_batteries_are():
    lines = {
        name: next(line for line in describe_log(read_log(path)) if line.startswith("battery"))
        for name, path in (
            ("no module", POSCTL),
            ("6S", FIXTURES / "quad_offboard_v1_16.ulg"),
        )
    }
    assert lines["no module"].startswith("battery: median 0.05 V is no pack voltage")
    assert "diagnose cannot examine battery sag" in lines["no module"]
    assert lines["6S"] == "battery: 21.0-22.3 V, a pack of 6-7 cells"
