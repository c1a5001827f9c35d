"""Registry and model-file entries of the issue-6 calibrators (polynomial, axis-nonlinear hybrid, ensembles).

Imported by ``ftcal/__init__.py`` after the core registry, so
``make_calibrator``, the benchmarks and the CLI know these names:

* ``"polynomial"``: :class:`~ftcal.PolynomialCalibrator` (no training schedule);
* ``"axis_nonlinear"``: :class:`~ftcal.AxisNonlinearCalibrator`, the hybrid (no schedule);
* ``"directional_ensemble"`` / ``"comparative_ensemble"``:
  :class:`~ftcal.EnsembleCalibrator` of ``n_members`` (default 5) directional /
  comparative networks; the named schedule and every other parameter go to
  the members, ``n_members`` and ``n_jobs`` to the ensemble.

It also registers the three classes with :mod:`ftcal._model_io`, so
``save_model`` / ``load_model`` handle them (an ensemble stores its members).
"""

from __future__ import annotations

import inspect
from collections.abc import Callable

from ._comparative import ComparativeCalibrator
from ._directional import DirectionalCalibrator
from ._auto import AutoCalibrator
from ._ensemble import EnsembleCalibrator
from ._gaussian_process import GaussianProcessCalibrator
from ._temperature import TemperatureCompensatedCalibrator
from ._hybrid import AxisNonlinearCalibrator
from ._model_io import register_model_type
from ._polynomial import PolynomialCalibrator
from ._registry import SCHEDULE_NAMES, register_calibrator, training_schedule

__all__ = ["ensemble_factory"]


def ensemble_factory(member_class: type) -> Callable[..., EnsembleCalibrator]:
    """A registry factory building an :class:`EnsembleCalibrator` of ``member_class`` networks.

    Examples
    --------
    >>> from ftcal import DirectionalCalibrator
    >>> ens = ensemble_factory(DirectionalCalibrator)(random_state=0, n_members=3, max_epochs=5)
    >>> ens.n_members, ens.estimator.max_epochs
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


register_calibrator("polynomial", PolynomialCalibrator)
register_calibrator("axis_nonlinear", AxisNonlinearCalibrator)
register_calibrator("gaussian_process", GaussianProcessCalibrator)
for _name, _cls in (("directional", DirectionalCalibrator), ("comparative", ComparativeCalibrator)):
    register_calibrator(
        f"{_name}_ensemble",
        ensemble_factory(_cls),
        schedules={s: training_schedule(s, _name) for s in SCHEDULE_NAMES},
    )

register_model_type(
    PolynomialCalibrator, ("alpha_", "n_features_in_"), ("zero_reading_", "input_scale_", "coef_", "intercept_")
)
register_model_type(
    AxisNonlinearCalibrator,
    ("alpha_", "n_features_in_", "ridge_"),
    ("zero_reading_", "base_matrix_", "base_offset_", "axis_scale_", "coefs_", "intercepts_"),
)
register_model_type(
    EnsembleCalibrator, ("alpha_", "n_features_in_"), ("zero_reading_", "member_seeds_"), children="estimators_"
)
register_model_type(
    GaussianProcessCalibrator,
    ("alpha_", "n_features_in_", "constant_", "noise_level_"),
    ("zero_reading_", "linear_matrix_", "linear_offset_", "input_scale_", "train_inputs_", "dual_coef_",
     "cholesky_", "residual_mean_", "residual_scale_", "output_variance_", "length_scale_"),
)

register_model_type(
    TemperatureCompensatedCalibrator, ("alpha_", "n_features_in_"),
    ("zero_reading_", "offset_per_deg_", "gain_per_deg_"), children="estimator_",
)

# "auto" chooses among the names above, so it is registered last (its schedule goes to its network candidates).
register_calibrator("auto", AutoCalibrator, schedules={s: {"schedule": s} for s in SCHEDULE_NAMES})
register_model_type(
    AutoCalibrator, ("alpha_", "n_features_in_", "best_name_", "cv_results_"), ("zero_reading_",),
    children="best_estimator_",
)
