"""Error metrics of the thesis (section IV-C): RMSE (eq. 18) and relative errors (eq. 19).

Conventions
-----------
* The RMSE is taken over every component of the **torque-scaled** wrench
  (torques multiplied by ``alpha``, eq. 6), i.e. eq. 18 with each of the
  ``6 n`` values counted once. It has the unit of force [N]. This is the
  quantity of the thesis' Tables II and IV.
* The per-sample RMSE is the same quantity for one row (over its 6
  components); its mean ± std over a test set is the "within the dataset"
  figure of Table IV.
* Relative errors (eq. 19) are per sample and separate for force and torque:
  ``||F - F_hat|| / ||F||`` and ``||T - T_hat|| / ||T||``. Rows whose true
  force (torque) norm is below ``min_norm`` times the largest one in the set
  are left out of that ratio, because a ratio to a near-zero load is
  meaningless; how many were left out is reported.
"""

from __future__ import annotations

from dataclasses import dataclass, asdict

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._exceptions import CalibrationInputError
from ._wrench import WRENCH_LABELS, default_axes, force_columns, scale_torques, torque_columns, torque_slice

__all__ = ["wrench_rmse", "per_sample_rmse", "axis_rmse", "relative_errors", "CalibrationMetrics",
           "calibration_metrics", "neg_scaled_rmse", "mean_std"]


def _pair(y_true: ArrayLike, y_pred: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    t = np.asarray(y_true, dtype=float)
    p = np.asarray(y_pred, dtype=float)
    for name, a in (("y_true", t), ("y_pred", p)):
        if a.ndim != 2 or a.shape[1] < 1:
            raise CalibrationInputError(
                f"{name} must have shape (n_samples, n_axes), e.g. 6 axes [Fx, Fy, Fz, Tx, Ty, Tz]; got shape "
                f"{a.shape}."
            )
        if not np.all(np.isfinite(a)):
            row = int(np.argwhere(~np.isfinite(a))[0, 0])
            raise CalibrationInputError(f"{name} contains NaN or inf (first at row {row}).")
    if t.shape != p.shape:
        raise CalibrationInputError(f"y_true has shape {t.shape} but y_pred has shape {p.shape}; they must match.")
    if t.shape[0] == 0:
        raise CalibrationInputError("y_true and y_pred are empty; metrics need at least one sample.")
    return t, p


def _axes(width: int, axes) -> tuple[str, ...]:
    """The axes of a target of ``width`` columns: ``axes`` if given, else Fx..Tz for six, else forces only
    (a target of another width is not torque-scaled, as in the calibrators)."""
    if axes is None:
        return WRENCH_LABELS if width == len(WRENCH_LABELS) else ("F",) * width
    torque_slice(width, axes)  # the one check that the axes name every column, with its message
    return tuple(axes)


def wrench_rmse(y_true: ArrayLike, y_pred: ArrayLike, alpha: float = 1.0, axes=None) -> float:
    """RMSE over all components of the torque-scaled wrench (eq. 18) [N], over the axes that exist.

    ``axes`` names the columns (``("Fx", "Fy", "Fz")`` for a 3-axis load cell: no torque to scale); default Fx..Tz
    for six columns.

    Examples
    --------
    >>> wrench_rmse([[0, 0, 0, 0, 0, 0.0]], [[6.0, 0, 0, 0, 0, 0]])
    2.449...
    >>> wrench_rmse([[0, 0, 0, 0, 0, 0.0]], [[0, 0, 0, 0, 0, 0.1]], alpha=60.0)
    2.449...
    """
    t, p = _pair(y_true, y_pred)
    return float(_checked_rms(scale_torques(t - p, alpha, axes), alpha))


def per_sample_rmse(y_true: ArrayLike, y_pred: ArrayLike, alpha: float = 1.0, axes=None) -> NDArray[np.float64]:
    """RMSE of each row over its torque-scaled components [N], shape (n_samples,).

    Examples
    --------
    >>> per_sample_rmse([[0, 0, 0, 0, 0, 0.0], [0, 0, 0, 0, 0, 0]],
    ...                 [[6.0, 0, 0, 0, 0, 0], [0, 0, 0, 0, 0, 0]])
    array([2.449..., 0. ])
    """
    t, p = _pair(y_true, y_pred)
    return _checked_rms(scale_torques(t - p, alpha, axes), alpha, axis=1)


def _checked_rms(errors: NDArray[np.float64], alpha: float, axis: int | None = None):
    """Root mean square of ``errors`` (along ``axis``); an error, not inf, when the squares overflow float64."""
    with np.errstate(over="ignore"):
        out = np.sqrt(np.mean(errors ** 2, axis=axis))
    if not np.isfinite(out).all() and np.isfinite(errors).all():
        raise CalibrationInputError(
            f"the RMSE overflows float64: the torque-scaled errors reach {np.abs(errors).max():.3g} "
            f"(alpha = {alpha:g} 1/m). Fix: check alpha (Fmax / Tmax of the sensor, usually 1-1000 1/m) and the units."
        )
    return out


def axis_rmse(y_true: ArrayLike, y_pred: ArrayLike) -> NDArray[np.float64]:
    """RMSE of each wrench axis in its own unit, shape (6,): [N] x3 then [N·m] x3.

    Examples
    --------
    >>> axis_rmse([[0, 0, 0, 0, 0, 0.0], [0, 0, 0, 0, 0, 0]],
    ...           [[3.0, 0, 0, 0, 0, 1], [-3.0, 0, 0, 0, 0, 1]])
    array([3., 0., 0., 0., 0., 1.])
    """
    t, p = _pair(y_true, y_pred)
    return np.sqrt(np.mean((t - p) ** 2, axis=0))


def relative_errors(
    y_true: ArrayLike, y_pred: ArrayLike, min_norm: float = 1e-3, axes=None
) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Per-sample relative force and torque errors (eq. 19).

    Parameters
    ----------
    y_true, y_pred : array-like of shape (n_samples, 6)
        Reference and predicted wrenches in [N] and [N·m].
    min_norm : float, default=1e-3
        Rows whose true force (torque) norm is below ``min_norm`` times the
        largest true force (torque) norm are left out of the force (torque)
        ratios.
    axes : sequence of str, optional
        The axes of the columns; a sensor without torques has no torque ratios (empty).

    Returns
    -------
    force, torque : ndarray
        The relative errors of the kept rows (dimensionless); their lengths may differ.

    Examples
    --------
    >>> f, t = relative_errors([[10.0, 0, 0, 0, 0, 2], [0, 0, 0, 0, 0, 0]],
    ...                        [[11.0, 0, 0, 0, 0, 2], [0, 0, 0, 0, 0, 0]])
    >>> f, t
    (array([0.1]), array([0.]))
    """
    t, p = _pair(y_true, y_pred)
    named = _axes(t.shape[1], axes)
    out = []
    for part in (force_columns(named), torque_columns(named)):
        if not part:
            out.append(np.zeros(0))
            continue
        norm = np.linalg.norm(t[:, part], axis=1)
        keep = norm > min_norm * max(float(norm.max()), np.finfo(float).tiny)
        err = np.linalg.norm(t[keep][:, part] - p[keep][:, part], axis=1)
        out.append(err / norm[keep])
    return out[0], out[1]


@dataclass(frozen=True)
class CalibrationMetrics:
    """Summary of a calibrator's errors on one test set.

    Attributes
    ----------
    rmse : float
        RMSE over the torque-scaled wrench [N] (eq. 18).
    rmse_per_sample_mean, rmse_per_sample_std : float
        Mean and std of the per-sample RMSE [N] (Table IV's "within the dataset").
    rel_force_mean, rel_force_std, rel_torque_mean, rel_torque_std : float
        Mean and std of the relative errors (eq. 19), dimensionless.
    axis_rmse : dict
        RMSE per axis in [N] / [N·m], keyed by the axes that exist (``Fx`` ... ``Tz``).
    alpha : float
        The torque scale used [m⁻¹].
    n_samples, n_force_ratios, n_torque_ratios : int
        Sample count and how many rows entered each relative error.
    """

    rmse: float
    rmse_per_sample_mean: float
    rmse_per_sample_std: float
    rel_force_mean: float
    rel_force_std: float
    rel_torque_mean: float
    rel_torque_std: float
    axis_rmse: dict
    alpha: float
    n_samples: int
    n_force_ratios: int
    n_torque_ratios: int
    axes: tuple = WRENCH_LABELS

    def to_dict(self) -> dict:
        """Plain-JSON form of the metrics."""
        return asdict(self)


def mean_std(values: ArrayLike, *, ddof: int) -> dict:
    """Mean, standard deviation and count of the finite entries of ``values`` (NaN, inf and None left out).

    The one mean/std of ftcal: ``ddof=0`` for the spread of a whole test set
    (per-sample errors, Tables III-IV "within the dataset"), ``ddof=1`` for a
    sample of datasets or seeds (Table II's "across datasets"). With no
    finite value the mean and std are NaN; with one and ``ddof=1`` the std is 0.

    Examples
    --------
    >>> mean_std([1.0, 2.0, 3.0, float("nan")], ddof=1)
    {'mean': 2.0, 'std': 1.0, 'n': 3}
    >>> mean_std([1.0, 3.0], ddof=0)
    {'mean': 2.0, 'std': 1.0, 'n': 2}
    """
    v = np.asarray([x for x in np.ravel(np.asarray(values, dtype=object)) if x is not None], dtype=float)
    v = v[np.isfinite(v)]
    if v.size == 0:
        return {"mean": float("nan"), "std": float("nan"), "n": 0}
    std = float(v.std(ddof=ddof)) if v.size > ddof else 0.0
    return {"mean": float(v.mean()), "std": std, "n": int(v.size)}


def calibration_metrics(
    y_true: ArrayLike, y_pred: ArrayLike, alpha: float = 1.0, min_norm: float = 1e-3, axes=None
) -> CalibrationMetrics:
    """Every metric of section IV-C for one prediction, as a :class:`CalibrationMetrics`, over the axes that exist
    (``axes``, default Fx..Tz for six columns: a 3-axis load cell has no torque scaling and no torque ratios).

    Examples
    --------
    >>> r = calibration_metrics([[10.0, 0, 0, 0, 0, 1]], [[11.0, 0, 0, 0, 0, 1]], alpha=10.0)
    >>> round(r.rmse, 4), r.rel_force_mean, r.axis_rmse["Fx"]
    (0.4082, 0.1, 1.0)
    """
    t, p = _pair(y_true, y_pred)
    named = _axes(t.shape[1], axes) if axes is not None else default_axes(t.shape[1])
    ps = per_sample_rmse(t, p, alpha, axes)
    f, tq = relative_errors(t, p, min_norm, axes)
    force, torque, per_sample = mean_std(f, ddof=0), mean_std(tq, ddof=0), mean_std(ps, ddof=0)
    return CalibrationMetrics(
        rmse=wrench_rmse(t, p, alpha, axes),
        rmse_per_sample_mean=per_sample["mean"],
        rmse_per_sample_std=per_sample["std"],
        rel_force_mean=force["mean"],
        rel_force_std=force["std"],
        rel_torque_mean=torque["mean"],
        rel_torque_std=torque["std"],
        axis_rmse=dict(zip(named, map(float, axis_rmse(t, p)))),
        alpha=float(alpha),
        n_samples=int(t.shape[0]),
        n_force_ratios=int(f.size),
        n_torque_ratios=int(tq.size),
        axes=tuple(named),
    )


def _torque_scale_of(estimator) -> tuple[float, tuple | None]:
    """The ``alpha_`` (and the wrench ``axes_`` its target named, or None) of ``estimator``, or of the fitted
    calibrator it wraps: the final step of a ``Pipeline``
    (nested ones too), the ``best_estimator_`` of a search (``GridSearchCV``, ...), a ``FrozenEstimator``'s
    estimator. Refuses (``CalibrationInputError``) when there is none, rather than scoring with alpha = 1."""
    path, current = [], estimator
    for _ in range(100):  # a chain of wrappers, never a cycle
        path.append(type(current).__name__)
        alpha = current.__dict__.get("alpha_") if hasattr(current, "__dict__") else None
        if alpha is not None:
            alpha = float(alpha)
            if not 0 < alpha < np.inf:
                raise CalibrationInputError(f"neg_scaled_rmse: the {path[-1]}'s alpha_ is {alpha!r}; a torque scale "
                                            "is a finite number > 0 [1/m]. Fix: fit the calibrator again.")
            axes = current.__dict__.get("axes_")
            return alpha, None if axes is None else tuple(str(a) for a in axes)
        steps = getattr(current, "steps", None)
        if isinstance(steps, list) and steps and isinstance(steps[-1], tuple) and len(steps[-1]) == 2:
            current = steps[-1][1]  # a Pipeline: its final estimator
        elif "best_estimator_" in getattr(current, "__dict__", {}):
            current = current.best_estimator_  # a fitted search (GridSearchCV, RandomizedSearchCV, ...)
        elif type(current).__name__ == "FrozenEstimator":
            current = current.estimator
        else:
            break
    raise CalibrationInputError(
        f"neg_scaled_rmse needs the torque scale alpha_ [1/m] of a fitted ftcal calibrator (eq. 18), but "
        f"{' -> '.join(path)} has none (it looks through Pipeline final steps, a search's best_estimator_ and "
        "FrozenEstimator). Fix: end the pipeline with an ftcal calibrator, or score with a fixed torque scale: "
        "sklearn.metrics.make_scorer(ftcal.core.wrench_rmse, greater_is_better=False, alpha=<Fmax / Tmax in 1/m>).")


def neg_scaled_rmse(estimator, X: ArrayLike, y: ArrayLike) -> float:
    """scikit-learn scorer: minus the torque-scaled RMSE (eq. 18), with the fitted calibrator's own ``alpha_`` (and
    the wrench axes its target named: a plate's ``Fz, Tx, Ty`` has its torques scaled).

    Use it as ``scoring=neg_scaled_rmse`` in ``cross_validate`` or ``GridSearchCV`` (greater is better, as
    scikit-learn expects), on a calibrator or on a ``Pipeline`` ending with one (nested pipelines, a fitted
    search's ``best_estimator_`` and a ``FrozenEstimator`` are looked through). An estimator without such a
    calibrator is refused with a :class:`~ftcal.core.CalibrationInputError`: torques scored with ``alpha = 1`` would
    count a torque error in N·m as a force error in N. For a fixed torque scale use
    ``make_scorer(wrench_rmse, greater_is_better=False, alpha=...)``.

    Examples
    --------
    >>> import numpy as np
    >>> from sklearn.pipeline import make_pipeline
    >>> from sklearn.preprocessing import StandardScaler
    >>> from ftcal import LinearCalibrator
    >>> raw = np.random.default_rng(0).normal(size=(30, 6)); wrench = raw @ np.diag([1, 1, 1, .1, .1, .1])
    >>> pipe = make_pipeline(StandardScaler(), LinearCalibrator(alpha=10.0)).fit(raw, wrench)
    >>> round(neg_scaled_rmse(pipe, raw, wrench + [0, 0, 0, 0, 0, 0.6]), 6)  # 0.6 N·m x 10 / m, one of six
    -2.44949
    """
    alpha, axes = _torque_scale_of(estimator)  # the torques of the axes the calibrator was fitted on
    return -wrench_rmse(y, estimator.predict(X), alpha, axes)
