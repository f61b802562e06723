"""The suite's start order (tests/conftest.py): each xdist worker's first block of tests begins
with its share of the slow ones."""

from __future__ import annotations

from tests.conftest import block_sizes, dealt

EXPECTED_S = {"demo": 180.0, "study": 90.0, "bench": 80.0, "batch": 75.0, "cli": 10.0}


def test_block_sizes_are_worksteals_first_split():
    assert block_sizes(10, 3) == [3, 3, 4]
    assert block_sizes(2, 3) == [0, 1, 1]
    assert block_sizes(7, 1) == [7]


def test_slow_tests_are_dealt_longest_first_to_the_least_loaded_block():
    items = ["a", "cli", "b", "batch", "c", "bench", "d", "study", "e", "demo", "f", "g"]
    order = dealt(items, block_sizes(len(items), 3), EXPECTED_S.get)
    assert order == ["demo", "a", "b", "c", "study", "cli", "d", "e", "bench", "batch", "f", "g"]


def test_without_xdist_the_slow_tests_run_first_longest_first():
    items = ["a", "cli", "b", "demo", "study"]
    assert dealt(items, [5], EXPECTED_S.get) == ["demo", "study", "cli", "a", "b"]


def test_slow_tests_beyond_a_blocks_size_go_to_the_next_with_room():
    order = dealt(["demo", "study", "bench", "a"], [1, 1, 2], EXPECTED_S.get)
    assert order == ["demo", "study", "bench", "a"]
