"""Using an estimator before ``fit``: scikit-learn's NotFittedError and the check that raises it.

Apart from gp.errors and gp.validation because it imports scikit-learn (and scipy.stats with
it: about 2 s of CPU per process). A process that flies a model file and fits nothing (the
companion, a study's or a cluster's flight workers) loads the posterior, its inputs' checks and
their errors without it.
"""

from __future__ import annotations

from sklearn.exceptions import NotFittedError as _SklearnNotFittedError


class NotFittedError(_SklearnNotFittedError):
    """A model was used before ``fit`` (a scikit-learn NotFittedError: ValueError and
    AttributeError)."""


def check_fitted(estimator: object, attribute: str = "posterior_") -> None:
    """Raise NotFittedError unless ``estimator`` has the fitted ``attribute``."""
    if not hasattr(estimator, attribute):
        raise NotFittedError(
            f"this {type(estimator).__name__} is not fitted yet; call fit(X, Y) before using it"
        )
