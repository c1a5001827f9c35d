"""ftcal: calibration of multi-axis force/torque sensors.

Turns raw strain-gauge readings (N channels) into a wrench
``[Fx, Fy, Fz, Tx, Ty, Tz]`` in [N] and [N·m] with scikit-learn estimators:
a linear transformation model, the direct-mapping DNN of Oh et al. and the
directional DNN of Kolff (2024), plus the artificial benchmark and the
robot-held calibration experiment of that thesis.
"""

from ._dataset import CalibrationDataset
from ._exceptions import (
    BenchmarkOutputExistsError,
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
from ._comparative import ComparativeCalibrator
from ._directional import DirectionalCalibrator
from ._linear import LinearCalibrator
from ._model_io import load_model, save_model
from ._registry import CALIBRATOR_NAMES, calibrator_parameters, make_calibrator, register_calibrator, training_schedule
from ._auto import AutoCalibrator
from ._ensemble import EnsembleCalibrator
from ._gaussian_process import GaussianProcessCalibrator
from ._hybrid import AxisNonlinearCalibrator
from ._polynomial import PolynomialCalibrator
from . import _registry_extra  # registers "polynomial", "axis_nonlinear", "*_ensemble" (issue 6)
from ._search import search_calibrator

# --- artificial data and sensors (issue 3) ------------------------------------
from ._artificial import VirtualSensor, make_artificial_dataset, noise_floor
from ._ati import read_ati_calibration
from ._benchmark_artificial import run_artificial_benchmark
from ._error_models import ErrorModel, SampledErrors
from ._presets import ERROR_PRESETS, error_preset
from ._sensor import SensorProfile, default_calibration_matrix

# --- robot kinematics and the real-world experiment (issue 4) -----------------
from ._benchmark_real_world import run_real_world_benchmark
from ._experiment import NoLoadModel, PairedRuns, fit_no_load_model, pair_runs, prepare_dataset, rotation_delta
from ._ik import IKResult, solve_gravity_direction_ik, solve_orientation_ik
from ._loads import (
    STANDARD_GRAVITY,
    LoadConfiguration,
    reference_wrench,
    reference_wrench_at_joints,
    thesis_load_configurations,
)
from ._logs import RunLog, read_run_log, write_run_log
from ._pose_planning import (
    CalibrationPlan,
    gravity_directions_in_sensor,
    gravity_in_sensor_from_pitch_yaw,
    icosphere,
    pitch_yaw_from_gravity_in_sensor,
    plan_calibration_poses,
    sensor_rotation_from_pitch_yaw,
)
from ._robot import BUILTIN_ROBOTS, RobotModel, example_robot_data_dir, frame_pose_in_base, load_robot, sensor_pose_in_base
from ._virtual_experiment import MountingDevice, simulate_experiment
from ._tool_load import ToolLoad, identify_tool_load
from ._temperature import TemperatureCompensatedCalibrator, ThermalDrift

__version__ = "0.1.0"

__all__ = [
    "BenchmarkOutputExistsError",
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
    "CALIBRATOR_NAMES",
    "calibrator_parameters",
    "ComparativeCalibrator",
    "DirectionalCalibrator",
    "LinearCalibrator",
    "load_model",
    "make_calibrator",
    "register_calibrator",
    "save_model",
    "training_schedule",
    "AutoCalibrator",
    "AxisNonlinearCalibrator",
    "EnsembleCalibrator",
    "GaussianProcessCalibrator",
    "PolynomialCalibrator",
    "search_calibrator",
    # artificial data and sensors (issue 3)
    "ERROR_PRESETS",
    "ErrorModel",
    "SampledErrors",
    "SensorProfile",
    "VirtualSensor",
    "default_calibration_matrix",
    "error_preset",
    "make_artificial_dataset",
    "noise_floor",
    "read_ati_calibration",
    "run_artificial_benchmark",
    # robot kinematics and the real-world experiment (issue 4)
    "BUILTIN_ROBOTS",
    "CalibrationPlan",
    "IKResult",
    "LoadConfiguration",
    "MountingDevice",
    "NoLoadModel",
    "PairedRuns",
    "RobotModel",
    "RunLog",
    "STANDARD_GRAVITY",
    "example_robot_data_dir",
    "fit_no_load_model",
    "frame_pose_in_base",
    "gravity_directions_in_sensor",
    "gravity_in_sensor_from_pitch_yaw",
    "icosphere",
    "load_robot",
    "pair_runs",
    "pitch_yaw_from_gravity_in_sensor",
    "plan_calibration_poses",
    "prepare_dataset",
    "read_run_log",
    "reference_wrench",
    "reference_wrench_at_joints",
    "rotation_delta",
    "run_real_world_benchmark",
    "sensor_pose_in_base",
    "sensor_rotation_from_pitch_yaw",
    "simulate_experiment",
    "solve_gravity_direction_ik",
    "solve_orientation_ik",
    "thesis_load_configurations",
    "ToolLoad",
    "identify_tool_load",
    "TemperatureCompensatedCalibrator",
    "ThermalDrift",
    "write_run_log",
]
