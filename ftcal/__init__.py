"""ftcal: calibration of multi-axis force/torque sensors.

Turns raw strain-gauge readings (N channels) into a wrench
``[Fx, Fy, Fz, Tx, Ty, Tz]`` in [N] and [N·m] with scikit-learn estimators:
a linear transformation model, the direct-mapping DNN of Oh et al. and the
directional DNN of Kolff (2024), plus the artificial benchmark and the
robot-held calibration experiment of that thesis.

The top level keeps what a user calls first: the calibrators (the
estimators, meta-estimators included), the dataset classes
(``CalibrationDataset``, ``ColumnMap``), ``load_model`` / ``save_model``,
``make_calibrator`` / ``register_calibrator``, and the few functions of a
first session (``make_artificial_dataset``, ``neg_scaled_rmse``,
``export_onnx``, ``calibration_certificate``), with ``FtcalError``, the base
of every error ftcal raises. Everything else is in its public subpackage
(``ftcal.core``, ``ftcal.model_selection``, ``ftcal.io``, ``ftcal.calibrators``,
``ftcal.networks``, ``ftcal.compose``, ``ftcal.persistence``,
``ftcal.reporting``, ``ftcal.robot``, ``ftcal.simulation``,
``ftcal.experiment``, ``ftcal.benchmark``), each with its own ``__all__``.

Layer: the package itself imports nothing at import time (PEP 562 lazy names).

Examples
--------
>>> import ftcal
>>> ftcal.LinearCalibrator is ftcal.calibrators.LinearCalibrator
True
"""

from __future__ import annotations

from .core._lazy import lazy_namespace

__version__ = "0.1.0"

#: Public name -> the private module that defines it. Imported on first access (PEP 562), so that
#: ``import ftcal.cli`` and ``ftcal --help`` load neither torch nor pinocchio.
_PUBLIC: dict[str, str] = {
    "LinearCalibrator": "calibrators._linear",
    "PolynomialCalibrator": "calibrators._polynomial",
    "AxisNonlinearCalibrator": "calibrators._axis_nonlinear",
    "GaussianProcessCalibrator": "calibrators._gaussian_process",
    "DirectionalCalibrator": "networks._directional",
    "ComparativeCalibrator": "networks._comparative",
    "AutoCalibrator": "compose._auto",
    "EnsembleCalibrator": "compose._ensemble",
    "TemperatureCompensatedCalibrator": "compose._temperature_compensation",
    "HistoryCalibrator": "compose._history",
    "CalibrationDataset": "io._dataset",
    "ColumnMap": "io._readers",
    "load_model": "persistence._model_io",
    "save_model": "persistence._model_io",
    "make_calibrator": "compose._registry",
    "register_calibrator": "compose._registry",
    "make_artificial_dataset": "simulation._artificial",
    "neg_scaled_rmse": "core._metrics",
    "export_onnx": "persistence._onnx",
    "calibration_certificate": "reporting._certificate",
    "FtcalError": "core._exceptions",
}

#: The public subpackages (imported on first access: ``ftcal.robot`` after ``import ftcal``).
SUBPACKAGES = ("core", "model_selection", "io", "calibrators", "networks", "compose", "persistence", "reporting", "robot", "simulation", "experiment", "benchmark", "workflow")

__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC, SUBPACKAGES)
