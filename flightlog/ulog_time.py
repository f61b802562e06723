"""A ULog's time line: each topic's samples in time order, and the span its data covers.

A damaged file can hold older data after the damage: a failing SD card leaves blocks written
earlier where later ones belong, and pyulog, resynchronising on the next sync marker, reads them
as if they followed. A real v1.17 log went, after its damage, from 5519.8 s back to 5402.6 s
after boot, and later to 5228.6 s. Interpolating a topic whose timestamps go back gives a row
the values of other times without an error (the attitude, thrust and command of a multirotor
log so damaged were off by up to 9 deg, 40 % and 1.1 m/s). So only the samples later than
every earlier sample of their topic are kept: the log's own time line, and what follows it in
time once the stale block is over. Stale data is not sorted back in: it may be another flight's
or another boot's. A single sample out of line with its neighbours, which are in order (a bit
flipped in its timestamp: ULog carries no checksum), is left out first, so that a far-future
timestamp does not take the rest of its topic with it. A topic's last sample, which has no
next one, is out of line when it is more than twice as late (after boot) as all the log's other
data: a sound log's topics all run to its end, and the real v1.15 POSCTL flight with bit 40 of
its last local position's timestamp flipped read as 12.7 days long.

The span starts at the later of the file header's timestamp (the logging start) and the first
non-zero data timestamp: some files record 0 in the header (a v1.17 flight logged from 408.9 s
after boot read as 504 s long), and some topics' first sample has a zero timestamp.
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np

Topics = Mapping[str, Mapping[str, np.ndarray]]


def in_time_order(topics: Topics) -> tuple[dict[str, dict[str, np.ndarray]], int]:
    """``topics`` (name -> field -> array, ``timestamp`` in us) with, in each topic, only the
    samples not earlier than every sample before them, less a lone sample out of line (module
    docstring); and how many samples were left out."""
    kept: dict[str, dict[str, np.ndarray]] = {}
    left_out = 0
    keeps = {}
    for name, topic in topics.items():
        t = np.asarray(topic["timestamp"], dtype=float)
        keep = ~_out_of_line(t)
        running_max = np.maximum.accumulate(np.where(keep, t, -np.inf))
        keep[1:] &= t[1:] >= running_max[:-1]
        keeps[name] = (t, keep)
    _leave_out_lone_last_samples(keeps)
    for name, topic in topics.items():
        keep = keeps[name][1]
        if keep.all():
            kept[name] = dict(topic)
            continue
        left_out += int(np.sum(~keep))
        kept[name] = {field: np.asarray(values)[keep] for field, values in topic.items()}
    return kept, left_out


def _leave_out_lone_last_samples(keeps: dict[str, tuple[np.ndarray, np.ndarray]]) -> None:
    """In ``keeps`` (topic -> (timestamps, kept mask)), un-keep each topic's last kept sample
    that is more than twice as late as every other kept sample of the log (one per topic)."""
    lasts = {}
    for name, (_, keep) in keeps.items():
        kept_at = np.flatnonzero(keep)
        if len(kept_at):
            lasts[name] = kept_at[-1]
    for name, last in lasts.items():
        t, keep = keeps[name]
        before = t[np.flatnonzero(keep)[-2]] if keep.sum() >= 2 else -np.inf
        others = [keeps[o][0][i] for o, i in lasts.items() if o != name]
        latest_other = max([before, *others])
        if latest_other > 0 and t[last] > 2.0 * latest_other:
            keep[last] = False


def _out_of_line(t: np.ndarray) -> np.ndarray:
    """Samples later than the next one while the next one is in order with the one before
    (or, for the first sample, later than the next two: later than only the next, it is the
    next that is out of line, too early, and the running maximum leaves that one out): one bad
    timestamp, not a stale block."""
    bad = np.zeros(len(t), dtype=bool)
    if len(t) >= 2:
        bad[0] = t[0] > t[1] and (len(t) == 2 or t[0] > t[2])
    if len(t) >= 3:
        bad[1:-1] = (t[1:-1] > t[2:]) & (t[2:] >= t[:-2])
    return bad


def data_span_us(topics: Topics, header_us: float) -> tuple[float, float]:
    """(start, end) of the data [us since boot]: from the later of ``header_us`` (the file
    header's logging start) and the first non-zero sample time, to the last sample time.
    ``topics`` in time order (:func:`in_time_order`); without samples, the header's time twice."""
    firsts, lasts = [], []
    for topic in topics.values():
        t = np.asarray(topic["timestamp"], dtype=float)
        nonzero = t[t > 0]
        if len(nonzero):
            firsts.append(nonzero[0])
            lasts.append(nonzero[-1])
    if not firsts:
        return float(header_us), float(header_us)
    start = max(float(header_us), min(firsts))
    return start, max(start, max(lasts))
