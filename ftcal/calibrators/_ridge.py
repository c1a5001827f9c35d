"""Ridge least squares that leaves the linear terms unpenalised (shared by the polynomial and hybrid models).

scikit-learn's :class:`~sklearn.linear_model.Ridge` penalises every
coefficient alike; these models penalise only their corrections. With the
intercept unpenalised, centring the features and the targets removes it
exactly; the penalty on the remaining columns is then the augmented least-squares
system ``[F; 0 √λ I] c = [y; 0]``, solved by one :func:`numpy.linalg.lstsq`
(its minimum-norm solution for rank-deficient features, as
:class:`~sklearn.linear_model.LinearRegression` gives). It is the exact
minimiser, and about ten times faster than composing scikit-learn estimators
(the hybrid's cross-validated penalty solves a few thousand small systems);
``tests/test_ridge.py`` checks it against scikit-learn's ``Ridge`` and
``LinearRegression``.

With ``groups``, each group has an intercept of its own (unpenalised: a pose's
or a session's offset) and centring *within each group* removes them exactly
(the fixed-effects or "within" estimator); the intercept returned is their mean
over the groups, each group weighing the same (the expected offset of a new one).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["ridge_least_squares", "group_means"]


def group_means(values: NDArray[np.float64], groups: NDArray, weights: NDArray[np.float64] | None = None
                ) -> tuple[NDArray[np.float64], NDArray[np.intp]]:
    """Each group's mean row of ``values`` (groups in sorted label order; weighted by ``weights``, a group of zero
    weight has NaN means) and each row's group index.

    Examples
    --------
    >>> means, index = group_means(np.array([[1.0], [3.0], [10.0]]), np.array(["b", "b", "a"]))
    >>> means.ravel().tolist(), index.tolist()
    ([10.0, 2.0], [1, 1, 0])
    """
    from scipy.sparse import csr_matrix

    index = np.unique(groups, return_inverse=True)[1].ravel()
    w = np.ones(len(index)) if weights is None else weights
    members = csr_matrix((w, (index, np.arange(len(index)))), shape=(index.max(initial=-1) + 1, len(index)))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.asarray(members @ values) / np.asarray(members.sum(axis=1)), index


def ridge_least_squares(
    features: NDArray[np.float64], y: NDArray[np.float64], penalty: float, n_unpenalised: int,
    groups: NDArray | None = None, sample_weight: NDArray[np.float64] | None = None,
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``coef, intercept`` minimising ``||y - features @ coef - intercept||² + penalty ||coef[n_unpenalised:]||²``.

    The intercept and the first ``n_unpenalised`` columns' coefficients are
    not penalised; ``penalty = inf`` is the limit (penalised coefficients
    exactly zero, the rest ordinary least squares), ``penalty = 0`` ordinary
    least squares (the minimum-norm solution for rank-deficient features).
    ``groups`` (one label per row): one intercept per group instead of one in
    all, and the mean of the groups' intercepts returned (see the module). ``sample_weight`` (one weight >= 0 per
    row): weighted least squares, ``sum_i w_i ||r_i||²`` (the means weighted too; a group of zero weight has no
    intercept of its own to average).

    Examples
    --------
    >>> f = np.array([[0.0, 0.0], [1.0, 1.0], [2.0, 4.0]])
    >>> coef, b = ridge_least_squares(f, f @ [[2.0], [0.5]] + 1.0, 0.0, n_unpenalised=1)
    >>> np.round(coef.ravel(), 6).tolist(), np.round(b, 6).tolist()
    ([2.0, 0.5], [1.0])
    """
    n_features, k = features.shape[1], y.shape[1]
    if groups is None:
        feature_mean, target_mean = (np.average(v, axis=0, weights=sample_weight) for v in (features, y))
        centred, target = features - feature_mean, y - target_mean
    else:  # each group centred on its own means; the intercept: the mean over the groups of theirs
        means, index = group_means(np.hstack([features, y]), groups, sample_weight)  # one pass over the rows
        weighed = ~np.isnan(means[:, 0])  # groups of zero weight: their rows count for nothing
        feature_means, target_means = np.nan_to_num(means[:, :n_features]), np.nan_to_num(means[:, n_features:])
        centred, target = features - feature_means[index], y - target_means[index]
        feature_mean, target_mean = feature_means[weighed].mean(axis=0), target_means[weighed].mean(axis=0)
    if sample_weight is not None:  # sum_i w_i r_i²: each row scaled by sqrt(w_i)
        root = np.sqrt(sample_weight)[:, None]
        centred, target = centred * root, target * root
    n_penalised = n_features - n_unpenalised
    coef = np.zeros((n_features, k))
    if np.isinf(penalty):  # the limit: penalised coefficients zero, the free ones by least squares
        coef[:n_unpenalised] = np.linalg.lstsq(centred[:, :n_unpenalised], target, rcond=None)[0]
    elif penalty == 0 or n_penalised == 0:
        coef = np.linalg.lstsq(centred, target, rcond=None)[0]
    else:
        prior = np.zeros((n_penalised, n_features))
        prior[:, n_unpenalised:] = np.sqrt(penalty) * np.eye(n_penalised)
        coef = np.linalg.lstsq(np.vstack([centred, prior]), np.vstack([target, np.zeros((n_penalised, k))]),
                               rcond=None)[0]
    return coef, target_mean - feature_mean @ coef
