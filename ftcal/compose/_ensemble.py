"""Seed ensembles of calibrators: lower across-dataset variance of the network models."""

from __future__ import annotations

import inspect
from numbers import Integral
from collections.abc import Callable

import numpy as np
from joblib import Parallel, delayed
from numpy.typing import NDArray
from sklearn.base import clone
from sklearn.utils import check_random_state
from sklearn.utils._param_validation import HasMethods, Interval

from ..calibrators._base import calibration_tags, declare
from ..networks._directional import DirectionalCalibrator
from ..networks._stacked import fit_stacked
from ._wrapper import CalibratorWrapper

__all__ = ["EnsembleCalibrator", "ensemble_factory"]


class EnsembleCalibrator(CalibratorWrapper):
    """Average of ``n_members`` copies of a calibrator trained with different seeds.

    The thesis (VI-a) notes that the networks' accuracy varies a lot across
    datasets and initialisations. Each member is a clone of ``estimator``
    with its own ``random_state`` (drawn from this ensemble's
    ``random_state``), so members differ in weight initialisation, batch
    order and validation split; all see the same data. The prediction is
    the plain mean of the members' predictions, in [N] and [N·m]. Averaging
    cancels the members' independent (seed) part of the error only; what
    the members share stays: the data's own noise floor and the model's
    bias. Measured on the artificial benchmark (30 datasets per preset, 5
    directional members, short schedule; ``benchmarks/RESULTS.md``, issue
    6): the excess RMSE over the noise floor drops from 1.82 to 0.49 N
    (``thesis``) and 2.17 to 0.89 N (``asymmetric``), and its
    across-dataset std 7x and 3.7x; the std of the RMSE itself only falls to
    0.72x-0.73x, because the noise floor's own std (0.39-0.49 N) is part of
    every model's. On ``stress`` it barely helps (0.91x): there the directional
    model's error is bias (it cannot represent intra-axis nonlinearity),
    which every seed shares; use :class:`~ftcal.AxisNonlinearCalibrator`.
    Network members (:class:`~ftcal.DirectionalCalibrator`,
    :class:`~ftcal.ComparativeCalibrator` on the CPU, without ``callbacks``)
    are trained together as one stacked module (:func:`~ftcal.networks.fit_stacked`):
    five members cost about one fit's time (``benchmarks/network_speed.py``),
    with the weights separate fits would reach. Other members cost one fit
    each, run in parallel with ``n_jobs``.
    ``predict`` (from :class:`~ftcal.calibrators._base.BaseCalibrator`) validates the
    readings once and returns the members' mean.

    Parameters
    ----------
    estimator : calibrator, regressor or None, default=None
        The member template (e.g. :class:`~ftcal.DirectionalCalibrator` with a
        schedule); ``None`` means ``DirectionalCalibrator()``. Its own
        ``random_state`` is replaced per member. Any scikit-learn regressor
        may be given: it is composed into a calibrator
        (:func:`~ftcal.calibrators.as_calibrator`: a
        :class:`~ftcal.calibrators.StockCalibrator` around it, whose seed does
        not reach the regressor's own ``random_state``).
    n_members : int, default=5
        Number of members averaged.
    n_jobs : int or None, default=None
        joblib workers for fitting members that are not stacked networks
        (``None`` = 1).
    random_state : int, RandomState or None, default=None
        Seed of the members' seeds; an int makes the ensemble reproducible.

    Attributes
    ----------
    estimators_ : list of fitted calibrators
        The members.
    member_seeds_ : ndarray of shape (n_members,)
        ``random_state`` of each member.
    alpha_, zero_reading_, n_features_in_
        As for every calibrator (from the members, which share them).

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import DirectionalCalibrator, EnsembleCalibrator
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(40, 6)); raw = w @ rng.normal(size=(6, 6))
    >>> member = DirectionalCalibrator(phase1_epochs=2, plateau_epochs=1, max_recover_epochs=1)
    >>> ensemble = EnsembleCalibrator(member, n_members=3, random_state=0).fit(raw, w)
    >>> mean = np.mean([m.predict(raw) for m in ensemble.estimators_], axis=0)
    >>> bool(np.allclose(ensemble.predict(raw), mean))
    True
    """

    _fitted_state = ("member_seeds_", "estimators_")
    _fitted_constraints: dict = {"member_seeds_": [Interval(Integral, 0, np.iinfo(np.int32).max, closed="both")]}
    _default = DirectionalCalibrator
    _parameter_constraints: dict = {
        "estimator": [HasMethods(["fit", "predict"]), None],
        "n_members": [Interval(Integral, 1, None, closed="left")],
        "n_jobs": [Interval(Integral, 1, 1024, closed="both"), Interval(Integral, -1024, -1, closed="both"), None],
        "random_state": ["random_state"],
    }

    def __init__(self, estimator=None, *, n_members=5, n_jobs=None, random_state=None):
        self.estimator = estimator
        self.n_members = n_members
        self.n_jobs = n_jobs
        self.random_state = random_state

    def __sklearn_tags__(self):
        # n_members fits: costly work for auto's scheduling whatever the member (a network's when it is one)
        return declare(super().__sklearn_tags__(), cost="network" if calibration_tags(self._inner()).network
                       else "heavy")

    def _fit_inner(self, X, y, template, routed):
        """Every member fitted (stacked when they are CPU networks and no metadata is routed): the first gives the
        torque scale and the tare, which the members share."""
        n = self.n_members
        member = calibration_tags(template)
        if member.network:  # every member's training memory, before building any
            template._check_network_memory(X.shape[1], len(X), members=int(n))
        rng = check_random_state(self.random_state)
        self.member_seeds_ = rng.randint(np.iinfo(np.int32).max, size=int(n))
        members = [clone(template).set_params(random_state=int(s)) for s in self.member_seeds_]
        if member.stackable and template.device == "cpu" and not routed:
            self.estimators_ = fit_stacked(members, X, y)  # one stacked module: ~1 fit's time, not n_members'
        else:
            self.estimators_ = Parallel(n_jobs=self.n_jobs)(delayed(m.fit)(X, y, **routed) for m in members)
        return self.estimators_[0], None

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        return np.mean([member.predict(X) for member in self.estimators_], axis=0)

    def _emit_onnx(self, g, x: str) -> str:
        members = [g.calibration(member, x) for member in self.estimators_]
        total = members[0] if len(members) == 1 else g.op("Sum", *members)
        return g.op("Div", total, g.const(float(len(members))))


def ensemble_factory(member_class: type) -> Callable[..., EnsembleCalibrator]:
    """A registry factory building an :class:`EnsembleCalibrator` of ``member_class`` networks.

    Examples
    --------
    >>> from ftcal import DirectionalCalibrator
    >>> ens = ensemble_factory(DirectionalCalibrator)(random_state=0, n_members=3, phase1_epochs=5)
    >>> ens.n_members, ens.estimator.phase1_epochs
    (3, 5)
    """

    def build(random_state=None, n_members=5, n_jobs=None, **member_params) -> EnsembleCalibrator:
        return EnsembleCalibrator(member_class(**member_params), n_members=n_members, n_jobs=n_jobs,
                                  random_state=random_state)

    build.__name__ = f"{member_class.__name__}_ensemble"
    # The registry (and `ftcal fit --param`) read the accepted names from the signature: the ensemble's own
    # parameters plus every member parameter.
    own = [p for p in inspect.signature(build).parameters.values() if p.kind is not inspect.Parameter.VAR_KEYWORD]
    members = [p.replace(kind=inspect.Parameter.KEYWORD_ONLY)
               for p in inspect.signature(member_class).parameters.values() if p.name != "random_state"]
    build.__signature__ = inspect.Signature(own + members)
    return build
