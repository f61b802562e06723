"""A topic's samples out of time order: a stale block after damage is left out from where
time goes back until it is over; one bad timestamp is left out alone."""

from __future__ import annotations

import numpy as np

from flightlog.ulog_time import data_span_us, in_time_order


def topic(times_s: list[float]) -> dict[str, np.ndarray]:
    t = np.asarray(times_s) * 1e6
    return {"timestamp": t, "x": np.arange(len(t), dtype=float)}


def test_a_stale_block_is_left_out_until_time_passes_where_it_went_back() -> None:
    kept, left_out = in_time_order({"a": topic([10, 11, 12, 5, 6, 7, 13, 14])})
    np.testing.assert_array_equal(kept["a"]["x"], [0, 1, 2, 6, 7])
    assert left_out == 3


def test_one_far_future_timestamp_is_left_out_alone_not_the_rest_of_its_topic() -> None:
    for times, bad in (([10, 11, 9e6, 12, 13], 2), ([9e6, 10, 11, 12], 0)):
        kept, left_out = in_time_order({"a": topic(times)})
        assert left_out == 1 and bad not in kept["a"]["x"], (times, kept)
        assert len(kept["a"]["x"]) == len(times) - 1


def test_a_sound_topic_is_kept_whole_and_the_span_starts_at_the_data() -> None:
    sound = {"a": topic([0, 408.9, 409.0, 504.1]), "b": topic([409.5, 410.0])}
    kept, left_out = in_time_order(sound)
    assert left_out == 0 and len(kept["a"]["x"]) == 4
    start, end = data_span_us(kept, header_us=0.0)  # a header that recorded 0
    assert (start, end) == (408.9e6, 504.1e6)
    assert data_span_us(kept, header_us=409.2e6)[0] == 409.2e6  # the logging start


def test_a_far_past_timestamp_second_is_left_out_not_the_sound_first_sample() -> None:
    """[10, 0.5, 11, 12]: the 0.5 is the bad one (out of line with both neighbours); the first
    sample, in order with the rest, is kept (it was left out, and the 0.5 kept as the start)."""
    kept, left_out = in_time_order({"a": topic([10, 0.5, 11, 12])})
    assert left_out == 1
    np.testing.assert_array_equal(kept["a"]["x"], [0, 2, 3])


def test_a_far_future_last_sample_is_left_out_and_a_late_sound_one_kept() -> None:
    """A last sample has no next one to be out of line with: one more than twice as late as
    the rest of the log is left out (it made the span 9e6 s); a topic's late last sample
    within that is kept (a landing detected after a long gap)."""
    topics = {"a": topic([10, 11, 12, 9e6]), "b": topic([10, 11, 12.1])}
    kept, left_out = in_time_order(topics)
    assert left_out == 1 and len(kept["a"]["x"]) == 3 and len(kept["b"]["x"]) == 3
    assert data_span_us(kept, header_us=10e6) == (10e6, 12.1e6)
    late = {"landed": topic([10, 60]), "b": topic([10, 50, 100])}
    assert in_time_order(late)[1] == 0
