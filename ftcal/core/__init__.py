"""Shared basics every layer uses: the domain errors, the wrench conventions (units, torque scaling),
input validation, the error measures of one prediction (:class:`CalibrationMetrics`), CSV columns, safe
output files, the memory guard and the thermal drift model.

Layer: the lowest. Imports only numpy, scipy, scikit-learn and the standard library; never another ftcal
package.
"""

from ._lazy import lazy_namespace

#: Public names of this package -> the private module holding each.
_PUBLIC = dict(
    FtcalError="_exceptions", CalibrationInputError="_exceptions", CalFileError="_exceptions",
    DatasetFileError="_exceptions", KinematicsError="_exceptions", LogFormatError="_exceptions",
    ModelFileError="_exceptions", ExportError="_exceptions", ExportExistsError="_exceptions",
    PlanningError="_exceptions", BenchmarkOutputExistsError="_exceptions",
    WRENCH_LABELS="_wrench", alpha_from_wrenches="_wrench", scale_torques="_wrench", unscale_torques="_wrench",
    MIN_CHANNELS="_wrench", ALPHA_RANGE_PER_M="_wrench", check_alpha="_wrench",
    CalibrationMetrics="_metrics", calibration_metrics="_metrics", wrench_rmse="_metrics", axis_rmse="_metrics",
    per_sample_rmse="_metrics", relative_errors="_metrics", neg_scaled_rmse="_metrics", mean_std="_metrics",
    ThermalDrift="_temperature",
    plain_json="_files", write_json="_files", atomic_output="_files", is_finite_number="_files",
    check_allocation="_memory", MemoryLimitError="_memory", memory_limit_bytes="_memory",
)
_PUBLIC.update(  # names the CLI uses
    content_twins="_files", values_sha256="_files", limit_threads_here="_threads", MAX_TRAINING_MAGNITUDE="_validation", MODEL_SUFFIX="_files",
    NO_SETTING="_exceptions", OutputSet="_files", Placeholder="_exceptions", TooFewSamplesError="_exceptions",
    atomic_output_set="_files", axis_unit="_wrench", check_writable_dir="_files", csv_rows="_columns",
    default_axes="_wrench", force_columns="_wrench", is_number="_columns", model_file_name="_files",
    named_targets="_wrench", parse_number="_columns", read_header="_columns", same_file="_files",
    torque_columns="_wrench",
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
