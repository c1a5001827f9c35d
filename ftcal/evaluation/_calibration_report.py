"""The calibration report a sensor ships with: one self-contained HTML page per calibration.

Like a sensor maker's calibration certificate, it states per axis the **held-out** accuracy (grouped
cross-validation: whole poses or load configurations held out), in the data's units and in % of full
scale, with the 95 % expanded uncertainty and how often held-out errors actually fell within it; the
model choice beside the stock scikit-learn baselines on the same folds; the calibrated range; the
residuals against load magnitude and direction; temperature coefficients and tool parameters when
present; and who, what and when (hashes of the model and data files, the date, ftcal's version).

The page needs no network: styles are inline and every picture is a PNG data URI.
:func:`calibration_certificate` computes the facts (a JSON-able dict), :func:`render_report_html`
turns them into the page, :func:`write_calibration_report` does both and writes ``.html`` and
``.json`` beside each other.

Definitions (stated on the page too)
------------------------------------
full scale (FS)
    Per axis, the largest absolute reference load of the calibration data (the calibrated range);
    or the sensor's rated range when given (``full_scale=``).
expanded uncertainty U95
    ``k * u`` with coverage factor ``k = 2`` and ``u`` the held-out RMS error of the axis (GUM, normal
    errors: about 95 %). The *coverage* column reports the fraction of held-out errors within ±U95,
    so a reader sees whether the 95 % holds on these data.
"""

from __future__ import annotations

import base64
import datetime as _dt
import hashlib
import html
import io
import json
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..core._exceptions import CalibrationInputError
from ..core._files import atomic_output, plain_json
from ..calibrators._history import reads_history
from ..core._model_selection import calibration_folds, rmse_and_se
from ..core._wrench import FORCE, TORQUE, WRENCH_LABELS, alpha_from_wrenches, scale_torques
from ..io._dataset import CalibrationDataset
from ..models._auto import provides_std

__all__ = ["model_inputs", "calibration_certificate", "render_report_html", "write_calibration_report", "report_json", "file_sha256",
           "COVERAGE_FACTOR"]

#: k of the expanded uncertainty U = k u (about 95 % for normal errors).
COVERAGE_FACTOR = 2.0
_UNITS = ("N", "N", "N", "N·m", "N·m", "N·m")


def file_sha256(path: str | Path) -> str:
    """SHA-256 of a file's bytes (hex), the identity of a model or data file."""
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def model_inputs(model: Any, data: CalibrationDataset) -> NDArray[np.float64]:
    """The ``X`` a fitted model takes from a dataset: the raw channels, plus the temperature column for a
    temperature-compensated model; a dataset of another sensor (other channel count) is refused."""
    n = int(getattr(model, "n_features_in_", data.n_channels))
    if n == data.n_channels:
        return data.raw
    if n == data.n_channels + 1 and data.temperature is not None:
        return data.features(temperature=True)
    extra = " and a temperature column" if n == data.n_channels + 1 else ""
    raise CalibrationInputError(
        f"the model takes {n} inputs but the dataset has {data.n_channels} raw channels{extra}; a report needs the "
        "data the model was calibrated on (same sensor, same channel order)."
    )


def _fit(estimator: Any, X: NDArray, y: NDArray, groups: NDArray | None) -> Any:
    from ..calibrators._base import BaseCalibrator
    from ..calibrators._routing import requests_groups

    kwargs = {}  # the stock baselines take no groups; an ftcal calibrator gets them when its routing asks
    if groups is not None and isinstance(estimator, BaseCalibrator) and requests_groups(estimator):
        kwargs["groups"] = groups
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return estimator.fit(X, y, **kwargs)


def _held_out(template: Any, X: NDArray, y: NDArray, groups: NDArray | None, folds: list) -> dict:
    """Out-of-fold predictions (and std where the model gives one) on ``folds``."""
    from sklearn.base import clone

    pred = np.full(y.shape, np.nan)
    std = np.full(y.shape, np.nan)
    has_std = True
    for train, test in folds:
        est = _fit(clone(template), X[train], y[train], None if groups is None else groups[train])
        has_std = has_std and provides_std(est)  # auto may choose a GP in one fold and not in another
        if has_std:
            out = est.predict(X[test], return_std=True)
            pred[test], std[test] = np.asarray(out[0]), np.asarray(out[1])
        else:
            pred[test] = np.asarray(est.predict(X[test]))
    return {"pred": pred, "std": std if has_std else None}


def _png(fig) -> str:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=100)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _residual_figures(y: NDArray, pred: NDArray, name: str) -> dict[str, str]:
    """Residuals against load magnitude and load direction, as PNG data URIs."""
    from matplotlib.figure import Figure

    from ._plots import model_color

    color = model_color(name)
    err = pred - y
    f_mag = np.linalg.norm(y[:, FORCE], axis=1)
    t_mag = np.linalg.norm(y[:, TORQUE], axis=1)
    fig = Figure(figsize=(10, 3.6), layout="constrained")
    a, b = fig.subplots(1, 2)
    a.scatter(f_mag, np.linalg.norm(err[:, FORCE], axis=1), s=5, alpha=0.5, color=color, linewidths=0)
    a.set_xlabel("load |F| [N]")
    a.set_ylabel("held-out force error |ΔF| [N]")
    b.scatter(t_mag, np.linalg.norm(err[:, TORQUE], axis=1), s=5, alpha=0.5, color=color, linewidths=0)
    b.set_xlabel("load |T| [N·m]")
    b.set_ylabel("held-out torque error |ΔT| [N·m]")
    for ax in (a, b):
        ax.grid(alpha=0.3)
    fig.suptitle("Residuals against load magnitude")
    magnitude = _png(fig)
    loaded = f_mag > 1e-9
    fig = Figure(figsize=(10, 3.8), layout="constrained")
    ax = fig.add_subplot()
    if loaded.any():
        d = y[loaded, :3] / f_mag[loaded, None]
        lon = np.degrees(np.arctan2(d[:, 1], d[:, 0]))
        lat = np.degrees(np.arcsin(np.clip(d[:, 2], -1, 1)))
        sc = ax.scatter(lon, lat, c=np.linalg.norm(err[loaded, :3], axis=1), s=10, cmap="viridis")
        fig.colorbar(sc, ax=ax, label="held-out |ΔF| [N]")
    ax.set_xlim(-180, 180)
    ax.set_ylim(-90, 90)
    ax.set_xlabel("load direction: azimuth atan2(Fy, Fx) [deg]")
    ax.set_ylabel("elevation asin(Fz/|F|) [deg]")
    ax.grid(alpha=0.3)
    ax.set_title("Force error by load direction (sensor frame)")
    return {"residuals_vs_magnitude": magnitude, "residuals_vs_direction": _png(fig)}


def calibration_certificate(
    model: Any,
    dataset: CalibrationDataset,
    *,
    model_path: str | Path | None = None,
    dataset_path: str | Path | None = None,
    sensor: str | None = None,
    cv: int = 5,
    baselines: bool = True,
    full_scale: NDArray | None = None,
    tool: Any = None,
    alpha: float | None = None,
    random_state: int = 0,
    figures: bool = True,
) -> dict:
    """The facts of a calibration report: identity, data, held-out accuracy, model choice, range.

    Parameters
    ----------
    model : fitted calibrator
        The calibration (e.g. from :func:`ftcal.load_model`); cloned and refitted on each fold for the
        held-out figures (its parameters, not its fitted state, are judged).
    dataset : CalibrationDataset
        The calibration data (the training data of ``model``).
    model_path, dataset_path : path, optional
        Files whose SHA-256 identifies the model and the data.
    sensor : str, optional
        Sensor name / serial number; default the dataset's ``meta['sensor']``.
    cv : int
        Folds: whole groups held out when the dataset has groups, else shuffled rows (contiguous blocks for a
        load-history model, which reads its rows in time order).
    baselines : bool
        Also cross-validate :func:`ftcal.models.stock_baselines` on the same folds.
    full_scale : array-like of shape (6,), optional
        Rated range per axis [N, N·m]; default the largest absolute reference load per axis.
    tool : ToolLoad, optional
        A tool's identified parameters, to print.
    alpha : float, optional
        Torque scale [1/m] of the RMSE; default the model's ``alpha_``, else from the wrenches.
    figures : bool
        Include the residual plots (PNG data URIs).

    Returns
    -------
    dict
        JSON-able; ``render_report_html`` shows it.
    """
    from sklearn.base import clone

    import ftcal
    from ..models._baselines import stock_baselines

    X = model_inputs(model, dataset)
    y = dataset.wrench
    groups = dataset.group
    if groups is not None and np.unique(groups).size < 2:
        groups = None
    ordered = reads_history(model)  # a load-history model reads its rows as a time series: never shuffle them
    folds = calibration_folds(len(y), groups, cv, random_state, shuffle=not ordered)
    alpha = float(alpha or getattr(model, "alpha_", None) or alpha_from_wrenches(y))
    fs = np.max(np.abs(y), axis=0) if full_scale is None else np.asarray(full_scale, dtype=float)
    if fs.shape != (6,) or not np.all(np.isfinite(fs)):
        raise CalibrationInputError(f"full_scale must hold 6 finite values [N, N·m]; got shape {fs.shape}.")
    fs = np.where(fs > 0, fs, np.nan)
    name = type(model).__name__
    candidates = [(f"{name} (this calibration)", clone(model))]
    if baselines:
        candidates += list(stock_baselines(X.shape[1]).items())
    choice, main = [], None
    for label, template in candidates:
        try:
            out = _held_out(template, X, y, groups, folds)
        except Exception as exc:  # a baseline that cannot fit these data is reported, not fatal
            if main is None:
                raise
            choice.append({"model": label, "status": f"failed: {type(exc).__name__}: {str(exc)[:120]}"})
            continue
        sq = np.sum((scale_torques(out["pred"], alpha) - scale_torques(y, alpha)) ** 2, axis=1)
        rmse, se = rmse_and_se(sq / 6.0, groups)
        choice.append({"model": label, "status": "scored", "rmse": rmse, "rmse_se": se,
                       "axis_rmse": np.sqrt(np.mean((out["pred"] - y) ** 2, axis=0)).tolist()})
        if main is None:
            main = out
    err = main["pred"] - y
    rms = np.sqrt(np.mean(err**2, axis=0))
    u95 = COVERAGE_FACTOR * rms
    accuracy = []
    for k, label in enumerate(WRENCH_LABELS):
        accuracy.append({
            "axis": label, "unit": _UNITS[k], "full_scale": fs[k], "rms": rms[k], "max": float(np.max(np.abs(err[:, k]))),
            "rms_pct_fs": 100 * rms[k] / fs[k], "max_pct_fs": 100 * float(np.max(np.abs(err[:, k]))) / fs[k],
            "u95": u95[k], "u95_pct_fs": 100 * u95[k] / fs[k],
            "coverage_u95": float(np.mean(np.abs(err[:, k]) <= u95[k])),
            "coverage_std": (None if main["std"] is None
                             else float(np.mean(np.abs(err[:, k]) <= COVERAGE_FACTOR * main["std"][:, k]))),
        })
    temperature = None if dataset.temperature is None else [float(dataset.temperature.min()),
                                                            float(dataset.temperature.max())]
    coefficients = None
    if hasattr(model, "gain_per_deg_"):
        coefficients = {"reference_temperature": float(model.reference_temperature),
                        "gain_per_deg": np.asarray(model.gain_per_deg_).tolist(),
                        "offset_per_deg": np.asarray(model.offset_per_deg_).tolist()}
    report = {
        "format": "ftcal-calibration-report", "format_version": 1,
        "date_utc": _dt.datetime.now(_dt.timezone.utc).strftime("%Y-%m-%d %H:%M:%S UTC"),
        "ftcal_version": getattr(ftcal, "__version__", "unknown"),
        "sensor": sensor or str(dataset.meta.get("sensor", "not named (pass --sensor NAME)")),
        "model": {"type": name, "file": None if model_path is None else str(model_path),
                  "sha256": None if model_path is None else file_sha256(model_path),
                  "params": {k: v for k, v in model.get_params(deep=False).items() if not hasattr(v, "fit")},
                  "alpha": alpha},
        "data": {"file": None if dataset_path is None else str(dataset_path),
                 "sha256": None if dataset_path is None else file_sha256(dataset_path),
                 "rows": dataset.n_samples, "channels": dataset.n_channels,
                 "groups": None if dataset.group is None else int(np.unique(dataset.group).size),
                 "wrench_min": y.min(axis=0).tolist(), "wrench_max": y.max(axis=0).tolist(),
                 "max_force_norm": float(np.linalg.norm(y[:, FORCE], axis=1).max()),
                 "max_torque_norm": float(np.linalg.norm(y[:, TORQUE], axis=1).max()),
                 "temperature_range": temperature,
                 "units": {k: dataset.meta[k] for k in ("source_force_unit", "source_torque_unit") if k in dataset.meta}},
        "validation": {"folds": len(folds), "split": "whole groups held out (GroupKFold)" if groups is not None
                       else "contiguous blocks of rows (KFold, time order kept: a load-history model)" if ordered
                       else "shuffled rows (KFold; no group column)", "coverage_factor": COVERAGE_FACTOR},
        "accuracy": accuracy,
        "model_choice": choice,
        "calibrated_range": {"raw_min": dataset.raw.min(axis=0).tolist(), "raw_max": dataset.raw.max(axis=0).tolist(),
                             "wrench_abs_max": np.max(np.abs(y), axis=0).tolist()},
        "temperature_coefficients": coefficients,
        "tool": None if tool is None else tool.to_dict(),
        "figures": _residual_figures(y, main["pred"], name) if figures else {},
    }
    return plain_json(report)


def _fmt(value: Any, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return "–"
    if isinstance(value, float):
        return f"{value:.{digits}g}"
    return html.escape(str(value))


_CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;margin:2em auto;max-width:60em;color:#222;
line-height:1.45;padding:0 1em}h1{font-size:1.6em;margin-bottom:.2em}h2{font-size:1.2em;border-bottom:1px solid #ccc;
margin-top:1.8em}table{border-collapse:collapse;margin:.6em 0;font-size:.92em}th,td{border:1px solid #ccc;
padding:.25em .6em;text-align:right}th{background:#f3f3f3}td:first-child,th:first-child{text-align:left}
.note{color:#555;font-size:.9em}img{max-width:100%;height:auto}code{background:#f3f3f3;padding:0 .2em}
.best{font-weight:bold}@media print{h2{page-break-after:avoid}img{page-break-inside:avoid}}
"""


def _table(head: list[str], rows: list[list[str]], classes: list[str] | None = None) -> str:
    out = ["<table><thead><tr>" + "".join(f"<th>{h}</th>" for h in head) + "</tr></thead><tbody>"]
    for i, row in enumerate(rows):
        cls = f' class="{classes[i]}"' if classes and classes[i] else ""
        out.append(f"<tr{cls}>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>")
    out.append("</tbody></table>")
    return "\n".join(out)


def render_report_html(report: dict) -> str:
    """The report as one self-contained HTML page (inline CSS, pictures as data URIs, no script, no network)."""
    m, d, v = report["model"], report["data"], report["validation"]
    acc = report["accuracy"]
    parts = [
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        '<meta http-equiv="Content-Security-Policy" content="default-src \'none\'; img-src data:; '
        'style-src \'unsafe-inline\'">',
        f"<title>Calibration report: {_fmt(report['sensor'])}</title><style>{_CSS}</style></head><body>",
        f"<h1>Calibration report: {_fmt(report['sensor'])}</h1>",
        f"<p class=\"note\">Issued {_fmt(report['date_utc'])} by ftcal {_fmt(report['ftcal_version'])}.</p>",
        "<h2>Identity</h2>",
        _table(["", "value"], [
            ["sensor", _fmt(report["sensor"])],
            ["model", f"{_fmt(m['type'])} (alpha = {_fmt(m['alpha'])} 1/m)"],
            ["model file", _fmt(m["file"])], ["model SHA-256", f"<code>{_fmt(m['sha256'])}</code>"],
            ["data file", _fmt(d["file"])], ["data SHA-256", f"<code>{_fmt(d['sha256'])}</code>"],
        ]),
        "<h2>Frames and units</h2>",
        "<p>Wrenches are <code>[Fx, Fy, Fz, Tx, Ty, Tz]</code> in the <b>sensor frame</b>: forces in N, torques in "
        "N·m about the sensor frame's origin. Raw channels are in the sensor's own unit, in the channel order of the "
        "data file. RMSE of the whole wrench is over <code>[F, alpha·T]</code> in N (thesis eq. 18)."
        + (f" The data file declared {_fmt(', '.join(f'{k[7:]}: {u}' for k, u in d['units'].items()))}; values "
           "were converted to N and N·m." if d["units"] else "") + "</p>",
        "<h2>Data</h2>",
        _table(["", "value"], [
            ["rows", _fmt(d["rows"])], ["raw channels", _fmt(d["channels"])],
            ["groups (poses / load configurations)", _fmt(d["groups"])],
            ["largest |F|", f"{_fmt(d['max_force_norm'])} N"], ["largest |T|", f"{_fmt(d['max_torque_norm'])} N·m"],
            ["temperature", "not recorded" if d["temperature_range"] is None else
             f"{_fmt(d['temperature_range'][0])} to {_fmt(d['temperature_range'][1])} °C"],
        ]),
        f"<h2>Held-out accuracy per axis</h2><p class=\"note\">{v['folds']}-fold cross-validation, "
        f"{_fmt(v['split'])}: every error below is on data the fitted calibration did not see. Full scale (FS): the "
        f"largest absolute load of the data per axis (the calibrated range) unless a rated range was given. "
        f"U95 = k·u, k = {v['coverage_factor']:g}, u the held-out RMS error; <i>coverage</i> is the fraction of held-out "
        "errors within ±U95.</p>",
        _table(["axis", "full scale", "RMS error", "RMS [% FS]", "max error", "max [% FS]", "U95", "U95 [% FS]",
                "coverage of U95", "coverage of ±2 std"],
               [[a["axis"], f"{_fmt(a['full_scale'])} {a['unit']}", f"{_fmt(a['rms'])} {a['unit']}",
                 _fmt(a["rms_pct_fs"]), f"{_fmt(a['max'])} {a['unit']}", _fmt(a["max_pct_fs"]),
                 f"{_fmt(a['u95'])} {a['unit']}", _fmt(a["u95_pct_fs"]), f"{100 * a['coverage_u95']:.1f} %",
                 "model gives no std" if a["coverage_std"] is None else f"{100 * a['coverage_std']:.1f} %"]
                for a in acc]),
        "<h2>Model choice (same folds)</h2><p class=\"note\">This calibration beside the stock scikit-learn models "
        "a user would try first (<code>ftcal.models.stock_baselines</code>). Held-out RMSE of the torque-scaled "
        "wrench [N], ± its standard error over groups.</p>",
    ]
    scored = [c for c in report["model_choice"] if c["status"] == "scored"]
    best = min((c["rmse"] for c in scored), default=None)
    rows, classes = [], []
    for c in report["model_choice"]:
        if c["status"] != "scored":
            rows.append([_fmt(c["model"]), _fmt(c["status"])] + [""] * 7)
            classes.append("")
            continue
        rows.append([_fmt(c["model"]), _fmt(c["rmse"]), _fmt(c["rmse_se"], 2)] + [_fmt(x) for x in c["axis_rmse"]])
        classes.append("best" if c["rmse"] == best else "")
    parts.append(_table(["model", "RMSE [N]", "± SE"] + [f"{a} [{u}]" for a, u in zip(WRENCH_LABELS, _UNITS)],
                        rows, classes))
    r = report["calibrated_range"]
    parts += [
        "<h2>Calibrated range</h2><p class=\"note\">Readings or loads beyond these were not calibrated "
        "(<code>ftcal predict</code> flags them).</p>",
        _table(["axis", "min", "max", "|max|"], [[f"{a} [{u}]", _fmt(lo), _fmt(hi), _fmt(m_)] for a, u, lo, hi, m_ in
                                               zip(WRENCH_LABELS, _UNITS, d["wrench_min"], d["wrench_max"],
                                                   r["wrench_abs_max"])]),
        _table(["raw channel", "min", "max"], [[f"s{i}", _fmt(lo), _fmt(hi)] for i, (lo, hi) in
                                               enumerate(zip(r["raw_min"], r["raw_max"]))]),
    ]
    for key, title in (("residuals_vs_magnitude", "Residuals against load magnitude"),
                       ("residuals_vs_direction", "Residuals against load direction")):
        if key in report["figures"]:
            parts.append(f"<h2>{title}</h2><img alt=\"{title}\" src=\"{report['figures'][key]}\">")
    tc = report["temperature_coefficients"]
    if tc is not None:
        parts += [f"<h2>Temperature coefficients</h2><p class=\"note\">raw = f(w)(1 + g ΔT) + o ΔT, ΔT from "
                  f"{_fmt(tc['reference_temperature'])} °C.</p>",
                  _table(["channel", "gain g [1/°C]", "offset o [unit/°C]"],
                         [[f"s{i}", _fmt(g), _fmt(o)] for i, (g, o) in
                          enumerate(zip(tc["gain_per_deg"], tc["offset_per_deg"]))])]
    tool = report["tool"]
    if tool is not None:
        parts += ["<h2>Tool</h2>", _table(["", "value"], [
            ["mass", f"{_fmt(tool['mass_kg'])} ± {_fmt(tool['mass_std_error_kg'], 2)} kg"],
            ["centre of mass (sensor frame)", f"{', '.join(_fmt(c) for c in tool['center_of_mass_m'])} m"],
            ["bias", ", ".join(_fmt(b) for b in tool["bias"]) + " [N, N·m]"]])]
    parts.append("</body></html>")
    return "\n".join(parts)


def write_calibration_report(report: dict, html_path: str | Path, *, overwrite: bool = False) -> tuple[Path, Path]:
    """Write the page (``.html``) and its facts (``.json`` beside it); return both paths."""
    html_path = Path(html_path)
    if html_path.suffix.lower() != ".html":
        raise CalibrationInputError(f"report path {html_path} must end in .html")
    json_path = html_path.with_suffix(".json")
    with atomic_output(html_path, overwrite=overwrite, error=CalibrationInputError) as tmp:
        tmp.write_text(render_report_html(report), encoding="utf-8")
    with atomic_output(json_path, overwrite=overwrite, error=CalibrationInputError) as tmp:
        tmp.write_text(report_json(report), encoding="utf-8")
    return html_path, json_path


def report_json(report: dict) -> str:
    """The report's facts as JSON text (the pictures left out)."""
    facts = {k: v for k, v in report.items() if k != "figures"}
    return json.dumps(plain_json(facts), indent=2, default=str) + "\n"
