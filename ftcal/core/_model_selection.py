"""Cross-validation that respects how calibration data are collected (issue 12).

Calibration data come in groups: the rows of one robot pose, one load
configuration or one recording session share their error sources (the pose's
gravity direction, the mounting, the drift of that session). Random folds put
rows of the same group on both sides of a split and so flatter every flexible
model; a calibration must work on poses it has not seen. Every model choice
in ftcal (the hybrid's ridge, :class:`~ftcal.AutoCalibrator`,
:func:`~ftcal.search_calibrator`, ``ftcal tune``, ``ftcal benchmark dataset``)
therefore splits with :func:`calibration_folds`: whole groups when the data
have them, shuffled k-fold otherwise.
"""

from __future__ import annotations

import numbers

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.model_selection import GroupKFold, KFold

from ._exceptions import CalibrationInputError

__all__ = ["check_groups", "calibration_folds", "paired_standard_error", "simplest_within_one_se"]


def check_groups(groups: ArrayLike | None, n_samples: int) -> NDArray | None:
    """Validate ``groups`` (one label per row, at least two distinct labels); ``None`` passes through.

    Examples
    --------
    >>> check_groups([0, 0, 1], 3).tolist()
    [0, 0, 1]
    >>> check_groups([0, 0, 0], 3)
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.CalibrationInputError: groups holds one group only (label 0) for the 3 rows; grouped cross-validation needs at least 2 groups (e.g. poses or load configurations). Fix: pass groups=None for random folds.
    """
    if groups is None:
        return None
    g = np.asarray(groups)
    if g.ndim != 1 or g.shape[0] != n_samples:
        raise CalibrationInputError(
            f"groups must have shape ({n_samples},), one label per row of X; got shape {g.shape}."
        )
    if g.dtype.kind == "f" and not np.isfinite(g).all():
        raise CalibrationInputError("groups holds NaN or inf; give every row a group label.")
    labels = np.unique(g)
    if labels.size < 2:
        raise CalibrationInputError(
            f"groups holds one group only (label {labels[0]}) for the {n_samples} rows; grouped cross-validation "
            "needs at least 2 groups (e.g. poses or load configurations). Fix: pass groups=None for random folds."
        )
    return g


def calibration_folds(
    n_samples: int, groups: ArrayLike | None, n_splits: int = 5, random_state: int | None = 0
) -> list[tuple[NDArray[np.int64], NDArray[np.int64]]]:
    """Train/test index pairs: :class:`~sklearn.model_selection.GroupKFold` on ``groups``, else shuffled k-fold.

    With groups, ``min(n_splits, number of groups)`` folds and no group is
    ever split between a training and a test set.

    Examples
    --------
    >>> folds = calibration_folds(6, [0, 0, 1, 1, 2, 2], n_splits=5)
    >>> len(folds), sorted(len(test) for _, test in folds)
    (3, [2, 2, 2])
    """
    if isinstance(n_splits, bool) or not isinstance(n_splits, numbers.Integral) or n_splits < 2:
        raise CalibrationInputError(f"cv must be an integer >= 2 (the number of folds); got {n_splits!r}.")
    g = check_groups(groups, n_samples)
    index = np.arange(n_samples)
    if g is None:
        splitter = KFold(n_splits=min(int(n_splits), n_samples), shuffle=True, random_state=random_state)
        return list(splitter.split(index))
    splitter = GroupKFold(n_splits=min(int(n_splits), np.unique(g).size))
    return list(splitter.split(index, groups=g))


def paired_standard_error(errors_a: NDArray, errors_b: NDArray, units: NDArray | None = None) -> tuple[float, float]:
    """Mean and standard error of ``errors_a - errors_b``, paired per unit (a group, or a row without groups).

    Rows of one group are not independent, so with ``units`` the difference
    is averaged per group first and the standard error is over groups.
    """
    diff = np.asarray(errors_a, float) - np.asarray(errors_b, float)
    if units is not None:
        _, inverse = np.unique(units, return_inverse=True)
        diff = np.bincount(inverse, weights=diff) / np.bincount(inverse)
    if diff.size < 2:
        return float(diff.mean()), float("inf")
    return float(diff.mean()), float(diff.std(ddof=1) / np.sqrt(diff.size))


def simplest_within_one_se(errors: NDArray, units: NDArray | None = None) -> int:
    """Index of the first (simplest) candidate whose mean error is within one paired standard error of the best.

    ``errors[k, i]`` is candidate ``k``'s held-out squared error on row ``i``;
    candidates are ordered from the simplest to the most flexible; rows of
    a candidate that was not scored are NaN (never chosen).

    Examples
    --------
    >>> errors = np.array([[1.1, 0.9, 1.2, 0.9], [1.0, 1.0, 1.0, 1.0], [2.0, 2.0, 2.1, 1.9]])
    >>> simplest_within_one_se(errors)  # 0 is within noise of the best (1)
    0
    """
    errors = np.asarray(errors, dtype=float)
    scored = ~np.isnan(errors).any(axis=1)
    if not scored.any():
        raise CalibrationInputError("no candidate could be scored; see cv_results_ for why each one failed.")
    means = np.where(scored, np.nanmean(np.where(scored[:, None], errors, 0.0), axis=1), np.inf)
    best = int(np.argmin(means))
    for k in range(best):
        if scored[k]:
            mean, se = paired_standard_error(errors[k], errors[best], units)
            if mean <= se:
                return k
    return best
