"""ftcal: calibration of multi-axis force/torque sensors.

Turns raw strain-gauge readings (N channels) into a wrench
``[Fx, Fy, Fz, Tx, Ty, Tz]`` in [N] and [N·m] with scikit-learn estimators:
a linear transformation model, the direct-mapping DNN of Oh et al. and the
directional DNN of Kolff (2024), plus the artificial benchmark and the
robot-held calibration experiment of that thesis.
"""

from __future__ import annotations

from .core._lazy import lazy_namespace

__version__ = "0.1.0"

#: Public name -> the private module that defines it. Imported on first access (PEP 562), so that
#: ``import ftcal.cli`` and ``ftcal --help`` load neither torch nor pinocchio.
_PUBLIC: dict[str, str] = {
    "BenchmarkOutputExistsError": "core._exceptions",
    "CalibrationDataset": "io._dataset",
    "CalibrationReport": "core._metrics",
    "CalFileError": "core._exceptions",
    "CalibrationInputError": "core._exceptions",
    "DatasetFileError": "core._exceptions",
    "FtcalError": "core._exceptions",
    "KinematicsError": "core._exceptions",
    "LogFormatError": "core._exceptions",
    "ModelFileError": "core._exceptions",
    "ExportError": "core._exceptions",
    "export_onnx": "models._onnx",
    "WRENCH_LABELS": "core._wrench",
    "alpha_from_wrenches": "core._wrench",
    "axis_rmse": "core._metrics",
    "calibration_report": "core._metrics",
    "neg_scaled_rmse": "core._metrics",
    "per_sample_rmse": "core._metrics",
    "relative_errors": "core._metrics",
    "scale_torques": "core._wrench",
    "unscale_torques": "core._wrench",
    "wrench_rmse": "core._metrics",
    "CALIBRATOR_NAMES": "models._registry",
    "calibrator_parameters": "models._registry",
    "ComparativeCalibrator": "neural_network._comparative",
    "DirectionalCalibrator": "neural_network._directional",
    "LinearCalibrator": "calibrators._linear",
    "load_model": "models._model_io",
    "make_calibrator": "models._registry",
    "register_calibrator": "models._registry",
    "save_model": "models._model_io",
    "training_schedule": "models._registry",
    "AutoCalibrator": "models._auto",
    "AxisNonlinearCalibrator": "calibrators._axis_nonlinear",
    "EnsembleCalibrator": "models._ensemble",
    "fit_stacked": "neural_network._stacked",
    "StackedMLP": "neural_network._stacked",
    "GaussianProcessCalibrator": "calibrators._gaussian_process",
    "PolynomialCalibrator": "calibrators._polynomial",
    "search_calibrator": "models._search",
    "ERROR_PRESETS": "simulation._presets",
    "ErrorModel": "simulation._error_models",
    "SampledErrors": "simulation._error_models",
    "SensorProfile": "simulation._sensor",
    "VirtualSensor": "simulation._artificial",
    "default_calibration_matrix": "simulation._sensor",
    "error_preset": "simulation._presets",
    "make_artificial_dataset": "simulation._artificial",
    "make_dead_weight_dataset": "simulation._field_sensors",
    "make_robot_held_dataset": "simulation._field_sensors",
    "make_soft_sensor_dataset": "simulation._field_sensors",
    "noise_floor": "simulation._artificial",
    "read_ati_calibration": "simulation._ati",
    "run_artificial_benchmark": "evaluation._benchmark_artificial",
    "BUILTIN_ROBOTS": "robot._robot",
    "CalibrationPlan": "robot._pose_planning",
    "IKResult": "robot._ik",
    "LoadConfiguration": "robot._loads",
    "MountingDevice": "experiment._virtual_experiment",
    "NoLoadModel": "experiment._experiment",
    "PairedRuns": "experiment._experiment",
    "RobotModel": "robot._robot",
    "RunLog": "io._logs",
    "STANDARD_GRAVITY": "robot._loads",
    "example_robot_data_dir": "robot._robot",
    "fit_no_load_model": "experiment._experiment",
    "frame_pose_in_base": "robot._robot",
    "gravity_directions_in_sensor": "robot._pose_planning",
    "gravity_in_sensor_from_pitch_yaw": "robot._pose_planning",
    "icosphere": "robot._pose_planning",
    "load_robot": "robot._robot",
    "pair_runs": "experiment._experiment",
    "pitch_yaw_from_gravity_in_sensor": "robot._pose_planning",
    "plan_calibration_poses": "robot._pose_planning",
    "prepare_dataset": "experiment._experiment",
    "read_run_log": "io._logs",
    "reference_wrench": "robot._loads",
    "reference_wrench_at_joints": "robot._loads",
    "rotation_delta": "experiment._experiment",
    "run_real_world_benchmark": "evaluation._benchmark_real_world",
    "sensor_pose_in_base": "robot._robot",
    "sensor_rotation_from_pitch_yaw": "robot._pose_planning",
    "simulate_experiment": "experiment._virtual_experiment",
    "solve_gravity_direction_ik": "robot._ik",
    "solve_orientation_ik": "robot._ik",
    "thesis_load_configurations": "robot._loads",
    "ToolLoad": "experiment._tool_load",
    "identify_tool_load": "experiment._tool_load",
    "TemperatureCompensatedCalibrator": "calibrators._temperature_compensation",
    "ThermalDrift": "core._temperature",
    "write_run_log": "io._logs",
}

__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
