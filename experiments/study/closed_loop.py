"""Never worse than not learning, in closed loop: a learned model flies only if it tracked no
worse on the training seeds than the model it replaces and the identified structure alone.

The open-loop check (gp.prediction_check) judges predictions under the logged commands, on
the paths those flights took; the NMPC then chooses its own commands and exploits what the
model gets wrong off them, which that check cannot see (`study --regime wind_field
--trajectories 2 --repeats 3 --seed 1`: a refit passed it at 0.0489 m against the lag's
0.1173 m over 2 s and flew 0.156 m where its predecessor flew 0.053 m). So, in the spirit of
[Ostafew16]'s trial after trial, every model that would fly is flown on the training
trajectories and seeds (0..repeats-1; the comparison's held-out seeds stay untouched) and
compared flight for flight, on the same (trajectory, seed), with the model it replaces:

    e = sqrt(sum_f n_f e_f^2 / sum_f n_f)        [m]

the tracking RMSE pooled over the flights f (e_f a flight's tracking RMSE, n_f its rows, as
the study pools its figures). The candidate passes when e_candidate <= e_incumbent: no margin
either way, since the flights are lockstep and seeded (the same gusts for both, no run-to-run
noise: a difference is the model's), a margin for the incumbent would refuse models that help
a little, and a margin for the candidate would let a worse one fly. A refused model gives way
to the one it replaced, which must pass the same comparison with its own predecessor and the
structure; ultimately the structure alone flies.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

from experiments.study.jobs import FlightSummary
from experiments.study.metrics import pooled_rmse

STRUCTURE = "the structure alone"  # the learned model's nominal model without the GP


@dataclass(frozen=True)
class TrackingComparison:
    """Two models' tracking RMSE pooled over the same training flights.

    Attributes:
        candidate, incumbent: the models' names.
        candidate_rmse_m, incumbent_rmse_m: pooled tracking RMSE [m].
        n_flights: flights per model (the same (trajectory, seed) pairs).
        flown_on: where, in words ("the training seeds"; the trial view: "trial 3's seed").
    """

    candidate: str
    incumbent: str
    candidate_rmse_m: float
    incumbent_rmse_m: float
    n_flights: int
    flown_on: str = "the training seeds"

    @property
    def passed(self) -> bool:
        """No worse than the incumbent (see the module docstring for why no margin)."""
        return self.candidate_rmse_m <= self.incumbent_rmse_m

    def describe(self) -> str:
        """One line: the verdict and both RMSEs."""
        verdict = "tracks no worse than" if self.passed else "tracks WORSE than"
        return (
            f"{self.candidate} {verdict} {self.incumbent} in closed loop on {self.flown_on}: "
            f"tracking RMSE {self.candidate_rmse_m:.4f} m vs {self.incumbent_rmse_m:.4f} m "
            f"({self.n_flights} flight{'s' if self.n_flights != 1 else ''} each)"
        )

    def to_dict(self) -> dict[str, object]:
        return {
            "candidate": self.candidate,
            "incumbent": self.incumbent,
            "candidate_rmse_m": self.candidate_rmse_m,
            "incumbent_rmse_m": self.incumbent_rmse_m,
            "n_flights": self.n_flights,
            "passed": self.passed,
        }


@dataclass(frozen=True)
class ClosedLoopVerdict:
    """Which of a selection's models flies, and the comparisons that decided it.

    Attributes:
        flies: index into the lineage of the model that flies, or None: the structure alone.
        flies_name: its name (STRUCTURE's for None).
        comparisons: every comparison made, newest candidate first.
    """

    flies: int | None
    flies_name: str
    comparisons: tuple[TrackingComparison, ...]

    def refusals(self) -> list[str]:
        """One line per refused model: what it tracked worse than, both RMSEs, and what
        flies in its place."""
        candidates = list(dict.fromkeys(c.candidate for c in self.comparisons))
        lines = []
        for k, name in enumerate(candidates):
            lost = [c for c in self.comparisons if c.candidate == name and not c.passed]
            if not lost:
                continue
            against = " and than ".join(
                f"{c.incumbent} ({c.candidate_rmse_m:.4f} m vs {c.incumbent_rmse_m:.4f} m)"
                for c in lost
            )
            instead = candidates[k + 1] if k + 1 < len(candidates) else self.flies_name
            lines.append(
                f"refusing {name}: it tracks worse in closed loop on {lost[0].flown_on} than "
                f"{against} over {lost[0].n_flights} flights; {instead} flies in its place"
            )
        return lines

    def to_dict(self) -> dict[str, object]:
        """The record the model file keeps (``structure_flies``: the companion flies the
        identified structure without the GP, gp.prediction_check.structure_only)."""
        return {
            "flies": self.flies_name,
            "structure_flies": self.flies is None,
            "comparisons": [c.to_dict() for c in self.comparisons],
        }


def compare_tracking(
    candidate: str,
    candidate_flights: Sequence[FlightSummary],
    incumbent: str,
    incumbent_flights: Sequence[FlightSummary],
    flown_on: str = "the training seeds",
) -> TrackingComparison:
    """Compare two models flown on the same (trajectory, seed) pairs (``flown_on``: where,
    in words, for the comparison's line).

    Raises:
        ValueError: the two sets of flights are not the same pairs (one line).
    """
    cand, inc = _by_pair(candidate_flights), _by_pair(incumbent_flights)
    if set(cand) != set(inc) or not cand:
        raise ValueError(
            f"{candidate} and {incumbent} were not flown on the same (trajectory, seed) pairs "
            f"({sorted(cand)} vs {sorted(inc)}); fly both on {flown_on}"
        )
    pairs = sorted(cand)

    def pooled(flights: dict[tuple[int, int], FlightSummary]) -> float:
        chosen = [flights[p] for p in pairs]
        return pooled_rmse([f.tracking_rmse_m for f in chosen], [f.n_residuals for f in chosen])

    return TrackingComparison(candidate, incumbent, pooled(cand), pooled(inc), len(pairs), flown_on)


def confirm_lineage(
    lineage: Sequence[tuple[str, Sequence[FlightSummary]]],
    structure_flights: Sequence[FlightSummary],
) -> ClosedLoopVerdict:
    """The newest model of ``lineage`` (name, training flights; oldest first, each replacing
    the one before it, the first replacing the structure) that tracks no worse than its
    predecessor and than the structure alone (``structure_flights``); None if none does."""
    comparisons: list[TrackingComparison] = []
    for k in range(len(lineage) - 1, -1, -1):
        name, flights = lineage[k]
        incumbents = [lineage[k - 1]] if k > 0 else []
        incumbents.append((STRUCTURE, structure_flights))
        made = [compare_tracking(name, flights, inc, inc_fl) for inc, inc_fl in incumbents]
        comparisons += made
        if all(c.passed for c in made):
            return ClosedLoopVerdict(k, name, tuple(comparisons))
    return ClosedLoopVerdict(None, STRUCTURE, tuple(comparisons))


def _by_pair(flights: Sequence[FlightSummary]) -> dict[tuple[int, int], FlightSummary]:
    return {(f.trajectory, f.seed): f for f in flights}
