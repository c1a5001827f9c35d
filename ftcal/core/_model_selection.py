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

__all__ = ["check_groups", "calibration_folds", "grouped_subsample", "rmse_and_se", "simplest_within_one_se"]


def check_groups(groups: ArrayLike | None, n_samples: int, *, labels: bool = True,
                 purpose: str = "grouped cross-validation", fix: str = "pass {groups} for random folds"
                 ) -> NDArray | None:
    """Validate ``groups`` (one label per row, at least two distinct labels); ``None`` passes through.

    ``labels=False`` checks the shape only (groups a calibrator does not use); ``purpose`` and ``fix`` word the
    one-group error for what the groups are for (``{groups}`` in ``fix`` stands for ``groups=None``, an error
    field a front end spells in its own terms).

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
    try:
        g = np.asarray(groups)
    except ValueError:  # ragged nested sequences
        raise CalibrationInputError(f"groups must be one label per row of X, shape ({n_samples},); got a ragged "
                                    "nested sequence.") from None
    if g.ndim != 1 or g.shape[0] != n_samples:
        raise CalibrationInputError(
            f"groups must have shape ({n_samples},), one label per row of X; got shape {g.shape}."
        )
    if not labels:
        return g
    if g.dtype.kind == "f" and not np.isfinite(g).all():
        raise CalibrationInputError("groups holds NaN or inf; give every row a group label.")
    if g.dtype.kind not in "biuUS":  # objects (None, mixed types), floats, complex, dates: no label order
        values = g.tolist()
        if g.dtype.kind == "f" and np.array_equal(g, np.round(g)):
            g = g.astype(np.int64)
        elif g.dtype.kind == "O" and all(isinstance(v, str) for v in values):
            g = g.astype(str)
        elif g.dtype.kind == "O" and all(isinstance(v, int) and not isinstance(v, bool) for v in values):
            g = np.asarray(values)
        else:
            first = g[0] if g.size else None
            raise CalibrationInputError(
                f"groups must hold integer or string labels (one per row); got dtype {g.dtype} "
                f"(first label {first!r}). Fix: number the groups 0, 1, 2, ...")
    names = np.unique(g)
    if names.size < 2:
        raise CalibrationInputError(
            f"groups holds {'one group only (label ' + str(names[0]) + ')' if names.size else 'no label'} for the "
            f"{n_samples} rows; {purpose} needs at least 2 groups (e.g. poses or load configurations).",
            parameter="groups", fix=fix, settings={"groups": None} if "{groups}" in fix else None,
        )
    return g


def calibration_folds(
    n_samples: int, groups: ArrayLike | None, n_splits: int = 5, random_state: int | None = 0, *,
    shuffle: bool = True,
) -> list[tuple[NDArray[np.int64], NDArray[np.int64]]]:
    """Train/test index pairs: :class:`~sklearn.model_selection.GroupKFold` on ``groups``, else shuffled k-fold
    (contiguous blocks with ``shuffle=False``: rows that are a time series, for a model that reads their history).

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
        splitter = KFold(n_splits=min(int(n_splits), n_samples), shuffle=shuffle,
                         random_state=random_state if shuffle else None)
        return list(splitter.split(index))
    splitter = GroupKFold(n_splits=min(int(n_splits), np.unique(g).size))
    return list(splitter.split(index, groups=g))


def grouped_subsample(rows: NDArray, groups: NDArray | None, size: int | None, seed: int) -> NDArray:
    """At most ``size`` of ``rows``, the same share from every group (all rows when they fit).

    Each group gets ``floor(share · its rows)``; the rows this leaves short of
    ``size`` are drawn at random from the rest, so exactly ``size`` rows come
    back (a group smaller than ``1 / share`` rows may get none).

    Examples
    --------
    >>> rows = grouped_subsample(np.arange(100), np.repeat([0, 1], [80, 20]), 10, seed=0)
    >>> len(rows), int((rows >= 80).sum())
    (10, 2)
    """
    if size is None or rows.size <= size:
        return rows
    rng = np.random.default_rng(seed)
    if groups is None:
        return np.sort(rng.choice(rows, size=size, replace=False))
    _, label = np.unique(groups[rows], return_inverse=True)
    order = np.argsort(label, kind="stable")
    starts = np.searchsorted(label[order], np.arange(label.max() + 1))
    counts = np.diff(np.append(starts, rows.size))
    quota = np.floor(counts * (size / rows.size)).astype(int)
    chosen = np.zeros(rows.size, dtype=bool)
    for start, count, take in zip(starts, counts, quota):  # one pass over the groups, each sliced once
        if take:
            chosen[order[start + rng.choice(count, size=take, replace=False)]] = True
    rest = np.flatnonzero(~chosen)
    chosen[rng.choice(rest, size=size - int(quota.sum()), replace=False)] = True
    return np.sort(rows[chosen])


def _per_unit(values: NDArray, units: NDArray | None) -> NDArray:
    """``values`` averaged per unit (a group; each row its own unit without groups)."""
    values = np.asarray(values, dtype=float)
    if units is None:
        return values
    _, inverse = np.unique(units, return_inverse=True)
    return np.bincount(inverse, weights=values) / np.bincount(inverse)


def rmse_and_se(row_errors: ArrayLike, units: ArrayLike | None = None) -> tuple[float, float]:
    """RMSE and its standard error from per-row mean squared errors (delta method over groups, or rows).

    ``row_errors[i]`` is the mean over the six torque-scaled components of row
    ``i``'s squared error, so ``sqrt(mean(row_errors))`` is eq. 18.

    Examples
    --------
    >>> rmse, se = rmse_and_se([1.0, 1.0, 4.0, 4.0], units=[0, 0, 1, 1])
    >>> round(rmse, 4), round(se, 4)
    (1.5811, 0.4743)
    """
    row_errors = np.asarray(row_errors, dtype=float)
    per_unit = _per_unit(row_errors, None if units is None else np.asarray(units))
    mse = float(row_errors.mean())
    se_mse = float(per_unit.std(ddof=1) / np.sqrt(per_unit.size)) if per_unit.size > 1 else float("inf")
    rmse = float(np.sqrt(mse))
    return rmse, se_mse / (2.0 * rmse) if rmse > 0 else 0.0


#: Relative excess of mean squared error below which two candidates tie (1 %, i.e. 0.5 % in RMSE).
TIE_TOLERANCE = 0.01


def simplest_within_one_se(errors: NDArray, units: NDArray | None = None, *, complexity: ArrayLike | None = None,
                           eligible: ArrayLike | None = None) -> int:
    """The one-standard-error rule of ftcal: the simplest candidate whose error is within one SE of the best.

    ``errors[k, i]`` is candidate ``k``'s held-out squared error on row ``i``
    (NaN when ``k`` was not scored: never chosen). The best is the eligible
    candidate of lowest mean error; a candidate qualifies when its mean error
    exceeds the best's by at most one **paired** standard error of the
    difference (per group with ``units``: rows of one group are not
    independent; per row without), or by at most :data:`TIE_TOLERANCE` of the
    best's mean squared error (averaged per unit like the differences; 0.5 %
    in RMSE: a gain that small is a tie even
    when it is consistent, as on noise-free data). Among those that qualify the one of lowest
    ``complexity`` wins (default: the row order, simplest first); between
    candidates of equal complexity (two estimates of equally flexible models)
    the lower mean error decides, then the earlier row. Every model choice in
    ftcal uses this one rule (``auto``, ``ftcal benchmark dataset``, the
    hybrid's ridge, the history term's time constant).

    Parameters
    ----------
    errors : ndarray of shape (n_candidates, n_samples)
    units : ndarray of shape (n_samples,) or None
        Group of each row.
    complexity : array-like of shape (n_candidates,) or None
        Complexity rank of each candidate (lower = simpler); ``None``: ``0, 1, 2, ...``.
    eligible : array-like of bool, shape (n_candidates,) or None
        Candidates that may be chosen (``None``: every scored one).

    Examples
    --------
    >>> errors = np.array([[1.1, 0.9, 1.2, 0.9], [1.0, 1.0, 1.0, 1.0], [2.0, 2.0, 2.1, 1.9]])
    >>> simplest_within_one_se(errors)  # 0 is within noise of the best (1)
    0
    >>> simplest_within_one_se(errors, complexity=[2, 1, 0])  # now 1 is the simplest within noise
    1
    >>> simplest_within_one_se(errors, complexity=[0, 0, 1])  # 0 and 1 equally simple: the lower error
    1
    """
    errors = np.asarray(errors, dtype=float)
    n = errors.shape[0]
    ok = ~np.isnan(errors).any(axis=1)
    if eligible is not None:
        ok &= np.asarray(eligible, dtype=bool)
    if not ok.any():
        raise CalibrationInputError("no candidate could be scored; see cv_results_ for why each one failed.")
    rank = np.arange(n, dtype=float) if complexity is None else np.asarray(complexity, dtype=float)
    means = np.where(ok, np.nanmean(np.where(ok[:, None], errors, 0.0), axis=1), np.inf)
    best = int(np.argmin(means))
    units = None if units is None else np.asarray(units)
    qualified = []
    tie = TIE_TOLERANCE * float(_per_unit(errors[best], units).mean())  # per unit, like the differences
    for k in np.flatnonzero(ok):
        diff = _per_unit(errors[k] - errors[best], units)
        se = float(diff.std(ddof=1) / np.sqrt(diff.size)) if diff.size > 1 else float("inf")
        if k == best or float(diff.mean()) <= max(se, tie):
            qualified.append(int(k))
    return min(qualified, key=lambda k: (rank[k], means[k], k))
