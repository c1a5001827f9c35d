"""ftcal: calibration of multi-axis force/torque sensors.

Turns raw strain-gauge readings (N channels) into a wrench
``[Fx, Fy, Fz, Tx, Ty, Tz]`` in [N] and [N·m] with scikit-learn estimators:
a linear transformation model, the direct-mapping DNN of Oh et al. and the
directional DNN of Kolff (2024), plus the artificial benchmark and the
robot-held calibration experiment of that thesis.
"""

from ._dataset import CalibrationDataset
from ._exceptions import (
    CalFileError,
    CalibrationInputError,
    DatasetFileError,
    FtcalError,
    KinematicsError,
    LogFormatError,
    ModelFileError,
)
from ._metrics import (
    CalibrationReport,
    axis_rmse,
    calibration_report,
    neg_scaled_rmse,
    per_sample_rmse,
    relative_errors,
    wrench_rmse,
)
from ._wrench import WRENCH_LABELS, alpha_from_wrenches, scale_torques, unscale_torques

# --- calibrators (issue 2, issue 6) -------------------------------------------

# --- artificial data and sensors (issue 3) ------------------------------------

# --- robot kinematics and the real-world experiment (issue 4) -----------------

__version__ = "0.1.0"

__all__ = [
    "CalibrationDataset",
    "CalibrationReport",
    "CalFileError",
    "CalibrationInputError",
    "DatasetFileError",
    "FtcalError",
    "KinematicsError",
    "LogFormatError",
    "ModelFileError",
    "WRENCH_LABELS",
    "alpha_from_wrenches",
    "axis_rmse",
    "calibration_report",
    "neg_scaled_rmse",
    "per_sample_rmse",
    "relative_errors",
    "scale_torques",
    "unscale_torques",
    "wrench_rmse",
    # calibrators (issue 2, issue 6)
    # artificial data and sensors (issue 3)
    # robot kinematics and the real-world experiment (issue 4)
]
