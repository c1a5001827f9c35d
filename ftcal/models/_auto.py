"""Let the data choose the calibrator: grouped cross-validation over ftcal's models (issue 12)."""

from __future__ import annotations

import inspect
from numbers import Integral, Real
import time
import warnings

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.base import clone
from sklearn.utils._param_validation import Interval, StrOptions

from ..calibrators._base import BaseCalibrator, resolve_alpha
from ..core._exceptions import CalibrationInputError
from ..core._model_selection import calibration_folds, check_groups, simplest_within_one_se
from ..core._validation import check_zero_reading, validate_training_data
from ..core._wrench import scale_torques
from ..calibrators._zero_load import estimate_zero_reading, reading_noise

__all__ = ["AutoCalibrator", "default_candidates", "score_candidates", "with_alpha_and_tare"]


def default_candidates(schedule: str = "short") -> list[tuple[str, BaseCalibrator]]:
    """The candidates of :class:`AutoCalibrator`, simplest and cheapest first.

    Examples
    --------
    >>> [name for name, _ in default_candidates()][:3]
    ['linear', 'polynomial(degree=2, ridge=0.01)', 'polynomial(degree=2, ridge=0.0001)']
    """
    from ._registry import make_calibrator

    candidates: list[tuple[str, BaseCalibrator]] = [("linear", make_calibrator("linear"))]
    for degree in (2, 3):
        for ridge in (1e-2, 1e-4):
            candidates.append((f"polynomial(degree={degree}, ridge={ridge:g})",
                               make_calibrator("polynomial", degree=degree, ridge=ridge)))
    candidates.append(("axis_nonlinear", make_calibrator("axis_nonlinear")))
    candidates.append(("gaussian_process", make_calibrator("gaussian_process")))
    for name in ("directional", "comparative", "directional_ensemble", "comparative_ensemble"):
        candidates.append((name, make_calibrator(name, schedule=schedule)))
    return candidates


def with_alpha_and_tare(estimator, alpha: float, zero_reading):
    """A clone of ``estimator`` with the shared torque scale and tare (an ensemble passes them to its members)."""
    estimator = clone(estimator)
    params = estimator.get_params()
    prefix = "" if "alpha" in params else "estimator__" if "estimator__alpha" in params else None
    if prefix is not None:
        estimator.set_params(**{f"{prefix}alpha": alpha, f"{prefix}zero_reading": zero_reading})
    return estimator


def _fit_accepts_groups(estimator) -> bool:
    return "groups" in inspect.signature(estimator.fit).parameters


def _fit(estimator, X, y, groups):
    if groups is not None and _fit_accepts_groups(estimator):
        return estimator.fit(X, y, groups=groups)
    return estimator.fit(X, y)


def score_candidates(
    candidates, X: NDArray[np.float64], y: NDArray[np.float64], *, groups=None, cv: int = 5, alpha: float,
    zero_reading=None, time_budget: float | None = None, random_state: int | None = 0,
) -> tuple[dict, NDArray[np.float64], list]:
    """Cross-validate every candidate on the same folds; the engine of ``auto`` and ``ftcal benchmark dataset``.

    Returns
    -------
    results : dict of lists
        Per candidate: ``name``, ``status`` (``"scored"``, ``"skipped: ..."``,
        ``"failed: ..."``), ``rmse`` (held-out, torque-scaled [N]),
        ``rmse_se`` (its standard error over groups or rows), ``axis_rmse``
        (6 values, [N] and [N·m]), ``fit_seconds`` (mean per fold).
    errors : ndarray of shape (n_candidates, n_samples)
        Held-out squared torque-scaled error of each row (NaN when not scored).
    predictions : list of ndarray of shape (n_samples, 6) or None
        Out-of-fold predictions.
    """
    folds = calibration_folds(len(X), groups, cv, random_state)
    start = time.perf_counter()
    n = len(candidates)
    errors = np.full((n, len(X)), np.nan)
    results: dict = {k: [] for k in ("name", "status", "rmse", "rmse_se", "axis_rmse", "fit_seconds")}
    results["n_splits"] = len(folds)
    predictions: list = []
    previous_fold_seconds = 0.0
    for k, (name, template) in enumerate(candidates):
        status, seconds, pred = "scored", [], np.full(y.shape, np.nan)
        for i, (train, test) in enumerate(folds):
            # Projected time of the remaining folds: this candidate's own fold time once known, before that the
            # previous candidate's (candidates come cheapest first, so that is a lower bound).
            per_fold = np.mean(seconds) if seconds else previous_fold_seconds
            remaining = None if time_budget is None else time_budget - (time.perf_counter() - start)
            # the first candidate (the LTM by default) always runs, so there is always an answer
            if k > 0 and remaining is not None and (remaining <= 0 or per_fold * (len(folds) - i) > remaining):
                status = f"skipped: time budget ({time_budget:g} s) would be exceeded"
                break
            estimator = with_alpha_and_tare(template, alpha, zero_reading)
            t0 = time.perf_counter()
            try:
                with warnings.catch_warnings():
                    warnings.simplefilter("ignore", UserWarning)
                    _fit(estimator, X[train], y[train], None if groups is None else np.asarray(groups)[train])
                pred[test] = estimator.predict(X[test])
            except Exception as exc:  # a candidate that cannot fit these data is recorded, not fatal
                status = f"failed: {type(exc).__name__}: {' '.join(str(exc).split())[:200]}"
                break
            seconds.append(time.perf_counter() - t0)
        if seconds:
            previous_fold_seconds = max(previous_fold_seconds, float(np.mean(seconds)))
        results["name"].append(name)
        results["status"].append(status)
        results["fit_seconds"].append(float(np.mean(seconds)) if seconds else None)
        if status == "scored":
            sq = np.sum((scale_torques(pred, alpha) - scale_torques(y, alpha)) ** 2, axis=1)
            errors[k] = sq
            units = None if groups is None else np.asarray(groups)
            rmse, se = _rmse_and_se(sq, units)
            results["rmse"].append(rmse)
            results["rmse_se"].append(se)
            results["axis_rmse"].append(np.sqrt(np.mean((pred - y) ** 2, axis=0)).tolist())
            predictions.append(pred)
        else:
            for key in ("rmse", "rmse_se", "axis_rmse"):
                results[key].append(None)
            predictions.append(None)
    return results, errors, predictions


def _rmse_and_se(squared_errors: NDArray, units: NDArray | None) -> tuple[float, float]:
    """RMSE and its standard error (delta method over groups, or over rows)."""
    if units is not None:
        _, inverse = np.unique(units, return_inverse=True)
        per_unit = np.bincount(inverse, weights=squared_errors) / np.bincount(inverse)
    else:
        per_unit = squared_errors
    mse = float(np.mean(squared_errors))
    se_mse = float(per_unit.std(ddof=1) / np.sqrt(per_unit.size)) if per_unit.size > 1 else float("inf")
    rmse = float(np.sqrt(mse))
    return rmse, se_mse / (2.0 * rmse) if rmse > 0 else 0.0


class AutoCalibrator(BaseCalibrator):
    """Choose the calibrator by (grouped) cross-validation, refit it on all data, and keep the comparison.

    No single model wins on every sensor: on real sensors the LTM, a kernel
    method and the thesis' networks each win somewhere, and a random-fold
    score flatters every flexible model. ``fit`` therefore

    1. builds the folds with :func:`~ftcal.core._model_selection.calibration_folds`:
       with ``groups`` (a pose or load configuration per row, the dataset's
       ``group`` column) whole groups are held out, so the score says how the
       calibration does on poses it has not seen; without, shuffled k-fold;
    2. scores the candidates **in this order** (simplest and cheapest first):
       ``linear`` (the LTM); ``polynomial`` of degree 2 and 3, each with ridge
       1e-2 and 1e-4 (a cross-validated degree and ridge); ``axis_nonlinear``
       (the hybrid, its own ridge chosen on the same groups);
       ``gaussian_process``; ``directional`` and ``comparative`` (the
       ``schedule``'s epochs); their 5-member ensembles. Each candidate
       sees the same folds, the same torque scale and the given tare;
    3. keeps to the **time budget**: a fold is started only when the budget
       left covers the candidate's remaining folds at its own fold time, or,
       before its first fold, at the slowest fold time seen so far (the list
       runs from cheap to expensive, so that is a lower bound). The budget is
       therefore exceeded by at most one fold of the first candidate that
       turns out too slow (plus the final refit). The first candidate always
       runs, so there is always an answer. Candidates that do not fit
       are recorded as skipped, never silently dropped. With the default 150 s
       on 2 cores the closed-form models and the GP run on any data set the
       GP's subset keeps small; the networks run when the data are small
       enough, or with a larger budget;
    4. picks, by the **one-standard-error rule**, the simplest candidate whose
       held-out error is within one paired standard error (over groups, or
       rows) of the best: a flexible model must show that it pays;
    5. refits the winner on all rows (``best_estimator_``).

    ``cv_results_`` keeps the whole comparison (RMSE, its standard error,
    per-axis RMSE, fit time and status per candidate); it is stored in the
    model file and printed by ``ftcal fit --model auto``.

    Parameters
    ----------
    candidates : list of (name, estimator) or None, default=None
        ``None``: :func:`default_candidates` with ``schedule``. Order them
        from the simplest to the most flexible (the 1-SE rule prefers earlier ones).
    cv : int, default=5
        Number of folds (capped by the number of groups).
    time_budget : float or None, default=150
        Seconds for the cross-validation; ``None`` = no limit.
    schedule : {"short", "thesis"}, default="short"
        Training schedule of the network candidates.
    alpha : float or None, default=None
        Torque scale ``Fmax / Tmax`` [m⁻¹], shared by every candidate; ``None`` derives it from ``y``.
    zero_reading : array-like of shape (N,) or None, default=None
        Measured tare, given to every candidate; ``None``: each estimates its own.
    random_state : int or None, default=None
        Seed of the folds (``None`` = 0, so a fit is reproducible).

    Attributes
    ----------
    best_estimator_ : calibrator
        The chosen candidate, refitted on all data.
    best_name_ : str
        Its name.
    cv_results_ : dict
        The comparison (see :func:`score_candidates`), plus ``chosen``.
    alpha_, zero_reading_, n_features_in_
        As for every calibrator.

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import AutoCalibrator, LinearCalibrator, PolynomialCalibrator
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(200, 6)); raw = w @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(200, 6))
    >>> auto = AutoCalibrator(candidates=[("linear", LinearCalibrator()),
    ...                                   ("polynomial", PolynomialCalibrator(degree=2))]).fit(raw, w)
    >>> auto.best_name_
    'linear'
    """

    _fitted_state = ("best_name_", "cv_results_", "best_estimator_")
    #: The folds hold out whole groups: requested by default (metadata routing, like a group splitter).
    __metadata_request__fit = {"groups": True}
    _parameter_constraints: dict = {
        **BaseCalibrator._parameter_constraints,
        "candidates": [list, tuple, None],
        "cv": [Interval(Integral, 2, None, closed="left")],
        "time_budget": [Interval(Real, 0, None, closed="neither"), None],
        "schedule": [StrOptions({"short", "thesis"})],
    }

    def __init__(self, *, candidates=None, cv=5, time_budget=150.0, schedule="short", alpha=None,
                 zero_reading=None, random_state=None):
        self.candidates = candidates
        self.cv = cv
        self.time_budget = time_budget
        self.schedule = schedule
        self.alpha = alpha
        self.zero_reading = zero_reading
        self.random_state = random_state

    def _candidates(self) -> list[tuple[str, BaseCalibrator]]:
        if self.candidates is None:
            return default_candidates(self.schedule)
        pairs = list(self.candidates)
        if not pairs or not all(isinstance(p, tuple) and len(p) == 2 and isinstance(p[1], BaseCalibrator)
                                for p in pairs):
            raise CalibrationInputError(
                "candidates must be a non-empty list of (name, calibrator) pairs, e.g. "
                "[('linear', LinearCalibrator()), ('gp', GaussianProcessCalibrator())]; got "
                f"{self.candidates!r:.120}."
            )
        return pairs

    def fit(self, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None):
        """Cross-validate the candidates on ``X`` (n, N), ``y`` (n, 6), refit the best on all rows.

        Parameters
        ----------
        groups : array-like of shape (n,) or None
            Group of each row (pose, load configuration); folds keep groups whole.

        Returns
        -------
        self
        """
        self._check_parameters()
        candidates = self._candidates()
        X, y = validate_training_data(self, X, y)
        groups = check_groups(groups, len(X))
        self.alpha_ = resolve_alpha(self.alpha, y)
        given = None if self.zero_reading is None else check_zero_reading(self.zero_reading, X.shape[1])
        seed = 0 if self.random_state is None else self.random_state
        results, errors, _ = score_candidates(
            candidates, X, y, groups=groups, cv=self.cv, alpha=self.alpha_, zero_reading=given,
            time_budget=self.time_budget, random_state=seed,
        )
        if np.isnan(errors).any(axis=1).all():
            why = "; ".join(f"{n}: {st}" for n, st in zip(results["name"], results["status"]))
            raise CalibrationInputError(f"no candidate could be fitted on these data ({why[:400]}).")
        chosen = simplest_within_one_se(errors, groups)
        results["chosen"] = results["name"][chosen]
        results["folds"] = "group" if groups is not None else "kfold"
        self.cv_results_ = results
        self.best_name_ = results["name"][chosen]
        best = with_alpha_and_tare(candidates[chosen][1], self.alpha_, given)
        self.best_estimator_ = _fit(best, X, y, groups)
        best_zero = getattr(self.best_estimator_, "zero_reading_", None)
        self.zero_reading_ = estimate_zero_reading(X, y, self.alpha_) if best_zero is None else np.asarray(best_zero)
        self.reading_noise_ = reading_noise(X, y)
        self.reading_range_ = np.vstack([X.min(axis=0), X.max(axis=0)])
        self.__dict__.pop("tare_reading_", None)
        return self

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        return self.best_estimator_.predict(X)

    def _emit_onnx(self, g, x: str) -> str:
        return g.calibration(self.best_estimator_, x)

    def summary(self) -> str:
        """The comparison as a markdown table (held-out RMSE ± standard error, fit time, status)."""
        r = self.cv_results_
        lines = ["| candidate | held-out RMSE [N] | ± SE | fit [s/fold] | status |", "|---|---|---|---|---|"]
        for i, name in enumerate(r["name"]):
            rmse = "" if r["rmse"][i] is None else f"{r['rmse'][i]:.4g}"
            se = "" if r["rmse_se"][i] is None else f"{r['rmse_se'][i]:.2g}"
            sec = "" if r["fit_seconds"][i] is None else f"{r['fit_seconds'][i]:.2f}"
            mark = " **(chosen)**" if name == r["chosen"] else ""
            lines.append(f"| {name}{mark} | {rmse} | {se} | {sec} | {r['status'][i]} |")
        return "\n".join(lines)
