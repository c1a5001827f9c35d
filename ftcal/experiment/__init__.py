"""The robot-held experiment and in-situ use: pairing load / no-load runs into a calibration dataset
(R_delta, reference wrenches), the virtual experiment that writes such runs (and its continuous
recordings), still poses found in a continuous recording, a robot's recordings read into static poses, the identification of a tool's load and its bias
drift for gravity compensation, and which poses to measure next.

Layer: above :mod:`ftcal.robot` and :mod:`ftcal.simulation`. Imports :mod:`ftcal.core`,
:mod:`ftcal.model_selection` (the drift's choice by held-out error), :mod:`ftcal.io`, :mod:`ftcal.robot` and
:mod:`ftcal.simulation`.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package -> the private module holding each.
_PUBLIC = dict(
    prepare_dataset="_experiment", pair_runs="_experiment", PairedRuns="_experiment", NoLoadModel="_experiment",
    fit_no_load_model="_experiment", rotation_delta="_experiment",
    simulate_experiment="_virtual_experiment", MountingDevice="_virtual_experiment",
    StillPoses="_still_poses", find_still_poses="_still_poses",
    ToolLoad="_tool_load", identify_tool_load="_tool_load", wrench_in_sensor_frame="_tool_load",
    tool_gravity_compensation_yaml="_tool_load", BiasDrift="_drift", DriftExtrapolationWarning="_drift",
    identification_summary="_tool_load", propose_next_poses="_next_poses", PoseProposal="_next_poses",
    FrameCheck="_tool_checks", check_wrench_frame="_tool_checks", OrderDrift="_tool_checks",
    drift_in_recording_order="_tool_checks", Observability="_mounting", ParameterBlock="_mounting",
    tool_load_observability="_tool_checks", continuous_recording="_virtual_recording",
    ContinuousRecording="_virtual_recording", StaticPoses="_static_poses", static_poses="_static_poses",
    RecordingRows="_static_poses", recording_rows="_static_poses", RecordingOptions="_static_poses",
    recording_kind="_static_poses", bag_run_log="_static_poses", DEFAULT_STILL_TOLERANCE_DEG="_still_poses",
    DEFAULT_MIN_STILL_S="_still_poses", tool_onnx_model="_drift", write_run_bags="_virtual_recording",  # the CLI's
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
