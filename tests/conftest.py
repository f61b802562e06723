"""Suite-wide ordering: every xdist worker starts on its share of the slow end-to-end tests.

``make test`` runs ``pytest -n 4 --dist worksteal``: xdist hands each worker one contiguous
block of the collected order (an equal share each), and a worker that runs out of tests takes
the back half of the longest queue left. Put first in one list, every slow test fell in the
first block: one worker flew them one after the other while the others ran the short tests,
then stole the back of its queue, and the run ended when its last minutes-long test did. So
the slow tests are dealt over the blocks, longest first, each to the block with the least
expected time so far, and each block is filled up with short tests behind them: every worker
starts on long tests, and what is stolen from the back of a queue and what is left at the end
are short ones.
A slow test that takes minutes says so (``@pytest.mark.slow(expected_s=180)``, its wall time
[s] in ``make test``); one that does not counts ``SLOW_DEFAULT_S``. Without xdist the slow tests
simply run first, longest first. Otherwise the order is the collection order, the same on every
worker, as xdist requires.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TypeVar

import pytest

T = TypeVar("T")

SLOW_DEFAULT_S = 10.0  # expected wall time [s] of a slow test that gives none


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Deal the ``slow``-marked tests over the blocks xdist's worksteal hands its workers."""
    workers = getattr(config, "workerinput", {}).get("workercount", 1)
    items[:] = dealt(items, block_sizes(len(items), workers), _expected_s)


def block_sizes(n_items: int, n_workers: int) -> list[int]:
    """How many tests worksteal first sends each worker, in collection order: of what is left,
    an equal share per worker still to serve (xdist.scheduler.worksteal.check_schedule)."""
    sizes = []
    for remaining_workers in range(n_workers, 0, -1):
        sizes.append((n_items - sum(sizes)) // remaining_workers)
    return sizes


def dealt(items: list[T], sizes: list[int], expected_s: Callable[[T], float | None]) -> list[T]:
    """``items`` reordered into blocks of ``sizes``: the items with an ``expected_s`` (not
    None) longest first, each to the block with room and the least expected time [s] so far,
    then the others in their order filling the blocks up."""
    slow = sorted((i for i in items if expected_s(i) is not None), key=lambda i: -expected_s(i))
    blocks: list[list[T]] = [[] for _ in sizes]
    loads = [0.0 for _ in sizes]
    for item in slow:
        room = [b for b, size in enumerate(sizes) if len(blocks[b]) < size]
        best = min(room, key=loads.__getitem__)
        blocks[best].append(item)
        loads[best] += expected_s(item)
    rest = iter(i for i in items if expected_s(i) is None)
    for block, size in zip(blocks, sizes, strict=True):
        block.extend(next(rest) for _ in range(size - len(block)))
    return [item for block in blocks for item in block]


def _expected_s(item: pytest.Item) -> float | None:
    """The wall time [s] a ``slow`` test expects (``SLOW_DEFAULT_S`` if it gives none), None
    for the others."""
    slow = item.get_closest_marker("slow")
    if slow is None:
        return None
    return float(slow.kwargs.get("expected_s", SLOW_DEFAULT_S))
