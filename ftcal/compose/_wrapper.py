"""The composition every ftcal wrapper shares: a calibrator around an inner calibrator (or any regressor).

:class:`CalibratorWrapper` is to a calibrator what scikit-learn's
:class:`~sklearn.compose.TransformedTargetRegressor` is to a regressor: it owns what lies around the inner model
once, so that a wrapper (:class:`~ftcal.EnsembleCalibrator`, :class:`~ftcal.TemperatureCompensatedCalibrator`,
:class:`~ftcal.HistoryCalibrator`) only says what it does in between:

* the inner model: ``estimator`` (a calibrator, or a user's regressor composed by
  :func:`~ftcal.calibrators.as_calibrator`), or the wrapper's default; the wrapper's own ``alpha``,
  ``zero_reading`` and ``random_state`` given to it where they are not None;
* ``fit``: the parameters checked, the data validated (the wrench axes ``y`` names kept), a load-history model
  inside refused, ``groups`` and ``sample_weight`` routed to the inner model (:mod:`ftcal.compose._routing`), and
  the calibration recorded around the fitted inner model
  (:meth:`~ftcal.calibrators._base.BaseCalibrator._adopt_fitted`: its torque scale ``alpha_`` and tare
  ``zero_reading_``, the wrapper's own calibrated range and reading noise, no re-tare);
* ``predict``, :meth:`~ftcal.calibrators._base.BaseCalibrator.retare` and
  :meth:`~ftcal.calibrators._base.BaseCalibrator.out_of_range` of every calibrator, on what the wrapper is given;
* the tags of the inner model it inherits (its cost, whether it uses groups).
"""

from __future__ import annotations

from numpy.typing import ArrayLike, NDArray
import numpy as np

from ..calibrators._base import BaseCalibrator, calibration_tags, declare, with_settings
from ..calibrators._baselines import as_calibrator
from ..calibrators._linear import LinearCalibrator
from ..core._exceptions import CalibrationInputError
from ..core._validation import validate_training_data
from ..core._wrench import named_targets
from ._routing import routed_fit_params, wrapper_routing

__all__ = ["CalibratorWrapper", "reads_history", "refuse_history_inside"]


def reads_history(model) -> bool:
    """Whether ``model`` reads its rows as a time series (a load-history model: :class:`~ftcal.HistoryCalibrator`),
    as its tags declare (:class:`~ftcal.calibrators._base.CalibrationTags`)."""
    return calibration_tags(model).reads_history


def refuse_history_inside(estimator, owner: str) -> None:
    """Refuse a load-history model as the inner calibrator of wrapper ``owner``: its history would restart at every
    chunk of a stream and its rows be shuffled by the wrapper's resampling; it must be the outermost model."""
    if reads_history(estimator):
        fix = ("use one HistoryCalibrator: it chooses the time constant itself" if owner == "HistoryCalibrator" else
               f"Put the history term outermost, e.g. HistoryCalibrator({owner}(...))")
        raise CalibrationInputError(
            f"{owner} cannot wrap {type(estimator).__name__}, a load-history model: it reads its rows as a time "
            f"series, which {owner} does not keep. {fix}.")


class CalibratorWrapper(BaseCalibrator):
    """Base of a calibrator around the calibrator ``estimator``; not meant to be used directly.

    A subclass names its default inner model (``_default``, a class) and implements
    ``_fit_inner(X, y, inner, routed)``: fit ``inner`` (a fresh, unfitted one; ``y`` names its wrench axes) with
    the routed ``fit`` parameters and return the fitted calibrator whose torque scale and tare the wrapper takes,
    and the zero-load reading of the wrapper's own columns (None: that calibrator's).
    """

    #: Accepts the groups of the rows and passes them on when the inner calibrator requests them.
    __metadata_request__fit = {"groups": True}
    _default: type = LinearCalibrator

    def _inner(self) -> BaseCalibrator:
        """The inner calibrator, unfitted: ``estimator`` composed into a calibrator, or the default."""
        return self._default() if self.estimator is None else as_calibrator(self.estimator)

    def _settled(self, inner: BaseCalibrator, **given) -> BaseCalibrator:
        """A clone of ``inner`` with the wrapper's ``alpha``, ``zero_reading``, ``random_state`` (those it has and
        that are not None; ``given`` first): where the wrapper leaves one None, the inner calibrator's own stays."""
        own = {name: getattr(self, name, None) for name in ("alpha", "zero_reading", "random_state")}
        return with_settings(inner, **{**own, **given})

    def _given_alpha(self) -> float | None:
        """The wrapper's ``alpha``, else the inner calibrator's own (None: derived from the training targets)."""
        alpha = getattr(self, "alpha", None)
        return getattr(self._inner(), "alpha", None) if alpha is None else alpha

    def __sklearn_tags__(self):
        inner = calibration_tags(self._inner())
        # a model that chose itself by cross-validation (auto) inside: the wrapper is no more refitted per fold by
        # the held-out check before saving than the model alone (which checked its held-out predictions in fit)
        return declare(super().__sklearn_tags__(), cost=inner.cost, uses_groups=inner.uses_groups,
                       chooses_model=inner.chooses_model)

    def get_metadata_routing(self):
        """Routing of ``fit``'s ``groups`` and ``sample_weight`` to ``estimator`` (:mod:`ftcal.compose._routing`)."""
        return wrapper_routing(self, estimator=self._inner())

    def fit(self, X: ArrayLike, y: ArrayLike, groups: ArrayLike | None = None, sample_weight: ArrayLike | None = None):
        """Fit on raw readings ``X`` (n, N) and wrenches ``y`` (n, 6).

        Parameters
        ----------
        groups : array-like of shape (n,) or None
            Group of each row (pose, load configuration), passed to ``estimator`` when it requests them (metadata
            routing), so that an inner model choice (``auto``, the hybrid's ridge) holds out whole groups.
        sample_weight : array-like of shape (n,) or None
            Weight of each row, passed to ``estimator`` (metadata routing); an error when it does not take weights.

        Returns
        -------
        self
        """
        self._check_parameters()
        axes = self._remember_axes(y)
        X, y = validate_training_data(self, X, y)
        inner = self._inner()
        refuse_history_inside(inner, type(self).__name__)
        routed = routed_fit_params(self, groups, sample_weight=sample_weight, inner=inner)
        fitted, zero_reading = self._fit_inner(X, named_targets(y, axes), inner, routed)
        self._adopt_fitted(X, y, fitted, zero_reading=zero_reading)
        return self

    def _fit_inner(self, X: NDArray[np.float64], y, inner: BaseCalibrator,
                   routed: dict) -> tuple[BaseCalibrator, NDArray[np.float64] | None]:  # pragma: no cover
        raise NotImplementedError
