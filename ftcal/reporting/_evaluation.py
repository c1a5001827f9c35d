"""Comparison tables of calibration reports (markdown, readable in a terminal), and evaluation plots."""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import numpy as np

from ..core._metrics import CalibrationMetrics, per_sample_rmse
from ..core._wrench import WRENCH_LABELS

__all__ = ["comparison_table", "axis_table", "EVALUATION_PLOTS", "predicted_plot_name", "write_evaluation_plots"]


def _pm(mean: float, std: float, scale: float = 1.0, digits: int = 3) -> str:
    if not np.isfinite(mean):
        return "n/a"
    return f"{mean * scale:.{digits}g} ± {std * scale:.2g}"


def comparison_table(reports: Mapping[str, CalibrationMetrics], noise_floor: float | None = None) -> str:
    """Markdown table: RMSE, per-sample RMSE, relative force / torque errors per model.

    Examples
    --------
    >>> from ftcal.core import calibration_metrics
    >>> r = calibration_metrics([[10.0, 0, 0, 0, 0, 1]], [[11.0, 0, 0, 0, 0, 1]], alpha=10.0)
    >>> print(comparison_table({"linear": r}))  # doctest: +NORMALIZE_WHITESPACE
    | model | RMSE [N] | per-sample RMSE [N] | rel. force error [%] | rel. torque error [%] |
    |---|---|---|---|---|
    | linear | 0.408 | 0.408 ± 0 | 10 ± 0 | 0 ± 0 |
    """
    lines = ["| model | RMSE [N] | per-sample RMSE [N] | rel. force error [%] | rel. torque error [%] |",
             "|---|---|---|---|---|"]
    lines += [f"| {name} | {r.rmse:.3g} | {_pm(r.rmse_per_sample_mean, r.rmse_per_sample_std)} | "
              f"{_pm(r.rel_force_mean, r.rel_force_std, 100)} | {_pm(r.rel_torque_mean, r.rel_torque_std, 100)} |"
              for name, r in reports.items()]
    if noise_floor is not None and np.isfinite(noise_floor):
        lines.append(f"| noise floor | {noise_floor:.3g} | | | |")
    return "\n".join(lines)


def axis_table(reports: Mapping[str, CalibrationMetrics]) -> str:
    """Markdown table of the RMSE per axis: forces [N], torques [N·m]."""
    axes = list(next(iter(reports.values())).axis_rmse) if reports else list(WRENCH_LABELS)  # the axes that exist
    head = " | ".join(f"{k} [{'N' if k.startswith('F') else 'N·m'}]" for k in axes)
    rows = [f"| {name} | " + " | ".join(f"{r.axis_rmse[k]:.3g}" for k in axes) + " |" for name, r in reports.items()]
    return "\n".join([f"| model | {head} |", "|---" * (len(axes) + 1) + "|", *rows])


#: File names of the evaluation plots (the per-model one takes the model label).
EVALUATION_PLOTS = ("rmse_distribution.png", "axis_rmse.png")


def predicted_plot_name(label: str) -> str:
    """File name of a model's prediction-error plot."""
    return f"errors_{label}.png"


def write_evaluation_plots(paths: Mapping[str, Path], y_true: np.ndarray, predictions: Mapping[str, np.ndarray],
                           alpha: float, noise_floor: float | None = None, dataset_name: str = "test set",
                           axes=None) -> None:
    """The three evaluation plots: per-sample RMSE distributions, per-axis RMSE, errors vs reference.

    ``paths`` maps ``"distribution"``, ``"axis"`` and each model label to a PNG path; ``axes`` names the wrench
    columns (e.g. ``("Fx", "Fy", "Fz")`` for a 3-axis load cell: no torque to scale), default Fx..Tz.
    """
    from . import _plots
    from ..core._metrics import axis_rmse, wrench_rmse
    from ..core._wrench import axis_unit, default_axes, force_columns, torque_columns

    named = tuple(axes) if axes is not None else default_axes(np.shape(y_true)[1])
    scaled = bool(torque_columns(named)) and (bool(force_columns(named)) or alpha != 1.0)  # [F, alpha*T] in N
    units = {axis_unit(a) for a in named}
    unit = units.pop() if len(units) == 1 else "N"

    _plots.plot_error_distributions(
        {name: per_sample_rmse(y_true, p, alpha, named) for name, p in predictions.items()}, paths["distribution"],
        overall={name: wrench_rmse(y_true, p, alpha, named) for name, p in predictions.items()},
        noise_floor=noise_floor,
        title=f"Per-sample RMSE on the {dataset_name} ({len(y_true)} samples"
              + (f", α = {alpha:.3g} m⁻¹)" if scaled else ")"),
        xlabel="RMSE of the torque-scaled wrench [N]" if scaled else f"RMSE of {', '.join(named)} [{unit}]")
    _plots.plot_axis_errors({name: axis_rmse(y_true, p) for name, p in predictions.items()}, paths["axis"],
                            title=f"RMSE per axis on the {dataset_name}", axes=named)
    for name, p in predictions.items():
        _plots.plot_predicted_vs_reference(y_true, p, paths[name], model_name=name, axes=named)
