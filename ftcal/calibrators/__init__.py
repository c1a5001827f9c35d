"""The calibrators with closed-form or kernel fits: the shared scikit-learn base (validation, torque
scale, zero-load reading, re-tare, capability tags), the linear transformation model, polynomial,
axis-nonlinear and Gaussian-process calibrators, and the stock scikit-learn baselines kept as a model
(:class:`StockCalibrator`).

Layer: above :mod:`ftcal.model_selection`. Imports only :mod:`ftcal.core` and :mod:`ftcal.model_selection`.
A new closed-form calibrator goes here (subclass :class:`BaseCalibrator`, implement ``_fit`` and
``_predict_wrench``, declare its tags) with one registry line in :mod:`ftcal.compose`.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package -> the private module holding each.
_PUBLIC = dict(
    LinearCalibrator="_linear", PolynomialCalibrator="_polynomial", AxisNonlinearCalibrator="_axis_nonlinear",
    GaussianProcessCalibrator="_gaussian_process", StockCalibrator="_baselines",
    BaseCalibrator="_base", GroupsFit="_base", CalibrationTags="_base", calibration_tags="_base", declare="_base",
    stock_baselines="_baselines", STOCK_BASELINE_NAMES="_baselines", SubsampledRegressor="_baselines",
    as_calibrator="_baselines", retare_shift="_base",
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
