"""The report's cause table prints an explained fraction that is not a number as n/a, one
that made the error larger as none, and no share explained for what is left unexplained."""

from diagnosis.cause import Cause
from diagnosis.report import EXPLAINED_LEGEND, _cause_row, _percent


def test_a_fraction_prints_as_whole_percent_and_nan_as_not_available():
    assert _percent(0.374) == "37 %"
    assert _percent(float("nan")) == "n/a"


def test_a_cause_that_made_it_worse_explains_nothing_and_unexplained_explains_no_share():
    """On a real PX4 log: ground_effect's 4.808 -> 4.845 N read -100 %, and the unexplained
    row read 0 % on one log and 100 % on another (there: the share left)."""
    worse = Cause("ground_effect", {"max_gain": 1.0}, -1.0, 0.0, "4.808 -> 4.845 N")
    assert _cause_row(worse) == "| `ground_effect` | max_gain = 1 | 0 % | 0.00 | 4.808 -> 4.845 N |"
    left = Cause("unexplained", {"rms_force_n": 5.7}, 1.0, 1.0, "stays")
    assert _cause_row(left) == "| `unexplained` | rms_force_n = 5.7 | - | 1.00 | stays |"
    named = Cause("payload", {"mass_ratio": 1.2}, 0.913, 0.86, "5.9 -> 2.2 N")
    assert _cause_row(named) == "| `payload` | mass_ratio = 1.2 | 91 % | 0.86 | 5.9 -> 2.2 N |"
    assert EXPLAINED_LEGEND.startswith("*explained*: the share of the held-out error above")
