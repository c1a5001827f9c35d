"""Files of calibration data: the calibration dataset (:class:`CalibrationDataset`: CSV, NPZ, MAT), column
mappings and declared units (:class:`ColumnMap`), the recorded run logs of a robot-held experiment
(:class:`RunLog`), pose files (orientation + wrench per row) and ROS bags; the readings checked before use
(:func:`check_readings`: impossible values, spikes, stuck channels, repeated rows, each named by file and line).

Layer: above :mod:`ftcal.core`. Imports only :mod:`ftcal.core`.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package -> the private module holding each.
_PUBLIC = dict(
    CalibrationDataset="_dataset", ColumnMap="_readers", RunLog="_logs", read_run_log="_logs",
    write_run_log="_logs", run_log_files="_logs", PoseRecording="_poses", read_pose_file="_poses", BagRecording="_bags",
    read_bag="_bags", write_bag="_bags", FORCE_UNITS="_readers", TORQUE_UNITS="_readers",
    RowSources="_dataset", check_readings="_checks", ReadingChecks="_checks", ReadingFinding="_checks",
    FindingKind="_checks", has_header="_readers", join_headerless="_readers", JoinedTable="_readers",
    range_excess="_checks", RangeExcess="_checks", AxisExcess="_checks",
)
_PUBLIC.update(  # names the CLI uses
    DEFAULT_MAX_SAMPLES="_bags", PLAUSIBLE_LEVER_ARM_M="_readers", canonical_wrench_name="_readers",
    check_rosbags="_bags", bag_values="_bags", expand_names="_readers", is_bag="_bags", is_pose_file="_poses",
    lever_arm_m="_readers", lever_arm_problem="_readers", parse_column_slice="_readers",
    read_channels="_dataset", unit_scale="_readers", ArrayFile="_readers", not_utf8_error="_readers",
    check_separator="_readers", refuse_twin_recordings="_twins",
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
