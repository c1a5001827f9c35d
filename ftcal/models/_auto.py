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
from sklearn import config_context
from sklearn.base import clone
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.validation import check_is_fitted

from ..calibrators._history import refuse_history_inside
from ..calibrators._base import BaseCalibrator, GroupsFit, calibrated_range, resolve_alpha, with_settings
from ..core._exceptions import CalibrationInputError
from ..core._model_selection import (calibration_folds, check_groups, grouped_subsample, rmse_and_se,
                                     simplest_within_one_se)
from ..core._threads import limit_threads_here
from ..core._validation import check_zero_reading, validate_training_data
from ..core._wrench import scale_torques, unscale_torques
from ..calibrators._zero_load import estimate_zero_reading, reading_noise

__all__ = ["AutoCalibrator", "StackedCalibrator", "provides_std", "comparison_table", "default_candidates", "score_candidates",
           "with_alpha_and_tare", "minimum_training_rows"]

#: Most candidates a stack combines (the best-scoring eligible ones).
STACK_SIZE = 3
#: Training rows up to which a kernel model's fit is light work: with no network to train either, the candidates
#: are scored in this process (worker processes would take longer to start than the fits).
LIGHT_KERNEL_ROWS = 200


def default_candidates(schedule: str = "short", grouped: bool = False) -> list[tuple[str, BaseCalibrator]]:
    """The candidates of :class:`AutoCalibrator`, in the documented complexity order (simplest first).

    ``grouped`` (the rows come in groups, at least 3, within which the loads vary): each of ``linear`` and
    ``polynomial(degree=2, ridge=0.01)`` is followed by its twin with one offset per group
    (``group_offsets=True``, see :class:`~ftcal.PolynomialCalibrator`).

    Examples
    --------
    >>> [name for name, _ in default_candidates()][:3]
    ['linear', 'polynomial(degree=2, ridge=0.01)', 'polynomial(degree=2, ridge=0.0001)']
    >>> [name for name, _ in default_candidates(grouped=True)][:3]
    ['linear', 'linear(group offsets)', 'polynomial(degree=2, ridge=0.01)']
    """
    from ._registry import make_calibrator

    candidates: list[tuple[str, BaseCalibrator]] = [("linear", make_calibrator("linear"))]
    if grouped:
        candidates.append(("linear(group offsets)", make_calibrator("polynomial", degree=1, group_offsets=True)))
    for degree in (2, 3):
        for ridge in (1e-2, 1e-4):
            candidates.append((f"polynomial(degree={degree}, ridge={ridge:g})",
                               make_calibrator("polynomial", degree=degree, ridge=ridge)))
            if grouped and degree == 2 and ridge == 1e-2:
                candidates.append((f"polynomial(degree={degree}, ridge={ridge:g}, group offsets)", make_calibrator(
                    "polynomial", degree=degree, ridge=ridge, group_offsets=True)))
    candidates.append(("axis_nonlinear", make_calibrator("axis_nonlinear")))
    candidates.append(("gaussian_process", make_calibrator("gaussian_process", random_state=0)))
    for name in ("directional", "comparative"):
        candidates.append((name, make_calibrator(name, schedule=schedule, random_state=0)))
    return candidates


def complexity_ranks(candidates: list[tuple[str, BaseCalibrator]], n_rows: int) -> NDArray[np.int64]:
    """The complexity of each row of the comparison for the one-SE rule, when the rows come in groups.

    Each row's rank is its position, except that a candidate with one offset per group (``group_offsets=True``)
    and the same model without them (the LTM for ``degree=1``), listed before or after it, share the earlier of
    their two positions. Both predict with the same map and one intercept, so they are equally flexible: the offsets
    change how the map is estimated (within the groups, free of their shifts), not what it can fit, and between the
    two the lower score decides (:func:`~ftcal.core._model_selection.simplest_within_one_se`). ``alpha`` and
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
    return ranks


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
    """Fewest training rows on which a held-out score says something about ``estimator`` (N channels).

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
    from ..calibrators._axis_nonlinear import AxisNonlinearCalibrator
    from ..calibrators._gaussian_process import GaussianProcessCalibrator
    from ..calibrators._linear import LinearCalibrator
    from ..calibrators._polynomial import PolynomialCalibrator

    if isinstance(estimator, LinearCalibrator):
        return n_channels + 2
    if isinstance(estimator, PolynomialCalibrator):
        return comb(n_channels + int(estimator.degree), int(estimator.degree))
    if isinstance(estimator, AxisNonlinearCalibrator):
        return 3 * (n_channels + 1)
    if isinstance(estimator, GaussianProcessCalibrator):
        return 10 * n_channels
    return 25 * n_channels


def _is_network(estimator) -> bool:
    from ..neural_network._base import NetworkCalibrator

    return isinstance(estimator, NetworkCalibrator) and not estimator.callbacks


def _fit(estimator, X, y, groups):
    """Fit, passing ``groups`` to estimators whose ``fit`` takes them (routing off: they are ours, not a user's)."""
    import inspect

    with config_context(enable_metadata_routing=False):
        if groups is not None and "groups" in inspect.signature(estimator.fit).parameters:
            return estimator.fit(X, y, groups=groups)
        return estimator.fit(X, y)


def _out_of_fold(estimator, X, y, folds, groups, network_samples, seed) -> list[tuple[NDArray, NDArray]]:
    """Out-of-fold predictions of ``estimator`` on ``folds``: ``(test rows, their predictions)`` per fold.

    Networks: the K fold models are trained as one stacked fit
    (:func:`ftcal.fit_stacked`), each on at most ``network_samples`` rows of its
    training fold (the same share of every group); everything else fold by
    fold, as :func:`sklearn.model_selection.cross_val_predict` does (with
    ``groups`` when its ``fit`` takes them, for its own inner model choice),
    but for any subset of the folds, so that the folds of one model can run
    in different jobs (each returns only its folds' rows).
    """
    if _is_network(estimator):
        from ..neural_network._stacked import fit_stacked

        models = [clone(estimator) for _ in folds]
        train = [grouped_subsample(tr, groups, network_samples, seed) for tr, _ in folds]
        fit_stacked(models, [X[t] for t in train], [y[t] for t in train])
        return [(test, model.predict(X[test])) for model, (_, test) in zip(models, folds)]
    return [(test, _fit(clone(estimator), X[train], y[train], None if groups is None else groups[train]).predict(
        X[test])) for train, test in folds]


def _row_errors(pred: NDArray, y: NDArray, alpha: float) -> NDArray:
    """Per-row mean of the six squared torque-scaled errors: their mean is eq. 18's MSE."""
    return np.mean((scale_torques(pred, alpha) - scale_torques(y, alpha)) ** 2, axis=1)


def _nnls_weights(predictions: list[NDArray], target: NDArray) -> NDArray:
    """Non-negative weights of the (torque-scaled) predictions that best fit ``target`` in least squares."""
    design = np.column_stack([p.ravel() for p in predictions])
    weights, _ = nnls(design, target.ravel())
    return weights


def score_candidates(
    candidates, X: NDArray[np.float64], y: NDArray[np.float64], *, groups=None, cv: int = 5, alpha: float,
    zero_reading=None, random_state: int | None = 0, network_samples: int | None = 2000,
    baselines: dict | None = None, stack: bool = False, n_jobs: int | None = None,
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
    :func:`ftcal.models.stock_baselines`) are scored on the same folds and
    never eligible. ``n_jobs`` candidates are scored at once
    (:class:`joblib.Parallel`, processes; ``None`` is 1 unless in a
    :func:`joblib.parallel_config` context); the figures do not depend on it.
    Light work stays in this process whatever ``n_jobs`` says: when every
    job is a closed form (the LTM, polynomials, the hybrid, the stock linear
    and polynomial pipelines) or a kernel model on at most
    :data:`LIGHT_KERNEL_ROWS` training rows (a count of work, not a time).

    Returns
    -------
    results : dict of lists
        Per row: ``name``, ``kind`` (``"candidate"``, ``"stack"``,
        ``"baseline"``), ``status`` (``"scored"``, ``"skipped: ..."``, ``"failed: ..."``),
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
    folds = calibration_folds(n, groups, cv, seed)
    smallest_train = min(len(tr) for tr, _ in folds)
    results: dict = {k: [] for k in ("name", "kind", "status", "eligible", "rmse", "rmse_se", "axis_rmse",
                                     "fit_seconds")}
    results.update(n_splits=len(folds), min_training_rows=smallest_train)
    errors: list[NDArray] = []
    predictions: list = []

    def record(name, kind, status, eligible, pred, seconds):
        results["name"].append(name)
        results["kind"].append(kind)
        results["status"].append(status)
        results["fit_seconds"].append(seconds)
        ok = pred is not None
        results["eligible"].append(bool(eligible and ok))
        row = _row_errors(pred, y, alpha) if ok else np.full(n, np.nan)
        rmse, se = rmse_and_se(row, groups) if ok else (None, None)
        results["rmse"].append(rmse)
        results["rmse_se"].append(se)
        results["axis_rmse"].append(np.sqrt(np.mean((pred - y) ** 2, axis=0)).tolist() if ok else None)
        errors.append(row)
        predictions.append(pred)

    rows, tasks = [], []  # (name, kind, skipped status or None); the work of the rows that are fitted
    for name, template in candidates:
        estimator = with_alpha_and_tare(template, alpha, zero_reading)
        needed = minimum_training_rows(estimator, n_channels)
        if smallest_train < needed:  # too few rows to judge it: not fitted, never chosen
            rows.append((name, "candidate", f"skipped: training folds of {smallest_train} rows < the {needed} it "
                                            "needs"))
            continue
        rows.append((name, "candidate", None))
        tasks.append((len(rows) - 1, estimator, network_samples))
    for name, regressor in (baselines or {}).items():
        rows.append((name, "baseline", None))
        tasks.append((len(rows) - 1, regressor, None))
    # a job per fold (a stacked network fit and a structure search take all folds in one), the costliest first
    # (kernel models, then networks), so that the last job to finish is a short one
    jobs = [(row, est, samples, [fold] if _per_fold(est) else folds)
            for row, est, samples in tasks for fold in (folds if _per_fold(est) else [None])]
    jobs.sort(key=lambda job: _cost_rank(job[1]))
    # never more worker processes than cores or jobs (each costs a Python with torch imported), and none when
    # every job is light (no network, kernel models on few rows): starting workers would cost more than the work
    heavy = not all(_is_light(est, smallest_train) for _, est, _ in tasks)
    workers = min(effective_n_jobs(n_jobs), os.cpu_count() or 1, max(len(jobs), 1)) if heavy else 1
    done = Parallel(n_jobs=workers)(delayed(_score_one)(est, X, y, part, groups, samples, seed)
                                   for _, est, samples, part in jobs)
    outcomes: dict = {}
    for (row, *_), outcome in zip(jobs, done):
        outcomes.setdefault(row, []).append(outcome)
    fitted = {}
    for i, (name, kind, skipped) in enumerate(rows):
        if stack and kind == "baseline" and rows[i - 1][1] == "candidate":  # the stack after the candidates
            _score_stack(results, errors, predictions, record, y, alpha, folds)
        model, pred, status, seconds = (None, None, skipped, None) if skipped else _merge(outcomes[i], y.shape)
        if model is not None:
            fitted[name] = model
        record(name, kind, status, kind == "candidate" and not skipped, pred, seconds)
    if stack and rows and rows[-1][1] == "candidate":
        _score_stack(results, errors, predictions, record, y, alpha, folds)
    return results, np.vstack(errors), predictions, fitted


def _per_fold(estimator) -> bool:
    """Whether ``estimator``'s folds may run as separate jobs (not a stacked network, not a structure search)."""
    return not _is_network(estimator) and not hasattr(estimator, "structure_params")


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


def _is_light(estimator, training_rows: int) -> bool:
    """Whether ``estimator`` fits in a moment: a closed form (ftcal's or a stock linear / polynomial pipeline) or a
    kernel model on at most :data:`LIGHT_KERNEL_ROWS` rows; anything else (networks, ensembles, wrappers) is not."""
    from sklearn.linear_model import LinearRegression, Ridge, RidgeCV
    from sklearn.pipeline import Pipeline
    from sklearn.preprocessing import PolynomialFeatures, StandardScaler

    from ..calibrators._axis_nonlinear import AxisNonlinearCalibrator
    from ..calibrators._linear import LinearCalibrator
    from ..calibrators._polynomial import PolynomialCalibrator

    if _cost_rank(estimator) == 0:
        return training_rows <= LIGHT_KERNEL_ROWS
    closed = (LinearCalibrator, PolynomialCalibrator, AxisNonlinearCalibrator, LinearRegression, Ridge, RidgeCV)
    steps = [step for _, step in estimator.steps] if isinstance(estimator, Pipeline) else [estimator]
    return all(isinstance(step, (*closed, StandardScaler, PolynomialFeatures)) for step in steps) and \
        isinstance(steps[-1], closed)


def _cost_rank(estimator) -> int:
    """0 for kernel models (the GP, the stock kernel baselines: cubic in the rows), 1 for networks, 2 the rest."""
    from ..calibrators._gaussian_process import GaussianProcessCalibrator
    from ._baselines import SubsampledRegressor

    if isinstance(estimator, (GaussianProcessCalibrator, SubsampledRegressor)):
        return 0
    return 1 if _is_network(estimator) else 2


def _score_one(estimator, X, y, folds, groups, network_samples, seed):
    """One candidate's (or baseline's) all-rows structure fit, if it has one, and out-of-fold predictions.

    Returns ``(fitted on all rows or None, [(test rows, predictions)] per fold or None, status, seconds)``; a
    candidate that cannot fit these data is recorded as failed, not fatal.
    """
    t0 = time.perf_counter()
    try:
        # small matrices: BLAS threads only contend on a shared machine (and with the other jobs)
        with limit_threads_here(1), warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            fitted = None
            if hasattr(estimator, "structure_params"):  # choose the structure once, on all rows
                fitted = _fit(clone(estimator), X, y, groups)
                estimator = clone(estimator).set_params(**fitted.structure_params())
            pred = _out_of_fold(estimator, X, y, folds, groups, network_samples, seed)
        return fitted, pred, "scored", time.perf_counter() - t0
    except Exception as exc:
        return None, None, f"failed: {type(exc).__name__}: {' '.join(str(exc).split())[:200]}", None


def _score_stack(results, errors, predictions, record, y, alpha, folds) -> None:
    """Score the non-negative combination of the best eligible candidates (weights cross-fitted over folds)."""
    ranked = sorted((r, k) for k, r in enumerate(results["rmse"]) if results["eligible"][k])
    members = [k for _, k in ranked[:STACK_SIZE]]
    if len(members) < 2:
        return
    scaled = [scale_torques(predictions[k], alpha) for k in members]
    target = scale_torques(y, alpha)
    oof = np.empty_like(target)
    for train, test in folds:
        w = _nnls_weights([p[train] for p in scaled], target[train])
        oof[test] = sum(wk * p[test] for wk, p in zip(w, scaled))
    weights = _nnls_weights(scaled, target)
    names = [results["name"][k] for k in members]
    results["stack_members"] = names
    results["stack_weights"] = weights.tolist()
    record("stack(" + " + ".join(names) + ")", "stack", "scored", True, unscale_torques(oof, alpha), None)


def provides_std(model) -> bool:
    """Whether ``model.predict(X, return_std=True)`` gives a standard deviation: a Gaussian process, or an
    :class:`AutoCalibrator` that chose one.

    Examples
    --------
    >>> from ftcal import GaussianProcessCalibrator, LinearCalibrator
    >>> provides_std(GaussianProcessCalibrator()), provides_std(LinearCalibrator())
    (True, False)
    """
    import inspect

    inner = getattr(model, "best_estimator_", model)
    return "return_std" in inspect.signature(inner.predict).parameters


class StackedCalibrator(GroupsFit, BaseCalibrator):
    """A non-negative weighted sum of fitted calibrators' predictions (what ``auto`` builds when it pays).

    Parameters
    ----------
    estimators : list of calibrator
        The members (cloned and fitted on all rows by ``fit``).
    weights : array-like of shape (n_members,)
        Non-negative weight of each member (on the torque-scaled wrench; the sum need not be 1).
    alpha, zero_reading : as for every calibrator

    ``fit(X, y, groups=None)`` hands ``groups`` to the members that use them
    (one offset per group, grouped choices inside).

    Attributes
    ----------
    estimators_ : list of calibrator
        The fitted members.
    weights_ : ndarray of shape (n_members,)

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import LinearCalibrator, PolynomialCalibrator
    >>> from ftcal.models._auto import StackedCalibrator
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

    def _fit(self, X, y) -> None:
        members = list(self.estimators or [])
        for member in members:
            refuse_history_inside(member, type(self).__name__)
        self.weights_ = np.asarray(self.weights, dtype=float)
        if not members or self.weights_.shape != (len(members),) or (self.weights_ < 0).any():
            raise CalibrationInputError(
                f"StackedCalibrator needs a non-empty list of estimators and one non-negative weight each; got "
                f"{len(members)} estimators and weights {self.weights_.tolist()}.")
        # AutoCalibrator hands over the members exactly as it cross-validated them (the GP with its structure,
        # networks on their subsample, with the groups); a clone has none and fits its templates
        self.estimators_ = self.__dict__.pop("_fitted_members", None) or [
            _fit(with_alpha_and_tare(e, self.alpha_, self.zero_reading), X, y, self._fit_groups) for e in members]

    def _uses_groups(self) -> bool:
        return any(isinstance(e, GroupsFit) and e._uses_groups() for e in self.estimators or [])

    def _predict_wrench(self, X):
        scaled = sum(w * scale_torques(e.predict(X), self.alpha_) for w, e in zip(self.weights_, self.estimators_))
        return unscale_torques(scaled, self.alpha_)

    def _emit_onnx(self, g, x: str) -> str:
        # torque scaling is linear per component, so the weighted sum commutes with it
        terms = [g.op("Mul", g.calibration(e, x), g.const(float(w))) for w, e in zip(self.weights_, self.estimators_)]
        return terms[0] if len(terms) == 1 else g.op("Sum", *terms)


class AutoCalibrator(BaseCalibrator):
    """Choose the calibrator by (grouped) cross-validation, refit it on all data, and keep the comparison.

    No single model wins on every sensor: on real sensors the LTM, a kernel
    method and the thesis' networks each win somewhere, and a random-fold
    score flatters every flexible model. ``fit`` therefore

    1. builds the folds with :func:`~ftcal.core._model_selection.calibration_folds`:
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
    3. reports the stock scikit-learn baselines (``baselines``,
       :func:`ftcal.models.stock_baselines`) on the same folds, never chosen:
       the margin over what is free;
    4. picks by the **one-standard-error rule**
       (:func:`~ftcal.core._model_selection.simplest_within_one_se`): the
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
    ``cv_results_`` keeps the whole comparison; it is stored in the model file
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
    baselines : bool, default=True
        Report the stock scikit-learn baselines beside (never chosen); the kernel ones
        (``sk_kernel_ridge``, ``sk_gp``) fitted on at most 1000 rows, the GP candidate's ``max_samples``.
    network_samples : int or None, default=2000
        Most training rows a network candidate sees, in each fold and in the
        final refit (a grouped subsample; ``None``: all).
    n_jobs : int or None, default=None
        Candidates scored at once, in separate processes (:class:`joblib.Parallel`);
        ``None`` is 1 unless in a :func:`joblib.parallel_config` context, ``-1``
        all cores. The choice and every figure are the same for any value.
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
    cv_results_ : dict
        The comparison (see :func:`score_candidates`), plus ``chosen`` and ``folds``.
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

    _fitted_state = ("best_name_", "cv_results_", "best_estimator_")
    #: Chooses a model by cross-validation: a wrapper that refits its estimator many times (the history term)
    #: fits it once and refits the model it chose (:class:`~ftcal.HistoryCalibrator`).
    _chooses_a_model = True
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
        "baselines": ["boolean"],
        "network_samples": [Interval(Integral, 10, None, closed="left"), None],
        "n_jobs": [Interval(Integral, 1, 1024, closed="both"), Interval(Integral, -1024, -1, closed="both"), None],
    }

    def __init__(self, *, candidates=None, cv=5, schedule="short", stack=True, baselines=True,
                 network_samples=2000, n_jobs=None, alpha=None, zero_reading=None, random_state=None):
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

    def _candidates(self, grouped: bool = False) -> list[tuple[str, BaseCalibrator]]:
        if self.candidates is None:
            return default_candidates(self.schedule, grouped)
        pairs = list(self.candidates)
        if not pairs or not all(isinstance(p, tuple) and len(p) == 2 and isinstance(p[1], BaseCalibrator)
                                for p in pairs):
            raise CalibrationInputError(
                "candidates must be a non-empty list of (name, calibrator) pairs, e.g. "
                "[('linear', LinearCalibrator()), ('gp', GaussianProcessCalibrator())]; got "
                f"{self.candidates!r:.120}."
            )
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

    def fit(self, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None):
        """Cross-validate the candidates on ``X`` (n, N), ``y`` (n, 6), refit the best on all rows.

        Parameters
        ----------
        groups : array-like of shape (n,) or None
            Group of each row (pose, load configuration); folds keep groups
            whole. In a ``Pipeline`` or ``GridSearchCV`` request it with
            ``set_fit_request(groups=True)`` (scikit-learn metadata routing).

        Returns
        -------
        self
        """
        from ._baselines import stock_baselines

        self._check_parameters()
        self._candidates()  # checked before the data
        X, y = validate_training_data(self, X, y)
        groups = check_groups(groups, len(X))
        candidates = self._candidates(grouped=_offsets_identifiable(y, groups))
        if groups is None and len(X) < self.cv:
            raise CalibrationInputError(
                f"X has {len(X)} rows, fewer than the cv={self.cv} folds; record more rows or lower cv "
                f"(at least 2 and at most {len(X)}).", parameter="X", value=len(X))
        self.alpha_ = resolve_alpha(self.alpha, y)
        given = None if self.zero_reading is None else check_zero_reading(self.zero_reading, X.shape[1])
        seed = 0 if self.random_state is None else int(self.random_state)
        results, errors, _, fitted = score_candidates(
            candidates, X, y, groups=groups, cv=self.cv, alpha=self.alpha_, zero_reading=given,
            random_state=seed, network_samples=self.network_samples, stack=self.stack, n_jobs=self.n_jobs,
            # the stock kernel models on as many rows as ftcal's GP (its default max_samples): the same budget
            baselines=stock_baselines(X.shape[1], random_state=seed)
            if self.baselines else None,
        )
        if not any(results["eligible"]):
            why = "; ".join(f"{n}: {st}" for n, st in zip(results["name"], results["status"]))
            raise CalibrationInputError(f"no candidate could be fitted and judged on these data ({why[:400]}); "
                                        "record more rows or lower cv.")
        ranks = None if groups is None else complexity_ranks(candidates, len(errors))  # twins: only with groups
        chosen = simplest_within_one_se(errors, groups, eligible=results["eligible"], complexity=ranks)
        results["chosen"] = results["name"][chosen]
        results["folds"] = "group" if groups is not None else "kfold"
        self.cv_results_ = results
        self.best_name_ = results["name"][chosen]
        templates = dict(candidates)

        def refit(name):
            """A candidate on all rows (networks on their grouped subsample), as it was cross-validated."""
            if name in fitted:  # fitted on all rows already, when it chose its structure
                return fitted[name]
            model = with_alpha_and_tare(templates[name], self.alpha_, given)
            rows = grouped_subsample(np.arange(len(X)), groups, self.network_samples, seed) \
                if _is_network(model) else np.arange(len(X))
            return _fit(model, X[rows], y[rows], None if groups is None else groups[rows])

        if results["kind"][chosen] == "stack":
            best = StackedCalibrator(estimators=[templates[n] for n in results["stack_members"]],
                                     weights=results["stack_weights"], alpha=self.alpha_, zero_reading=given)
            best._fitted_members = [refit(n) for n in results["stack_members"]]
            self.best_estimator_ = best.fit(X, y)
        else:
            self.best_estimator_ = refit(self.best_name_)
        best_zero = getattr(self.best_estimator_, "zero_reading_", None)
        self.zero_reading_ = estimate_zero_reading(X, y, self.alpha_) if best_zero is None else np.asarray(best_zero)
        self.reading_noise_ = reading_noise(X, y)
        self.calibrated_range_ = calibrated_range(X)
        self.__dict__.pop("tare_reading_", None)
        return self

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.best_estimator_.predict(X)

    def _emit_onnx(self, g, x: str) -> str:
        return g.calibration(self.best_estimator_, x)

    def predict(self, X: ArrayLike, return_std: bool = False):
        """Wrench [N, N·m] for raw readings ``X``; with ``return_std`` also the chosen model's standard deviation.

        ``return_std=True`` needs a chosen model that gives one (the Gaussian
        process); otherwise a :class:`~ftcal.CalibrationInputError` says which was chosen.
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
        return comparison_table(self.cv_results_)


def comparison_table(results: dict) -> str:
    """``cv_results_`` (or ``ftcal benchmark dataset``'s results) as a markdown table, baselines marked.

    The RMSE is eq. 18 over all 6 n torque-scaled values [N]; the ratio column
    is each row's RMSE over the best stock baseline's.
    """
    base = [r for r, k in zip(results["rmse"], results["kind"]) if k == "baseline" and r is not None]
    best_base = min(base) if base else None
    lines = ["| model | kind | held-out RMSE (eq. 18) [N] | ± SE | / best stock baseline | fit [s, all folds] | "
             "status |", "|---|---|---|---|---|---|---|"]
    for i, name in enumerate(results["name"]):
        rmse = results["rmse"][i]
        cells = ["" if rmse is None else f"{rmse:.4g}",
                 "" if results["rmse_se"][i] is None else f"{results['rmse_se'][i]:.2g}",
                 "" if rmse is None or not best_base else f"{rmse / best_base:.3f}",
                 "" if results["fit_seconds"][i] is None else f"{results['fit_seconds'][i]:.1f}"]
        mark = " **(chosen)**" if name == results.get("chosen") else ""
        lines.append(f"| {name}{mark} | {results['kind'][i]} | " + " | ".join(cells) + f" | {results['status'][i]} |")
    return "\n".join(lines)
