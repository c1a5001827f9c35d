"""The calibration certificate as a typed result: :class:`CalibrationCertificate` (identity, data, accuracy,
comparison, uncertainty budget, warnings, conditions) computed by :func:`calibration_certificate` from small
functions, written as JSON (:meth:`~CalibrationCertificate.to_json`), CSV (the applied-vs-indicated table,
:meth:`~CalibrationCertificate.to_csv`) and one self-contained HTML page (:meth:`~CalibrationCertificate.to_html`,
from the template of :mod:`ftcal.reporting._page`).

Definitions (stated on the page too)
------------------------------------
full scale (FS)
    Per axis, the sensor's rated capacity when given (``rated=``); otherwise the largest absolute reference load
    of the calibration data (the calibrated range), and the page says so.
expanded uncertainty U95
    ``U = k u_c`` of the axis' uncertainty budget (:mod:`ftcal.reporting._budget`: GUM, Welch-Satterthwaite, the
    t-factor at 95.45 %). The *coverage* column reports the fraction of held-out errors within ±U, so a reader
    sees whether the 95 % holds on these data.
specification
    The largest U95 allowed per axis, in % FS (``spec=``): an axis PASSES when its U95 in % FS is at most its
    specification.
"""

from __future__ import annotations

import datetime as _dt
import json
import math
import warnings
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..calibrators._base import calibration_tags
from ..compose._auto import provides_std, training_data_sha256
from ..compose._history import reads_history
from ..core._exceptions import CalibrationInputError
from ..core._files import plain_json
from ..core._wrench import alpha_from_wrenches
from ..io._dataset import CalibrationDataset
from ..model_selection import Comparison, ComparisonRow, FoldPlan, RowStatus, compare, model_cost
from ._budget import COVERAGE_PROBABILITY, AxisBudget, channel_lsb, resolution_uncertainty, uncertainty_budget
from ._calibration_report import (CASES_IN_JSON, COVERAGE_FACTOR, dataset_axis_names, _figures, _held_out, _matrix,
                                  _per_axis, _round, _warnings, add_interval, axis_units, check_conditions,
                                  file_sha256, load_case_labels, model_inputs, _iso_date)

__all__ = ["CalibrationCertificate", "LoadCases", "calibration_certificate", "FORMAT_VERSION"]

#: Version of the certificate's JSON (3: the uncertainty budget, the paired comparison, names of groups/channels).
FORMAT_VERSION = 3


@dataclass
class LoadCases:
    """The applied-vs-indicated table: one case per group and applied load (rows averaged), worst first."""

    applied: NDArray
    indicated: NDArray
    error_pct_fs: NDArray
    worst_pct_fs: NDArray
    rows: NDArray
    first_row: NDArray
    group: list | None

    @property
    def by(self) -> str:
        return "row" if self.rows.max() <= 1 else \
            f"load case (rows{' of one group' if self.group is not None else ''} under one applied load, averaged)"

    @staticmethod
    def columns(axes: list[dict], sep: str = "_", pct_fs: str = "%FS") -> list[str]:
        """The applied, indicated and error column names of ``axes`` (``{"name", "unit"}`` each) in the table."""
        return [f"{a['name']}{sep}{what} [{pct_fs if what == 'error' else a['unit']}]"
                for what in ("applied", "indicated", "error") for a in axes]

    def to_dict(self, axes: list[str], limit: int = CASES_IN_JSON) -> dict:
        """JSON-able (rounded lists), at most ``limit`` cases (the worst)."""
        shown = min(len(self.applied), limit)
        return {"by": self.by, "count": len(self.applied), "in_json": shown, "order": "worst first", "axes": axes,
                "applied": _round(self.applied[:shown]), "indicated": _round(self.indicated[:shown]),
                "error_pct_fs": _round(self.error_pct_fs[:shown], 4), "rows": self.rows[:shown].tolist(),
                "first_row": self.first_row[:shown].tolist(),
                "group": None if self.group is None else list(self.group[:shown])}


@dataclass
class CalibrationCertificate:
    """The facts of a calibration certificate; ``to_dict()`` is JSON-able, ``to_html()`` the page.

    Attributes
    ----------
    identity : dict
        format, version, date of issue, ftcal version, command, sensor, model (type, file, SHA-256, matrix...).
    data : dict
        The data's file, SHA-256, rows, channels and their names, groups and their names, readings dropped or
        flagged, ranges.
    accuracy : list of dict
        Per axis: full scale, held-out RMS and max error, U95 (from the budget) in units and % FS, coverage, spec,
        verdict.
    comparison : dict
        This calibration against the best stock model (paired SE beside the combined SE, symmetric words) and
        every row of the comparison (``rows``) with the fold plan's facts.
    budget : list of AxisBudget
        The uncertainty budget per axis (JSON ``uncertainty_budget``).
    warnings : list of dict
        ``{"kind", "text"}`` a reader must know before trusting the figures.
    conditions : dict
        Conditions and traceability (reference standard, operator, dates...).
    axes, validation, verdict, spec_pct_fs, full_scale_source, calibrated_range, extrapolation,
    temperature_coefficients, tool, recalibration_overdue
        The rest of the page's facts (JSON-able).
    cases : LoadCases
        The applied-vs-indicated table (every case, as arrays; the CSV).
    held_out_predictions : ndarray of shape (n, k)
        The model's out-of-fold predictions (what ``ftcal fit`` checks before it saves a model).
    figures : dict of str
        PNG data URIs of the page's pictures.
    """

    identity: dict
    data: dict
    accuracy: list
    comparison: dict
    budget: list
    warnings: list
    conditions: dict
    axes: list
    validation: dict
    verdict: str | None
    spec_pct_fs: list | None
    full_scale_source: str
    calibrated_range: dict
    extrapolation: list | None = None
    temperature_coefficients: dict | None = None
    tool: dict | None = None
    recalibration_overdue: bool | None = None
    cases: LoadCases | None = field(default=None, repr=False)
    held_out_predictions: NDArray | None = field(default=None, repr=False)
    figures: dict = field(default_factory=dict, repr=False)

    @property
    def sensor(self) -> str:
        return self.identity["sensor"]

    def to_dict(self, *, cases: bool = True) -> dict:
        """Every fact as plain JSON types (no arrays, no pictures): ``json.dumps(cert.to_dict())`` works."""
        out = dict(self.identity)
        out.update(axes=self.axes, data=self.data, validation=self.validation,
                   full_scale_source=self.full_scale_source, spec_pct_fs=self.spec_pct_fs, verdict=self.verdict,
                   accuracy=self.accuracy, uncertainty_budget=[b.to_dict() for b in self.budget],
                   comparison={k: v for k, v in self.comparison.items() if k != "rows"},
                   model_choice=self.comparison.get("rows", []), warnings=self.warnings, conditions=self.conditions,
                   recalibration_overdue=self.recalibration_overdue, calibrated_range=self.calibrated_range,
                   extrapolation=self.extrapolation, temperature_coefficients=self.temperature_coefficients,
                   tool=self.tool)
        out = plain_json(out)
        if cases and self.cases is not None:
            out["cases"] = self.cases.to_dict([a["name"] for a in self.axes])
        return out

    def to_json(self) -> str:
        """The facts as JSON text (the pictures left out; the cases written compactly at the end)."""
        text = json.dumps(self.to_dict(cases=False), indent=1, default=str, allow_nan=False)
        if self.cases is None:
            return text + "\n"
        # plain already (rounded lists) and large: compact, by the C encoder (indentation takes the slow one)
        cases = json.dumps(self.cases.to_dict([a["name"] for a in self.axes]), separators=(",", ":"), allow_nan=False)
        return text[:-1].rstrip() + f',\n "cases": {cases}\n}}\n'

    def to_csv(self) -> str:
        """The applied-vs-indicated table (every case, worst first) as CSV text."""
        import csv
        import io

        out = io.StringIO()
        writer = csv.writer(out, lineterminator="\n")
        writer.writerow(["rank", "group", "first_row", "rows"] + LoadCases.columns(self.axes))
        c = self.cases
        if c is not None:
            block = np.column_stack([c.applied, c.indicated, c.error_pct_fs])
            writer.writerows([i + 1, "" if c.group is None else c.group[i], int(c.first_row[i]), int(c.rows[i])]
                             + [f"{x:.7g}" for x in block[i]] for i in range(len(block)))
        return out.getvalue()

    def to_html(self) -> str:
        """The certificate as one self-contained HTML page (inline CSS, pictures as data URIs, no script)."""
        from ._page import render_page

        return render_page(self)


# ---------------------------------------------------------------------------------------------------------- names
def _sensor_name(sensor: str | None, meta: dict) -> str:
    """The sensor's name: given, else the data file's (``sensor``, ``sensor_name``, ``serial``...)."""
    if sensor:
        return str(sensor)
    for key in ("sensor", "sensor_name", "sensor_id", "serial", "serial_number", "device"):
        value = meta.get(key)
        if isinstance(value, (str, int)) and str(value).strip():
            return str(value).strip()
        if isinstance(value, dict) and (value.get("name") or value.get("serial")):
            return str(value.get("name") or value.get("serial"))
    return "not named (give the sensor's name or serial number)"


def group_names(dataset: CalibrationDataset) -> list[str] | None:
    """The name of each group label ``0..G-1``: ``meta["group_names"]`` (or the loader's ``group_labels``), else
    the data files of a folder when the groups are its files; None when the groups are plain numbers."""
    meta = dataset.meta
    for key in ("group_names", "group_labels"):
        if isinstance(meta.get(key), (list, tuple)) and meta[key]:
            return [str(v) for v in meta[key]]
    files = meta.get("source_files")
    if dataset.group is not None and isinstance(files, (list, tuple)) and len(files) == np.unique(dataset.group).size:
        return [str(v) for v in files]
    return None


def _named_groups(groups: NDArray | None, names: list[str] | None) -> list | None:
    """Each group label as its name (or the label itself when the names do not cover it)."""
    if groups is None:
        return None
    if names is None:
        return [str(g) for g in groups]
    return [names[int(g)] if float(g).is_integer() and 0 <= int(g) < len(names) else str(g) for g in groups]


def channel_names(dataset: CalibrationDataset, n: int) -> list[str]:
    """The data's channel names (``meta["channel_names"]``), else ``s0..``; a temperature input last."""
    names = dataset.meta.get("channel_names") or dataset.meta.get("channels")
    if not isinstance(names, (list, tuple)) or len(names) != dataset.n_channels:
        names = [f"s{i}" for i in range(dataset.n_channels)]
    return [str(c) for c in names] + ["temperature"] * (n - dataset.n_channels)


# ------------------------------------------------------------------------------------------------ the comparison
class _KnownPredictions:
    """A stand-in regressor whose out-of-fold predictions are already known (the certificate's own held-out
    predictions, scored by :func:`~ftcal.model_selection.compare` on the same plan beside the stock models)."""

    def __init__(self, pred: NDArray) -> None:
        self.pred = pred

    def fit(self, X, y):
        return self

    def predict(self, X):
        raise NotImplementedError("out-of-fold predictions only")

    def folds(self, estimator, X, y, folds, groups) -> list:
        return [(test, self.pred[test]) for _, test in folds]


def _auto_comparison(model: Any, plan: FoldPlan, X: NDArray, y: NDArray, groups) -> Comparison | None:
    """An auto model's own comparison when it was scored on this very plan (same folds, same rows' hash): the
    certificate then takes its choice's out-of-fold predictions, and its stock rows when they still hold their
    rows' errors (fitted in this process; a model file keeps the figures, not the errors)."""
    comp, own = getattr(model, "comparison_", None), getattr(model, "fold_plan_", None)
    if not calibration_tags(model).chooses_model or not isinstance(comp, Comparison) \
            or not isinstance(own, FoldPlan) or not plan.same_folds(own):
        return None
    return comp if comp.training_sha256 == training_data_sha256(X, y, groups) else None


def _reusable_stock(reused: Comparison | None, chosen: str | None) -> list[ComparisonRow] | None:
    """The stock rows of an auto model's comparison, when every scored one can still be paired."""
    if reused is None:
        return None
    rows = [r for r in reused.rows if r.kind in ("stock", "baseline") and r.name != chosen]
    ok = rows and all(r.row_errors is not None for r in rows if r.status is RowStatus.SCORED)
    return rows if ok else None


def _comparison_rows(label: str, pred: NDArray, X: NDArray, y: NDArray, plan: FoldPlan, *, alpha: float,
                     axes: tuple, stock: list[ComparisonRow] | None, baselines: bool, seed: int,
                     n_jobs: int | None) -> Comparison:
    """This calibration (its held-out predictions) and the stock models on ``plan``, as one comparison: ``stock``
    rows already scored on the plan (an auto model's), else :func:`~ftcal.calibrators.stock_baselines` scored
    by :func:`~ftcal.model_selection.compare`."""
    known = _KnownPredictions(pred)
    this = compare([(label, known)], X, y, plan, alpha=alpha, race=False, kinds={label: "calibration"},
                   out_of_fold=known.folds, min_rows=lambda est, n: 0, refuse_degenerate=False, axes=axes)
    if stock is None and baselines:
        from ..calibrators._baselines import stock_baselines

        models = list(stock_baselines(X.shape[1], random_state=seed).items())
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            # a stock model is scored whenever its training folds hold more rows than an affine map's parameters
            stock = compare(models, X, y, plan, alpha=alpha, n_jobs=n_jobs, axes=axes,
                            kinds={name: "stock" for name, _ in models}, min_rows=lambda est, n: n + 2).rows
    return Comparison(rows=this.rows + list(stock or []), plan=plan, alpha=alpha)


def comparison_facts(comp: Comparison) -> dict:
    """The JSON-able comparison: this calibration against the best stock model (paired SE beside the combined SE,
    the verdict in symmetric words) and every row."""
    this = comp.rows[0]
    rows = []
    for r in comp.rows:
        row = {"model": r.name, "kind": "calibration" if r is this else "baseline", "status": r.status.value,
               "reason": r.reason, "rmse": r.rmse, "rmse_se": r.rmse_se, "paired_se": None, "against": None,
               "axis_rmse": None if r.axis_rmse is None else np.asarray(r.axis_rmse).tolist()}
        if r is not this and r.row_errors is not None and r.rmse is not None and this.row_errors is not None:
            d = comp.paired(r.name, this.name)
            row["paired_se"] = d.paired_se
            row["against"] = {"better": f"{d.percent:.1f} % better", "worse": f"{d.percent:.1f} % worse",
                              "equivalent": "equivalent within noise"}[d.verdict] + f" (paired SE {d.paired_se:.2g} N)"
        rows.append(row)
    facts = {"plan": comp.plan.to_dict(), "rows": rows, "best_stock": None}
    stock = [r for r in comp.scored()[1:] if r.rmse is not None and r.row_errors is not None]
    if not stock:
        return {**facts, "sentence": "No stock model was compared (the stock models were left out or could not be "
                                     "scored on these folds)."}
    best = min(stock, key=lambda r: r.rmse)
    d = comp.paired(this.name, best.name)
    outcome = {"better": "better", "worse": "stock better", "equivalent": "equivalent"}[d.verdict]
    sentence = (d.words().replace(this.name, "This calibration", 1) + f", on the same {comp.plan.n_splits} folds "
                f"(standard errors over the {comp.plan.units_name}s).")
    return {**facts, "best_stock": best.name, "best_stock_rmse": best.rmse, "rmse": this.rmse,
            "ratio": this.rmse / best.rmse if best.rmse > 0 else math.inf, "difference": d.difference,
            "paired_se": d.paired_se, "combined_se": d.combined_se, "verdict": d.verdict, "outcome": outcome,
            "sentence": sentence}


# ------------------------------------------------------------------------------------------------- the budget
def _reference_uncertainty(k: int, y: NDArray, absolute: ArrayLike | None, relative: float | None
                           ) -> tuple[NDArray | None, str]:
    """The reference's standard uncertainty per axis (its expanded k = 2 figure halved) and where it comes from."""
    if absolute is not None:  # 0 is an ideal reference (its uncertainty negligible), not a missing one
        given = np.asarray(absolute, dtype=float)
        U = _per_axis(np.where(given == 0, 1.0, given), k, "reference_uncertainty")  # the rest checked positive
        return (np.where(np.broadcast_to(given, U.shape) == 0, 0.0, U) / 2,
                "reference standard's expanded uncertainty (k = 2) as given per axis, halved (Type B)")
    if relative is not None:
        if not (np.isfinite(relative) and 0 <= relative < 1):  # 0: an ideal reference
            raise CalibrationInputError(f"reference_relative must be a fraction in [0, 1) (0.0005 for 0.05 %); got "
                                        f"{relative!r}.")
        top = np.max(np.abs(y), axis=0)
        return relative * top / 2, (f"reference standard's expanded uncertainty {100 * relative:.4g} % (k = 2) of "
                                    "the largest applied load of the axis, halved (Type B)")
    return None, ""


def _budget(model: Any, X: NDArray, y: NDArray, pred: NDArray, names: list[str], cases: NDArray, plan: FoldPlan,
            *, reference: tuple, temperature: tuple) -> list[AxisBudget]:
    """The uncertainty budget per axis from the held-out errors, the readings' LSB, the reference, temperature."""
    lsb = channel_lsb(X)
    try:
        res = resolution_uncertainty(model, X, lsb) if lsb.any() else None
    except Exception:  # a model whose predict cannot take single perturbed rows: no resolution line
        res = None
    grouped = plan.kind == "group"
    n_units = int(np.unique(plan.units).size) if grouped else int(np.unique(cases).size)
    coef, deviation = temperature
    temp = None if coef is None or deviation is None else np.abs(coef) * float(deviation) / math.sqrt(3)
    return uncertainty_budget(
        pred - y, axes=names, cases=cases, n_units=n_units, units_name="groups" if grouped else "load cases",
        resolution=None if res is None else np.broadcast_to(res, (y.shape[1],)),
        resolution_note="" if res is None else "channel LSB " + ", ".join(f"{v:.3g}" for v in lsb)
        + " (the quantisation step of each channel's values; 0: continuous), LSB/√12", reference=reference[0],
        reference_note=reference[1], temperature=temp,
        temperature_note=f"coefficient × ±{deviation} °C, rectangular (Type B)")


def _accuracy(y: NDArray, pred: NDArray, std: NDArray | None, names: list[str], units: list[str], fs: NDArray,
              data_max: NDArray, rated: NDArray | None, spec: NDArray | None, budget: list[AxisBudget]) -> list[dict]:
    """Per axis: held-out RMS and max error, U95 of the budget, coverage, spec and verdict."""
    err = pred - y
    out = []
    for j, b in enumerate(budget):
        rms, top, U = float(np.sqrt(np.mean(err[:, j] ** 2))), float(np.max(np.abs(err[:, j]))), b.expanded_uncertainty
        out.append({
            "axis": names[j], "unit": units[j], "full_scale": fs[j], "rated": None if rated is None else rated[j],
            "data_max": data_max[j], "rms": rms, "max": top, "rms_pct_fs": 100 * rms / fs[j],
            "max_pct_fs": 100 * top / fs[j], "coverage_factor": b.coverage_factor, "u95": U,
            "u95_pct_fs": 100 * U / fs[j], "coverage_u95": float(np.mean(np.abs(err[:, j]) <= U)),
            "coverage_std": None if std is None else float(np.mean(np.abs(err[:, j]) <= COVERAGE_FACTOR * std[:, j])),
            "spec_pct_fs": None if spec is None else spec[j],
            "verdict": None if spec is None else "PASS" if np.isfinite(100 * U / fs[j]) and 100 * U / fs[j] <= spec[j]
            else "FAIL"})
    return out


# --------------------------------------------------------------------------------------------- other sections
def _extrapolation(model: Any, X: NDArray, channels: list[str]) -> list[dict] | None:
    """Per channel, the rows beyond the model's calibrated range and the largest distance from its centre in
    half-ranges (x the range; 1 = its edge); None when the data lie within it or the model keeps no range."""
    limits = getattr(model, "calibrated_range_", None)
    if limits is None or np.shape(limits) != (2, X.shape[1]):
        return None
    lo, hi = np.asarray(limits, dtype=float)
    beyond = (X < lo) | (X > hi)
    if not beyond.any():
        return None
    half = np.where(hi > lo, (hi - lo) / 2, 1.0)
    factor = np.max(np.abs(X - (lo + hi) / 2) / half, axis=0)
    return [{"channel": channels[c], "rows_beyond": int(beyond[:, c].sum()), "rows": len(X),
             "largest_x_range": float(factor[c])} for c in range(X.shape[1]) if beyond[:, c].any()]


def _data_facts(dataset: CalibrationDataset, y: NDArray, torque: NDArray, dataset_path, dataset_sha256,
                groups: list[str] | None, channels: list[str]) -> dict:
    meta = dataset.meta
    return {"file": None if dataset_path is None else str(dataset_path),
            "sha256": dataset_sha256 or (None if dataset_path is None else file_sha256(dataset_path)),
            "rows": dataset.n_samples, "channels": dataset.n_channels, "channel_names": channels[:dataset.n_channels],
            "groups": None if dataset.group is None else int(np.unique(dataset.group).size), "group_names": groups,
            "wrench_min": y.min(axis=0).tolist(), "wrench_max": y.max(axis=0).tolist(),
            "max_force_norm": float(np.linalg.norm(y[:, ~torque], axis=1).max()) if (~torque).any() else None,
            "max_torque_norm": float(np.linalg.norm(y[:, torque], axis=1).max()) if torque.any() else None,
            "temperature_range": None if dataset.temperature is None else [float(dataset.temperature.min()),
                                                                           float(dataset.temperature.max())],
            "units": {u: meta[u] for u in ("source_force_unit", "source_torque_unit") if u in meta},
            "readings_dropped": list(meta.get("readings_dropped") or []),
            "readings_flagged": list(meta.get("readings_flagged") or [])}


def _due_date(conditions: dict, today: _dt.date) -> tuple[bool | None, dict | None]:
    """Fill ``recalibration_due`` from the interval (counted from the calibration date, else the issue date);
    ``(overdue, warning or None)``."""
    interval = conditions["recalibration_interval"]
    if conditions["recalibration_due"] is not None or interval is None:
        return None, None
    measured = None if conditions["calibration_date"] is None else _iso_date(conditions["calibration_date"])
    due = add_interval(measured or today, interval)
    overdue = due < today
    conditions["recalibration_due"] = f"{due.isoformat()} (" + (
        f"calibration date {measured.isoformat()}" if measured else "issue date") + f" + {interval})" + (
        ": OVERDUE on the date of issue" if overdue else "")
    warning = {"kind": "recalibration overdue", "text": (
        f"The recalibration was due {due.isoformat()} ({interval} after the calibration of "
        f"{conditions['calibration_date']}), before this report's date of issue: these figures describe the sensor "
        "as it was then, not now.")} if overdue else None
    return overdue, warning


def _model_facts(model: Any, model_path, model_sha256, alpha: float | None, names, units, channels: list[str]) -> dict:
    return {"type": type(model).__name__, "file": None if model_path is None else Path(model_path).name,
            "path": None if model_path is None else str(model_path),
            "sha256": model_sha256 or (None if model_path is None else file_sha256(model_path)),
            "params": {p: v for p, v in model.get_params(deep=False).items() if not hasattr(v, "fit")},
            "alpha": alpha, "chosen": getattr(model, "best_name_", None),
            "matrix": _matrix(model, names, units, channels)}


def _temperature_coefficients(model: Any) -> dict | None:
    if not calibration_tags(model).temperature_column:
        return None
    return {"reference_temperature": float(model.reference_temperature),
            "gain_per_deg": np.asarray(model.gain_per_deg_).tolist(),
            "offset_per_deg": np.asarray(model.offset_per_deg_).tolist()}


# -------------------------------------------------------------------------------------------- the entry point
def _held_out_of(model: Any, reused: Comparison | None, X, y, groups, plan: FoldPlan, seed: int, n_jobs
                 ) -> tuple[NDArray, NDArray | None]:
    """``(the out-of-fold predictions, their std or None)``: an auto model's own
    predictions of its choice when its comparison is reused (refitted only for a std), else a refit per fold."""
    from sklearn.base import clone

    template = clone(model) if reused is None else clone(model.best_estimator_)
    known = getattr(model, "held_out_predictions_", None)
    if reused is not None and not provides_std(template) and known is not None and np.shape(known) == y.shape:
        return np.asarray(known, dtype=float), None
    # light work (a closed form, a kernel model on few rows) in this process, as the comparison engine scores it:
    # starting worker processes (each importing ftcal) costs more than the fits
    light = model_cost(template, min((len(train) for train, _ in plan.folds), default=0)) == "closed_form"
    return _held_out(template, X, y, groups, list(plan.folds), seed=seed, n_jobs=None if light else n_jobs)


def _alpha(model: Any, y: NDArray, torque: NDArray, alpha: float | None) -> float | None:
    """The torque scale [1/m] of a calibration of forces and torques; None for one of forces (or torques) only."""
    if not (torque.any() and (~torque).any()):
        return None
    return float(alpha or getattr(model, "alpha_", None) or alpha_from_wrenches(y))


def _held_out_and_comparison(model: Any, plan: FoldPlan, X: NDArray, y: NDArray, groups, names: list[str],
                             alpha: float | None, baselines: bool, seed: int, n_jobs: int | None) -> tuple:
    """``(the reused auto comparison or None, the reused stock rows or None, the out-of-fold predictions, their
    std or None, the comparison's facts)`` of the model on ``plan`` (:func:`_held_out_of`, :func:`comparison_facts`)."""
    name = type(model).__name__
    reused = _auto_comparison(model, plan, X, y, groups)
    chosen = model.best_name_ if reused is not None else getattr(model, "baseline", None)  # a stock model's baseline
    label = f"{name}: {chosen} (this calibration)" if isinstance(chosen, str) else f"{name} (this calibration)"
    pred, std = _held_out_of(model, reused, X, y, groups, plan, seed, n_jobs)
    stock = _reusable_stock(reused, getattr(model, "best_name_", None)) if baselines else None
    comp = comparison_facts(_comparison_rows(label, pred, X, y, plan, alpha=alpha or 1.0, axes=tuple(names),
                                             stock=stock, baselines=baselines, seed=seed, n_jobs=n_jobs))
    return reused, stock, pred, std, comp


def calibration_certificate(
    model: Any, dataset: CalibrationDataset, *, model_path: str | Path | None = None,
    model_sha256: str | None = None, dataset_path: str | Path | None = None, dataset_sha256: str | None = None,
    sensor: str | None = None, cv: int = 5, baselines: bool = True, full_scale: ArrayLike | None = None,
    rated: ArrayLike | None = None, spec: ArrayLike | float | None = None, conditions: dict | None = None,
    tool: Any = None, alpha: float | None = None, random_state: int = 0, figures: bool = True,
    n_jobs: int | None = None, command: str | None = None, reference_uncertainty: ArrayLike | None = None,
    reference_relative: float | None = None, temperature_coefficient: ArrayLike | None = None,
    temperature_deviation: float | None = None,
) -> CalibrationCertificate:
    """The calibration certificate of a fitted model on its data: held-out accuracy, uncertainty budget, verdict.

    Parameters
    ----------
    model : fitted calibrator
        The calibration (e.g. from :func:`ftcal.load_model`); cloned and refitted on each fold of the one fold
        plan (:meth:`ftcal.model_selection.FoldPlan.for_data`) for the held-out figures. An auto model scored on
        the same plan (same folds, same rows) lends its comparison and its choice's out-of-fold predictions.
    dataset : CalibrationDataset
        The calibration data (the training data of ``model``); ``k`` output axes (named by the dataset).
    model_path, dataset_path : path, optional
        File names shown on the page.
    model_sha256, dataset_sha256 : str, optional
        SHA-256 of the bytes written / read; default the hash of the file at the path now.
    sensor : str, optional
        Sensor name / serial number; default the data file's (``meta['sensor']``...).
    cv : int
        Folds asked of the fold plan.
    baselines : bool
        Also score :func:`ftcal.calibrators.stock_baselines` on the same folds (:func:`ftcal.model_selection.compare`).
    rated : array-like of shape (k,), optional
        Rated capacity per axis [N, N·m]: the full scale of every % FS figure (default the largest absolute load
        per axis). ``full_scale`` is its older name.
    spec : float or array-like of shape (k,), optional
        Largest U95 allowed per axis [% FS]; each axis PASSES or FAILS against it.
    conditions : dict, optional
        Conditions and traceability (:data:`CONDITION_FIELDS`).
    tool : ToolLoad, optional
        A tool's identified parameters, to print.
    alpha : float, optional
        Torque scale [1/m] of the whole-wrench RMSE of a calibration of forces and torques.
    random_state : int
        Seed of the folds.
    figures : bool
        Include the plots (PNG data URIs).
    n_jobs : int, optional
        Processes that fit folds at once; the figures do not depend on it.
    command : str, optional
        The command that made the certificate, printed on the page.
    reference_uncertainty : array-like of shape (k,), optional
        Expanded uncertainty (k = 2) of the reference load per axis [N, N·m].
    reference_relative : float, optional
        Or relative: of the largest applied load per axis (0.0005 for 0.05 %).
    temperature_coefficient : array-like of shape (k,), optional
        Temperature coefficient of the indication per axis [axis unit / °C]; with ``temperature_deviation`` (the
        largest deviation from the calibration's temperature in use, °C) adds a temperature component.

    Returns
    -------
    CalibrationCertificate

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import CalibrationDataset, LinearCalibrator
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(80, 6)) * [50, 50, 50, 1, 1, 1]; raw = w @ rng.normal(size=(6, 6)) / 50
    >>> data = CalibrationDataset(raw=raw + 1e-4 * rng.normal(size=raw.shape), wrench=w)
    >>> cert = calibration_certificate(LinearCalibrator().fit(data.raw, w), data, baselines=False, figures=False,
    ...                                rated=[500, 500, 900, 20, 20, 20], spec=1.0, reference_relative=0.0005)
    >>> cert.verdict, [a["verdict"] for a in cert.accuracy][:2], cert.budget[0].components[-1].name
    ('PASS', ['PASS', 'PASS'], 'reference standard')
    """
    X = model_inputs(model, dataset)
    y = np.asarray(dataset.wrench, dtype=float)
    k = y.shape[1]
    names = dataset_axis_names(dataset, k)
    if getattr(model, "n_outputs_", None) is not None and int(model.n_outputs_) != k:
        raise CalibrationInputError(
            f"the model gives {int(model.n_outputs_)} output axis(es) but the dataset has {k} ({', '.join(names)}); a "
            "report certifies the model's own axes on data of those axes. Fix: select the model's axes from the data "
            "(the wrench mapping naming their columns only, e.g. Fz), or report a model of all these axes.")
    units = axis_units(names)
    torque = np.array([u != "N" for u in units])
    groups = dataset.group if dataset.group is not None and np.unique(dataset.group).size >= 2 else None
    plan = FoldPlan.for_data(X, y, groups, cv=cv, seed=random_state, ordered=reads_history(model))
    if plan.kind == "none":
        raise CalibrationInputError(f"no held-out figure can be made on these data: {plan.note}.")
    rated_fs = _per_axis(full_scale if rated is None else rated, k, "rated")
    spec_pct = _per_axis(spec, k, "spec")
    conditions = check_conditions(conditions)
    reference = _reference_uncertainty(k, y, reference_uncertainty, reference_relative)
    coef = None if temperature_coefficient is None else np.broadcast_to(
        np.asarray(temperature_coefficient, dtype=float), (k,))
    data_max = np.max(np.abs(y), axis=0)
    fs = rated_fs if rated_fs is not None else np.where(data_max > 0, data_max, np.nan)
    alpha = _alpha(model, y, torque, alpha)
    reused, stock, pred, std, comp = _held_out_and_comparison(model, plan, X, y, groups, names, alpha, baselines,
                                                              random_state, n_jobs)
    gnames = group_names(dataset)
    channels = channel_names(dataset, X.shape[1])
    case_of, table = load_case_labels(y, pred, groups, fs)
    cases = LoadCases(**table, group=_named_groups(None if groups is None else np.asarray(groups)[table["first_row"]],
                                                   gnames))
    budget = _budget(model, X, y, pred, names, case_of, plan,
                     reference=reference, temperature=(coef, temperature_deviation))
    accuracy = _accuracy(y, pred, std, names, units, fs, data_max, rated_fs, spec_pct, budget)
    verdict = None if spec_pct is None else ("PASS" if all(a["verdict"] == "PASS" for a in accuracy) else "FAIL")
    date = _dt.datetime.now(_dt.timezone.utc)
    overdue, overdue_warning = _due_date(conditions, date.date())
    warn = [w for w in [overdue_warning] if w] + _warnings(accuracy, comp, X, list(plan.folds), groups, rated_fs)
    if reference[0] is None:
        warn.append({"kind": "no reference uncertainty", "text": (
            "The reference standard's uncertainty was not given: the budget leaves it out. State it (reference "
            "uncertainty, e.g. 0.05 % of the load at k = 2) for a complete budget.")})
    import ftcal

    identity = {"format": "ftcal-calibration-report", "format_version": FORMAT_VERSION,
                "date_utc": date.strftime("%Y-%m-%d %H:%M:%S UTC"),
                "ftcal_version": getattr(ftcal, "__version__", "unknown"), "command": command,
                "sensor": _sensor_name(sensor, dataset.meta),
                "model": _model_facts(model, model_path, model_sha256, alpha, names, units, channels)}
    cert = CalibrationCertificate(
        identity=identity, data=_data_facts(dataset, y, torque, dataset_path, dataset_sha256, gnames, channels),
        accuracy=accuracy, comparison=comp, budget=budget, warnings=warn, conditions=conditions,
        axes=[{"name": a, "unit": u} for a, u in zip(names, units)],
        validation={"folds": plan.n_splits, "plan": plan.to_dict(), "split": plan.note,
                    "coverage_probability": COVERAGE_PROBABILITY, "reused_auto_comparison": stock is not None,
                    "reused_auto_predictions": reused is not None},
        verdict=verdict, spec_pct_fs=None if spec_pct is None else spec_pct.tolist(),
        full_scale_source="rated capacity" if rated_fs is not None else
        "the largest absolute load of the calibration data per axis (no rated capacity given)",
        calibrated_range={"raw_min": dataset.raw.min(axis=0).tolist(), "raw_max": dataset.raw.max(axis=0).tolist(),
                          "wrench_abs_max": data_max.tolist()},
        extrapolation=_extrapolation(model, X, channels), temperature_coefficients=_temperature_coefficients(model),
        tool=None if tool is None else tool.to_dict(), recalibration_overdue=overdue, cases=cases,
        held_out_predictions=pred)
    if figures:
        band = spec_pct if spec_pct is not None else np.array([a["u95_pct_fs"] for a in accuracy])
        cert.figures = _figures(y, pred, names, units, fs, band, "spec" if spec_pct is not None else "U95")
    return cert
