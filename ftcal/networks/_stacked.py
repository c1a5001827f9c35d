"""Several network calibrators trained at once in the one engine (:func:`fit_stacked`)."""

from __future__ import annotations

from collections.abc import Sequence

from numpy.typing import ArrayLike

from ..core._exceptions import CalibrationInputError
from ..calibrators._base import calibration_tags
from ._base import NetworkCalibrator, train_networks
from ._modules import StackedMLP

__all__ = ["StackedMLP", "fit_stacked"]


def _stacking_key(estimator) -> tuple:
    """What stacked members must share: class and every training parameter (not seed, tare or scale)."""
    may_differ = ("random_state", "alpha", "zero_reading", "verbose")
    return type(estimator), tuple(sorted((k, repr(v)) for k, v in estimator.get_params(deep=False).items()
                                         if k not in may_differ))


def _datasets(X, y, K: int) -> list[tuple]:
    if isinstance(X, (list, tuple)) != isinstance(y, (list, tuple)):
        raise CalibrationInputError(
            "fit_stacked: pass X and y both as arrays (one dataset for every estimator) or both as lists "
            f"(one dataset per estimator); got X as {type(X).__name__} and y as {type(y).__name__}.")
    if not isinstance(X, (list, tuple)):
        return [(X, y)] * K
    if len(X) != K or len(y) != K:
        raise CalibrationInputError(f"fit_stacked: {K} estimators need {K} datasets; got {len(X)} X and {len(y)} y.")
    return list(zip(X, y))


def fit_stacked(estimators: Sequence[NetworkCalibrator], X: ArrayLike | Sequence[ArrayLike],
                y: ArrayLike | Sequence[ArrayLike]) -> list[NetworkCalibrator]:
    """Fit ``K`` network calibrators of one kind together, as one stacked module.

    Each member keeps its own seed, data, loss, Adam state and schedule, so each estimator ends fitted as its own
    ``fit`` would leave it (``net_``, its history, scales and tare), up to float32 rounding, for far less than ``K``
    fits (``benchmarks/network_speed.py``). The rounding of a stacked step differs from a lone one's, and training
    can amplify it (a plateau or a stop decided one epoch apart): usually the two fits agree to 1e-7, but a
    comparative network on 100 rows of the soft-sensor preset ended 5 % apart (``benchmarks/RESULTS.md``).

    Parameters
    ----------
    estimators : sequence of DirectionalCalibrator or ComparativeCalibrator
        ``K >= 1`` calibrators of one class with the same parameters except ``random_state``, ``alpha``,
        ``zero_reading`` and ``verbose`` (they share the architecture and the schedule); for ``K > 1`` without
        ``callbacks`` (a skorch callback sees one net: fit such an estimator by itself).
    X : array-like of shape (n, N), or a list of K of them
        Raw readings: one dataset for every estimator (seed ensembles), or one per estimator (K datasets at once).
    y : array-like of shape (n, 6), or a list of K of them
        Reference wrenches, like ``X``.

    Returns
    -------
    list
        The fitted estimators (the same objects).

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import DirectionalCalibrator
    >>> from ftcal.networks import fit_stacked
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(60, 6)); raw = w @ rng.normal(size=(6, 6))
    >>> nets = [DirectionalCalibrator(phase1_epochs=3, plateau_epochs=1, max_recover_epochs=1, random_state=s)
    ...         for s in range(3)]
    >>> fitted = fit_stacked(nets, raw, w)
    >>> [m.predict(raw[:1]).shape for m in fitted]
    [(1, 6), (1, 6), (1, 6)]
    """
    estimators = list(estimators)
    if not estimators:
        raise CalibrationInputError("fit_stacked needs at least one estimator (K >= 1); got an empty list.")
    for k, est in enumerate(estimators):
        if not calibration_tags(est).network:  # its tags: a network trained by skorch
            problem = (f" trains network calibrators (DirectionalCalibrator, ComparativeCalibrator); estimator {k} is "
                       f"{type(est).__name__}. Fit it with its own fit().")
        elif est.callbacks and len(estimators) > 1:
            problem = (f": estimator {k} has callbacks={est.callbacks!r}; skorch callbacks run per net, so fit that "
                       "estimator by itself.")
        elif _stacking_key(est) != _stacking_key(estimators[0]):
            problem = (f": estimator {k} differs from estimator 0 in a training parameter; stacked nets share the "
                       "architecture and the schedule (only random_state, alpha and zero_reading may differ).")
        elif est.device != "cpu":
            problem = f" trains on the CPU; estimator {k} has device={est.device!r}."
        else:
            continue
        raise CalibrationInputError(f"fit_stacked{problem}")
    with estimators[0]._thread_limit():  # as BaseCalibrator.fit does around _prepare_fit
        datasets = [est._prepare_fit(X_k, y_k) for est, (X_k, y_k) in zip(estimators, _datasets(X, y, len(estimators)))]
    train_networks(estimators, datasets)
    return estimators
