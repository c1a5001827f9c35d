"""Ridge least squares that leaves the linear terms unpenalised (shared by the polynomial and hybrid models)."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["ridge_least_squares"]


def ridge_least_squares(
    features: NDArray[np.float64], y: NDArray[np.float64], penalty: float, n_unpenalised: int
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``coef, intercept`` minimising ``||y - features @ coef - intercept||² + penalty ||coef[n_unpenalised:]||²``.

    The intercept and the first ``n_unpenalised`` columns' coefficients are
    not penalised; ``penalty = inf`` is the limit (penalised coefficients
    exactly zero, the rest ordinary least squares). Solved as an augmented least-squares problem on centred
    data (``numpy.linalg.lstsq``), which stays exact for ``penalty = 0`` and
    rank-deficient features.

    Examples
    --------
    >>> f = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 4.0]])
    >>> coef, b = ridge_least_squares(f, f @ [[2.0], [0.5]] + 1.0, 0.0, n_unpenalised=1)
    >>> np.round(coef.ravel(), 6).tolist(), np.round(b, 6).tolist()
    ([2.0, 0.5], [1.0])
    """
    f_mean = features.mean(axis=0)
    y_mean = y.mean(axis=0)
    fc = features - f_mean
    yc = y - y_mean
    n_penalised = features.shape[1] - n_unpenalised
    if np.isinf(penalty):  # the limit: penalised coefficients are zero, the rest is plain least squares
        coef = np.zeros((features.shape[1], y.shape[1]))
        coef[:n_unpenalised], *_ = np.linalg.lstsq(fc[:, :n_unpenalised], yc, rcond=None)
        return coef, y_mean - f_mean @ coef
    if penalty > 0 and n_penalised > 0:
        rows = np.hstack([np.zeros((n_penalised, n_unpenalised)), np.sqrt(penalty) * np.eye(n_penalised)])
        fc = np.vstack([fc, rows])
        yc = np.vstack([yc, np.zeros((n_penalised, y.shape[1]))])
    coef, *_ = np.linalg.lstsq(fc, yc, rcond=None)
    return coef, y_mean - f_mean @ coef
