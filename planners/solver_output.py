"""What an NLP solver path returns to the planner."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class SolverOutput:
    """One solve's outcome.

    Attributes:
        w: last iterate, shape (n_w,) (see :mod:`planners.nmpc_formulation` for the layout).
        ok: True when the solver reports success.
        reason: empty when ok, otherwise the solver's failure status.
        iterations: iterations used.
    """

    w: np.ndarray
    ok: bool
    reason: str
    iterations: int
