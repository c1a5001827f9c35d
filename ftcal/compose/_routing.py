"""``groups`` through scikit-learn's metadata routing, for ftcal's wrappers and its model-choosing calibrators.

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

No signature is inspected: what a calibrator receives is what its routing says.
"""

from __future__ import annotations

from sklearn.utils.metadata_routing import MetadataRouter, MethodMapping, get_routing_for_object, process_routing

__all__ = ["wrapper_routing", "routed_fit_params", "requests_groups"]


def wrapper_routing(owner, estimator) -> MetadataRouter:
    """The routing of a wrapper: it accepts ``groups`` itself and routes ``fit`` metadata to ``estimator``."""
    return MetadataRouter(owner=owner).add_self_request(owner).add(
        estimator=estimator, method_mapping=MethodMapping().add(caller="fit", callee="fit"))


def routed_fit_params(owner, groups) -> dict:
    """The ``fit`` parameters ``owner``'s routing gives its inner ``estimator`` for these ``groups``."""
    if groups is None:
        return {}
    return dict(process_routing(owner, "fit", groups=groups).estimator.fit)


def requests_groups(estimator) -> bool:
    """Whether ``estimator.fit`` (or a calibrator inside it) asks for ``groups`` through its routing.

    Examples
    --------
    >>> from ftcal import AxisNonlinearCalibrator, LinearCalibrator
    >>> requests_groups(AxisNonlinearCalibrator()), requests_groups(LinearCalibrator())
    (True, False)
    """
    return "groups" in get_routing_for_object(estimator).consumes(method="fit", params=["groups"])
