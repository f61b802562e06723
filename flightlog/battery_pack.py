"""What a logged battery voltage says of the pack: its reading, and the cell counts it can have.

A lithium cell reads from about 3.0 V (empty, under load) to 4.45 V (a high-voltage cell
charged), so a pack of n cells reads within n times that range: a log's voltage tells the cell
counts its pack can have, and a voltage below one cell's least is no pack reading at all (a
flight controller without a power module logs battery_status near 0 V).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

CELL_RANGE_V = (3.0, 4.45)  # a lithium cell's voltage, empty under load to charged HV [V]
# Percentiles of the logged voltage [%] read as the pack's least and most (a sag under a burst
# of thrust, a spike, is not the pack).
PACK_PERCENTILES = (5.0, 95.0)


@dataclass(frozen=True)
class PackReading:
    """A log's battery voltage, read as a pack: its least, median and most [V]."""

    least_v: float
    median_v: float
    most_v: float

    @classmethod
    def of(cls, volts: Sequence[np.ndarray]) -> PackReading | None:
        """The reading of ``volts`` (arrays [V], NaN where not logged); None without a finite
        value."""
        every = np.concatenate([np.asarray(v, float) for v in volts]) if volts else np.zeros(0)
        every = every[np.isfinite(every)]
        if not every.size:
            return None
        least, median, most = np.percentile(every, (PACK_PERCENTILES[0], 50.0, PACK_PERCENTILES[1]))
        return cls(float(least), float(median), float(most))

    def is_pack(self, floor_v: float = CELL_RANGE_V[0]) -> bool:
        """Whether its median reaches ``floor_v`` [V] (one cell's least by default)."""
        return self.median_v >= floor_v

    def cells(self) -> range:
        """The cell counts the pack can have."""
        return cell_counts(self.least_v, self.most_v)


def cell_counts(least_v: float, most_v: float) -> range:
    """The cell counts a lithium pack that reads ``least_v`` to ``most_v`` [V] can have
    (:data:`CELL_RANGE_V` per cell); empty when none."""
    return range(math.ceil(most_v / CELL_RANGE_V[1]), math.floor(least_v / CELL_RANGE_V[0]) + 1)


def counts_in_words(counts: range) -> str:
    """Cell counts in words: "4", "4-5", "no whole number of"."""
    if not counts:
        return "no whole number of"
    return str(counts[0]) if len(counts) == 1 else f"{counts[0]}-{counts[-1]}"
