"""Suite-wide ordering: the slow end-to-end tests run first.

With ``pytest -n 2 --dist worksteal`` (``make test``) a worker that runs out of tests takes
half of what another has left, so the run ends when the last test ends. Started first, the
minutes-long tests overlap each other and the hundreds of short ones fill in at the end; left in
file order, one worker ran the diagnosis tests alone for minutes after the other had finished.
The order within each group is the collection order, the same on every worker.
"""

from __future__ import annotations

import pytest


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Put the ``slow``-marked tests before the others (a stable sort)."""
    items.sort(key=lambda item: item.get_closest_marker("slow") is None)
