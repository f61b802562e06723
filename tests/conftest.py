"""Suite-wide ordering: the slow end-to-end tests run first.

With ``pytest -n 2 --dist worksteal`` (``make test``) a worker that runs out of tests takes
half of what another has left, so the run ends when the last test ends. Started first, the
minutes-long tests overlap each other and the hundreds of short ones fill in at the end; left in
file order, one worker ran the diagnosis tests alone for minutes after the other had finished.
A slow test that takes minutes on its own says so (``@pytest.mark.slow(expected_s=180)``) and
starts before the other slow ones, longest first: the initial split hands every slow test to the
first worker, and the demo, last of them in file order, used to start when the other worker
stole it near the end and then ran alone for its three minutes. Otherwise the order within each
group is the collection order, the same on every worker.
"""

from __future__ import annotations

import pytest


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Put the ``slow``-marked tests before the others, those with the longest ``expected_s``
    [s] first (a stable sort)."""
    items.sort(key=_start_order)


def _start_order(item: pytest.Item) -> tuple[bool, float]:
    """(not slow, minus the expected duration [s] the slow marker gives, 0 if none)."""
    slow = item.get_closest_marker("slow")
    if slow is None:
        return True, 0.0
    return False, -float(slow.kwargs.get("expected_s", 0.0))
