"""``groups`` and ``sample_weight`` through scikit-learn's metadata routing, for ftcal's wrappers and its
model-choosing calibrators.

Calibration data come in groups (the rows of one pose, one load
configuration); a calibrator that chooses something by cross-validation
inside its ``fit`` (the hybrid's ridge, :class:`~ftcal.AutoCalibrator`) must
hold out whole groups. ``groups`` reach it the scikit-learn way:

* a calibrator that uses them **requests** them by default
  (``__metadata_request__fit = {"groups": True}``, like scikit-learn's group
  splitters); ``set_fit_request(groups=False)`` turns that off;
* a wrapper (:class:`~ftcal.EnsembleCalibrator`,
  :class:`~ftcal.TemperatureCompensatedCalibrator`) is a **router**: its
  ``get_metadata_routing`` names its inner calibrator, and ``fit(X, y,
  groups=...)`` passes them on with :func:`~sklearn.utils.metadata_routing.process_routing`
  when the inner calibrator requests them. It accepts ``groups`` whatever it
  wraps, so a dataset's groups can always be given;
* with ``sklearn.set_config(enable_metadata_routing=True)``,
  :class:`~sklearn.pipeline.Pipeline`, :class:`~sklearn.model_selection.GridSearchCV`
  and :func:`~sklearn.model_selection.cross_validate` pass them through to
  every ftcal calibrator that requests them (and to their group splitters).

``sample_weight`` goes the same way: the calibrators that weigh their rows (a weighted least squares:
:class:`~ftcal.LinearCalibrator`, :class:`~ftcal.PolynomialCalibrator`) request it by default, and a wrapper
given weights passes them to its inner calibrator, as scikit-learn's ``StackingRegressor`` passes them to its
estimators; a wrapper whose inner calibrator does not take them refuses them with an error naming it (weights
silently dropped would be a fit other than the one asked for).

No signature is inspected: what a calibrator receives is what its routing says.
"""

from __future__ import annotations

from sklearn.utils.metadata_routing import MetadataRouter, MethodMapping, get_routing_for_object, process_routing

from ..core._exceptions import CalibrationInputError

__all__ = ["wrapper_routing", "routed_fit_params", "requests_groups", "requests"]


def wrapper_routing(owner, **children) -> MetadataRouter:
    """The routing of a wrapper (its ``estimator``) or a calibrator of several models (``children``: name ->
    model): it accepts ``groups`` (and ``sample_weight``) itself and routes ``fit`` metadata to each child."""
    return MetadataRouter(owner=owner).add_self_request(owner).add(
        **children, method_mapping=MethodMapping().add(caller="fit", callee="fit"))


def routed_fit_params(owner, groups=None, *, sample_weight=None, inner=None) -> dict:
    """The ``fit`` parameters ``owner``'s routing gives its inner ``estimator`` for these ``groups`` and weights.

    Raises
    ------
    CalibrationInputError
        ``sample_weight`` given while the inner calibrator (``inner``, named in the message) does not take or
        request it.
    """
    params = {name: value for name, value in (("groups", groups), ("sample_weight", sample_weight))
              if value is not None}
    if not params:
        return {}
    if sample_weight is not None and not requests(owner, "sample_weight"):
        what = type(inner).__name__ if inner is not None else "its estimator"
        raise CalibrationInputError(
            f"{type(owner).__name__} was given sample_weight but {what} does not take sample weights (its fit has "
            "no sample_weight, or it was set with set_fit_request(sample_weight=False)); use an estimator that "
            "weighs its rows (LinearCalibrator, PolynomialCalibrator) or fit without sample_weight.",
            parameter="sample_weight")
    return dict(process_routing(owner, "fit", **params).estimator.fit)


def requests(estimator, name: str) -> bool:
    """Whether ``estimator.fit`` (or a calibrator inside it) asks for the metadata ``name`` through its routing."""
    return name in get_routing_for_object(estimator).consumes(method="fit", params=[name])


def requests_groups(estimator) -> bool:
    """Whether ``estimator.fit`` (or a calibrator inside it) asks for ``groups`` through its routing.

    Examples
    --------
    >>> from ftcal import AxisNonlinearCalibrator, LinearCalibrator
    >>> requests_groups(AxisNonlinearCalibrator()), requests_groups(LinearCalibrator())
    (True, False)
    """
    return requests(estimator, "groups")
