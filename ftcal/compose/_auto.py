"""Let the data choose the calibrator: grouped cross-validation over ftcal's models, stock baselines beside."""

from __future__ import annotations

from numbers import Integral

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import nnls
from sklearn.base import clone
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.validation import check_is_fitted
from sklearn.utils.metadata_routing import process_routing

from ._history import refuse_history_inside
from ._routing import wrapper_routing
from ._registry import make_calibrator, registered_candidates
from ..calibrators._base import COSTS, BaseCalibrator, calibration_tags, declare, resolve_alpha, with_settings
from ..calibrators._baselines import STOCK_BASELINE_NAMES, StockCalibrator
from ..calibrators._linear import LinearCalibrator
from ..calibrators._polynomial import MIN_WITHIN_FRACTION, PolynomialCalibrator, within_group_load_fraction
from ..core._exceptions import CalibrationInputError, FtcalError
from ..model_selection._comparison import (COST_TIERS, LIGHT_KERNEL_ROWS, TIER_STEP, Comparison, ComparisonRow,
                                           RowStatus, choice_stability, compare, model_cost)
from ..model_selection._plan import FoldPlan
from ..model_selection._selection import (DegenerateCalibrationError, check_groups, check_not_degenerate,
                                          degenerate_reason, fold_predictions, grouped_subsample,
                                          held_out_predictions, routed_groups)
from ..core._threads import limit_threads_here
from ..core._validation import check_bool, check_zero_reading, validate_readings, validate_training_data
from ..core._wrench import named_targets, scale_torques, unscale_torques

__all__ = ["AutoCalibrator", "StackedCalibrator", "provides_std", "comparison_table", "default_candidates",
           "score_candidates", "add_stack", "complexity_of", "with_alpha_and_tare", "minimum_training_rows",
           "check_calibration"]

#: Most candidates a stack combines (the best-scoring eligible ones).
STACK_SIZE = 3
#: Most rows on which the choice's stability is repeated over other fold seeds (when every model within one SE
#: of the best is light work: a count of work, never a time).
STABILITY_ROWS = 5000
#: Fold seeds of the stability repeats (the plan's own seed is the first repeat).
STABILITY_SEEDS = (1, 2, 3, 4)
#: Most rows ``auto`` chooses on by default (a subsample, the same share of every group); the winner is refitted
#: on all rows. A count of rows, never a time.
CHOICE_SAMPLES = 20000


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
    tags = [calibration_tags(est) for _, est in candidates]
    for k in range(len(candidates)):
        if tags[k].stock_baseline and tags[k].family:
            first = next((j for j in range(k) if tags[j].family == tags[k].family
                          and not tags[j].stock_baseline), None)
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


def _unscored_ltm(plan: FoldPlan, alpha: float) -> Comparison:
    """The comparison of a fit that no folds could judge: the LTM alone, chosen unscored."""
    row = ComparisonRow(name="linear", kind="candidate", status=RowStatus.SKIPPED,
                        reason="no folds can judge a model", verdict="chosen (no folds can judge a model)")
    return Comparison(rows=[row], plan=plan, alpha=alpha, chosen="linear",
                      why=f"linear (the LTM) chosen without a held-out score: folds {plan.note}.")


def complexity_of(candidates: list[tuple[str, object]], training_rows: int) -> list[float]:
    """Each candidate's complexity for the one-SE rule: what it can fit, by its tags' ``cost`` tier (a closed
    form, then a kernel model, then a model of unknown cost, then a network:
    :data:`~ftcal.model_selection._comparison.COST_TIERS`), then its position (:func:`complexity_ranks`: a twin
    with group offsets and a stock model of a family as simple as their counterpart). A network never wins a
    one-SE tie over a closed-form model, nor over a stack of closed-form models (a stack ranks just after its
    most complex member).

    Examples
    --------
    >>> from ftcal import LinearCalibrator, PolynomialCalibrator
    >>> complexity_of([("a", PolynomialCalibrator(degree=2)), ("b", LinearCalibrator())], 100)
    [0.0, 1.0]
    """
    ranks = complexity_ranks(candidates, len(candidates))
    return [COST_TIERS[model_cost(est)] * TIER_STEP + float(ranks[k]) for k, (_, est) in enumerate(candidates)]



def _has_offsets(estimator: BaseCalibrator) -> bool:
    offsets = estimator.get_params(deep=False).get("group_offsets")
    return isinstance(offsets, (bool, np.bool_)) and bool(offsets)


def _model_without_offsets(estimator: BaseCalibrator) -> tuple[type, dict]:
    """``estimator``'s class and the parameters that make its flexibility (``group_offsets``, the seed, ``alpha`` and
    ``zero_reading`` left out); a degree-1 polynomial is the LTM (its ridge penalises no linear term)."""
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


def _nnls_weights(predictions: list[NDArray], target: NDArray) -> NDArray:
    """Non-negative weights of the (torque-scaled) predictions that best fit ``target`` in least squares."""
    design = np.column_stack([p.ravel() for p in predictions])
    weights, _ = nnls(design, target.ravel())
    return weights


def _auto_out_of_fold(network_samples: int | None, seed: int):
    """The fold runner ``auto`` gives :func:`~ftcal.model_selection.compare`: :func:`_out_of_fold` with its
    network subsample and seed, BLAS on one thread (small matrices; the jobs share the cores)."""
    def run(estimator, X, y, folds, groups):
        with limit_threads_here(1):
            return _out_of_fold(estimator, X, y, folds, groups, network_samples, seed)
    return run


def score_candidates(
    candidates, X: NDArray[np.float64], y, *, groups=None, cv: int = 5, alpha: float, zero_reading=None,
    random_state: int | None = 0, network_samples: int | None = 2000, baselines: dict | None = None,
    stack: bool = False, n_jobs: int | None = None, plan: FoldPlan | None = None, axes=None, race: bool = True,
    progress=None, race_ties: bool = False,
) -> Comparison:
    """Score every candidate on one fold plan with :func:`~ftcal.model_selection.compare`; the engine of ``auto``
    and ``ftcal benchmark dataset``.

    Every figure is eq. 18's RMSE (over the torque-scaled values, [N]). The candidates get the shared torque
    scale and tare (:func:`with_alpha_and_tare`); a candidate needs :func:`minimum_training_rows` in its training
    folds (else SKIPPED); the costly ones are raced (``race``: STOPPED when they cannot come within one SE of
    the best; with ``race_ties``, also when they cannot come better than it beyond one SE); networks' folds train as one stacked fit on at most ``network_samples`` rows each. ``baselines``
    (name -> regressor) are scored on the same folds, never eligible. With ``stack``, a non-negative combination
    of the best (up to :data:`STACK_SIZE`) eligible candidates is scored too, its weights cross-fitted over the
    folds (:func:`add_stack`). ``plan`` defaults to :meth:`FoldPlan.for_data` with ``cv`` and the seed.

    Returns
    -------
    Comparison
        Rows in the candidates' order, then the stack, then the baselines; not yet chosen
        (:meth:`~ftcal.model_selection.Comparison.choose`).
    """

    seed = 0 if random_state is None else int(random_state)
    y_arr = np.asarray(y, dtype=float)
    if plan is None:
        plan = FoldPlan.for_data(X, y_arr, groups, cv=cv, seed=seed)
    models = [(name, with_alpha_and_tare(t, alpha, zero_reading)) for name, t in candidates]
    kinds = {name: "stock" if calibration_tags(t).stock_baseline else "candidate" for name, t in candidates}
    complexity = complexity_of(candidates, plan.n_rows)
    for name, regressor in (baselines or {}).items():
        models.append((name, regressor))
        kinds[name] = "baseline"
        complexity.append(COST_TIERS[model_cost(regressor)] * TIER_STEP + len(complexity))
    comparison = compare(models, X, named_targets(y, axes) if not hasattr(y, "iloc") else y, plan, alpha=alpha,
                         groups=groups, n_jobs=n_jobs, race=race, race_ties=race_ties, kinds=kinds, progress=progress, axes=axes,
                         complexity=complexity, out_of_fold=_auto_out_of_fold(network_samples, seed),
                         min_rows=minimum_training_rows)
    if stack:
        families = {name: calibration_tags(t).family for name, t in candidates}
        add_stack(comparison, y_arr, families, axes)
    return comparison


def add_stack(comparison: Comparison, y: NDArray, families: dict, axes=None) -> None:
    """Score the non-negative combination of the best eligible candidates (weights cross-fitted over the plan's
    folds) and insert it after the candidates; a stock model and ftcal's model of the same family (``families``:
    name -> tags' family) never both. Its complexity is just after its most complex member's."""
    rows = comparison.rows
    ranked = sorted((r for r in rows if r.eligible and r.status is RowStatus.SCORED and r.kind != "stack"),
                    key=lambda r: r.rmse)
    members: list = []
    for r in ranked:
        # a stock model beside ftcal's model of its family (sk_linear and the LTM: the same least squares) adds
        # no kind of model to the combination, only a column its twin already gives (weights split arbitrarily)
        family = families.get(r.name)
        if family and any(families.get(m.name) == family and "stock" in (m.kind, r.kind) for m in members):
            continue
        members.append(r)
        if len(members) == STACK_SIZE:
            break
    if len(members) < 2:
        return
    alpha = comparison.alpha
    scaled = [scale_torques(m.predictions, alpha, axes) for m in members]
    target = scale_torques(y, alpha, axes)
    oof = np.empty_like(target)
    for train, test in comparison.plan.folds:
        w = _nnls_weights([p[train] for p in scaled], target[train])
        oof[test] = sum(wk * p[test] for wk, p in zip(w, scaled))
    comparison.stack_members = [m.name for m in members]
    comparison.stack_weights = _nnls_weights(scaled, target).tolist()
    at = next((k for k, r in enumerate(rows) if r.kind == "baseline"), len(rows))
    comparison.add_scored("stack(" + " + ".join(comparison.stack_members) + ")", "stack",
                          unscale_torques(oof, alpha, axes), y, complexity=max(m.complexity for m in members) + 0.5,
                          axes=axes, index=at)


def is_light(estimator, training_rows: int) -> bool:
    """Whether ``estimator`` fits in a moment (its tags' ``cost``): a closed form, or a kernel model on at most
    :data:`LIGHT_KERNEL_ROWS` rows; anything else (networks, ensembles, wrappers of unknown cost) is not."""
    return model_cost(estimator, training_rows) == "closed_form"


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


def training_data_sha256(X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None) -> str:
    """SHA-256 (hex) of training arrays' shapes and float64 values (and of the group labels, which make the
    folds; :func:`ftcal.core.values_sha256`): the identity of the data a comparison was scored on (a report
    reuses ``auto``'s comparison only on the very same rows, grouped the same way).

    Examples
    --------
    >>> a = np.arange(6.0).reshape(3, 2)
    >>> training_data_sha256(a, a) == training_data_sha256(a[:2], a[:2])
    False
    >>> training_data_sha256(a, a, [0, 0, 1]) == training_data_sha256(a, a, [0, 1, 1])
    False
    """
    from ..core import values_sha256

    # the labels themselves: the group folds depend on them, not only on the partition
    return values_sha256([np.asarray(X, dtype=np.float64), np.asarray(y, dtype=np.float64), groups])


def check_calibration(estimator, X: ArrayLike, y: ArrayLike, *, groups: ArrayLike | None = None, cv: int = 5,
                      random_state: int = 0, predictions: ArrayLike | None = None, held_out: bool = True,
                      plan: FoldPlan | None = None) -> None:
    """Refuse a fitted calibration that must not be saved: what ``ftcal fit`` calls before it writes a model file.

    Raises :class:`~ftcal.model_selection._selection.DegenerateCalibrationError` (one line, the reason) when the
    model's predictions on ``X`` are constant or all zero, or its held-out predictions (``predictions``, else made
    here on ``plan``, by default :meth:`~ftcal.model_selection.FoldPlan.for_data`, the one fold rule that
    ``auto`` and the certificate use, by :func:`~ftcal.model_selection._selection.held_out_predictions`) are
    degenerate (constant, all zero, no better than the mean). A model that chose itself by cross-validation
    (``auto``: its tags' ``chooses_model``) checked its held-out predictions in ``fit`` on the same plan; only its
    predictions on ``X`` are checked again. ``held_out=False`` says the given ``predictions`` are of the training
    readings (a network fitted without a report: a held-out check would train it ``cv`` more times); the refusal
    then says so.

    Examples
    --------
    >>> from ftcal import LinearCalibrator
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(60, 6)); raw = w @ rng.normal(size=(6, 6))
    >>> check_calibration(LinearCalibrator().fit(raw, w), raw, w)  # nothing to refuse
    """
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
        if plan is None:
            plan = FoldPlan.for_data(X, y, groups, cv=cv, seed=random_state,
                                     ordered=calibration_tags(estimator).reads_history)
        if not plan.n_splits:
            return
        try:
            _, predictions = held_out_predictions(clone(estimator), X, y, groups=groups, folds=list(plan.folds))
        except FtcalError as exc:  # the fit took every row; say why the check has fewer
            smallest = min(len(train) for train, _ in plan.folds)
            raise exc.located(f"the held-out check before saving (cross-validation, {plan.n_splits} folds) trains "
                              f"on {smallest} of the {len(X)} rows: ") from exc
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
        super().__init__(alpha=alpha, zero_reading=zero_reading, random_state=random_state)

    #: Accepts the groups of the rows and passes them on to the members that request them.
    __metadata_request__fit = {"groups": True}

    def get_metadata_routing(self):
        """Routing of ``fit``'s ``groups`` to each member (``member0``, ``member1``, ...)."""
        return wrapper_routing(self, **{f"member{i}": member for i, member in enumerate(self.estimators or [])})

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

    1. builds the folds with :meth:`~ftcal.model_selection.FoldPlan.for_data` (the one fold rule, shared with
       the save gate of ``ftcal fit`` and the certificate; kept as ``fold_plan_``):
       with ``groups`` (a pose or load configuration per row, the dataset's
       ``group`` column) whole groups are held out, so the score says how the
       calibration does on poses it has not seen; without, shuffled k-fold;
    2. scores every candidate on those folds with :func:`~ftcal.model_selection.compare` (the cheap ones on
       every fold; the costly ones, by their tags' ``cost``, raced: fitted on the first fold and STOPPED when
       they cannot come within one standard error of the best, ``race=True``), **in this complexity order**
       (simplest first): ``linear`` (the LTM); ``polynomial`` of degree 2 and 3,
       each with ridge 1e-2 and 1e-4 (with ``groups``, at least 3 within which
       the loads vary, the LTM and the degree-2 polynomial with ridge 1e-2 are
       each followed by a twin with one offset per group, ``group_offsets=True``:
       for poses or sessions whose readings shift as a whole); ``axis_nonlinear`` (the hybrid);
       ``gaussian_process`` (its mean and kernel chosen on the first fold's
       training rows, by held-out error, and kept for the other folds and the
       refit; its hyperparameters refitted on every training fold);
       ``directional`` and ``comparative`` (the ``schedule``'s epochs; the K fold models trained as one stacked fit, each on at most
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
    4. picks by the **one-standard-error rule** over a complexity that says what a model can fit
       (:func:`complexity_of`: a closed form, then a kernel model, then a model of unknown cost, then a network,
       by their tags' ``cost``; a stack just after its most complex member: a network never wins a tie over
       closed-form models or a stack of them)
       (:func:`~ftcal.model_selection._selection.simplest_within_one_se`): the
       best-scoring candidate and every one within one paired standard error
       of it (over groups, or rows), or within 0.5 % of its RMSE (a tie:
       ``TIE_TOLERANCE``, 1 % of the mean squared error), qualify, and the
       simplest in the order above wins (a twin with group offsets counts as
       simple as its model without: the same map and one intercept, estimated
       within the groups; between the two the lower score wins). **The choice is cross-validated against the
       simplest model** (the LTM; :func:`~ftcal.model_selection._selection.choice_beats_simplest`): a choice more
       complex than it is kept only when the rule, applied again without each fold and scored on that fold (the
       held-out errors reused, nothing refitted), beats the simplest beyond one paired SE; else the simplest
       wins (the best of many on the folds it was chosen on is flattered by the choice: on unseen poses a model
       that won on a few lucky ones does worse than the LTM). A candidate whose training folds are smaller than
       :func:`minimum_training_rows` is not fitted and never chosen (on 15-50
       dead-weight rows that leaves the LTM and the mildest models);
    5. refits the winner on all rows (``best_estimator_``). On more than ``choice_samples`` rows, steps 1-4 run
       on a subsample of that many, the same share of every group, and the winner is refitted on all rows.

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
    race : bool, default=True
        Race the costly candidates (stop those that cannot come within one SE of the best after their first
        fold); ``False`` scores every candidate on every fold.
    choice_samples : int or None, default=20000
        Most rows the comparison is made on: with more, the candidates are compared on a subsample of that many
        (the same share of every group, so that grouped folds still hold out whole groups) and the winner is
        refitted on all rows; ``comparison_``, ``fold_plan_`` and ``held_out_predictions_`` are then of the
        subsample (``comparison_.why`` says so), and a raced model that cannot come better than the best cheap
        one beyond one SE on its first fold is stopped there (``race_ties`` of
        :func:`~ftcal.model_selection.compare`: the one-SE rule would not choose it). ``None``: always all rows.
    random_state : int or None, default=None
        Seed of the folds and subsamples (``None`` = 0, so a fit is reproducible).

    Attributes
    ----------
    best_estimator_ : calibrator
        The chosen candidate (or :class:`StackedCalibrator`), refitted on all data.
    best_name_ : str
        Its name.
    comparison_ : Comparison
        The comparison (:class:`~ftcal.model_selection.Comparison`): one row per candidate with its
        :class:`~ftcal.model_selection.RowStatus` (scored, skipped, failed, stopped) and reason, held-out RMSE ±
        SE, seconds, complexity, verdict (chosen / within one SE but more complex / beyond one SE / ...) and
        the row against the choice in symmetric words; ``chosen``, ``why``, ``stability`` (the choice repeated
        on folds with other seeds, where cheap). ``to_dict()`` gives JSON columns.
    fold_plan_ : FoldPlan
        The folds the comparison was scored on.
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

    _fitted_state = ("best_name_", "comparison_", "best_estimator_", "held_out_predictions_", "fold_plan_")
    #: Typed results a model file stores as their own state (and reads back, also from an earlier file's dict).
    _typed_state = {"comparison_": Comparison.from_dict, "fold_plan_": FoldPlan.from_state}
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
        "race": ["boolean"],
        "choice_samples": [Interval(Integral, 100, None, closed="left"), None],
    }

    def __init__(self, *, candidates=None, cv=5, schedule="short", stack=True, baselines=True,
                 network_samples=2000, n_jobs=-1, race=True, choice_samples=CHOICE_SAMPLES, alpha=None,
                 zero_reading=None, random_state=None):
        self.candidates = candidates
        self.race = race
        self.choice_samples = choice_samples
        self.cv = cv
        self.schedule = schedule
        self.stack = stack
        self.baselines = baselines
        self.network_samples = network_samples
        self.n_jobs = n_jobs
        super().__init__(alpha=alpha, zero_reading=zero_reading, random_state=random_state)

    def _candidates(self, grouped: bool = False) -> list[tuple[str, BaseCalibrator]]:
        """The candidates in their complexity order, the choosable stock baselines placed among them."""
        if self.candidates is None:
            pairs = default_candidates(self.schedule, grouped)
        else:
            pairs = list(self.candidates)
            if not pairs or not all(isinstance(p, tuple) and len(p) == 2 and hasattr(p[1], "fit")
                                    and hasattr(p[1], "predict") for p in pairs):
                raise CalibrationInputError(
                    "candidates must be a non-empty list of (name, regressor) pairs (any scikit-learn regressor; "
                    "ftcal's tags optional), e.g. [('linear', LinearCalibrator()), ('ridge', Ridge())]; got "
                    f"{self.candidates!r:.120}."
                )
        pairs = with_stock_candidates(pairs, self._stock())
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
                if hasattr(candidate, "_check_parameters"):
                    candidate._check_parameters()
            except CalibrationInputError as exc:
                raise CalibrationInputError(f"candidate {name!r}: {exc}") from None
        return pairs

    def _stock(self) -> list[tuple[str, BaseCalibrator]]:
        """The choosable free models: the stock baselines (``baselines=True``), a user's own, or none."""
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
        try:
            pairs = self._candidates(grouped=True)
        except CalibrationInputError:  # said by fit, with the data
            pairs = []
        return wrapper_routing(self, **dict(pairs))

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
        candidates = self._candidates(grouped=_offsets_identifiable(y, groups))
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
        # large data: the choice on a subsample of rows, the same share of every group; the winner refitted on all
        chosen_rows = grouped_subsample(np.arange(len(X)), groups, self.choice_samples, seed)
        Xc, yc = X[chosen_rows], y[chosen_rows]
        gc = None if groups is None else groups[chosen_rows]
        plan = FoldPlan.for_data(Xc, yc, gc, cv=self.cv, seed=seed)
        self.fold_plan_ = plan
        if not plan.n_splits:  # nothing can be judged: the LTM, the simplest model, never a stack
            comparison = _unscored_ltm(plan, self.alpha_)
            candidates = [("linear", make_calibrator("linear"))]
        else:
            comparison = score_candidates(
                candidates, Xc, named_targets(yc, axes), groups=gc, cv=self.cv, alpha=self.alpha_,
                zero_reading=given, random_state=seed, network_samples=self.network_samples, stack=self.stack,
                n_jobs=self.n_jobs, plan=plan, axes=axes, race=self.race,
                race_ties=len(chosen_rows) < len(X))  # large data: a costly model that cannot win is not raced on
            if not any(r.eligible and r.status is RowStatus.SCORED for r in comparison.rows):
                why = "; ".join(f"{r.name}: {r.status_text}" for r in comparison.rows)
                raise DegenerateCalibrationError(
                    f"no candidate could be fitted and judged on these data ({why[:400]}); nothing was saved. "
                    "Record more rows (each axis loaded in more than one group) or lower cv.")
            comparison.choose()
            comparison.stability = self._stability(comparison, candidates, Xc, yc, gc, given, axes)
            if len(chosen_rows) < len(X):
                comparison.why += (f" Chosen on {len(chosen_rows)} of the {len(X)} rows (the same share of every "
                                   "group: AutoCalibrator(choice_samples=...)), refitted on all of them.")
        templates = dict(candidates)
        structures = comparison.structures
        named = named_targets(y, axes)  # the chosen model refitted on the named table, as it was scored
        comparison.training_sha256 = training_data_sha256(Xc, yc, gc)  # what the comparison was scored on
        self.comparison_ = comparison
        self.best_name_ = comparison.chosen
        # the winner's out-of-fold predictions, for a report on the same folds
        self.held_out_predictions_ = comparison.row(self.best_name_).predictions

        def refit(name):
            """A candidate on all rows (networks on their grouped subsample), as it was cross-validated (a model
            that chose its structure on the first fold keeps that structure)."""
            model = with_alpha_and_tare(templates[name], self.alpha_, given)
            if name in structures:
                model.set_params(**structures[name])
            rows = grouped_subsample(np.arange(len(X)), groups, self.network_samples, seed) \
                if _is_network(model) else np.arange(len(X))
            return _fit(model, X[rows], _rows(named, rows), None if groups is None else groups[rows])

        if comparison.row(self.best_name_).kind == "stack":
            members = comparison.stack_members
            best = StackedCalibrator(estimators=[templates[n] for n in members], weights=comparison.stack_weights,
                                     alpha=self.alpha_, zero_reading=given)
            self.best_estimator_ = best.fit(X, named, fitted_estimators=[refit(n) for n in members])
        else:
            self.best_estimator_ = refit(self.best_name_)
        self._adopt_fitted(X, y, self.best_estimator_)
        return self

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
        if not check_bool(return_std, "return_std"):
            return super().predict(X)
        check_is_fitted(self)
        if not provides_std(self.best_estimator_):
            raise CalibrationInputError(
                f"return_std=True: the chosen model {self.best_name_!r} gives no standard deviation; only the "
                "Gaussian process does (use AutoCalibrator(candidates=[('gaussian_process', "
                "GaussianProcessCalibrator())]) or a GaussianProcessCalibrator for uncertainties).")
        return self.best_estimator_.predict(self._retared(validate_readings(self, X)), return_std=True)

    def summary(self) -> str:
        """The comparison as a markdown table (:meth:`~ftcal.model_selection.Comparison.table`): held-out RMSE ± SE,
        each row against the choice in symmetric words, seconds, status (stopped rows with why), why the choice won
        and how stable it is over other fold seeds."""
        check_is_fitted(self)
        return comparison_table(self.comparison_)

    def _stability(self, comparison: Comparison, candidates, X, y, groups, given, axes):
        """How often the choice is made again on folds with other seeds, when that is cheap: at most
        :data:`STABILITY_ROWS` rows and every model within one SE of the best light work (a closed form, a kernel
        model on few rows, or a stack of them); the models within one SE (and the stack's members) are compared
        again, the stack rebuilt, a model that chooses its structure choosing it on each repeat's own first
        training fold (never on rows that repeat tests). None otherwise."""
        plan = self.fold_plan_
        within = [r for r in comparison.rows if r.verdict == "chosen" or r.verdict.startswith("within")]
        names = {r.name for r in within if r.kind != "stack"}
        if any(r.kind == "stack" for r in within):
            names |= set(comparison.stack_members)
        # a model that chooses its structure chooses it again in each repeat, on that repeat's first training fold
        # (compare does): the structure chosen on the plan's first fold saw the rows the repeats test on, a bias
        # toward that model; the repeats run only when every model compared is light work, so the search is cheap
        pairs = [(n, t) for n, t in candidates if n in names]
        smallest = comparison.min_training_rows or 0
        if plan.n_rows > STABILITY_ROWS or len(within) < 2 or \
                not all(model_cost(t, smallest) == "closed_form" for _, t in pairs):
            return None
        families = {n: calibration_tags(t).family for n, t in pairs}
        stack = self.stack and any(r.kind == "stack" for r in within)
        ranks = dict(zip([n for n, _ in candidates], complexity_of(candidates, plan.n_rows)))
        named = named_targets(y, axes)
        return choice_stability(
            [(n, with_alpha_and_tare(t, self.alpha_, given)) for n, t in pairs], X, named, plan,
            chosen=comparison.chosen, seeds=STABILITY_SEEDS, groups=groups, alpha=self.alpha_, axes=axes,
            complexity=[ranks[n] for n, _ in pairs], min_rows=minimum_training_rows,
            finish=(lambda c: add_stack(c, y, families, axes)) if stack else None,
            out_of_fold=_auto_out_of_fold(self.network_samples, int(self.random_state or 0)))


def comparison_table(comparison) -> str:
    """``comparison_`` (a :class:`~ftcal.model_selection.Comparison`, or the comparison dict of an earlier model
    file or of ``ftcal benchmark dataset``'s JSON) as a markdown table
    (:meth:`~ftcal.model_selection.Comparison.table`): every row's held-out RMSE ± SE, its excess mean squared
    error over the best and the **paired** SE of that excess (what the one-SE rule compared), the row against the
    choice in symmetric words (better / worse only beyond the paired SE, else equivalent within noise), its
    seconds and status, then why the choice won and how stable it is."""
    if not isinstance(comparison, Comparison):
        comparison = Comparison.from_dict(dict(comparison))
    return comparison.table()
