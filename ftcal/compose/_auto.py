"""Let the data choose the calibrator: grouped cross-validation over ftcal's models, stock baselines beside."""

from __future__ import annotations

from math import comb
import os
from numbers import Integral
import time
import warnings

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import nnls
from sklearn.base import clone
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.validation import check_is_fitted
from sklearn.utils.metadata_routing import MetadataRouter, MethodMapping, process_routing

from ._history import refuse_history_inside
from ..calibrators._base import (COSTS, BaseCalibrator, GroupsFit, calibrated_range, calibration_tags, declare,
                                 resolve_alpha, with_settings)
from ..core._exceptions import CalibrationInputError
from ..model_selection._selection import (DegenerateCalibrationError, calibration_folds, check_groups,
                                     degenerate_reason, fold_predictions, grouped_subsample, one_se_qualified,
                                     paired_excess, mean_and_se, rmse_and_se, routed_groups, se_units,
                                     se_units_name, simplest_within_one_se, unseen_outputs,
                                     TIE_TOLERANCE)
from ..core._threads import limit_threads_here
from ..core._validation import check_zero_reading, validate_training_data
from ..core._wrench import WRENCH_LABELS, named_targets, scale_torques, unscale_torques
from ..calibrators._zero_load import estimate_zero_reading, reading_noise

__all__ = ["AutoCalibrator", "StackedCalibrator", "provides_std", "comparison_table", "default_candidates", "score_candidates",
           "with_alpha_and_tare", "minimum_training_rows", "check_calibration", "judging_folds"]

#: Most candidates a stack combines (the best-scoring eligible ones).
STACK_SIZE = 3
#: Training rows up to which a kernel model's fit is light work: with no network to train either, the candidates
#: are scored in this process (worker processes would take longer to start than the fits).
LIGHT_KERNEL_ROWS = 200


def default_candidates(schedule: str = "short", grouped: bool = False) -> list[tuple[str, BaseCalibrator]]:
    """The candidates of :class:`AutoCalibrator`, in the documented complexity order (simplest first).

    They follow from the registry: each registration lists its candidates with a complexity
    (:func:`~ftcal.register_calibrator`'s ``candidates``). ``grouped`` (the rows come in groups, at least 3,
    within which the loads vary): each of ``linear`` and ``polynomial(degree=2, ridge=0.01)`` is followed by its
    twin with one offset per group (``group_offsets=True``, see :class:`~ftcal.PolynomialCalibrator`).

    Examples
    --------
    >>> [name for name, _ in default_candidates()][:3]
    ['linear', 'polynomial(degree=2, ridge=0.01)', 'polynomial(degree=2, ridge=0.0001)']
    >>> [name for name, _ in default_candidates(grouped=True)][:3]
    ['linear', 'linear(group offsets)', 'polynomial(degree=2, ridge=0.01)']
    """
    from ._registry import make_calibrator, registered_candidates

    return [(label, make_calibrator(name, schedule=schedule, **params))
            for name, label, params in registered_candidates(grouped)]


def complexity_ranks(candidates: list[tuple[str, BaseCalibrator]], n_rows: int) -> NDArray[np.int64]:
    """The complexity of each row of the comparison for the one-SE rule, when the rows come in groups.

    Each row's rank is its position, except that a candidate with one offset per group (``group_offsets=True``)
    and the same model without them (the LTM for ``degree=1``), listed before or after it, share the earlier of
    their two positions. Both predict with the same map and one intercept, so they are equally flexible: the offsets
    change how the map is estimated (within the groups, free of their shifts), not what it can fit, and between the
    two the lower score decides (:func:`~ftcal.model_selection._selection.simplest_within_one_se`). ``alpha`` and
    ``zero_reading`` are not compared (``auto`` shares its torque scale with every candidate, and a tare makes no
    model more flexible). Rows after the candidates (the stack, the baselines) keep their positions.

    Parameters
    ----------
    candidates : list of (name, calibrator)
        ``auto``'s candidates, in their order.
    n_rows : int
        Rows of the comparison (the candidates, then the stack and the baselines).

    Returns
    -------
    ndarray of int, shape (n_rows,)

    Examples
    --------
    >>> complexity_ranks(default_candidates(grouped=True)[:4], 5).tolist()
    [0, 0, 2, 2, 4]
    """
    ranks = np.arange(n_rows)
    keys = [_model_without_offsets(est) for _, est in candidates]
    twins = [_has_offsets(est) for _, est in candidates]
    for k in np.flatnonzero(twins):
        plain = next((j for j in range(len(candidates)) if not twins[j] and _same_model(keys[j], keys[k])), None)
        if plain is not None:
            ranks[k] = ranks[plain] = min(ranks[k], ranks[plain])
    # a stock baseline is as simple as the first of ftcal's candidates of its family (sk_linear the LTM, sk_gp
    # the GP): between the two the lower score decides, an earlier one winning a tie
    from ..calibrators._baselines import StockCalibrator

    families = [calibration_tags(est).family for _, est in candidates]
    for k, (_, est) in enumerate(candidates):
        if isinstance(est, StockCalibrator) and families[k]:
            first = next((j for j in range(k) if families[j] == families[k]
                          and not isinstance(candidates[j][1], StockCalibrator)), None)
            if first is not None:
                ranks[k] = ranks[first]
    return ranks


def with_stock_candidates(candidates: list[tuple[str, BaseCalibrator]], stock: list[tuple[str, BaseCalibrator]]
                          ) -> list[tuple[str, BaseCalibrator]]:
    """``candidates`` with the free models ``stock`` placed by what they are: each after the last candidate of
    its family (its tags' ``family``: ``sk_linear`` after the LTM, ``sk_poly2`` after the quadratics, ``sk_gp``
    after the GP), one of no listed family at the end.

    Examples
    --------
    >>> from ftcal.calibrators._baselines import StockCalibrator
    >>> pairs = with_stock_candidates(default_candidates()[:3], [("sk_linear", StockCalibrator())])
    >>> [name for name, _ in pairs]
    ['linear', 'sk_linear', 'polynomial(degree=2, ridge=0.01)', 'polynomial(degree=2, ridge=0.0001)']
    """
    pairs = list(candidates)
    for name, model in stock:
        family = calibration_tags(model).family
        after = [j for j, (_, est) in enumerate(pairs) if family and calibration_tags(est).family == family]
        pairs.insert(after[-1] + 1 if after else len(pairs), (name, model))
    return pairs


def make_ltm() -> BaseCalibrator:
    """The LTM (``make_calibrator("linear")``): ``auto``'s fallback when no folds can judge a model."""
    from ._registry import make_calibrator

    return make_calibrator("linear")


def _unscored_ltm(note: str) -> dict:
    """The comparison of a fit that no folds could judge: the LTM alone, chosen unscored."""
    return {"name": ["linear"], "kind": ["candidate"], "status": ["chosen unscored: no folds can judge a model"],
            "eligible": [True], "rmse": [None], "rmse_se": [None], "axis_rmse": [None], "fit_seconds": [None],
            "n_splits": 0, "min_training_rows": 0, "verdict": ["chosen (no folds can judge a model)"],
            "chosen": "linear", "se_units": "rows",
            "why": f"linear (the LTM) chosen without a held-out score: folds {note}."}


def explain_choice(results: dict, errors: NDArray, units: NDArray | None, chosen: int, ranks: NDArray) -> None:
    """Mark each row of ``results`` with why it was or was not chosen, and say in words why the winner won.

    ``verdict`` per row: ``chosen``; ``within one SE, more complex`` (or ``within one SE, as simple, higher
    error``); ``beyond one SE``; or the row's ``skipped``/``failed``/``refused`` status. ``why``: one sentence
    naming the winner, the best score it was within one standard error of, and its ratio to the best stock
    model (a free model of scikit-learn's) with whether that is within noise.
    """
    names, rmse, se = results["name"], results["rmse"], results["rmse_se"]
    best, within = one_se_qualified(errors, units, eligible=results["eligible"])
    verdicts = []
    for k in range(len(names)):
        if k == chosen:
            verdicts.append("chosen")
        elif not results["eligible"][k]:
            verdicts.append(results["status"][k] if results["status"][k] != "scored" else "reported only")
        elif within[k]:
            verdicts.append("within one SE, as simple (the lower or earlier wins)" if ranks[k] == ranks[chosen]
                            else "within one SE, more complex")
        else:
            verdicts.append("beyond one SE")
    results["verdict"] = verdicts
    results["chosen"] = names[chosen]
    unit = se_units_name(units)
    # what the rule compared, so that the table lets a reader check each verdict (the paired SE of the excess, not
    # each row's own SE: two models erring on the same rows differ by less than either's spread)
    excess, excess_se, tie = paired_excess(errors, best, units)
    results["excess_mse"] = [None if np.isnan(e) else float(e) for e in excess]
    results["excess_se"] = [None if np.isnan(e) else float(e) for e in excess_se]
    results["rule"] = {"best": names[best], "tie_mse": float(tie), "units": unit}
    if chosen == best:
        why = (f"{names[chosen]} won: the best held-out RMSE ({rmse[chosen]:.4g} ± {se[chosen]:.2g} N), and no "
               f"simpler model within one standard error of it (standard errors over the {unit})")
    else:
        why = (f"{names[chosen]} won: the simplest of the {int(within.sum())} models within one standard error of "
               f"the best, {names[best]} ({rmse[best]:.4g} ± {se[best]:.2g} N; {names[chosen]} "
               f"{rmse[chosen]:.4g} N; standard errors over the {unit})")
    stock = [k for k, kind in enumerate(results["kind"]) if kind in ("stock", "baseline") and rmse[k] is not None]
    if stock:
        s = min(stock, key=lambda k: rmse[k])
        ratio = rmse[chosen] / rmse[s] if rmse[s] else float("nan")
        if s == chosen:
            why += f". It is the best stock model itself ({names[s]})"
        else:
            gap, gap_se = mean_and_se(errors[chosen] - errors[s], units)
            if abs(ratio - 1.0) <= TIE_TOLERANCE / 2:
                how = "ties it"
            elif ratio < 1.0:
                how = f"beats it by {100 * (1 - ratio):.1f} %"
            elif gap <= gap_se:
                how = "trails it within its standard error (a tie within noise)"
            else:
                how = "trails it by more than one standard error, as the one-SE rule allows for a simpler model"
            why += f"; against the best stock model, {names[s]} ({rmse[s]:.4g} N), it is {ratio:.3f}x: it {how}"
    results["why"] = why + "."



def _has_offsets(estimator: BaseCalibrator) -> bool:
    offsets = estimator.get_params(deep=False).get("group_offsets")
    return isinstance(offsets, (bool, np.bool_)) and bool(offsets)


def _model_without_offsets(estimator: BaseCalibrator) -> tuple[type, dict]:
    """``estimator``'s class and the parameters that make its flexibility (``group_offsets``, the seed, ``alpha`` and
    ``zero_reading`` left out); a degree-1 polynomial is the LTM (its ridge penalises no linear term)."""
    from ..calibrators._linear import LinearCalibrator
    from ..calibrators._polynomial import PolynomialCalibrator

    ignored = ("group_offsets", "random_state", "alpha", "zero_reading")
    params = {k: v for k, v in estimator.get_params(deep=False).items() if k not in ignored}
    if type(estimator) is PolynomialCalibrator and params.get("degree") == 1:
        return LinearCalibrator, {"ridge": 0.0}
    return type(estimator), params


def _same_model(a: tuple[type, dict], b: tuple[type, dict]) -> bool:
    """Whether two :func:`_model_without_offsets` descriptions are equal (arrays compared by value)."""
    return a[0] is b[0] and a[1].keys() == b[1].keys() and all(
        np.array_equal(np.asarray(a[1][key], dtype=object), np.asarray(b[1][key], dtype=object)) for key in a[1])


def _offsets_identifiable(y: NDArray[np.float64], groups: NDArray | None) -> bool:
    """Whether one offset per group can be told from the loads: at least 3 groups (a grouped CV's training folds
    then hold two) within which the loads vary (:func:`~ftcal.calibrators._polynomial.within_group_load_fraction`)."""
    from ..calibrators._polynomial import MIN_WITHIN_FRACTION, within_group_load_fraction

    return groups is not None and np.unique(groups).size >= 3 and \
        within_group_load_fraction(y, groups) >= MIN_WITHIN_FRACTION


def with_alpha_and_tare(estimator, alpha: float, zero_reading):
    """A clone of ``estimator`` with the shared torque scale and, unless it is None, the shared tare (a candidate's
    own measured ``zero_reading`` stays when none is shared)."""
    params = estimator.get_params()
    prefix = "estimator__" if "alpha" not in params and "estimator__alpha" in params else ""
    return with_settings(estimator, **{f"{prefix}alpha": alpha, f"{prefix}zero_reading": zero_reading})


def minimum_training_rows(estimator, n_channels: int) -> int:
    """Fewest training rows on which a held-out score says something about ``estimator`` (N channels), as its tags
    declare (:class:`~ftcal.calibrators._base.CalibrationTags`).

    A candidate cross-validated on folds with fewer training rows is reported
    but never chosen: its score on a handful of rows is noise, and a flexible
    model chosen on it is what extrapolates worst. The rule, by family:
    linear ``N + 2`` (its coefficients plus one); polynomial its
    feature count; the hybrid ``3 (N + 1)``; the GP ``10 N`` (one length
    scale per channel to learn); networks and anything else ``25 N``.

    Examples
    --------
    >>> from ftcal import LinearCalibrator, PolynomialCalibrator
    >>> minimum_training_rows(LinearCalibrator(), 8), minimum_training_rows(PolynomialCalibrator(degree=2), 8)
    (10, 45)
    """
    return int(calibration_tags(estimator).min_training_rows(n_channels))


def _is_network(estimator) -> bool:
    """Whether ``estimator`` is a network that trains with others as one stacked module."""
    tags = calibration_tags(estimator)
    return tags.network and tags.stackable


def _fit(estimator, X, y, groups):
    """Fit, passing ``groups`` when ``estimator``'s metadata routing requests them (``set_fit_request``)."""
    return estimator.fit(X, y, **routed_groups(estimator, groups))


def _rows(y, rows):
    """The ``rows`` of ``y``, an array or a table named by its axes (:func:`~ftcal.core._wrench.named_targets`)."""
    return y.iloc[rows] if hasattr(y, "iloc") else y[rows]


def _out_of_fold(estimator, X, y, folds, groups, network_samples, seed) -> list[tuple[NDArray, NDArray]]:
    """Out-of-fold predictions of ``estimator`` on ``folds``: ``(test rows, their predictions)`` per fold.

    Networks: the K fold models are trained as one stacked fit
    (:func:`ftcal.networks.fit_stacked`), each on at most ``network_samples`` rows of its
    training fold (the same share of every group); everything else fold by
    fold with ftcal's held-out engine (:func:`~ftcal.model_selection._selection.fold_predictions`,
    on :func:`sklearn.model_selection.cross_validate`; ``groups`` when its routing
    requests them, for its own inner model choice), for any subset of the folds,
    so that the folds of one model can run in different jobs (each returns only
    its folds' rows).
    """
    if _is_network(estimator):
        from ..networks._stacked import fit_stacked

        models = [clone(estimator) for _ in folds]
        train = [grouped_subsample(tr, groups, network_samples, seed) for tr, _ in folds]
        fit_stacked(models, [X[t] for t in train], [_rows(y, t) for t in train])
        return [(test, model.predict(X[test])) for model, (_, test) in zip(models, folds)]
    return fold_predictions(estimator, X, y, folds, groups=groups)


def _row_errors(pred: NDArray, y: NDArray, alpha: float, axes=None) -> NDArray:
    """Per-row mean of the squared torque-scaled errors (the torques of ``axes``): their mean is eq. 18's MSE."""
    return np.mean((scale_torques(pred, alpha, axes) - scale_torques(y, alpha, axes)) ** 2, axis=1)


def _nnls_weights(predictions: list[NDArray], target: NDArray) -> NDArray:
    """Non-negative weights of the (torque-scaled) predictions that best fit ``target`` in least squares."""
    design = np.column_stack([p.ravel() for p in predictions])
    weights, _ = nnls(design, target.ravel())
    return weights


def score_candidates(
    candidates, X: NDArray[np.float64], y: NDArray[np.float64], *, groups=None, cv: int = 5, alpha: float,
    zero_reading=None, random_state: int | None = 0, network_samples: int | None = 2000,
    baselines: dict | None = None, stack: bool = False, n_jobs: int | None = None, folds=None, units=None,
    axes=None,
) -> tuple[dict, NDArray[np.float64], list, dict]:
    """Cross-validate every candidate on the same folds; the engine of ``auto`` and ``ftcal benchmark dataset``.

    Every figure is eq. 18's RMSE (over the 6 n torque-scaled values, [N]).
    Candidates whose training folds hold fewer rows than
    :func:`minimum_training_rows` are skipped (recorded, never chosen). A
    candidate that chooses its own structure (the GP's mean and kernel,
    ``structure_params``) chooses it once, fitted on all rows; its clones with
    that structure are then cross-validated (their hyperparameters fitted on
    each training fold alone), at a fifth of the cost. With ``stack``, a
    non-negative combination of the best (up to :data:`STACK_SIZE`) eligible
    candidates is scored too, its weights cross-fitted on the out-of-fold
    predictions (each fold's weights from the other folds' rows).
    ``baselines`` (name -> scikit-learn regressor, e.g.
    :func:`ftcal.calibrators.stock_baselines`) are scored on the same folds and
    never eligible. A candidate whose held-out predictions are degenerate
    (constant, all zero, no better than the mean:
    :func:`~ftcal.model_selection._selection.degenerate_reason`) is recorded as
    refused, never chosen. ``folds`` (train, test) made before replace those of
    :func:`calibration_folds` (``auto``'s fallback when grouped folds cannot
    judge), with ``units`` the units of their standard errors (None: rows).
    ``axes`` names ``y``'s columns (their torques are scaled; default: Fx..Tz for six, else forces only).
    Standard errors are over the groups when the folds hold out
    groups and there are at least
    :data:`~ftcal.model_selection._selection.MIN_SE_GROUPS` of them, with fewer the
    larger of the rows' and the groups' (:func:`~ftcal.model_selection._selection.mean_and_se`), else over rows.
    ``n_jobs`` candidates are scored at once
    (:class:`joblib.Parallel`, processes; ``None`` is 1 unless in a
    :func:`joblib.parallel_config` context); the figures do not depend on it.
    Light work stays in this process whatever ``n_jobs`` says: when every
    job is a closed form (the LTM, polynomials, the hybrid, the stock linear
    and polynomial pipelines) or a kernel model on at most
    :data:`LIGHT_KERNEL_ROWS` training rows (a count of work, not a time).

    Returns
    -------
    results : dict of lists
        Per row: ``name``, ``kind`` (``"candidate"``, ``"stock"`` (a stock
        baseline as a choosable candidate), ``"stack"``, ``"baseline"``),
        ``status`` (``"scored"``, ``"skipped: ..."``, ``"failed: ..."``, ``"refused: ..."``),
        ``eligible``, ``rmse`` (held-out, eq. 18 [N]), ``rmse_se`` (its
        standard error over groups or rows), ``axis_rmse`` (6 values, [N] and
        [N·m]), ``fit_seconds`` (all folds, and the all-rows structure fit); plus ``n_splits``,
        ``min_training_rows`` and, with a stack, ``stack_members`` and
        ``stack_weights``.
    errors : ndarray of shape (n_rows, n_samples)
        Held-out per-row errors (NaN when not scored).
    predictions : list of ndarray of shape (n_samples, 6) or None
        Out-of-fold predictions.
    fitted : dict
        Name -> the candidate fitted on all rows, for those that chose their structure there.
    """
    from joblib import effective_n_jobs
    from sklearn.utils.parallel import Parallel, delayed

    n, n_channels = X.shape
    seed = 0 if random_state is None else int(random_state)
    if folds is None:
        folds, units = calibration_folds(n, groups, cv, seed), se_units(groups)
    # distinct training rows: a repeated row (the same reading and wrench) teaches nothing new
    smallest_train = min(len(np.unique(np.column_stack([X[tr], y[tr]]), axis=0)) for tr, _ in folds)
    results: dict = {k: [] for k in ("name", "kind", "status", "eligible", "rmse", "rmse_se", "axis_rmse",
                                     "fit_seconds")}
    results.update(n_splits=len(folds), min_training_rows=smallest_train)
    errors: list[NDArray] = []
    predictions: list = []

    def record(name, kind, status, eligible, pred, seconds):
        ok = pred is not None
        reason = degenerate_reason(y, pred, alpha=alpha, axes=axes) if ok and kind != "baseline" else None
        if reason is not None:  # scored, shown, never chosen
            status, eligible = f"refused: {reason}", False
        results["name"].append(name)
        results["kind"].append(kind)
        results["status"].append(status)
        results["fit_seconds"].append(seconds)
        results["eligible"].append(bool(eligible and ok))
        row = _row_errors(pred, y, alpha, axes) if ok else np.full(n, np.nan)
        rmse, se = rmse_and_se(row, units) if ok else (None, None)
        results["rmse"].append(rmse)
        results["rmse_se"].append(se)
        results["axis_rmse"].append(np.sqrt(np.mean((pred - y) ** 2, axis=0)).tolist() if ok else None)
        errors.append(row)
        predictions.append(pred)

    rows, tasks = [], []  # (name, kind, skipped status or None); the work of the rows that are fitted
    families = {name: calibration_tags(template).family for name, template in candidates}
    from ..calibrators._baselines import StockCalibrator

    for name, template in candidates:
        estimator = with_alpha_and_tare(template, alpha, zero_reading)
        needed = minimum_training_rows(estimator, n_channels)
        kind = "stock" if isinstance(template, StockCalibrator) else "candidate"
        if smallest_train < needed:  # too few rows to judge it: not fitted, never chosen
            rows.append((name, kind, f"skipped: training folds of {smallest_train} rows < the {needed} it needs"))
            continue
        rows.append((name, kind, None))
        tasks.append((len(rows) - 1, estimator, network_samples))
    for name, regressor in (baselines or {}).items():
        rows.append((name, "baseline", None))
        tasks.append((len(rows) - 1, regressor, None))
    # never more worker processes than cores or jobs (each costs a Python with torch imported), and none when
    # every job is light (no network, kernel models on few rows): starting workers would cost more than the work
    heavy = not all(is_light(est, smallest_train) for _, est, _ in tasks)
    named = named_targets(y, axes)  # each fold's fits get their slice of the named table: they scale its torques

    def run(jobs):  # (row, estimator, network samples, folds, whether it chooses its structure first)
        workers = min(effective_n_jobs(n_jobs), os.cpu_count() or 1, max(len(jobs), 1)) if heavy else 1
        done = Parallel(n_jobs=workers)(delayed(_score_one)(est, X, named, part, groups, samples, seed, choose)
                                       for _, est, samples, part, choose in jobs)
        for (row, *_), outcome in zip(jobs, done):
            outcomes.setdefault(row, []).append(outcome)

    # First the all-rows structure fit of each candidate that chooses its structure, beside a job per fold of
    # every other model but the networks; then that candidate's folds, a job each with its structure fixed (so
    # they share the cores instead of running one after another in one job), beside the networks (one job
    # each, all folds: a stacked fit), which go first there, being the longest jobs. The costliest jobs first in
    # each round, so that the last job to finish is a short one.
    outcomes: dict = {}
    first = [(row, est, samples, [] if _searches(est) else [fold], True)
             for row, est, samples in tasks if not _is_network(est)
             for fold in ([None] if _searches(est) else folds)]
    run(sorted(first, key=lambda job: (not _searches(job[1]), _cost_rank(job[1]))))
    searched = [(row, outcomes[row][0][0], samples) for row, est, samples in tasks if _searches(est)]
    second = [(row, est, samples, folds, True) for row, est, samples in tasks if _is_network(est)]
    second += [(row, clone(fitted).set_params(**fitted.structure_params()), samples, [fold], False)
               for row, fitted, samples in searched if fitted is not None for fold in folds]
    run(second)
    fitted = {}
    for i, (name, kind, skipped) in enumerate(rows):
        if stack and kind == "baseline" and rows[i - 1][1] != "baseline":  # the stack after the candidates
            _score_stack(results, errors, predictions, record, y, alpha, folds, families, axes)
        model, pred, status, seconds = (None, None, skipped, None) if skipped else _merge(outcomes[i], y.shape)
        if model is not None:
            fitted[name] = model
        record(name, kind, status, kind != "baseline" and not skipped, pred, seconds)
    if stack and rows and rows[-1][1] != "baseline":
        _score_stack(results, errors, predictions, record, y, alpha, folds, families, axes)
    results["se_units"] = se_units_name(units)
    return results, np.vstack(errors), predictions, fitted


def _searches(estimator) -> bool:
    """Whether ``estimator`` chooses its structure on all rows first (``chooses_structure``; not a network)."""
    return not _is_network(estimator) and calibration_tags(estimator).chooses_structure


def _merge(parts: list, shape: tuple) -> tuple:
    """One model's ``(fitted, predictions of shape `shape`, status, seconds)`` from its jobs' (one per fold, or one)."""
    failed = [status for _, _, status, _ in parts if status != "scored"]
    if failed:
        return None, None, failed[0], None
    pred = np.full(shape, np.nan)
    for _, folds, _, _ in parts:
        for test, values in folds:
            pred[test] = values
    return parts[0][0], pred, "scored", sum(seconds for *_, seconds in parts)


def is_light(estimator, training_rows: int) -> bool:
    """Whether ``estimator`` fits in a moment (its tags' ``cost``): a closed form, or a kernel model on at most
    :data:`LIGHT_KERNEL_ROWS` rows; anything else (networks, ensembles, wrappers of unknown cost) is not."""
    cost = calibration_tags(estimator).cost
    return cost == "closed_form" or (cost == "kernel" and training_rows <= LIGHT_KERNEL_ROWS)


def _cost_rank(estimator) -> int:
    """Position of ``estimator``'s cost in :data:`~ftcal.calibrators._base.COSTS` (kernel models first)."""
    return COSTS.index(calibration_tags(estimator).cost)


def _score_one(estimator, X, y, folds, groups, network_samples, seed, choose_structure=True):
    """One candidate's (or baseline's) all-rows structure fit, if it has one and ``choose_structure``, and its
    out-of-fold predictions on ``folds`` (none: the structure fit alone).

    Returns ``(fitted on all rows or None, [(test rows, predictions)] per fold or None, status, seconds)``; a
    candidate that cannot fit these data is recorded as failed, not fatal.
    """
    t0 = time.perf_counter()
    try:
        # small matrices: BLAS threads only contend on a shared machine (and with the other jobs)
        with limit_threads_here(1), warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            fitted = None
            if choose_structure and calibration_tags(estimator).chooses_structure:  # once, on all rows
                fitted = _fit(clone(estimator), X, y, groups)
                estimator = clone(estimator).set_params(**fitted.structure_params())
            pred = _out_of_fold(estimator, X, y, folds, groups, network_samples, seed) if folds else []
        return fitted, pred, "scored", time.perf_counter() - t0
    except Exception as exc:
        return None, None, f"failed: {type(exc).__name__}: {' '.join(str(exc).split())[:200]}", None


def _score_stack(results, errors, predictions, record, y, alpha, folds, families: dict, axes=None) -> None:
    """Score the non-negative combination of the best eligible candidates (weights cross-fitted over folds), a
    stock model and ftcal's model of the same family (``families``: name -> tags' family) never both."""
    ranked = sorted((r, k) for k, r in enumerate(results["rmse"]) if results["eligible"][k])
    members: list[int] = []
    for _, k in ranked:
        # a stock model beside ftcal's model of its family (sk_linear and the LTM: the same least squares) adds
        # no kind of model to the combination, only a column its twin already gives (weights split arbitrarily)
        family = families.get(results["name"][k])
        if family and any(families.get(results["name"][j]) == family
                          and "stock" in (results["kind"][j], results["kind"][k]) for j in members):
            continue
        members.append(k)
        if len(members) == STACK_SIZE:
            break
    if len(members) < 2:
        return
    scaled = [scale_torques(predictions[k], alpha, axes) for k in members]
    target = scale_torques(y, alpha, axes)
    oof = np.empty_like(target)
    for train, test in folds:
        w = _nnls_weights([p[train] for p in scaled], target[train])
        oof[test] = sum(wk * p[test] for wk, p in zip(w, scaled))
    weights = _nnls_weights(scaled, target)
    names = [results["name"][k] for k in members]
    results["stack_members"] = names
    results["stack_weights"] = weights.tolist()
    record("stack(" + " + ".join(names) + ")", "stack", "scored", True, unscale_torques(oof, alpha, axes), None)


def provides_std(model) -> bool:
    """Whether ``model.predict(X, return_std=True)`` gives a standard deviation: a Gaussian process, or an
    :class:`AutoCalibrator` that chose one.

    Examples
    --------
    >>> from ftcal import GaussianProcessCalibrator, LinearCalibrator
    >>> provides_std(GaussianProcessCalibrator()), provides_std(LinearCalibrator())
    (True, False)
    """
    return calibration_tags(model).provides_std


def judging_folds(X: NDArray, y: NDArray, groups: NDArray | None, cv: int = 5, seed: int = 0
                  ) -> tuple[list | None, str, NDArray | None]:
    """Folds that can judge a model, what was done to get them, and the units of their standard errors.

    Grouped folds first; if a training fold leaves an output unseen (one group per loaded axis: holding out
    the ``Fx`` group leaves no ``Fx`` load to learn), folds over the rows instead; if those cannot judge
    either, ``None`` (the LTM, unscored). Folds over the rows keep repeated rows (the same reading and
    wrench) together: a copy on both sides of a split would flatter every model that interpolates.

    Examples
    --------
    >>> y = np.repeat(np.eye(6)[:3] * 10, 5, axis=0) * np.tile(np.linspace(-1, 1, 5), 3)[:, None]
    >>> X = y[:, :3] + np.random.default_rng(0).normal(size=(15, 3))
    >>> folds, how, units = judging_folds(X, y, np.repeat([0, 1, 2], 5))
    >>> how.split(":")[0], len(folds)
    ('kfold', 5)
    """
    n = len(y)
    names = WRENCH_LABELS if y.shape[1] == 6 else None
    cv = min(int(cv), n)
    if groups is not None:
        folds = calibration_folds(n, groups, cv, seed)
        unseen = unseen_outputs(y, folds, names)
        if not unseen:
            return folds, "group", se_units(groups)
    _, copies = np.unique(np.column_stack([X, y]), axis=0, return_inverse=True)
    copies = copies.ravel() if np.unique(copies).size < n else None
    distinct = n if copies is None else int(np.unique(copies).size)
    if distinct < 2:
        raise CalibrationInputError(f"X and y hold {n} copies of one row; record different loads.")
    folds = calibration_folds(n, copies, min(cv, distinct), seed)
    kind = "kfold" if copies is None else f"kfold over the {distinct} distinct rows (repeated rows kept together)"
    if groups is None:
        return folds, kind, se_units(copies)
    what = f"{', '.join(unseen)} {'is' if len(unseen) == 1 else 'are'} missing from a training fold"
    if not unseen_outputs(y, folds, names):
        return folds, (f"{kind}: the grouped folds cannot judge a model ({what}, e.g. one group per loaded "
                       f"axis); {len(folds)} folds over the rows instead"), se_units(copies)
    return None, (f"none: no folds can judge a model ({what} even in folds over the rows): the LTM, unscored "
                  "(record each axis' loads in more than one group and more rows)"), None


def training_data_sha256(X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None) -> str:
    """SHA-256 (hex) of training arrays' shapes and float64 values (and of the group labels, which make the
    folds): the identity of the data a comparison was scored on (a report reuses ``auto``'s comparison only on
    the very same rows, grouped the same way).

    Examples
    --------
    >>> a = np.arange(6.0).reshape(3, 2)
    >>> training_data_sha256(a, a) == training_data_sha256(a[:2], a[:2])
    False
    >>> training_data_sha256(a, a, [0, 0, 1]) == training_data_sha256(a, a, [0, 1, 1])
    False
    """
    import hashlib

    digest = hashlib.sha256()
    for a in (X, y):
        a = np.ascontiguousarray(a, dtype=np.float64)
        digest.update(repr(a.shape).encode("ascii"))
        digest.update(a.tobytes())
    if groups is not None:  # the labels themselves: the group folds depend on them, not only on the partition
        labels = np.asarray(groups)
        digest.update(b"groups" + repr((labels.shape, labels.dtype.str)).encode("ascii"))
        digest.update(np.ascontiguousarray(labels).tobytes() if labels.dtype.kind in "biuf"
                      else "\x00".join(map(str, labels.reshape(-1))).encode("utf-8"))
    return digest.hexdigest()


def check_calibration(estimator, X: ArrayLike, y: ArrayLike, *, groups: ArrayLike | None = None, cv: int = 5,
                      random_state: int = 0, predictions: ArrayLike | None = None, held_out: bool = True) -> None:
    """Refuse a fitted calibration that must not be saved: what ``ftcal fit`` calls before it writes a model file.

    Raises :class:`~ftcal.model_selection._selection.DegenerateCalibrationError` (one line, the reason) when the
    model's predictions on ``X`` are constant or all zero, or its held-out predictions (``predictions``, e.g.
    the report's, or else made here on :func:`judging_folds` by
    :func:`~ftcal.model_selection._selection.held_out_predictions`) are degenerate (constant, all zero, no better
    than the mean). A model that chose itself by cross-validation (``auto``: its tags' ``chooses_model``)
    checked its held-out predictions in ``fit``; only its predictions on ``X`` are checked again.
    ``held_out=False`` says the given ``predictions`` are of the training readings (a network fitted without a
    report: a held-out check would train it ``cv`` more times); the refusal then says so.

    Examples
    --------
    >>> from ftcal import LinearCalibrator
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(60, 6)); raw = w @ rng.normal(size=(6, 6))
    >>> check_calibration(LinearCalibrator().fit(raw, w), raw, w)  # nothing to refuse
    """
    from ..model_selection._selection import check_not_degenerate, held_out_predictions

    X, y = np.asarray(X, dtype=float), np.asarray(y, dtype=float)
    alpha, axes = float(getattr(estimator, "alpha_", 1.0)), getattr(estimator, "axes_", None)
    name = type(estimator).__name__
    fitted = np.asarray(estimator.predict(X), dtype=float).reshape(len(X), -1)
    reason = degenerate_reason(y, fitted, alpha=alpha, axes=axes)
    if reason is not None and "mean" not in reason:
        raise DegenerateCalibrationError(f"refusing the fitted {name}: {reason} of its own training data; nothing "
                                         "was saved. Fix: check the data (a constant channel, wrong columns).")
    if predictions is None:
        if calibration_tags(estimator).chooses_model:
            return
        groups = check_groups(groups, len(X))
        folds, _, _ = judging_folds(X, y, groups, cv, random_state)
        if folds is None:
            return
        _, predictions = held_out_predictions(clone(estimator), X, y, groups=groups, folds=folds)
    check_not_degenerate(y, predictions, what=f"the {name}", alpha=alpha, held_out=held_out, axes=axes)


class StackedCalibrator(BaseCalibrator):
    """A non-negative weighted sum of fitted calibrators' predictions (what ``auto`` builds when it pays).

    Parameters
    ----------
    estimators : list of calibrator
        The members (cloned and fitted on all rows by ``fit``).
    weights : array-like of shape (n_members,)
        Non-negative weight of each member (on the torque-scaled wrench; the sum need not be 1).
    alpha, zero_reading : as for every calibrator

    ``fit(X, y, groups=None)`` hands ``groups`` to the members whose metadata
    routing requests them (one offset per group, grouped choices inside);
    ``fitted_estimators`` gives members fitted already (what ``auto`` does: the
    members exactly as it cross-validated them), used as they are.

    Attributes
    ----------
    estimators_ : list of calibrator
        The fitted members.
    weights_ : ndarray of shape (n_members,)

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import LinearCalibrator, PolynomialCalibrator
    >>> from ftcal.compose._auto import StackedCalibrator
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(80, 6)); raw = w @ rng.normal(size=(6, 6))
    >>> s = StackedCalibrator(estimators=[LinearCalibrator(), PolynomialCalibrator(degree=2)],
    ...                       weights=[0.5, 0.5]).fit(raw, w)
    >>> bool(np.allclose(s.predict(raw[:3]), w[:3], atol=1e-6))
    True
    """

    _transient_params = ("estimators",)
    _fitted_state = ("weights_", "estimators_")
    _parameter_constraints: dict = {
        **BaseCalibrator._parameter_constraints,
        "estimators": [list, None],
        "weights": ["array-like"],
    }

    def __init__(self, *, estimators=None, weights=(), alpha=None, zero_reading=None, random_state=None):
        self.estimators = estimators
        self.weights = weights
        self.alpha = alpha
        self.zero_reading = zero_reading
        self.random_state = random_state

    #: Accepts the groups of the rows and passes them on to the members that request them.
    __metadata_request__fit = {"groups": True}

    def get_metadata_routing(self):
        """Routing of ``fit``'s ``groups`` to each member (``member0``, ``member1``, ...)."""
        router = MetadataRouter(owner=self).add_self_request(self)
        for i, member in enumerate(self.estimators or []):
            router.add(**{f"member{i}": member}, method_mapping=MethodMapping().add(caller="fit", callee="fit"))
        return router

    def fit(self, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None, *, fitted_estimators=None):
        """Fit the members on raw readings ``X`` (n, N) and wrenches ``y`` (n, 6) (or take them fitted).

        Parameters
        ----------
        groups : array-like of shape (n,) or None
            Group of each row, routed to the members that request them.
        fitted_estimators : list of fitted calibrators or None
            The members fitted already, one per ``estimators`` entry (``auto`` passes them as it
            cross-validated them: the GP with its structure, networks on their subsample); ``None`` fits clones of
            ``estimators``.

        Returns
        -------
        self
        """
        with limit_threads_here(1):  # as BaseCalibrator.fit
            X, y = self._prepare_fit(X, y)
            members = list(self.estimators or [])
            for member in members:
                refuse_history_inside(member, type(self).__name__)
            self.weights_ = np.asarray(self.weights, dtype=float)
            if not members or self.weights_.shape != (len(members),) or (self.weights_ < 0).any():
                raise CalibrationInputError(
                    f"StackedCalibrator needs a non-empty list of estimators and one non-negative weight each; got "
                    f"{len(members)} estimators and weights {self.weights_.tolist()}.")
            if fitted_estimators is not None:
                fitted = list(fitted_estimators)
                if len(fitted) != len(members):
                    raise CalibrationInputError(
                        f"fitted_estimators holds {len(fitted)} models for the {len(members)} estimators; give one "
                        "fitted model per estimator, in their order.")
                for model in fitted:
                    check_is_fitted(model)
                self.estimators_ = fitted
                return self
            uses = any(routed_groups(e, groups) for e in members)
            groups = check_groups(groups, len(X), labels=uses)
            named = named_targets(y, None if self.axes_ is None else tuple(self.axes_))
            self.estimators_ = [_fit(with_alpha_and_tare(e, self.alpha_, self.zero_reading), X, named, groups)
                                for e in members]
        return self

    def __sklearn_tags__(self):
        members = [calibration_tags(e) for e in self.estimators or []]
        return declare(super().__sklearn_tags__(), uses_groups=any(m.uses_groups for m in members),
                       min_training_rows=lambda n_channels: max([m.min_training_rows(n_channels) for m in members],
                                                                default=25 * n_channels),
                       cost=min((m.cost for m in members), key=COSTS.index, default="heavy"))  # the costliest

    def _predict_wrench(self, X):
        scaled = sum(w * scale_torques(e.predict(X), self.alpha_, self.axes_)
                     for w, e in zip(self.weights_, self.estimators_))
        return unscale_torques(scaled, self.alpha_, self.axes_)

    def _emit_onnx(self, g, x: str) -> str:
        # torque scaling is linear per component, so the weighted sum commutes with it
        terms = [g.op("Mul", g.calibration(e, x), g.const(float(w))) for w, e in zip(self.weights_, self.estimators_)]
        return terms[0] if len(terms) == 1 else g.op("Sum", *terms)


class AutoCalibrator(BaseCalibrator):
    """Choose the calibrator by (grouped) cross-validation, refit it on all data, and keep the comparison.

    No single model wins on every sensor: on real sensors the LTM, a kernel
    method and the thesis' networks each win somewhere, and a random-fold
    score flatters every flexible model. ``fit`` therefore

    1. builds the folds with :func:`~ftcal.model_selection._selection.calibration_folds`:
       with ``groups`` (a pose or load configuration per row, the dataset's
       ``group`` column) whole groups are held out, so the score says how the
       calibration does on poses it has not seen; without, shuffled k-fold;
    2. scores every candidate on those folds, **in this complexity order**
       (simplest first): ``linear`` (the LTM); ``polynomial`` of degree 2 and 3,
       each with ridge 1e-2 and 1e-4 (with ``groups``, at least 3 within which
       the loads vary, the LTM and the degree-2 polynomial with ridge 1e-2 are
       each followed by a twin with one offset per group, ``group_offsets=True``:
       for poses or sessions whose readings shift as a whole); ``axis_nonlinear`` (the hybrid);
       ``gaussian_process`` (its mean and kernel chosen once on all rows by
       marginal likelihood, its hyperparameters refitted on every training
       fold); ``directional`` and ``comparative`` (the ``schedule``'s epochs;
       the K fold models trained as one stacked fit, each on at most
       ``network_samples`` rows, the same share of every group); then, with
       ``stack``, a non-negative combination of the best three (weights
       fitted on out-of-fold predictions, cross-fitted over the folds so its
       score is held out too). There is no time budget: the same data and
       seed give the same choice on any machine;
    3. scores the stock scikit-learn baselines (``baselines``,
       :func:`ftcal.calibrators.stock_baselines`, as :class:`~ftcal.calibrators.StockCalibrator`)
       on the same folds **as candidates**, each placed in the order by what it
       is (``sk_linear`` as simple as the LTM, ``sk_poly2``/``sk_poly3`` beside
       the polynomials, ``sk_kernel_ridge`` and ``sk_gp`` beside the GP; between
       two equally simple models the lower score wins, the earlier a tie): the
       choice never loses to what is free by more than noise, and the stack may
       combine them. If the grouped folds leave an output unseen in training
       (one group per loaded axis), they cannot judge a model: shuffled folds
       over the rows are used instead, or, when even those cannot, the LTM is
       returned unscored (``comparison_["folds"]`` says which). A candidate
       whose held-out predictions are degenerate (constant, all zero, no
       better than the mean) is refused; if every one is, ``fit`` raises
       :class:`~ftcal.model_selection._selection.DegenerateCalibrationError`;
    4. picks by the **one-standard-error rule**
       (:func:`~ftcal.model_selection._selection.simplest_within_one_se`): the
       best-scoring candidate and every one within one paired standard error
       of it (over groups, or rows), or within 0.5 % of its RMSE (a tie:
       ``TIE_TOLERANCE``, 1 % of the mean squared error), qualify, and the
       simplest in the order above wins (a twin with group offsets counts as
       simple as its model without: the same map and one intercept, estimated
       within the groups; between the two the lower score wins). A candidate whose training folds are smaller than
       :func:`minimum_training_rows` is not fitted and never chosen (on 15-50
       dead-weight rows that leaves the LTM and the mildest models);
    5. refits the winner on all rows (``best_estimator_``).

    Every RMSE is eq. 18: over all 6 n torque-scaled values, in [N].
    ``comparison_`` keeps the whole comparison; it is stored in the model file
    and printed by ``ftcal fit --model auto``.

    Parameters
    ----------
    candidates : list of (name, estimator) or None, default=None
        ``None``: :func:`default_candidates` with ``schedule``. Order them
        from the simplest to the most flexible (the 1-SE rule prefers earlier ones);
        with ``groups``, a twin with ``group_offsets=True`` counts as simple as
        its model without offsets (:func:`complexity_ranks`). Names must differ.
    cv : int, default=5
        Number of folds (capped by the number of groups).
    schedule : {"short", "thesis"}, default="short"
        Training schedule of the network candidates.
    stack : bool, default=True
        Also score a non-negative combination of the best candidates.
    baselines : bool or dict, default=True
        ``True``: the stock scikit-learn baselines as choosable candidates (the kernel ones,
        ``sk_kernel_ridge`` and ``sk_gp``, fitted on at most 1000 rows, the GP candidate's ``max_samples``);
        a dict name -> regressor: your own free models instead (placed by their tags' ``family``, else last);
        ``False``: none.
    network_samples : int or None, default=2000
        Most training rows a network candidate sees, in each fold and in the
        final refit (a grouped subsample; ``None``: all).
    n_jobs : int or None, default=-1
        Candidates scored at once, in separate processes (:class:`joblib.Parallel`);
        ``-1`` (the default, as ``ftcal fit``) all cores, ``None`` 1 unless in a
        :func:`joblib.parallel_config` context. Light work (closed forms, kernel
        models on few rows) stays in this process whatever it says; ``fit``'s
        first log line (logger ``ftcal``) says how it scores. The choice and
        every figure are the same for any value.
    alpha : float or None, default=None
        Torque scale ``Fmax / Tmax`` [m⁻¹], shared by every candidate; ``None`` derives it from ``y``.
    zero_reading : array-like of shape (N,) or None, default=None
        Measured tare, given to every candidate; ``None``: each uses its own
        ``zero_reading`` if it has one, else estimates its own.
    random_state : int or None, default=None
        Seed of the folds and subsamples (``None`` = 0, so a fit is reproducible).

    Attributes
    ----------
    best_estimator_ : calibrator
        The chosen candidate (or :class:`StackedCalibrator`), refitted on all data.
    best_name_ : str
        Its name.
    comparison_ : dict
        The comparison (see :func:`score_candidates`), plus ``chosen``, ``folds`` (``"group"``, ``"kfold"``, or
        what was done when the grouped folds could not judge), ``verdict`` (per row: chosen / within one SE but
        more complex / beyond one SE / skipped, failed or refused) and ``why`` (one sentence: why the winner
        won, and its ratio to the best stock model). (``cv_results_``, its
        name before, still answers, with a ``FutureWarning``: scikit-learn's attribute of that name has another
        schema.)
    held_out_predictions_ : ndarray of shape (n_samples, n_outputs) or None
        The chosen row's out-of-fold predictions on the comparison's folds (the wrench, in the units of ``y``;
        ``None`` when no folds could judge), kept in the model file: the calibration report on the same rows
        and folds shows them (the very figures of the comparison), in memory or loaded, instead of refitting
        the choice on every fold in another way (a network on all rows of a fold, a stack with the weights of
        all rows).
    alpha_, zero_reading_, n_features_in_
        As for every calibrator.

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import AutoCalibrator, LinearCalibrator, PolynomialCalibrator
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(200, 6)); raw = w @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(200, 6))
    >>> auto = AutoCalibrator(candidates=[("linear", LinearCalibrator()),
    ...                                   ("polynomial", PolynomialCalibrator(degree=2))],
    ...                       baselines=False).fit(raw, w)
    >>> auto.best_name_
    'linear'
    """

    _fitted_state = ("best_name_", "comparison_", "best_estimator_", "held_out_predictions_")
    #: Fitted attributes earlier model files stored under another name (loaded under the new one).
    _renamed_state = {"cv_results_": "comparison_"}
    #: Parameters of earlier versions that model files may still carry (ignored when loading): the wall-clock
    #: budget, removed because a choice must not depend on the machine's speed.
    _removed_params = ("time_budget",)
    #: The folds hold out whole groups: requested by default (metadata routing, like a group splitter).
    __metadata_request__fit = {"groups": True}
    _parameter_constraints: dict = {
        **BaseCalibrator._parameter_constraints,
        "candidates": [list, tuple, None],
        "cv": [Interval(Integral, 2, None, closed="left")],
        "schedule": [StrOptions({"short", "thesis"})],
        "stack": ["boolean"],
        "baselines": ["boolean", dict],
        "network_samples": [Interval(Integral, 10, None, closed="left"), None],
        "n_jobs": [Interval(Integral, 1, 1024, closed="both"), Interval(Integral, -1024, -1, closed="both"), None],
    }

    def __init__(self, *, candidates=None, cv=5, schedule="short", stack=True, baselines=True,
                 network_samples=2000, n_jobs=-1, alpha=None, zero_reading=None, random_state=None):
        self.candidates = candidates
        self.cv = cv
        self.schedule = schedule
        self.stack = stack
        self.baselines = baselines
        self.network_samples = network_samples
        self.n_jobs = n_jobs
        self.alpha = alpha
        self.zero_reading = zero_reading
        self.random_state = random_state

    def _candidates(self, grouped: bool = False, n_channels: int | None = None) -> list[tuple[str, BaseCalibrator]]:
        """The candidates in their complexity order, the choosable stock baselines placed among them."""
        if self.candidates is None:
            pairs = default_candidates(self.schedule, grouped)
        else:
            pairs = list(self.candidates)
            if not pairs or not all(isinstance(p, tuple) and len(p) == 2 and isinstance(p[1], BaseCalibrator)
                                    for p in pairs):
                raise CalibrationInputError(
                    "candidates must be a non-empty list of (name, calibrator) pairs, e.g. "
                    "[('linear', LinearCalibrator()), ('gp', GaussianProcessCalibrator())]; got "
                    f"{self.candidates!r:.120}."
                )
        pairs = with_stock_candidates(pairs, self._stock(n_channels))
        names = [name for name, _ in pairs]
        repeated = sorted({repr(n) for n in names if names.count(n) > 1})
        if repeated or not all(isinstance(n, str) and n for n in names):
            what = f"{', '.join(repeated)} more than once" if repeated else "a name that is not a non-empty text"
            raise CalibrationInputError(
                f"candidates need one distinct, non-empty text name each (the comparison, the stack and the refit "
                f"find them by name); got {what} in {names!r:.120}: rename them, e.g. 'quadratic' and "
                "'quadratic (group offsets)'.")
        for name, candidate in pairs:  # its shuffled or grouped folds and chunked predict would break a history model
            refuse_history_inside(candidate, type(self).__name__)
            try:  # a user's mistake, said before any fitting rather than as a "failed" row of the table
                candidate._check_parameters()
            except CalibrationInputError as exc:
                raise CalibrationInputError(f"candidate {name!r}: {exc}") from None
        return pairs

    def _stock(self, n_channels: int | None) -> list[tuple[str, BaseCalibrator]]:
        """The choosable free models: the stock baselines (``baselines=True``), a user's own, or none."""
        from ..calibrators._baselines import STOCK_BASELINE_NAMES, StockCalibrator

        seed = 0 if self.random_state is None else int(self.random_state)
        if self.baselines is True:
            return [(name, StockCalibrator(baseline=name, random_state=seed)) for name in STOCK_BASELINE_NAMES]
        if not self.baselines:
            return []
        models = []
        for name, model in dict(self.baselines).items():
            if not (isinstance(name, str) and name and hasattr(model, "fit") and hasattr(model, "predict")):
                raise CalibrationInputError(
                    f"baselines must be True, False or a dict of name -> regressor (with fit and predict); got "
                    f"{name!r}: {model!r:.80}.")
            models.append((name, model if isinstance(model, BaseCalibrator) else
                           StockCalibrator(baseline=model, random_state=seed)))
        return models

    def get_metadata_routing(self):
        """``groups`` make this calibrator's folds and reach each candidate whose routing requests them (its
        default, or ``set_fit_request(groups=...)``): a router with one child per candidate, by name."""
        router = MetadataRouter(owner=self).add_self_request(self)
        try:
            pairs = self._candidates(grouped=True)
        except CalibrationInputError:  # said by fit, with the data
            pairs = []
        for name, candidate in pairs:
            router.add(**{name: candidate}, method_mapping=MethodMapping().add(caller="fit", callee="fit"))
        return router

    def fit(self, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None):
        """Cross-validate the candidates on ``X`` (n, N), ``y`` (n, 6), refit the best on all rows.

        Before the model is kept its held-out predictions are checked
        (:func:`~ftcal.model_selection._selection.check_not_degenerate`): a degenerate
        choice raises :class:`~ftcal.model_selection._selection.DegenerateCalibrationError`.

        Parameters
        ----------
        groups : array-like of shape (n,) or None
            Group of each row (pose, load configuration); folds keep groups
            whole, and each candidate whose routing requests them receives them.
            In a ``Pipeline`` or ``GridSearchCV`` request it with
            ``set_fit_request(groups=True)`` (scikit-learn metadata routing).

        Returns
        -------
        self
        """
        import logging

        self._check_parameters()
        self._candidates()  # checked before the data
        axes = self._remember_axes(y)  # the wrench axes y's columns name: the torques that are scaled
        X, y = validate_training_data(self, X, y)
        groups = check_groups(groups, len(X))
        if groups is not None:  # the candidates' requests (set_fit_request) are validated here
            process_routing(self, "fit", groups=groups)
        candidates = self._candidates(grouped=_offsets_identifiable(y, groups), n_channels=X.shape[1])
        if groups is None and len(X) < self.cv:
            raise CalibrationInputError(
                f"X has {len(X)} rows, fewer than the cv={self.cv} folds; record more rows or lower cv "
                f"(at least 2 and at most {len(X)}).", parameter="X", value=len(X))
        self.alpha_ = resolve_alpha(self.alpha, y, axes)
        given = None if self.zero_reading is None else check_zero_reading(self.zero_reading, X.shape[1])
        seed = 0 if self.random_state is None else int(self.random_state)
        workers = "all cores" if self.n_jobs == -1 else f"n_jobs={self.n_jobs}"
        logging.getLogger("ftcal").info(
            "auto: %d candidates on %d rows, scored %s (AutoCalibrator(n_jobs=...) sets it; light work stays in "
            "this process)", len(candidates), len(X), workers)
        folds, fold_note, units = judging_folds(X, y, groups, self.cv, seed)
        if folds is None:  # nothing can be judged: the LTM, the simplest model, never a stack
            results = _unscored_ltm(fold_note)
            templates = {"linear": make_ltm()}
            candidates = [("linear", templates["linear"])]
            errors, predictions, fitted = None, [None], {}
        else:
            results, errors, predictions, fitted = score_candidates(
                candidates, X, y, groups=groups, cv=self.cv, alpha=self.alpha_, zero_reading=given,
                random_state=seed, network_samples=self.network_samples, stack=self.stack, n_jobs=self.n_jobs,
                folds=folds, units=units, axes=axes)
            templates = dict(candidates)
        named = named_targets(y, axes)  # the chosen model refitted on the named table, as it was scored
        results["folds"] = fold_note
        results["training_sha256"] = training_data_sha256(X, y, groups)  # what the comparison was scored on
        if errors is not None:
            if not any(results["eligible"]):
                why = "; ".join(f"{n}: {st}" for n, st in zip(results["name"], results["status"]))
                raise DegenerateCalibrationError(
                    f"no candidate could be fitted and judged on these data ({why[:400]}); nothing was saved. "
                    "Record more rows (each axis loaded in more than one group) or lower cv.")
            ranks = complexity_ranks(candidates, len(errors))
            chosen = simplest_within_one_se(errors, units, eligible=results["eligible"], complexity=ranks)
            explain_choice(results, errors, units, chosen, ranks)
        self.comparison_ = results
        self.best_name_ = results["chosen"]
        # the winner's out-of-fold predictions, for a report on the same folds
        self.held_out_predictions_ = predictions[results["name"].index(self.best_name_)]

        def refit(name):
            """A candidate on all rows (networks on their grouped subsample), as it was cross-validated."""
            if name in fitted:  # fitted on all rows already, when it chose its structure
                return fitted[name]
            model = with_alpha_and_tare(templates[name], self.alpha_, given)
            rows = grouped_subsample(np.arange(len(X)), groups, self.network_samples, seed) \
                if _is_network(model) else np.arange(len(X))
            return _fit(model, X[rows], _rows(named, rows), None if groups is None else groups[rows])

        if results["kind"][results["name"].index(self.best_name_)] == "stack":
            members = results["stack_members"]
            best = StackedCalibrator(estimators=[templates[n] for n in members], weights=results["stack_weights"],
                                     alpha=self.alpha_, zero_reading=given)
            self.best_estimator_ = best.fit(X, named, fitted_estimators=[refit(n) for n in members])
        else:
            self.best_estimator_ = refit(self.best_name_)
        self._adopt_fitted(X, y, self.best_estimator_)
        return self

    @property
    def cv_results_(self) -> dict:
        """Deprecated name of :attr:`comparison_` (scikit-learn's ``cv_results_`` has another schema)."""
        warnings.warn("AutoCalibrator.cv_results_ is renamed comparison_ (scikit-learn's cv_results_ has another "
                      "schema); cv_results_ will be removed in a future release.", FutureWarning, stacklevel=2)
        return self.comparison_

    def __sklearn_tags__(self):
        # chooses a model by cross-validation: a wrapper that refits its estimator many times (the history term)
        # fits it once and refits the model it chose (HistoryCalibrator); a standard deviation if the chosen one has
        best = self.__dict__.get("best_estimator_")
        return declare(super().__sklearn_tags__(), chooses_model=True, uses_groups=True,
                       provides_std=best is not None and calibration_tags(best).provides_std)

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.best_estimator_.predict(X)

    def _emit_onnx(self, g, x: str) -> str:
        return g.calibration(self.best_estimator_, x)

    def predict(self, X: ArrayLike, return_std: bool = False):
        """Wrench [N, N·m] for raw readings ``X``; with ``return_std`` also the chosen model's standard deviation.

        ``return_std=True`` needs a chosen model that gives one (the Gaussian
        process); otherwise a :class:`~ftcal.core.CalibrationInputError` says which was chosen.
        """
        from ..core._validation import check_bool

        if not check_bool(return_std, "return_std"):
            return super().predict(X)
        check_is_fitted(self)
        if not provides_std(self.best_estimator_):
            raise CalibrationInputError(
                f"return_std=True: the chosen model {self.best_name_!r} gives no standard deviation; only the "
                "Gaussian process does (use AutoCalibrator(candidates=[('gaussian_process', "
                "GaussianProcessCalibrator())]) or a GaussianProcessCalibrator for uncertainties).")
        from ..core._validation import validate_readings

        return self.best_estimator_.predict(self._retared(validate_readings(self, X)), return_std=True)

    def summary(self) -> str:
        """The comparison as a markdown table (held-out RMSE ± standard error, fit time, status)."""
        return comparison_table(self.comparison_)


def comparison_table(results: dict) -> str:
    """``comparison_`` (or ``ftcal benchmark dataset``'s results) as a markdown table, baselines marked, and under
    it, when the choice was explained (:func:`explain_choice`), one line saying why the winner won.

    The RMSE is eq. 18 over all 6 n torque-scaled values [N]; the ratio column
    is each row's RMSE over the best stock model's (a choosable ``stock`` row or a ``baseline``); the status
    column says, per row, chosen / within one SE but more complex / beyond one SE / skipped / failed / refused.
    When the choice was explained, two columns and a line under the table give what the one-SE rule compared, so
    that every verdict can be checked: each row's excess mean squared error over the best and the **paired**
    standard error of that excess (:func:`~ftcal.model_selection._selection.paired_excess`). A row's own ``± SE`` may
    overlap the best's while the row is beyond one SE: the paired SE is smaller when both err on the same rows.
    """
    base = [r for r, k in zip(results["rmse"], results["kind"]) if k in ("baseline", "stock") and r is not None]
    best_base = min(base) if base else None
    verdicts = results.get("verdict") or results["status"]
    rule = results.get("rule")  # what the one-SE rule compared (explain_choice), when the choice was explained
    head = "| model | kind | held-out RMSE (eq. 18) [N] | ± SE | / best stock model | fit [s, all folds] | "
    head += "excess MSE over best [N²] | ± paired SE [N²] | status |" if rule else "status |"
    lines = [head, "|---" * (9 if rule else 7) + "|"]
    number = lambda v, form: "" if v is None else format(v, form)  # noqa: E731
    for i, name in enumerate(results["name"]):
        rmse = results["rmse"][i]
        cells = [number(rmse, ".4g"), number(results["rmse_se"][i], ".2g"),
                 "" if rmse is None or not best_base else f"{rmse / best_base:.3f}",
                 number(results["fit_seconds"][i], ".1f")]
        if rule:
            cells += [number(results["excess_mse"][i], ".3g"), number(results["excess_se"][i], ".2g")]
        mark = " **(chosen)**" if name == results.get("chosen") else ""
        lines.append(f"| {name}{mark} | {results['kind'][i]} | " + " | ".join(cells) + f" | {verdicts[i]} |")
    if rule:
        lines += ["", f"One-SE rule: a row is within one SE of the best ({rule['best']}) when its excess mean squared "
                      f"error over the best is at most its paired SE (the spread of the differences from the best over "
                      f"the {rule['units']}, not the row's own ± SE) or the tie margin "
                      f"{rule['tie_mse']:.3g} N² ({100 * TIE_TOLERANCE:g} % of the best's)."]
    if results.get("why"):
        lines += ["", results["why"]]
    return "\n".join(lines)
