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
A name that used to be here still answers, with a ``FutureWarning`` naming
its new home, for one release.

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
    "calibration_certificate": "reporting._calibration_report",
    "FtcalError": "core._exceptions",
}

#: The public subpackages (imported on first access: ``ftcal.robot`` after ``import ftcal``).
SUBPACKAGES = ("core", "model_selection", "io", "calibrators", "networks", "compose", "persistence", "reporting", "robot", "simulation", "experiment", "benchmark", "workflow")

#: Public names that moved to a subpackage or were renamed: each still answers, with a FutureWarning naming its
#: new home, for one release (then it is removed).
_MOVED: dict[str, str] = {
    "BenchmarkOutputExistsError": "ftcal.core.BenchmarkOutputExistsError",
    "linear_calibration_matrix": "ftcal.persistence.linear_calibration_matrix",
    "read_load_configurations": "ftcal.robot.read_load_configurations",
    "tool_gravity_compensation_yaml": "ftcal.experiment.tool_gravity_compensation_yaml",
    "CalFileError": "ftcal.core.CalFileError",
    "CalibrationInputError": "ftcal.core.CalibrationInputError",
    "DatasetFileError": "ftcal.core.DatasetFileError",
    "KinematicsError": "ftcal.core.KinematicsError",
    "LogFormatError": "ftcal.core.LogFormatError",
    "ModelFileError": "ftcal.core.ModelFileError",
    "ExportError": "ftcal.core.ExportError",
    "ExportExistsError": "ftcal.core.ExportExistsError",
    "PlanningError": "ftcal.core.PlanningError",
    "WRENCH_LABELS": "ftcal.core.WRENCH_LABELS",
    "alpha_from_wrenches": "ftcal.core.alpha_from_wrenches",
    "axis_rmse": "ftcal.core.axis_rmse",
    "per_sample_rmse": "ftcal.core.per_sample_rmse",
    "relative_errors": "ftcal.core.relative_errors",
    "scale_torques": "ftcal.core.scale_torques",
    "unscale_torques": "ftcal.core.unscale_torques",
    "wrench_rmse": "ftcal.core.wrench_rmse",
    "CALIBRATOR_NAMES": "ftcal.compose.CALIBRATOR_NAMES",
    "calibrator_parameters": "ftcal.compose.calibrator_parameters",
    "training_schedule": "ftcal.compose.training_schedule",
    "fit_stacked": "ftcal.networks.fit_stacked",
    "StackedMLP": "ftcal.networks.StackedMLP",
    "search_calibrator": "ftcal.compose.search_calibrator",
    "ERROR_PRESETS": "ftcal.simulation.ERROR_PRESETS",
    "ErrorModel": "ftcal.simulation.ErrorModel",
    "SampledErrors": "ftcal.simulation.SampledErrors",
    "SensorProfile": "ftcal.simulation.SensorProfile",
    "VirtualSensor": "ftcal.simulation.VirtualSensor",
    "default_calibration_matrix": "ftcal.simulation.default_calibration_matrix",
    "error_preset": "ftcal.simulation.error_preset",
    "make_dead_weight_dataset": "ftcal.simulation.make_dead_weight_dataset",
    "make_robot_held_dataset": "ftcal.simulation.make_robot_held_dataset",
    "make_soft_sensor_dataset": "ftcal.simulation.make_soft_sensor_dataset",
    "noise_floor": "ftcal.simulation.noise_floor",
    "read_ati_calibration": "ftcal.simulation.read_ati_calibration",
    "run_artificial_benchmark": "ftcal.benchmark.run_artificial_benchmark",
    "BUILTIN_ROBOTS": "ftcal.robot.BUILTIN_ROBOTS",
    "CalibrationPlan": "ftcal.robot.CalibrationPlan",
    "CandidatePoses": "ftcal.robot.CandidatePoses",
    "reachable_candidates": "ftcal.robot.reachable_candidates",
    "select_poses": "ftcal.robot.select_poses",
    "select_load_configurations": "ftcal.robot.select_load_configurations",
    "d_criterion": "ftcal.robot.d_criterion",
    "PLAN_STRATEGIES": "ftcal.robot.PLAN_STRATEGIES",
    "propose_next_poses": "ftcal.experiment.propose_next_poses",
    "PoseProposal": "ftcal.experiment.PoseProposal",
    "IKResult": "ftcal.robot.IKResult",
    "LoadConfiguration": "ftcal.robot.LoadConfiguration",
    "MountingDevice": "ftcal.experiment.MountingDevice",
    "NoLoadModel": "ftcal.experiment.NoLoadModel",
    "PairedRuns": "ftcal.experiment.PairedRuns",
    "RobotModel": "ftcal.robot.RobotModel",
    "RunLog": "ftcal.io.RunLog",
    "STANDARD_GRAVITY": "ftcal.robot.STANDARD_GRAVITY",
    "example_robot_data_dir": "ftcal.robot.example_robot_data_dir",
    "fit_no_load_model": "ftcal.experiment.fit_no_load_model",
    "frame_pose_in_base": "ftcal.robot.frame_pose_in_base",
    "gravity_directions_in_sensor": "ftcal.robot.gravity_directions_in_sensor",
    "gravity_in_sensor_from_pitch_yaw": "ftcal.robot.gravity_in_sensor_from_pitch_yaw",
    "icosphere": "ftcal.robot.icosphere",
    "load_robot": "ftcal.robot.load_robot",
    "pair_runs": "ftcal.experiment.pair_runs",
    "pitch_yaw_from_gravity_in_sensor": "ftcal.robot.pitch_yaw_from_gravity_in_sensor",
    "plan_calibration_poses": "ftcal.robot.plan_calibration_poses",
    "prepare_dataset": "ftcal.experiment.prepare_dataset",
    "read_run_log": "ftcal.io.read_run_log",
    "reference_wrench": "ftcal.robot.reference_wrench",
    "reference_wrench_at_joints": "ftcal.robot.reference_wrench_at_joints",
    "rotation_delta": "ftcal.experiment.rotation_delta",
    "run_real_world_benchmark": "ftcal.benchmark.run_real_world_benchmark",
    "sensor_pose_in_base": "ftcal.robot.sensor_pose_in_base",
    "sensor_rotation_from_pitch_yaw": "ftcal.robot.sensor_rotation_from_pitch_yaw",
    "simulate_experiment": "ftcal.experiment.simulate_experiment",
    "solve_gravity_direction_ik": "ftcal.robot.solve_gravity_direction_ik",
    "solve_orientation_ik": "ftcal.robot.solve_orientation_ik",
    "thesis_load_configurations": "ftcal.robot.thesis_load_configurations",
    "ToolLoad": "ftcal.experiment.ToolLoad",
    "BiasDrift": "ftcal.experiment.BiasDrift",
    "DriftExtrapolationWarning": "ftcal.experiment.DriftExtrapolationWarning",
    "identify_tool_load": "ftcal.experiment.identify_tool_load",
    "wrench_in_sensor_frame": "ftcal.experiment.wrench_in_sensor_frame",
    "StillPoses": "ftcal.experiment.StillPoses",
    "find_still_poses": "ftcal.experiment.find_still_poses",
    "PoseRecording": "ftcal.io.PoseRecording",
    "read_pose_file": "ftcal.io.read_pose_file",
    "BagRecording": "ftcal.io.BagRecording",
    "read_bag": "ftcal.io.read_bag",
    "write_bag": "ftcal.io.write_bag",
    "reading_history": "ftcal.compose.reading_history",
    "ThermalDrift": "ftcal.core.ThermalDrift",
    "write_run_log": "ftcal.io.write_run_log",
    "CalibrationReport": "ftcal.core.CalibrationMetrics",
    "calibration_report": "ftcal.core.calibration_metrics",
}

__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC, _MOVED, SUBPACKAGES)
