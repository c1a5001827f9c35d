"""``calibrate``: a dataset in, a fitted calibration out, judged on the one fold plan and, on request, certified."""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Callable

from ..calibrators._base import calibration_tags
from ..compose._auto import check_calibration
from ..compose._registry import make_calibrator
from ..compose._routing import requests_groups
from ..core._wrench import default_axes, named_targets
from ..io._dataset import CalibrationDataset
from ..model_selection._comparison import Comparison
from ..model_selection._plan import FoldPlan

__all__ = ["calibrate", "Calibration"]


@dataclass
class Calibration:
    """What :func:`calibrate` returns.

    Attributes
    ----------
    model : fitted calibrator
    summary : Comparison or None
        The fit summary of a model that chose among candidates (``auto``'s ``comparison_``), else None.
    plan : FoldPlan
        The folds the model was judged on (the save gate; ``auto``'s own folds when it chose).
    certificate : object or None
        The calibration certificate (:func:`ftcal.reporting.calibration_certificate`), with ``certify=True``; the
        save gate then judges the certificate's held-out predictions (the model is refitted once per fold, not
        twice).
    seconds : float
        Wall time of the fit [s].
    """

    model: Any
    summary: Comparison | None
    plan: FoldPlan
    certificate: Any = None
    seconds: float = 0.0


def calibrate(dataset: CalibrationDataset, model: Any = "auto", *, certify: bool = False, cv: int = 5,
              random_state: int = 0, check: bool = True, certificate_options: dict | None = None,
              fit: Callable[..., Any] | None = None, **params) -> Calibration:
    """Fit a calibration on ``dataset``, refuse it if it must not be kept, and certify it on request.

    What ``ftcal fit`` does (without writing files): the model (a registry name with ``params``, or an
    unfitted estimator) is fitted on the dataset's readings and wrench (the dataset's groups reach a model that
    requests them: ``auto``'s folds, one offset per group); then judged on the one fold plan
    (:meth:`~ftcal.model_selection.FoldPlan.for_data`, ``auto``'s own when it chose) by
    :func:`~ftcal.compose.check_calibration`: a calibration whose held-out predictions on that plan are degenerate
    (constant, all zero, no better than the mean wrench) raises
    :class:`~ftcal.model_selection.DegenerateCalibrationError`, whatever the model's cost (a network is refitted
    once per fold: a model can look fine on its training rows and fail held out). With ``certify`` the
    certificate of :func:`ftcal.reporting.calibration_certificate` is made on the same data.

    Parameters
    ----------
    dataset : CalibrationDataset
    model : str or estimator, default="auto"
        A name of :func:`~ftcal.make_calibrator` or an unfitted estimator (fitted in place).
    certify : bool, default=False
    cv : int, default=5
        Folds of the judging plan and of ``auto``.
    random_state : int, default=0
        Seed of the folds (and of the model, for a name).
    check : bool, default=True
        Refuse a degenerate calibration (the save gate).
    certificate_options : dict, optional
        Keyword arguments of :func:`ftcal.reporting.calibration_certificate` (``rated``, ``spec``, ...).
    fit : callable, optional
        ``fit(estimator, X, y, **fit_params)`` instead of ``estimator.fit(X, y, **fit_params)`` (the CLI's
        progress bar).
    **params
        Parameters of the named model.

    Returns
    -------
    Calibration

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import CalibrationDataset
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(80, 6)); raw = w @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(80, 6))
    >>> result = calibrate(CalibrationDataset(raw=raw, wrench=w), "linear")
    >>> type(result.model).__name__, result.summary is None, result.plan.kind
    ('LinearCalibrator', True, 'kfold')
    """
    if isinstance(model, str):
        if "cv" not in params and model == "auto":
            params["cv"] = cv
        estimator = make_calibrator(model, random_state=random_state, **params)
    elif params:
        raise TypeError(f"calibrate: parameters {sorted(params)} are for a model given by name; set them on the "
                        "estimator instead.")
    else:
        estimator = model
    # the raw channels, plus the temperature column for a model that reads it (its tags)
    X = dataset.features(temperature=True) if calibration_tags(estimator).temperature_column else dataset.raw
    axes = tuple(dataset.axes)
    y = named_targets(dataset.wrench, None if axes == default_axes(len(axes)) else axes)
    fit_params = {"groups": dataset.group} if dataset.group is not None and requests_groups(estimator) else {}
    start = time.perf_counter()
    (fit or (lambda est, X_, y_, **kw: est.fit(X_, y_, **kw)))(estimator, X, y, **fit_params)
    seconds = time.perf_counter() - start
    tags = calibration_tags(estimator)
    groups = fit_params.get("groups", dataset.group)
    plan = getattr(estimator, "fold_plan_", None)  # auto's own, unless it chose on a subsample of the rows
    if plan is None or plan.n_rows != len(X):
        plan = FoldPlan.for_data(X, dataset.wrench, groups, cv=cv, seed=random_state, ordered=tags.reads_history)
    summary = getattr(estimator, "comparison_", None) if tags.chooses_model else None
    certificate = None
    if certify:  # the certificate refits the model once per fold of the plan: the gate judges those predictions
        from ..reporting import calibration_certificate

        certificate = calibration_certificate(estimator, dataset, cv=cv, random_state=random_state,
                                              **(certificate_options or {}))
    if check:  # every model on its held-out predictions of the plan: a costly one is refitted per fold (once)
        held_out = None if certificate is None or tags.chooses_model else certificate.held_out_predictions
        check_calibration(estimator, X, dataset.wrench, groups=groups, random_state=random_state, plan=plan,
                          predictions=held_out)
    return Calibration(model=estimator, summary=summary, plan=plan, certificate=certificate, seconds=seconds)
