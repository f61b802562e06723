"""The report's cause table prints an explained fraction that is not a number as n/a."""

from diagnosis.report import _percent


def test_a_fraction_prints_as_whole_percent_and_nan_as_not_available():
    assert _percent(0.374) == "37 %"
    assert _percent(float("nan")) == "n/a"
