"""Ridge least squares that leaves the linear terms unpenalised (shared by the polynomial and hybrid models).

scikit-learn's :class:`~sklearn.linear_model.Ridge` penalises every
coefficient alike; these models penalise only their corrections. The
Frisch-Waugh-Lovell theorem reduces that to scikit-learn's estimators: the
penalised features and the targets are residualised on the unpenalised ones
(:class:`~sklearn.linear_model.LinearRegression` with intercept), ``Ridge``
(no intercept) fits the residuals, and a last ``LinearRegression`` gives the
unpenalised coefficients and the intercept. The result is the exact minimiser.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from sklearn.linear_model import LinearRegression, Ridge

__all__ = ["ridge_least_squares"]


def ridge_least_squares(
    features: NDArray[np.float64], y: NDArray[np.float64], penalty: float, n_unpenalised: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``coef, intercept`` minimising ``||y - features @ coef - intercept||² + penalty ||coef[n_unpenalised:]||²``.

    The intercept and the first ``n_unpenalised`` columns' coefficients are
    not penalised; ``penalty = inf`` is the limit (penalised coefficients
    exactly zero, the rest ordinary least squares), ``penalty = 0`` ordinary
    least squares (the minimum-norm solution for rank-deficient features).

    Examples
    --------
    >>> f = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 4.0]])
    >>> coef, b = ridge_least_squares(f, f @ [[2.0], [0.5]] + 1.0, 0.0, n_unpenalised=1)
    >>> np.round(coef.ravel(), 6).tolist(), np.round(b, 6).tolist()
    ([2.0, 0.5], [1.0])
    """
    k = y.shape[1]
    free, penalised = features[:, :n_unpenalised], features[:, n_unpenalised:]
    if penalty == 0 or penalised.shape[1] == 0:  # no penalty: one ordinary least-squares fit
        free, penalised = features, features[:, :0]
    if np.isinf(penalty) or penalised.shape[1] == 0:
        coef_penalised = np.zeros((penalised.shape[1], k))
    else:
        both = np.hstack([y, penalised])
        residual = both - LinearRegression().fit(free, both).predict(free)
        coef_penalised = Ridge(penalty, fit_intercept=False).fit(residual[:, k:], residual[:, :k]).coef_
        coef_penalised = coef_penalised.reshape(k, -1).T
    final = LinearRegression().fit(free, y - penalised @ coef_penalised)
    return np.vstack([final.coef_.reshape(k, -1).T, coef_penalised]), np.asarray(final.intercept_).reshape(k)
