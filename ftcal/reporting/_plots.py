"""PNG plots of calibration results, drawn with matplotlib's Agg canvas (no display needed).

Each ``plot_*`` function takes arrays, writes one PNG and returns its path;
the matching ``*_figure`` function returns the :class:`matplotlib.figure.Figure`
instead, for notebooks. Nothing here touches ``pyplot``'s global state, so the
functions are safe in scripts, servers and threads.

Colours: one table, one colour per model name, the same in every figure
(:func:`model_color`). The thesis' figures set three: the directional DNN blue,
the comparative DNN red, the linear model grey; every other registered
calibrator and every stock scikit-learn baseline has its own distinct colour;
a name outside the table gets a colour derived from the name itself (never
from its position in a figure), so it too keeps its colour across figures.
"""

from __future__ import annotations

from collections.abc import Mapping
from pathlib import Path

import matplotlib
import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import CalibrationInputError
from ..core._wrench import WRENCH_LABELS, axis_unit, default_axes, force_columns, torque_columns

__all__ = [
    "MODEL_COLORS",
    "model_color",
    "model_colors",
    "error_distributions_figure",
    "plot_error_distributions",
    "axis_errors_figure",
    "plot_axis_errors",
    "predicted_vs_reference_figure",
    "plot_predicted_vs_reference",
    "sphere_coverage_figure",
    "plot_sphere_coverage",
    "wrench_coverage_figure",
    "plot_wrench_coverage",
    "error_vs_load_figure",
    "residual_magnitude_figure",
    "residual_direction_figure",
]

#: The one colour table: model name -> colour, pairwise distinct (a label containing a name, e.g.
#: ``"linear (this calibration)"``, takes the colour of the longest name it contains).
MODEL_COLORS: dict[str, str] = {
    "directional": "#1f77b4", "comparative": "#d62728", "linear": "#7f7f7f",
    "polynomial": "#2ca02c", "axis_nonlinear": "#9467bd", "gaussian_process": "#ff7f0e", "auto": "#8c564b",
    "directional_ensemble": "#aec7e8", "comparative_ensemble": "#ff9896",
    "sk_linear": "#17becf", "sk_poly2": "#bcbd22", "sk_poly3": "#e377c2", "sk_kernel_ridge": "#98df8a",
    "sk_gp": "#c49c94",
}
#: Colours for names outside the table (chosen by a hash of the name).
_OTHER_COLORS = ("#393b79", "#637939", "#8c6d31", "#843c39", "#7b4173", "#3182bd", "#e6550d", "#31a354",
                 "#756bb1", "#636363", "#6baed6", "#fd8d3c")
_DPI = 120
# matplotlib 3.10 replaced ``vert=False`` by ``orientation="horizontal"`` (and deprecated ``vert`` in 3.11).
_HORIZONTAL = (
    {"orientation": "horizontal"}
    if tuple(int(p) for p in matplotlib.__version__.split(".")[:2]) >= (3, 10)
    else {"vert": False}
)


def model_color(name: str, index: int = 0) -> str:
    """Colour of a model in every plot, by its name only (``index`` is ignored; kept for old callers).

    Examples
    --------
    >>> model_color("directional"), model_color("Linear"), model_color("axis_nonlinear") != model_color("linear")
    ('#1f77b4', '#7f7f7f', True)
    """
    key = str(name).lower()
    if key in MODEL_COLORS:
        return MODEL_COLORS[key]
    contained = [known for known in MODEL_COLORS if known in key]
    if contained:
        return MODEL_COLORS[max(contained, key=len)]
    import zlib

    return _OTHER_COLORS[zlib.crc32(key.encode("utf-8")) % len(_OTHER_COLORS)]


def model_colors(names) -> dict[str, str]:
    """Colours of the models of one figure: :func:`model_color` each, a clash between two names outside the
    table moved to the next free colour (names in the table never clash)."""
    out: dict[str, str] = {}
    for name in names:
        color = model_color(name)
        if color in out.values() and color in _OTHER_COLORS:  # the next free colour after it, cyclically
            start = _OTHER_COLORS.index(color)
            color = next((c for c in _OTHER_COLORS[start:] + _OTHER_COLORS[:start] if c not in out.values()), color)
        out[name] = color
    return out


def _save(fig: Figure, path: str | Path, *, png_suffix: bool = True) -> Path:
    """Write ``fig`` as a PNG to ``path`` (which must end in ``.png`` unless ``png_suffix`` is False)."""
    path = Path(path)
    if png_suffix and path.suffix.lower() != ".png":
        raise CalibrationInputError(f"plot path {path} must end in .png")
    FigureCanvasAgg(fig)
    fig.savefig(path, dpi=_DPI, format="png")
    return path


def _plot_axes(axes, width: int | None = None) -> tuple[str, ...]:
    """The wrench axes a figure shows: ``axes`` (checked against ``width`` columns when given), default Fx..Tz
    for six columns, else :func:`~ftcal.core._wrench.default_axes`."""
    if axes is None:
        return WRENCH_LABELS if width in (None, len(WRENCH_LABELS)) else default_axes(width)
    names = tuple(str(a) for a in axes)
    if not names or len(set(names)) != len(names) or (width is not None and len(names) != width):
        raise CalibrationInputError(f"axes must name each of the {width if width is not None else 'plotted'} wrench "
                                    f"columns once (e.g. ('Fx', 'Fy', 'Fz')); got {axes!r}.")
    return names


def _wrench_array(name: str, a: ArrayLike, axes=None) -> NDArray[np.float64]:
    arr = np.asarray(a, dtype=float)
    want = len(axes) if axes is not None else None
    if arr.ndim != 2 or arr.shape[0] == 0 or arr.shape[1] == 0 or (want is not None and arr.shape[1] != want):
        shown = f"{want} [{', '.join(axes)}]" if axes is not None else "n_axes"
        raise CalibrationInputError(f"{name} must have shape (n_samples >= 1, {shown}); got shape {arr.shape}.")
    return arr


def _model_arrays(name: str, data: Mapping[str, ArrayLike], width: int | None) -> dict[str, NDArray]:
    if not data:
        raise CalibrationInputError(f"{name} is empty; give at least one model.")
    out = {}
    for model, values in data.items():
        arr = np.asarray(values, dtype=float).ravel()
        if arr.size == 0 or (width is not None and arr.size != width):
            want = f"{width} values" if width else "at least one value"
            raise CalibrationInputError(f"{name}[{model!r}] must hold {want}; got {arr.size}.")
        out[str(model)] = arr
    return out


# ------------------------------------------------------------------ error distributions
def error_distributions_figure(errors: Mapping[str, ArrayLike], *, noise_floor: float | None = None,
                               overall: Mapping[str, float] | None = None, title: str = "Error distribution per model",
                               xlabel: str = "RMSE of the torque-scaled wrench [N]") -> Figure:
    """Violin + box plot of each model's errors, one row per model (the thesis' Fig. 5 and 6).

    Parameters
    ----------
    errors : mapping of str to array-like
        Model name -> error values (per sample, or per dataset).
    noise_floor : float, optional
        The error a perfect calibrator would still make; drawn as a dashed line.
    overall : mapping of str to float, optional
        Model name -> the RMSE over the whole set (eq. 18), drawn as a black
        diamond; the number to hold against ``noise_floor`` when ``errors``
        are per-sample values.
    title, xlabel : str
        Figure title and axis label (with the unit).
    """
    data = _model_arrays("errors", errors, None)
    names = list(data)
    fig = Figure(figsize=(8.0, 1.2 + 1.1 * len(names)), layout="constrained")
    ax = fig.add_subplot()
    positions = np.arange(len(names))[::-1]
    rng = np.random.default_rng(0)
    colors = model_colors(names)
    for i, (name, pos) in enumerate(zip(names, positions)):
        values, color = data[name], colors[name]
        if values.size > 1 and np.ptp(values) > 0:
            parts = ax.violinplot(values, positions=[pos], showextrema=False, widths=0.8, **_HORIZONTAL)
            for body in parts["bodies"]:
                body.set_facecolor(color)
                body.set_edgecolor(color)
                body.set_alpha(0.35)
        ax.boxplot(values, positions=[pos], widths=0.25, showfliers=False, **_HORIZONTAL,
                   medianprops={"color": "black"}, boxprops={"color": color}, whiskerprops={"color": color},
                   capprops={"color": color})
        if values.size <= 200:  # few values (e.g. one per dataset): show each one
            ax.scatter(values, pos + rng.uniform(-0.12, 0.12, values.size), s=10, color=color, alpha=0.7, zorder=3)
        ax.annotate(f"mean {values.mean():.3g} ± {values.std():.2g}", xy=(1.0, pos), color=color,
                    xycoords=("axes fraction", "data"), xytext=(-4, 10), textcoords="offset points", ha="right",
                    fontsize=8)
        if overall is not None and name in overall:  # zorder 4: above every model's violin, box and points
            ax.scatter([overall[name]], [pos], marker="D", s=36, color="black", zorder=4,
                       label="RMSE over the set" if i == 0 else None)
    if noise_floor is not None and np.isfinite(noise_floor):
        ax.axvline(noise_floor, color="black", linestyle="--", linewidth=1, label=f"noise floor {noise_floor:.3g}")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(loc="lower right", fontsize=8)
    ax.set_yticks(positions, names)
    ax.set(xlabel=xlabel, title=title)
    ax.grid(axis="x", alpha=0.3)
    return fig


def plot_error_distributions(errors: Mapping[str, ArrayLike], path: str | Path, **kwargs) -> Path:
    """Write :func:`error_distributions_figure` to ``path`` (PNG) and return the path.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> d = tempfile.mkdtemp()
    >>> p = plot_error_distributions({"linear": [3.0, 4.0, 3.5], "directional": [1.0, 1.5, 1.2]},
    ...                              os.path.join(d, "rmse.png"), noise_floor=0.8)
    >>> p.stat().st_size > 0
    True
    """
    return _save(error_distributions_figure(errors, **kwargs), path)


# ------------------------------------------------------------------ per-axis errors
def axis_errors_figure(
    axis_errors: Mapping[str, ArrayLike], *, title: str = "RMSE per axis", axes=None
) -> Figure:
    """Grouped bars of each model's per-axis RMSE: forces [N] left, torques [N·m] right (one panel for a
    force-only or torque-only sensor).

    Parameters
    ----------
    axis_errors : mapping of str to array-like of shape (n_axes,)
        Model name -> RMSE of each axis in its own unit, [N] or [N·m].
    axes : sequence of str, optional
        The axes of those values, e.g. ``("Fx", "Fy", "Fz")`` for a 3-axis load cell; default Fx..Tz for six
        values, else the first ones of Fx..Tz.
    """
    first = next(iter(axis_errors.values()), None) if axis_errors else None
    names = _plot_axes(axes, None if axes is not None or first is None else np.asarray(first).size)
    data = _model_arrays("axis_errors", axis_errors, len(names))
    colors = model_colors(data)
    parts = [(cols, unit) for cols, unit in ((force_columns(names), "N"), (torque_columns(names), "N·m")) if cols]
    other = [k for k in range(len(names)) if k not in force_columns(names) + torque_columns(names)]
    if other:  # axes that are neither forces nor torques (unnamed outputs): their own panel
        parts.append((other, "output unit"))
    fig = Figure(figsize=(9.0 + 0.35 * max(0, len(data) - 3), 4.0), layout="constrained")
    panels = np.atleast_1d(fig.subplots(1, len(parts)))
    width = 0.8 / len(data)
    for ax, (part, unit) in zip(panels, parts):
        labels = [names[k] for k in part]
        x = np.arange(len(labels))
        for i, (name, values) in enumerate(data.items()):
            ax.bar(x + (i - (len(data) - 1) / 2) * width, values[part], width, label=name, color=colors[name])
        _label_bars(ax, x, width, [values[part] for values in data.values()])
        ax.set_xticks(x, labels)
        top = max(float(np.nanmax(values[part])) for values in data.values())
        ax.set(ylabel=f"RMSE [{unit}]", title={"N": "forces", "N·m": "torques"}.get(unit, "outputs"),
               ylim=(0, (top if top > 0 else 1.0) * 1.25))
        ax.grid(axis="y", alpha=0.3)
    # the legend goes below the panels, where it cannot hide a bar or its value
    fig.legend(*panels[0].get_legend_handles_labels(), loc="outside lower center", ncols=min(len(data), 5), fontsize=8)
    fig.suptitle(title)
    return fig


def _label_bars(ax, x: NDArray, width: float, heights: list[NDArray]) -> None:
    """Write each bar's value above it, vertically, so the labels of neighbouring (e.g. equal) bars never overlap."""
    n = len(heights)
    for i, values in enumerate(heights):
        for xi, v in zip(x + (i - (n - 1) / 2) * width, values):
            if np.isfinite(v):
                ax.annotate(f"{v:.3g}", xy=(xi, v), xytext=(0, 2), textcoords="offset points", ha="center",
                            va="bottom", rotation=90, fontsize=7)


def plot_axis_errors(axis_errors: Mapping[str, ArrayLike], path: str | Path, **kwargs) -> Path:
    """Write :func:`axis_errors_figure` to ``path`` (PNG) and return the path."""
    return _save(axis_errors_figure(axis_errors, **kwargs), path)


# ------------------------------------------------------------------ predicted vs reference
def predicted_vs_reference_figure(y_true: ArrayLike, y_pred: ArrayLike, *, model_name: str = "model",
                                  kind: str = "error", max_points: int = 5000, axes=None) -> Figure:
    """Predictions against the reference wrench, one panel per axis.

    Parameters
    ----------
    y_true, y_pred : array-like of shape (n_samples, n_axes)
        Reference and predicted wrenches in [N] and [N·m].
    model_name : str
        Shown in the title and used for the colour.
    kind : {"error", "value"}
        ``"error"`` (default) plots the prediction error ``predicted - reference``
        against the reference, with the ±RMSE band: calibration errors are a
        percent of the range, invisible on a plain predicted-vs-reference
        diagonal. ``"value"`` plots the predicted value with the identity line.
    max_points : int
        At most this many points are drawn (an evenly spaced subset), to keep
        the PNG readable; the RMSE in each panel uses every sample.
    axes : sequence of str, optional
        The axes of the columns, e.g. ``("Fx", "Fy", "Fz")`` for a 3-axis load cell; default Fx..Tz for six
        columns, else the first ones of Fx..Tz.
    """
    t = _wrench_array("y_true", y_true, None if axes is None else _plot_axes(axes))
    names = _plot_axes(axes, t.shape[1])
    p = _wrench_array("y_pred", y_pred, names)
    if t.shape != p.shape:
        raise CalibrationInputError(f"y_true has shape {t.shape} but y_pred has shape {p.shape}; they must match.")
    if kind not in ("error", "value"):
        raise CalibrationInputError(f"kind must be 'error' or 'value'; got {kind!r}.")
    shown = np.linspace(0, len(t) - 1, min(len(t), max_points)).astype(int)
    n_cols = min(3, len(names))
    n_rows = -(-len(names) // n_cols)
    fig = Figure(figsize=(11.0 * n_cols / 3 + (0.5 if n_cols < 3 else 0.0), 3.25 * n_rows), layout="constrained")
    panels = np.atleast_1d(fig.subplots(n_rows, n_cols)).ravel()
    for ax in panels[len(names):]:
        ax.set_visible(False)
    color = model_color(model_name)
    for k, ax in enumerate(panels[:len(names)]):
        unit = axis_unit(names[k])
        err = p[:, k] - t[:, k]
        rmse = float(np.sqrt(np.mean(err**2)))
        if kind == "error":
            ax.axhline(0.0, color="black", linewidth=0.8, label="ideal")
            ax.axhspan(-rmse, rmse, color=color, alpha=0.12, label="± RMSE")
        else:
            lo, hi = float(t[:, k].min()), float(t[:, k].max())
            pad = 0.05 * (hi - lo or 1.0)
            ax.plot([lo - pad, hi + pad], [lo - pad, hi + pad], color="black", linewidth=0.8, label="ideal")
        shown_y = err[shown] if kind == "error" else p[shown, k]
        ax.scatter(t[shown, k], shown_y, s=4, alpha=0.4, color=color, linewidths=0, label=model_name)
        ax.set_ylabel(f"predicted - reference [{unit}]" if kind == "error" else f"predicted [{unit}]")
        ax.set_title(f"{names[k]}   RMSE {rmse:.3g} {unit}", fontsize=10)
        ax.set_xlabel(f"reference {names[k]} [{unit}]")
        ax.grid(alpha=0.3)
    panels[0].legend(fontsize=8, loc="upper left", markerscale=3)
    what = "Prediction error" if kind == "error" else "Predicted"
    fig.suptitle(f"{what} vs reference wrench — {model_name} ({len(t)} samples)")
    return fig


def plot_predicted_vs_reference(y_true: ArrayLike, y_pred: ArrayLike, path: str | Path, **kwargs) -> Path:
    """Write :func:`predicted_vs_reference_figure` to ``path`` (PNG) and return the path."""
    return _save(predicted_vs_reference_figure(y_true, y_pred, **kwargs), path)


# ------------------------------------------------------------------ coverage
def _azimuth_elevation(d: NDArray) -> tuple[NDArray, NDArray]:
    """Azimuth ``atan2(y, x)`` and elevation ``asin(z)`` [deg] of unit directions (n, 3)."""
    return np.degrees(np.arctan2(d[:, 1], d[:, 0])), np.degrees(np.arcsin(np.clip(d[:, 2], -1, 1)))


def sphere_coverage_figure(
    directions: ArrayLike,
    *,
    reached: ArrayLike | None = None,
    title: str = "Gravity directions in the sensor frame",
) -> Figure:
    """Where on the sphere of load directions the calibration poses lie.

    Left: the unit directions in 3-D; right: the same as a longitude/latitude
    map, so gaps are easy to see. Points that the robot cannot reach (``reached``
    false) are drawn as grey crosses.

    Parameters
    ----------
    directions : array-like of shape (n, 3)
        Directions (normalised here), e.g. gravity in the sensor frame.
    reached : array-like of bool, shape (n,), optional
        Which directions have a feasible pose; all when omitted.
    """
    d = np.asarray(directions, dtype=float)
    if d.ndim != 2 or d.shape[1] != 3 or d.shape[0] == 0:
        raise CalibrationInputError(f"directions must have shape (n >= 1, 3); got shape {d.shape}.")
    norm = np.linalg.norm(d, axis=1)
    if not np.all(np.isfinite(norm)) or np.any(norm == 0):
        raise CalibrationInputError("directions must be finite and non-zero.")
    d = d / norm[:, None]
    ok = np.ones(len(d), bool) if reached is None else np.asarray(reached, dtype=bool).ravel()
    if ok.shape != (len(d),):
        raise CalibrationInputError(f"reached must have shape ({len(d)},); got shape {ok.shape}.")
    fig = Figure(figsize=(11.0, 5.0), layout="constrained")
    ax3 = fig.add_subplot(1, 2, 1, projection="3d")
    u, v = np.meshgrid(np.linspace(0, 2 * np.pi, 37), np.linspace(0, np.pi, 19))
    ax3.plot_wireframe(np.cos(u) * np.sin(v), np.sin(u) * np.sin(v), np.cos(v), color="0.85", linewidth=0.4)
    ax3.scatter(*d[ok].T, s=12, color="#1f77b4", label=f"reachable ({ok.sum()})", depthshade=False)
    if (~ok).any():
        ax3.scatter(*d[~ok].T, s=14, marker="x", color="0.5", label=f"unreachable ({(~ok).sum()})")
    for axis, label in ((ax3.xaxis, "x"), (ax3.yaxis, "y"), (ax3.zaxis, "z")):
        axis.set_ticks([-1, 0, 1])
        axis.set_label_text(label)
    ax3.set_box_aspect((1, 1, 1))
    ax3.legend(fontsize=8, loc="upper left")
    ax2 = fig.add_subplot(1, 2, 2)
    lon, lat = _azimuth_elevation(d)
    ax2.scatter(lon[ok], lat[ok], s=12, color="#1f77b4")
    if (~ok).any():
        ax2.scatter(lon[~ok], lat[~ok], s=14, marker="x", color="0.5")
    ax2.set(xlim=(-180, 180), ylim=(-90, 90), xticks=np.arange(-180, 181, 60), yticks=np.arange(-90, 91, 30),
            xlabel="azimuth atan2(y, x) [deg]", ylabel="elevation asin(z) [deg]")
    ax2.grid(alpha=0.3)
    ax2.set_title(f"{len(d)} directions, map view", fontsize=10)
    fig.suptitle(title)
    return fig


def plot_sphere_coverage(directions: ArrayLike, path: str | Path, **kwargs) -> Path:
    """Write :func:`sphere_coverage_figure` to ``path`` (PNG) and return the path."""
    return _save(sphere_coverage_figure(directions, **kwargs), path)


def wrench_coverage_figure(
    wrench: ArrayLike, *, alpha: float = 1.0, title: str = "Wrench coverage of the dataset", axes=None
) -> Figure:
    """Which loads a dataset holds, for any axis set: the torque-scaled magnitude and the loads per kind.

    Left: histogram of ``||[F, alpha T]||`` [N] over the axes that exist (the thesis' training spheres show as
    sharp peaks); then one panel for the forces and one for the torques, each that exists: the first two
    against each other (``Fx`` against ``Fy`` [N], ``Tx`` against ``Ty`` [N·m]), or the histogram of a single
    one (a 1-axis cell's ``Fz``, a plate's ``Fz``).

    Parameters
    ----------
    wrench : array-like of shape (n, k)
        Wrenches in [N] and [N·m].
    alpha : float
        Torque scale [m⁻¹] for the magnitude.
    title : str
    axes : sequence of str, optional
        The axes of the columns (``("Fz", "Tx", "Ty")`` for a plate); default Fx..Tz for six columns, else
        :func:`~ftcal.core._wrench.default_axes`.

    Examples
    --------
    >>> import numpy as np
    >>> fig = wrench_coverage_figure(np.random.default_rng(0).normal(size=(50, 3)), alpha=50, axes=("Fz", "Tx", "Ty"))
    >>> [ax.get_xlabel().split(" [")[0] for ax in fig.axes]
    ['‖[F, α·T]‖', 'Fz', 'Tx']
    """
    w = _wrench_array("wrench", wrench, None if axes is None else tuple(axes))
    names = tuple(axes) if axes is not None else default_axes(w.shape[1])
    if not np.isfinite(alpha) or alpha <= 0:
        raise CalibrationInputError(f"alpha must be a finite positive number; got {alpha}.")
    forces, torques = force_columns(names), torque_columns(names)
    scaled = w.copy()
    if forces and torques:  # alpha weighs torques against forces; a torque-only wrench keeps its unit
        scaled[:, torques] *= alpha
    kinds = [(columns, unit) for columns, unit in ((forces, "N"), (torques, "N·m")) if columns]
    fig = Figure(figsize=(4.0 * (1 + len(kinds)), 4.0), layout="constrained")
    panels = np.atleast_1d(fig.subplots(1, 1 + len(kinds)))
    panels[0].hist(np.linalg.norm(scaled, axis=1), bins=60, color="#1f77b4")
    panels[0].set_xlabel(f"‖[F, α·T]‖ [N]   (α = {alpha:.3g} m⁻¹)" if forces and torques else
                         f"‖{'F' if forces else 'T'}‖ [{'N' if forces else 'N·m'}]")
    panels[0].set_ylabel("samples")
    for ax, (columns, unit) in zip(panels[1:], kinds):
        if len(columns) >= 2:
            i, j = columns[:2]
            ax.scatter(w[:, i], w[:, j], s=3, alpha=0.4, color="#1f77b4", linewidths=0)
            ax.set_ylabel(f"{names[j]} [{unit}]")
            ax.set_aspect("equal", adjustable="datalim")
        else:
            i = columns[0]
            ax.hist(w[:, i], bins=60, color="#1f77b4")
            ax.set_ylabel("samples")
        ax.set_xlabel(f"{names[i]} [{unit}]")
    for ax in panels:
        ax.grid(alpha=0.3)
    fig.suptitle(f"{title} ({len(w)} samples)")
    return fig


def plot_wrench_coverage(wrench: ArrayLike, path: str | Path, **kwargs) -> Path:
    """Write :func:`wrench_coverage_figure` to ``path`` (PNG) and return the path."""
    return _save(wrench_coverage_figure(wrench, **kwargs), path)


def _draw_order(magnitude: NDArray, limit: int, seed: int = 0) -> NDArray[np.int64]:
    """Rows to draw, smallest first so that the largest are drawn on top: all rows up to ``limit``, else the
    ``limit // 10`` largest and a random draw of the rest (a figure of a million points shows no more)."""
    n = magnitude.shape[0]
    order = np.argsort(magnitude, kind="stable")
    if n <= limit:
        return order
    top = order[n - limit // 10:]
    rest = np.random.default_rng(seed).choice(order[:n - limit // 10], size=limit - top.size, replace=False)
    return np.concatenate([rest[np.argsort(magnitude[rest], kind="stable")], top])


def error_vs_load_figure(
    applied: ArrayLike, error_pct_fs: ArrayLike, *, axis_names, units, band_pct_fs: ArrayLike,
    band_label: str = "spec", max_points: int = 8000,
) -> Figure:
    """Per-axis panels of held-out error [% FS] against the applied load, the largest errors drawn on top.

    Parameters
    ----------
    applied : array-like of shape (n, k)
        Applied (reference) load per axis, in its unit.
    error_pct_fs : array-like of shape (n, k)
        Indicated minus applied, in % of each axis' full scale.
    axis_names, units : sequence of str, length k
        Axis names (``"Fx"`` ...) and their units.
    band_pct_fs : array-like of shape (k,)
        Half-width of the shaded band per axis [% FS] (the specification, or U95); errors outside it are drawn
        in red.
    band_label : str
        What the band is, for the legend.
    max_points : int
        Points drawn per panel at most (every large error is kept).

    Returns
    -------
    Figure

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> fig = error_vs_load_figure(rng.normal(size=(50, 3)), rng.normal(size=(50, 3)), axis_names=["Fx", "Fy", "Fz"],
    ...                            units=["N"] * 3, band_pct_fs=[1.0, 1.0, 1.0])
    >>> len(fig.axes)
    3
    """
    applied = np.asarray(applied, dtype=float)
    err = np.asarray(error_pct_fs, dtype=float)
    band = np.asarray(band_pct_fs, dtype=float)
    k = applied.shape[1]
    cols = 3 if k >= 3 else k
    rows = int(np.ceil(k / cols))
    fig = Figure(figsize=(10, 3.0 * rows + 0.4), layout="constrained")
    axes = np.atleast_1d(fig.subplots(rows, cols, squeeze=False)).ravel()
    for j, ax in enumerate(axes[:k]):
        e = err[:, j]
        order = _draw_order(np.abs(np.nan_to_num(e)), max_points, seed=j)
        outside = np.abs(e[order]) > band[j] if np.isfinite(band[j]) else np.zeros(order.size, bool)
        if np.isfinite(band[j]):
            ax.axhspan(-band[j], band[j], color="#2ca02c", alpha=0.15, linewidth=0,
                       label=f"±{band[j]:.3g} % FS ({band_label})")
        ax.scatter(applied[order[~outside], j], e[order][~outside], s=7, color="#4d4d4d", linewidths=0, alpha=0.6)
        if outside.any():
            ax.scatter(applied[order[outside], j], e[order][outside], s=14, color="#d62728", linewidths=0,
                       label=f"beyond the {band_label}", zorder=3)
        ax.axhline(0.0, color="black", linewidth=0.6)
        ax.set_title(axis_names[j], fontsize=11)
        ax.set_xlabel(f"applied {axis_names[j]} [{units[j]}]", fontsize=10)
        ax.set_ylabel("held-out error [% FS]", fontsize=10)
        ax.tick_params(labelsize=9)
        ax.grid(alpha=0.3)
        if j == 0:
            ax.legend(fontsize=8, loc="best")
    for ax in axes[k:]:
        ax.set_visible(False)
    return fig


def residual_magnitude_figure(applied: ArrayLike, error: ArrayLike, *, force_columns, torque_columns,
                              color: str = "#4d4d4d", max_points: int = 8000) -> Figure:
    """Held-out force (and torque) error magnitude against the load magnitude, the largest errors on top.

    ``applied`` and ``error`` are ``(n, k)`` in [N] / [N·m]; ``force_columns`` / ``torque_columns`` index them
    (a 3-axis load cell has no torque columns, and gets one panel).

    Examples
    --------
    >>> import numpy as np
    >>> w = np.random.default_rng(0).normal(size=(20, 3))
    >>> len(residual_magnitude_figure(w, 0.01 * w, force_columns=[0, 1, 2], torque_columns=[]).axes)
    1
    """
    applied = np.asarray(applied, dtype=float)
    error = np.asarray(error, dtype=float)
    panels = [(list(c), q, u) for c, q, u in ((force_columns, "F", "N"), (torque_columns, "T", "N·m")) if len(c)]
    fig = Figure(figsize=(10, 3.4), layout="constrained")
    for i, (cols, q, unit) in enumerate(panels):
        ax = fig.add_subplot(1, len(panels), i + 1)
        load = np.linalg.norm(applied[:, cols], axis=1)
        mag = np.linalg.norm(error[:, cols], axis=1)
        order = _draw_order(mag, max_points, seed=i)
        ax.scatter(load[order], mag[order], c=mag[order], cmap="viridis", s=8, linewidths=0)
        ax.set_xlabel(f"load |{q}| [{unit}]", fontsize=10)
        ax.set_ylabel(f"held-out error |Δ{q}| [{unit}]", fontsize=10)
        ax.tick_params(labelsize=9)
        ax.grid(alpha=0.3)
    fig.suptitle("Held-out error against load magnitude (largest errors drawn last, on top)", fontsize=11)
    return fig


def residual_direction_figure(force: ArrayLike, force_error: ArrayLike, *, max_points: int = 8000) -> Figure:
    """Held-out force error by load direction (sensor frame), the largest errors drawn on top.

    ``force`` and ``force_error`` are ``(n, 3)`` [N].

    Examples
    --------
    >>> import numpy as np
    >>> f = np.random.default_rng(0).normal(size=(30, 3))
    >>> len(residual_direction_figure(f, 0.1 * f).axes)
    2
    """
    force = np.asarray(force, dtype=float)
    err = np.linalg.norm(np.asarray(force_error, dtype=float), axis=1)
    mag = np.linalg.norm(force, axis=1)
    fig = Figure(figsize=(10, 3.8), layout="constrained")
    ax = fig.add_subplot()
    loaded = np.flatnonzero(mag > 1e-9)
    if loaded.size:
        d = force[loaded] / mag[loaded, None]
        order = _draw_order(err[loaded], max_points)
        lon, lat = _azimuth_elevation(d[order])
        sc = ax.scatter(lon, lat, c=err[loaded][order], s=12, cmap="viridis", linewidths=0)
        fig.colorbar(sc, ax=ax, label="held-out |ΔF| [N]")
    ax.set(xlim=(-180, 180), ylim=(-90, 90), xlabel="load direction: azimuth atan2(Fy, Fx) [deg]",
           ylabel="elevation asin(Fz/|F|) [deg]",
           title="Force error by load direction (sensor frame; largest errors on top)")
    ax.grid(alpha=0.3)
    return fig
