"""Cross-validation that respects how calibration data are collected.

Calibration data come in groups: the rows of one robot pose, one load
configuration or one recording session share their error sources (the pose's
gravity direction, the mounting, the drift of that session). Random folds put
rows of the same group on both sides of a split and so flatter every flexible
model; a calibration must work on poses it has not seen. Every model choice
in ftcal (the hybrid's ridge, :class:`~ftcal.AutoCalibrator`,
:func:`~ftcal.compose.search_calibrator`, ``ftcal tune``, ``ftcal benchmark dataset``)
therefore splits with :func:`calibration_folds`: whole groups when the data
have them, shuffled k-fold otherwise.
"""

from __future__ import annotations

import numbers

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.model_selection import GroupKFold, KFold

from ..core._exceptions import CalibrationInputError

__all__ = ["check_groups", "calibration_folds", "grouped_subsample", "rmse_and_se", "simplest_within_one_se",
           "choice_beats_simplest", "paired_excess", "mean_and_se", "tie_margin",
           "held_out_predictions", "fold_predictions", "routed_groups"]


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


def routed_groups(estimator, groups: ArrayLike | None) -> dict:
    """The ``fit`` parameters ``estimator`` gets for these ``groups``: ``{"groups": groups}`` when its metadata
    routing requests them (its default, or ``set_fit_request``), else ``{}``; what every meta-estimator of ftcal
    passes to an inner model (scikit-learn's :func:`~sklearn.utils.metadata_routing.get_routing_for_object`).
    One group only (a training fold that holds a single group of the caller's) routes none: the inner model's own
    grouped choice has no groups to hold out and makes row folds, where it would refuse the single group.

    Examples
    --------
    >>> from sklearn.linear_model import LinearRegression
    >>> routed_groups(LinearRegression(), [0, 1])
    {}
    """
    if groups is None or np.unique(np.asarray(groups)).size < 2:
        return {}
    from sklearn.utils.metadata_routing import get_routing_for_object

    wants = get_routing_for_object(estimator).consumes(method="fit", params=["groups"])
    return {"groups": groups} if "groups" in wants else {}


def fold_predictions(estimator, X: NDArray, y: NDArray, folds, *, groups: ArrayLike | None = None,
                     fit_params: dict | None = None, max_train_rows: int | None = None, random_state: int | None = 0,
                     chunk_rows: int | None = None, has_std=None, n_jobs: int | None = None) -> list[tuple]:
    """``(test rows, predictions)`` of a clone of ``estimator`` fitted on each ``(train, test)`` of ``folds``
    (``(test rows, predictions, std or None)`` with ``has_std``).

    Built on :func:`sklearn.model_selection.cross_validate` (``return_estimator``, ``return_indices``, its
    ``params=`` sliced to each training fold, ``n_jobs`` folds at once); ``groups`` reach the estimator through
    its metadata routing (:func:`routed_groups`). The folds need not cover every row (a subset of a split, scored
    in one job). ``max_train_rows`` fits each fold on at most that many of its training rows (drawn with
    ``random_state``); ``chunk_rows`` predicts the test rows in blocks of that many (a kernel model's cross-kernel
    of a large fold would otherwise take gigabytes; ``None`` for a model that reads its rows as one stream);
    ``has_std(fitted model)`` says whether a fold's model predicts its std (``predict(X, return_std=True)``).
    """
    from sklearn.model_selection import cross_validate

    folds = [(np.asarray(train), np.asarray(test)) for train, test in folds]
    if groups is not None and any(np.unique(np.asarray(groups)[train]).size < 2 for train, _ in folds):
        groups = None  # a training fold of one group (routed_groups): every fold's inner choice makes row folds
    params = {**routed_groups(estimator, None if groups is None else np.asarray(groups)), **(fit_params or {})}
    if max_train_rows is not None:  # the same draw for every fold (np.random.default_rng(random_state))
        folds = [(np.sort(np.random.default_rng(random_state).choice(train, size=max_train_rows, replace=False))
                  if len(train) > max_train_rows else train, test) for train, test in folds]
    result = cross_validate(estimator, X, y, cv=folds, params=params or None, scoring=_no_score, n_jobs=n_jobs,
                            return_estimator=True, return_indices=True, error_score="raise")
    out = []
    for model, test in zip(result["estimator"], result["indices"]["test"]):
        std = has_std is not None and bool(has_std(model))
        step = len(test) if chunk_rows is None else max(int(chunk_rows), 1)
        blocks = [test[i:i + step] for i in range(0, len(test), step)]
        parts = [model.predict(X[rows], return_std=True) if std else (model.predict(X[rows]), None) for rows in blocks]
        pred = np.concatenate([np.asarray(p, dtype=float) for p, _ in parts]).reshape(len(test), -1)
        sd = np.concatenate([np.asarray(s, dtype=float) for _, s in parts]).reshape(len(test), -1) if std else None
        out.append((test, pred) if has_std is None else (test, pred, sd))
    return out


def _no_score(estimator, X, y) -> float:
    """A scorer that costs nothing: the held-out predictions are made once, by :func:`fold_predictions`."""
    return 0.0


def held_out_predictions(
    estimator, X: ArrayLike, y: ArrayLike, *, groups: ArrayLike | None = None, cv: int = 5,
    random_state: int | None = 0, shuffle: bool = True, folds=None, max_train_rows: int | None = None,
    chunk_rows: int | None = None, has_std=None, n_jobs: int | None = None,
) -> tuple:
    """The one held-out engine of ftcal: the folds (:func:`calibration_folds`) and the out-of-fold predictions.

    Every held-out figure of ftcal comes from here or from the same folds: ``auto``'s comparison, the search,
    the history term's folds and the calibration report. ``groups`` make the folds (whole groups held out) and
    reach ``estimator`` when its routing requests them.

    Parameters
    ----------
    estimator : regressor
        Cloned for each fold.
    X : array-like of shape (n, N)
    y : array-like of shape (n, k)
    groups : array-like of shape (n,) or None
    cv : int, default=5
        Folds (capped by the groups or the rows).
    random_state : int or None, default=0
        Seed of the shuffled k-fold.
    shuffle : bool, default=True
        ``False``: contiguous blocks of rows (a time series).
    folds : list of (train, test) or None
        Folds made before (e.g. those of ``auto``'s comparison, to reuse them); ``None`` makes them.
    max_train_rows : int or None, default=None
        Fit each fold on at most this many of its training rows (drawn with ``random_state``; a stock baseline's
        budget in the calibration report).
    chunk_rows : int or None, default=None
        Predict each test fold in blocks of this many rows (bounded memory for kernel models); ``None``: at once,
        as a model that reads its rows as one stream needs.
    has_std : callable or None, default=None
        ``has_std(fitted fold model)``: whether that model predicts its std; given, a third result is returned.
    n_jobs : int or None, default=None
        Folds fitted at once (:func:`sklearn.model_selection.cross_validate`).

    Returns
    -------
    folds : list of (train, test) index arrays
    predictions : ndarray of shape (n, k)
        Each row predicted by the model that did not see it (NaN for a row no fold tests).
    std : ndarray of shape (n, k) or None
        Only with ``has_std``: the predictive std, or None when a fold's model gives none.

    Examples
    --------
    >>> from sklearn.linear_model import LinearRegression
    >>> X = np.arange(20.0).reshape(10, 2); y = X @ [[1.0], [2.0]]
    >>> folds, pred = held_out_predictions(LinearRegression(), X, y, cv=5)
    >>> len(folds), bool(np.allclose(pred, y))
    (5, True)
    """
    X, y = np.asarray(X), np.asarray(y)
    if folds is None:
        folds = calibration_folds(len(X), groups, cv, random_state, shuffle=shuffle)
    pieces = fold_predictions(estimator, X, y, folds, groups=groups, max_train_rows=max_train_rows,
                              random_state=random_state, chunk_rows=chunk_rows, has_std=has_std, n_jobs=n_jobs)
    width = pieces[0][1].shape[1] if pieces else (y.shape[1] if y.ndim == 2 else 1)
    predictions = np.full((len(X), width), np.nan)
    std = np.full((len(X), width), np.nan) if has_std is not None else None
    for test, values, *rest in pieces:
        predictions[test] = values
        if std is not None and rest[0] is None:
            std = None  # a fold whose model gives no std (auto chose a GP in one fold and not in another)
        elif std is not None:
            std[test] = rest[0]
    return (folds, predictions) if has_std is None else (folds, predictions, std)


def grouped_subsample(rows: NDArray, groups: NDArray | None, size: int | None, seed: int) -> NDArray:
    """At most ``size`` of ``rows``, the same share from every group (all rows when they fit).

    Each group gets ``floor(share · its rows)``, and at least one row when there are no more groups than
    ``size`` (taken from the largest quotas); the rows this leaves short of ``size`` are drawn at random from the
    rest, so exactly ``size`` rows come back.

    Examples
    --------
    >>> rows = grouped_subsample(np.arange(100), np.repeat([0, 1], [80, 20]), 10, seed=0)
    >>> len(rows), int((rows >= 80).sum())
    (10, 2)
    >>> rows = grouped_subsample(np.arange(103), np.repeat([0, 1, 2], [100, 2, 1]), 10, seed=0)
    >>> len(rows), sorted(set(np.repeat([0, 1, 2], [100, 2, 1])[rows].tolist()))  # every group kept
    (10, [0, 1, 2])
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
    if counts.size <= size:  # every group kept: the share of a small group rounded up to one row
        quota[quota == 0] = 1
        for i in np.argsort(-quota, kind="stable"):  # over by at most one row a group: from the largest quotas
            excess = int(quota.sum()) - size
            if excess <= 0:
                break
            quota[i] -= min(excess, quota[i] - 1)
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


def mean_and_se(values: ArrayLike, units: ArrayLike | None = None) -> tuple[float, float]:
    """Mean of per-row ``values`` and its standard error, the rows grouped in ``units`` (None: each row its own).

    The mean of the per-unit means, and their SE with at least :data:`MIN_SE_GROUPS` units; with fewer (2 to 4
    groups) the **larger** of the units' SE and the rows' SE. Rows of one group are not independent, so
    the rows' SE alone understates the uncertainty (one pose or load the models happen to differ on counts as many
    rows), and a few groups' SE alone is no evidence either (it is ~0 when 3 groups happen to agree); the larger
    of the two never understates what either shows. For the one-SE rule this is the conservative side: a larger
    SE only lets more candidates be within one SE, so a more complex model is chosen only when its gain exceeds
    both the spread over the rows and the spread between the groups (a gain in one group that the others do not
    share is not enough). ``inf`` with a single row or unit.

    Examples
    --------
    >>> mean_and_se([1.0, 1.2, 3.0, 3.2], units=[0, 0, 1, 1])  # 2 groups disagree: their SE, the larger
    (2.1, 1.0)
    """
    values = np.asarray(values, dtype=float)
    units = None if units is None else np.asarray(units)
    se = lambda v: float(v.std(ddof=1) / np.sqrt(v.size)) if v.size > 1 else float("inf")  # noqa: E731
    if units is None:
        return float(values.mean()), se(values)
    per_unit = _per_unit(values, units)
    return float(per_unit.mean()), se(per_unit) if per_unit.size >= MIN_SE_GROUPS else max(se(per_unit), se(values))


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
    mse, se_mse = float(row_errors.mean()), mean_and_se(row_errors, units)[1]
    rmse = float(np.sqrt(mse))
    return rmse, se_mse / (2.0 * rmse) if rmse > 0 else 0.0


#: Relative excess of mean squared error below which two candidates tie (1 %, i.e. 0.5 % in RMSE).
TIE_TOLERANCE = 0.01


def tie_margin(reference_errors: ArrayLike, units: ArrayLike | None = None) -> float:
    """The tie margin of ftcal's comparisons [the errors' units, N² for eq. 18's]: :data:`TIE_TOLERANCE` of the
    reference's mean error, averaged per unit like the paired differences it is set beside (:func:`mean_and_se`).
    The one helper of the one-SE rule (:func:`paired_excess`, the best row) and of the race
    (:func:`~ftcal.model_selection.race_stop`, the best cheap row on the first fold): a gain below it is a tie.

    Examples
    --------
    >>> tie_margin([1.0, 1.0, 1.0, 5.0])  # per row: 1 % of the mean 2.0
    0.02
    >>> tie_margin([1.0, 1.0, 1.0, 5.0], units=[0, 0, 0, 1])  # per group: 1 % of the mean of 1.0 and 5.0
    0.03
    """
    return TIE_TOLERANCE * mean_and_se(reference_errors, units)[0]


def one_se_qualified(errors: NDArray, units: NDArray | None = None, *, eligible: ArrayLike | None = None
                     ) -> tuple[int, NDArray[np.bool_]]:
    """The best candidate (lowest mean error among the eligible scored ones) and which are within one paired
    standard error of it (or within :data:`TIE_TOLERANCE`): the set :func:`simplest_within_one_se` chooses from.

    Examples
    --------
    >>> best, within = one_se_qualified(np.array([[1.1, 0.9, 1.2, 0.9], [1.0, 1.0, 1.0, 1.0], [2, 2, 2.1, 1.9]]))
    >>> best, within.tolist()
    (1, [True, True, False])
    """
    errors = np.asarray(errors, dtype=float)
    ok = ~np.isnan(errors).any(axis=1)
    if eligible is not None:
        ok &= np.asarray(eligible, dtype=bool)
    if not ok.any():
        raise CalibrationInputError("no candidate could be scored; see comparison_ for why each one failed.")
    means = np.where(ok, np.nanmean(np.where(ok[:, None], errors, 0.0), axis=1), np.inf)
    best = int(np.argmin(means))
    excess, se, tie = paired_excess(errors, best, units)
    within = ok & ((np.arange(errors.shape[0]) == best) | (excess <= np.maximum(se, tie)))
    return best, within


def paired_excess(errors: NDArray, best: int, units: NDArray | None = None) -> tuple[NDArray, NDArray, float]:
    """Each candidate's excess mean squared error over candidate ``best``, the **paired** standard error of that
    excess (the spread of the per-unit differences, not of each candidate's own errors), and the tie margin
    (:data:`TIE_TOLERANCE` of the best's mean squared error): candidate ``k`` is within one SE when
    ``excess[k] <= max(se[k], tie)`` (:func:`one_se_qualified`). In the units of ``errors`` ([N²] for eq. 18's);
    NaN for an unscored candidate.

    Examples
    --------
    >>> excess, se, tie = paired_excess(np.array([[1.1, 0.9, 1.2, 0.9], [1.0, 1.0, 1.0, 1.0]]), best=1)
    >>> excess.round(3).tolist(), se.round(3).tolist(), round(tie, 3)
    ([0.025, 0.0], [0.075, 0.0], 0.01)
    """
    errors = np.asarray(errors, dtype=float)
    units = None if units is None else np.asarray(units)
    tie = tie_margin(errors[best], units)
    excess, se = np.full(errors.shape[0], np.nan), np.full(errors.shape[0], np.nan)
    for k in np.flatnonzero(~np.isnan(errors).any(axis=1)):
        excess[k], se[k] = mean_and_se(errors[k] - errors[best], units)
    return excess, se, tie


def simplest_within_one_se(errors: NDArray, units: NDArray | None = None, *, complexity: ArrayLike | None = None,
                           eligible: ArrayLike | None = None) -> int:
    """The one-standard-error rule of ftcal: the simplest candidate whose error is within one SE of the best.

    ``errors[k, i]`` is candidate ``k``'s held-out squared error on row ``i``
    (NaN when ``k`` was not scored: never chosen). The best is the eligible
    candidate of lowest mean error; a candidate qualifies when its mean error
    exceeds the best's by at most one **paired** standard error of the
    difference (per group with ``units``: rows of one group are not
    independent; per row without; with fewer than :data:`MIN_SE_GROUPS` groups the larger of the two, see
    :func:`mean_and_se`), or by at most :data:`TIE_TOLERANCE` of the
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
    _, within = one_se_qualified(errors, units, eligible=eligible)
    rank = np.arange(n, dtype=float) if complexity is None else np.asarray(complexity, dtype=float)
    means = np.array([errors[k].mean() if within[k] else np.inf for k in range(n)])
    simplest = np.flatnonzero(within & (rank == rank[within].min()))
    lowest = float(means[simplest].min())
    # among the equally simple: the lowest error, unless an earlier one ties with it (within TIE_TOLERANCE of its
    # mean squared error: the same model estimated twice, e.g. the LTM and the stock least squares)
    return int(next(k for k in simplest if means[k] <= lowest * (1.0 + TIE_TOLERANCE)))


def choice_beats_simplest(errors: NDArray, units: NDArray | None, folds, *, complexity: ArrayLike,
                          eligible: ArrayLike) -> tuple[bool, int, float, float]:
    """Whether choosing by :func:`simplest_within_one_se` beats the simplest eligible candidate **on rows it did
    not choose on**: the choice made again without each fold's test rows and scored on them (no model refitted:
    the rows' held-out errors are reused), against the simplest candidate's errors (the lowest of those of least
    ``complexity``, e.g. the LTM). The best of many candidates on the folds it was chosen on is flattered by the
    choice (a winner's curse); a model more complex than the simplest is kept only when the cross-validated choice
    is better than the simplest beyond one paired SE (or the tie margin).

    With fewer than 3 folds the choice cannot be made again without a fold (one fold left has no standard error:
    every candidate would be within it, and the simplest always chosen again), so the check does not judge:
    ``beats`` is True and the one-SE choice stands. What it is not: a full nested cross-validation (the errors on a
    fold come from models fitted on the other folds, the fold left out of the choice included), and the simplest
    among equally simple rows is taken on all rows. It costs power: a model a little better than the simplest is
    kept less often than by the one-SE rule alone.

    Parameters
    ----------
    errors : ndarray of shape (n_candidates, n_rows)
        Each candidate's held-out squared error per row (NaN rows: not scored).
    units : ndarray of shape (n_rows,) or None
        The rows' SE units (groups, or folds); None: each row its own.
    folds : list of (train, test) index arrays
        The folds that made ``errors``.
    complexity : array-like of shape (n_candidates,)
        Lower is simpler.
    eligible : array-like of bool, shape (n_candidates,)
        The candidates that may be chosen.

    Returns
    -------
    beats : bool
    simplest : int
        The simplest candidate's row.
    gain, gain_se : float
        The simplest's excess mean error over the cross-validated choice, and its paired SE.

    Examples
    --------
    >>> errors = np.array([[1.0] * 6, [0.2, 0.2, 1.1, 1.1, 1.1, 1.1]])  # 1 wins on fold 0 only
    >>> tests = [np.arange(0, 2), np.arange(2, 4), np.arange(4, 6)]
    >>> folds = [(np.setdiff1d(np.arange(6), test), test) for test in tests]
    >>> simplest_within_one_se(errors)  # the one-SE rule alone chooses 1
    1
    >>> choice_beats_simplest(errors, None, folds, complexity=[0, 1], eligible=[1, 1])[:2]  # chosen again: 0
    (False, 0)
    >>> choice_beats_simplest(errors, None, folds[:2], complexity=[0, 1], eligible=[1, 1])[:2]  # 2 folds: no judge
    (True, 0)
    """
    errors, rank = np.asarray(errors, dtype=float), np.asarray(complexity, dtype=float)
    ok = np.asarray(eligible, dtype=bool) & ~np.isnan(errors).any(axis=1)
    simplest = simplest_within_one_se(errors, units, complexity=rank, eligible=ok & (rank == rank[ok].min()))
    if len(folds) < 3:  # one fold left out of each choice: nothing to choose again on
        return True, simplest, float("nan"), float("nan")
    honest = errors[simplest].copy()
    units = None if units is None else np.asarray(units)
    for _, test in folds:
        keep = ~np.isin(np.arange(errors.shape[1]), test)
        k = simplest_within_one_se(errors[:, keep], None if units is None else units[keep], complexity=rank,
                                   eligible=ok)
        honest[test] = errors[k, test]
    gain, gain_se = mean_and_se(errors[simplest] - honest, units)
    return bool(gain > max(gain_se, tie_margin(errors[simplest], units))), simplest, float(gain), float(gain_se)


class DegenerateCalibrationError(CalibrationInputError):
    """A calibration whose held-out predictions are degenerate (constant, all zero, or no better than the mean):
    refused before any model is returned or written."""


#: Held-out MSE at or above this fraction of the MSE of predicting the training mean: no better than the mean.
MEAN_MSE_FRACTION = 1.0


def degenerate_reason(y: ArrayLike, predictions: ArrayLike, *, alpha: float = 1.0, axes=None) -> str | None:
    """Why held-out ``predictions`` (n, k) of targets ``y`` are degenerate, in a few words, or None.

    Degenerate: all zero, the same for every row (while ``y`` varies), or no better than predicting the mean of
    ``y`` (the torque-scaled MSE, eq. 18, at least that of the mean). ``alpha`` scales the torques (of ``axes``; default: of 6 outputs).

    Examples
    --------
    >>> y = np.array([[1.0], [2.0], [3.0], [4.0]])
    >>> degenerate_reason(y, np.zeros_like(y))
    'it predicts 0 for every reading'
    >>> degenerate_reason(y, y + 0.1) is None
    True
    """
    from ..core._wrench import scale_torques

    y = np.asarray(y, dtype=float).reshape(len(y), -1)
    pred = np.asarray(predictions, dtype=float).reshape(len(y), -1)
    if not np.isfinite(pred).all():
        return "its held-out predictions hold NaN or inf"
    ys, ps = (scale_torques(a, alpha, axes) for a in (y, pred))  # the torques of the axes y has
    spread = np.ptp(ys, axis=0)
    if not spread.any():
        return None  # constant targets: nothing to be degenerate against (refused as input elsewhere)
    if not np.abs(ps).max() > 0:
        return "it predicts 0 for every reading"
    if (np.ptp(ps, axis=0) <= 1e-9 * np.maximum(spread, np.abs(ps).max(axis=0))).all():
        return "it predicts the same wrench for every reading"
    mse = float(np.mean((ps - ys) ** 2))
    mean_mse = float(np.mean((ys - ys.mean(axis=0)) ** 2))
    if mse >= MEAN_MSE_FRACTION * mean_mse:
        return (f"its held-out error (RMSE {np.sqrt(mse):.4g}) is no better than predicting the mean wrench "
                f"(RMSE {np.sqrt(mean_mse):.4g})")
    return None


def check_not_degenerate(y: ArrayLike, predictions: ArrayLike, *, what: str, alpha: float = 1.0,
                         held_out: bool = True, axes=None) -> None:
    """Raise :class:`DegenerateCalibrationError` (one line: ``what`` and why) if ``predictions`` are degenerate
    (:func:`degenerate_reason`); what ``AutoCalibrator.fit`` and ``ftcal fit`` call before a model is kept.
    ``held_out=False`` says the predictions are of the training readings (the message and its fix say so).

    Examples
    --------
    >>> check_not_degenerate([[1.0], [2.0]], [[0.0], [0.0]], what="the LTM")
    Traceback (most recent call last):
    ...
    ftcal.model_selection._selection.DegenerateCalibrationError: refusing the LTM: it predicts 0 for every reading on the readings it did not see; nothing was saved. Fix: record loads on every axis (each axis loaded in more than one group), or choose another model.
    """
    reason = degenerate_reason(y, predictions, alpha=alpha, axes=axes)
    if reason is None:
        return
    if not held_out:
        raise DegenerateCalibrationError(
            f"refusing {what}: {reason.replace('held-out ', '')} on its own training readings; nothing was saved. "
            "Fix: train it longer or with other parameters, check the data (a constant channel, wrong columns), "
            "or choose another model.")
    raise DegenerateCalibrationError(
        f"refusing {what}: {reason} on the readings it did not see; nothing was saved. Fix: record loads on "
        "every axis (each axis loaded in more than one group), or choose another model.")


#: An output whose training fold spans less than this fraction of its whole span counts as unseen in training.
UNSEEN_FRACTION = 0.05


def unseen_outputs(y: ArrayLike, folds, names: tuple[str, ...] | None = None) -> list[str]:
    """Outputs that some training fold leaves (nearly) unseen: spanning less than :data:`UNSEEN_FRACTION` of
    the output's whole span (e.g. grouped folds with one group per loaded axis: holding out the ``Fx`` group
    leaves no ``Fx`` load to learn from). Such folds cannot judge a model. Returns their names.

    Examples
    --------
    >>> y = np.array([[1.0, 0], [2, 0], [0, 1], [0, 2], [1, 1], [2, 2]])
    >>> unseen_outputs(y, calibration_folds(6, [0, 0, 1, 1, 0, 1], 2), names=("Fx", "Fy"))
    []
    >>> unseen_outputs(y[:4], calibration_folds(4, [0, 0, 1, 1], 2), names=("Fx", "Fy"))
    ['Fx', 'Fy']
    """
    y = np.asarray(y, dtype=float).reshape(len(y), -1)
    span = np.ptp(y, axis=0)
    unseen = np.zeros(y.shape[1], dtype=bool)
    for train, _ in folds:
        unseen |= (span > 0) & (np.ptp(y[train], axis=0) < UNSEEN_FRACTION * span)
    labels = names or tuple(f"output {j}" for j in range(y.shape[1]))
    return [labels[j] for j in np.flatnonzero(unseen)]


#: Fewest groups whose spread a standard error may be computed from (fewer: the rows' spread is used).
MIN_SE_GROUPS = 5


def se_units(groups: NDArray | None) -> NDArray | None:
    """The units of the standard errors of a comparison: the groups (rows of one group are not independent), or
    the rows (``None``) without groups. With fewer than :data:`MIN_SE_GROUPS` groups the SE is the larger of the
    rows' and the groups' (:func:`mean_and_se`): a standard error from 3 groups' means alone is no evidence (it
    can be ~0 when the groups happen to agree), the rows' alone understates it.

    Examples
    --------
    >>> se_units(np.array([0, 0, 1, 1, 2, 2])).tolist()
    [0, 0, 1, 1, 2, 2]
    """
    if groups is None or np.unique(groups).size < 2:
        return None
    return groups
