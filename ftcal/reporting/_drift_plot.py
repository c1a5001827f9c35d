"""The figure of an in-situ identification's report: the residual against time, with and without the bias drift."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from ._plots import _save

__all__ = ["drift_residuals_figure", "plot_drift_residuals"]

_COLORS = {"constant_bias": "#7f7f7f", "with_drift": "#1f77b4"}


def drift_residuals_figure(report: dict) -> Figure:
    """Force and torque residual norms of each pose against the drift variable (report of
    :func:`ftcal.experiment.identification_summary`): the constant bias in grey, the chosen drift in blue.

    Examples
    --------
    >>> report = {"axis": {"name": "time", "unit": "s"}, "values": [0.0, 1.0, 2.0], "drift_model": "linear in time",
    ...           "drift_rate": None, "residual": {k: {"force_N": [0.1, 0.2, 0.1], "torque_Nm": [0.01, 0.0, 0.01],
    ...           "rms": [0.1, 0.01]} for k in ("constant_bias", "with_drift")}}
    >>> len(drift_residuals_figure(report).axes)
    2
    """
    fig = Figure(figsize=(8.0, 5.5))
    axes = fig.subplots(2, 1, sharex=True)
    x = np.asarray(report["values"] if report["values"] is not None else [], dtype=float)
    order = np.argsort(x, kind="stable")
    for ax, key, unit in zip(axes, ("force_N", "torque_Nm"), ("N", "N·m")):
        for name, label in (("constant_bias", "constant bias"), ("with_drift", report["drift_model"])):
            values = report["residual"][name][key]
            if values is None:
                continue
            rms = report["residual"][name]["rms"][0 if key == "force_N" else 1]
            ax.plot(x[order], np.asarray(values)[order], "o-", ms=3, lw=1, color=_COLORS[name],
                    label=f"{label} (RMS {rms:.3g} {unit})")
        ax.set_ylabel(f"|{'F' if key == 'force_N' else 'τ'}| residual [{unit}]")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    axis = report["axis"]
    axes[1].set_xlabel(f"{axis['name']} [{axis['unit']}]")
    rate = report.get("drift_rate")
    title = f"tool identification: residual against {axis['name']}"
    if rate:
        pairs = zip(np.asarray(rate["force"]), np.asarray(rate["force_std_error"]))
        title += f"\ndrift rate F = [{', '.join(f'{v:.3g}±{s:.2g}' for v, s in pairs)}] {rate['unit_force']}"
    axes[0].set_title(title, fontsize=9)
    fig.tight_layout()
    return fig


def plot_drift_residuals(report: dict, path: str | Path) -> Path:
    """Write :func:`drift_residuals_figure` as a PNG to ``path`` (PNG whatever its suffix: a temporary file of an
    atomic output); returns the path."""
    return _save(drift_residuals_figure(report), path, png_suffix=False)
