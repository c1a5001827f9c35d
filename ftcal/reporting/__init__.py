"""What a calibration shows a person: the calibration report (a certificate: held-out accuracy per axis, U95,
PASS/FAIL, the uncertainty budget, the model's identity: a
:class:`CalibrationCertificate` written as HTML, JSON and CSV), the comparison tables and plots of an evaluation, and
the plots of tool drift. "Report" in ftcal means the certificate only; the error measures of one prediction
are :class:`ftcal.core.CalibrationMetrics` (they stay in :mod:`ftcal.core`: the simulation and the search,
below this layer, use them).

Layer: above :mod:`ftcal.persistence`. Imports :mod:`ftcal.core`, :mod:`ftcal.io`,
:mod:`ftcal.model_selection`, :mod:`ftcal.calibrators`, :mod:`ftcal.compose` and :mod:`ftcal.persistence`.
"""

from ..core._lazy import lazy_namespace

#: Public names of this package -> the private module holding each.
_PUBLIC = dict(
    calibration_certificate="_certificate", CalibrationCertificate="_certificate", AxisBudget="_budget",
    BudgetComponent="_budget", write_calibration_report="_calibration_report", model_inputs="_calibration_report", comparison_table="_evaluation", axis_table="_evaluation",
    write_evaluation_plots="_evaluation", MODEL_COLORS="_plots", model_color="_plots",
    plot_error_distributions="_plots", plot_axis_errors="_plots", plot_predicted_vs_reference="_plots",
    plot_sphere_coverage="_plots", plot_wrench_coverage="_plots", plot_drift_residuals="_drift_plot",
)
_PUBLIC.update(  # names the CLI uses (and plot_sphere_coverage, plot_wrench_coverage above)
    CONDITION_FIELDS="_calibration_report", EVALUATION_PLOTS="_evaluation", bytes_sha256="_calibration_report",
    check_conditions="_calibration_report", file_sha256="_calibration_report", dataset_axis_names="_calibration_report",
    predicted_plot_name="_evaluation",
)
__all__ = list(_PUBLIC)
__getattr__, __dir__ = lazy_namespace(__name__, _PUBLIC)
