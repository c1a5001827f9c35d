"""ftcal: calibration of multi-axis force/torque sensors.

Turns raw strain-gauge readings (N channels) into a wrench
``[Fx, Fy, Fz, Tx, Ty, Tz]`` in [N] and [N·m] with scikit-learn estimators:
a linear transformation model, the direct-mapping DNN of Oh et al. and the
directional DNN of Kolff (2024), plus the artificial benchmark and the
robot-held calibration experiment of that thesis.
"""

from __future__ import annotations

from importlib import import_module

__version__ = "0.1.0"

#: Public name -> the private module that defines it. Imported on first access (PEP 562), so that
#: ``import ftcal.cli`` and ``ftcal --help`` load neither torch nor pinocchio.
_PUBLIC: dict[str, str] = {
    "BenchmarkOutputExistsError": "_exceptions",
    "CalibrationDataset": "_dataset",
    "CalibrationReport": "_metrics",
    "CalFileError": "_exceptions",
    "CalibrationInputError": "_exceptions",
    "DatasetFileError": "_exceptions",
    "FtcalError": "_exceptions",
    "KinematicsError": "_exceptions",
    "LogFormatError": "_exceptions",
    "ModelFileError": "_exceptions",
    "ExportError": "_exceptions",
    "export_onnx": "_onnx",
    "WRENCH_LABELS": "_wrench",
    "alpha_from_wrenches": "_wrench",
    "axis_rmse": "_metrics",
    "calibration_report": "_metrics",
    "neg_scaled_rmse": "_metrics",
    "per_sample_rmse": "_metrics",
    "relative_errors": "_metrics",
    "scale_torques": "_wrench",
    "unscale_torques": "_wrench",
    "wrench_rmse": "_metrics",
    "CALIBRATOR_NAMES": "_registry",
    "calibrator_parameters": "_registry",
    "ComparativeCalibrator": "_comparative",
    "DirectionalCalibrator": "_directional",
    "LinearCalibrator": "_linear",
    "load_model": "_model_io",
    "make_calibrator": "_registry",
    "register_calibrator": "_registry",
    "save_model": "_model_io",
    "training_schedule": "_registry",
    "AutoCalibrator": "_auto",
    "AxisNonlinearCalibrator": "_hybrid",
    "EnsembleCalibrator": "_ensemble",
    "fit_stacked": "_stacked",
    "StackedMLP": "_stacked",
    "GaussianProcessCalibrator": "_gaussian_process",
    "PolynomialCalibrator": "_polynomial",
    "search_calibrator": "_search",
    "ERROR_PRESETS": "_presets",
    "ErrorModel": "_error_models",
    "SampledErrors": "_error_models",
    "SensorProfile": "_sensor",
    "VirtualSensor": "_artificial",
    "default_calibration_matrix": "_sensor",
    "error_preset": "_presets",
    "make_artificial_dataset": "_artificial",
    "noise_floor": "_artificial",
    "read_ati_calibration": "_ati",
    "run_artificial_benchmark": "_benchmark_artificial",
    "BUILTIN_ROBOTS": "_robot",
    "CalibrationPlan": "_pose_planning",
    "IKResult": "_ik",
    "LoadConfiguration": "_loads",
    "MountingDevice": "_virtual_experiment",
    "NoLoadModel": "_experiment",
    "PairedRuns": "_experiment",
    "RobotModel": "_robot",
    "RunLog": "_logs",
    "STANDARD_GRAVITY": "_loads",
    "example_robot_data_dir": "_robot",
    "fit_no_load_model": "_experiment",
    "frame_pose_in_base": "_robot",
    "gravity_directions_in_sensor": "_pose_planning",
    "gravity_in_sensor_from_pitch_yaw": "_pose_planning",
    "icosphere": "_pose_planning",
    "load_robot": "_robot",
    "pair_runs": "_experiment",
    "pitch_yaw_from_gravity_in_sensor": "_pose_planning",
    "plan_calibration_poses": "_pose_planning",
    "prepare_dataset": "_experiment",
    "read_run_log": "_logs",
    "reference_wrench": "_loads",
    "reference_wrench_at_joints": "_loads",
    "rotation_delta": "_experiment",
    "run_real_world_benchmark": "_benchmark_real_world",
    "sensor_pose_in_base": "_robot",
    "sensor_rotation_from_pitch_yaw": "_pose_planning",
    "simulate_experiment": "_virtual_experiment",
    "solve_gravity_direction_ik": "_ik",
    "solve_orientation_ik": "_ik",
    "thesis_load_configurations": "_loads",
    "ToolLoad": "_tool_load",
    "identify_tool_load": "_tool_load",
    "TemperatureCompensatedCalibrator": "_temperature_compensation",
    "ThermalDrift": "_temperature",
    "write_run_log": "_logs",
}

__all__ = list(_PUBLIC)


def __getattr__(name: str):
    module = _PUBLIC.get(name)
    if module is None:
        raise AttributeError(f"module 'ftcal' has no attribute {name!r}")
    value = getattr(import_module(f".{module}", __name__), name)
    globals()[name] = value  # later look-ups skip this function
    return value


def __dir__() -> list[str]:
    return sorted(set(globals()) | set(__all__))
