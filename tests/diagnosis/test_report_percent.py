"""The report's cause table prints an explained fraction that is not a number as n/a, and
says under it what its columns are."""

from diagnosis.cause import Cause
from diagnosis.report import EXPLAINED_LEGEND, _cause_row, _percent


def test_a_fraction_prints_as_whole_percent_and_nan_as_not_available():
    assert _percent(0.374) == "37 %"
    assert _percent(float("nan")) == "n/a"


def test_a_row_gives_the_cause_its_parameters_shares_and_evidence_and_the_legend_says_them():
    named = Cause("payload", {"mass_ratio": 1.2}, 0.913, 0.86, "5.9 -> 2.2 N")
    assert _cause_row(named) == "| `payload` | mass_ratio = 1.2 | 91 % | 0.86 | 5.9 -> 2.2 N |"
    assert EXPLAINED_LEGEND.startswith("*explained*: the share of the held-out error above")
    assert "for `unexplained`: the share of the config's held-out error left" in EXPLAINED_LEGEND
