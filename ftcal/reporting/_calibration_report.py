"""The calibration report a sensor ships with: one self-contained HTML page per calibration, a certificate.

Like a sensor maker's calibration certificate and accuracy report, it opens with a one-page summary
(sensor, model, date, per-axis 95 % expanded uncertainty in % of full scale with PASS/FAIL against a
specification, the comparison with the best stock model in one sentence, and warnings), then states the
calibration itself (the matrix of a linear model with its units, or the model file's name, SHA-256 and the
command that loads it), the applied-vs-indicated table of **held-out** predictions (grouped
cross-validation: whole poses or load configurations held out), worst case first, error-vs-load panels
with the specification band, the model choice beside the stock scikit-learn baselines on the same folds,
the calibrated range, the conditions and traceability of the calibration (reference standard, procedure,
operator, temperature, recalibration due date) and who, what and when.

The page needs no network: styles are inline and every picture is a PNG data URI. It prints to a
multi-page PDF (one section per page group, page numbers, tables not cut across pages).
:func:`calibration_certificate` computes the facts (a JSON-able dict), :func:`render_report_html`
turns them into the page, :func:`report_cases_csv` gives the applied-vs-indicated table as CSV,
:func:`write_calibration_report` writes ``.html``, ``.json`` and ``.csv`` beside each other.

Definitions (stated on the page too)
------------------------------------
full scale (FS)
    Per axis, the sensor's rated capacity when given (``rated=``); otherwise the largest absolute
    reference load of the calibration data (the calibrated range), and the page says so.
expanded uncertainty U95
    ``k * u`` with coverage factor ``k = 2`` and ``u`` the held-out RMS error of the axis (GUM, normal
    errors: about 95 %). The *coverage* column reports the fraction of held-out errors within ±U95,
    so a reader sees whether the 95 % holds on these data.
specification
    The largest U95 allowed per axis, in % FS (``spec=``): an axis PASSES when its U95 in % FS is at most
    its specification.
"""

from __future__ import annotations

import base64
import csv
import datetime as _dt
import hashlib
import html
import io
import json
import math
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import CalibrationInputError
from ..core._files import atomic_output, plain_json
from ..calibrators._base import calibration_tags
from ..calibrators import STOCK_BASELINE_NAMES
from ..compose._history import reads_history
from ..model_selection._selection import calibration_folds, held_out_predictions, rmse_and_se
from ..core._wrench import WRENCH_LABELS, alpha_from_wrenches
from ..io._dataset import CalibrationDataset
from ..compose._auto import LIGHT_KERNEL_ROWS, is_light, provides_std, training_data_sha256

__all__ = ["model_inputs", "calibration_certificate", "render_report_html", "write_calibration_report", "report_json",
           "report_cases_csv", "file_sha256", "bytes_sha256", "axis_units", "CONDITION_FIELDS", "COVERAGE_FACTOR",
           "BASELINE_WORK_BUDGET", "BASELINE_TRAINING_ROWS", "CASES_IN_JSON"]

#: k of the expanded uncertainty U = k u (about 95 % for normal errors).
COVERAGE_FACTOR = 2.0
#: The report's stock baselines may cost at most this many floating-point operations each (all folds): a count
#: of work, not a time, so that whether a baseline is skipped never depends on the machine's speed.
BASELINE_WORK_BUDGET = 3e11
#: Training rows a non-kernel stock baseline is fitted on at most per fold (a random subset beyond; the kernel
#: ones have their own, smaller subset): the report of a million rows stays a matter of seconds per baseline.
BASELINE_TRAINING_ROWS = 200_000
#: Test rows predicted at once in the report's cross-validation (a kernel model's cross-kernel stays small).
PREDICT_CHUNK_ROWS = 20_000
#: Load cases the JSON holds at most (the worst first; the CSV beside it holds them all).
CASES_IN_JSON = 200_000
#: The conditions and traceability fields of a calibration, in the order the page prints them.
CONDITION_FIELDS: dict[str, str] = {
    "reference_standard": "reference standard (dead weights, reference sensor, robot with a known load, ...)",
    "procedure": "procedure",
    "operator": "operator",
    "calibration_date": "date of the calibration measurements",
    "ambient_temperature": "ambient temperature",
    "recalibration_interval": "recalibration interval",
    "recalibration_due": "recalibration due",
    "location": "location",
    "notes": "notes",
}


def file_sha256(path: str | Path) -> str:
    """SHA-256 of a file's bytes (hex), the identity of a model or data file; of a folder (a dataset of one file
    per pose), the SHA-256 of the names and hashes of the data files the dataset loader reads from it
    (:func:`~ftcal.io._dataset.dataset_files`), in name order: a report or a note written beside them changes
    nothing."""
    from ..io._dataset import dataset_files

    path = Path(path)
    if path.is_dir():
        listing = "".join(f"{p.name}\t{file_sha256(p)}\n" for p in dataset_files(path))
        return hashlib.sha256(listing.encode("utf-8")).hexdigest()
    digest = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def bytes_sha256(data: bytes) -> str:
    """SHA-256 (hex) of bytes already in memory: the identity of exactly what was written or read."""
    return hashlib.sha256(data).hexdigest()


def axis_units(names) -> list[str]:
    """The unit of each output axis from its name: a torque (``T*``/``M*``) in N·m, anything else in N.

    Examples
    --------
    >>> axis_units(["Fx", "Fy", "Fz", "Tx"])
    ['N', 'N', 'N', 'N·m']
    """
    return ["N·m" if str(n)[:1].upper() in ("T", "M") else "N" for n in names]


def _axis_names(dataset: CalibrationDataset, k: int) -> list[str]:
    """The dataset's output axis names (``axis_names``, or its meta's), else ``Fx..Tz`` for 6 columns."""
    names = getattr(dataset, "axes", None) or dataset.meta.get("axis_names") or dataset.meta.get("axes")
    if names is not None and len(names) == k:
        return [str(n) for n in names]
    return list(WRENCH_LABELS) if k == 6 else [f"y{i}" for i in range(k)]


def model_inputs(model: Any, data: CalibrationDataset) -> NDArray[np.float64]:
    """The ``X`` a fitted model takes from a dataset: the raw channels, plus the temperature column for a
    temperature-compensated model (its tags say so); a dataset of another sensor (other channel count) is refused.

    The one definition: the report, ``ftcal evaluate`` and ``ftcal report`` all take a model's inputs here.

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import CalibrationDataset, LinearCalibrator
    >>> rng = np.random.default_rng(0)
    >>> raw = rng.normal(size=(30, 6))
    >>> data = CalibrationDataset(raw=raw, wrench=raw @ rng.normal(size=(6, 6)))
    >>> model_inputs(LinearCalibrator().fit(data.raw, data.wrench), data).shape
    (30, 6)
    """
    n = int(getattr(model, "n_features_in_", data.n_channels))
    temperature = calibration_tags(model).temperature_column
    if n == data.n_channels and not temperature:
        return data.raw
    if temperature and n == data.n_channels + 1 and data.temperature is not None:
        return data.features(temperature=True)
    wants = f"{n - 1} raw channels and a temperature column" if temperature else f"{n} raw channels"
    has = f"{data.n_channels} raw channels" + (" and no temperature column" if temperature and data.temperature is None
                                               else "")
    raise CalibrationInputError(f"the model takes {wants} but the dataset has {has}; use the data the model was "
                                "calibrated on (same sensor, same channel order).")


def _held_out(template: Any, X: NDArray, y: NDArray, groups: NDArray | None, folds: list, *, want_std: bool = True,
              max_rows: int | None = None, seed: int = 0, n_jobs: int | None = None) -> dict:
    """Out-of-fold predictions (and std where the model gives one in every fold) on ``folds``, from ftcal's one
    held-out engine (:func:`~ftcal.model_selection._selection.held_out_predictions`): ``groups`` reach the model through
    its metadata routing; each training fold capped at ``max_rows`` rows; the test folds predicted in blocks (one
    stream for a model that reads the load history); the fits' BLAS on one thread where no other thread sees it."""
    from ..core._threads import limit_threads_here

    history = reads_history(template)
    with limit_threads_here(1), warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        _, pred, std = held_out_predictions(
            template, X, y, groups=groups, folds=folds, max_train_rows=max_rows, random_state=seed,
            chunk_rows=None if history else PREDICT_CHUNK_ROWS, n_jobs=n_jobs,
            has_std=provides_std if want_std else (lambda model: False))
    return {"pred": pred.reshape(y.shape), "std": None if not want_std or std is None else std.reshape(y.shape)}


def baseline_cost(name: str, estimator: Any, n_train: int, n_features: int, n_outputs: int,
                  n_folds: int) -> tuple[float, float, int]:
    """``(bytes of its largest allocation, floating-point operations over all folds, rows fitted per fold)`` of a
    stock baseline (:func:`ftcal.calibrators.stock_baselines`) on training folds of ``n_train`` rows.

    Estimates, from the shapes alone, of what the fit would allocate and compute (polynomial features and the
    ridge's decomposition; the kernel models' kernel matrices, grid search and likelihood gradients).

    Examples
    --------
    >>> from ftcal.calibrators import stock_baselines
    >>> b = stock_baselines(500)
    >>> bytes_, flops, rows = baseline_cost("sk_poly3", b["sk_poly3"], 960, 500, 6, 5)
    >>> bytes_ > 100 * 2**30
    True
    """
    from ..calibrators._baselines import SubsampledRegressor

    if isinstance(estimator, SubsampledRegressor):
        m = n_train if estimator.max_samples is None else min(n_train, int(estimator.max_samples))
        if "gp" in name:  # K and its p + 2 hyperparameter gradients; L-BFGS steps (more with more hyperparameters)
            steps = 50 + 2 * (n_features + 2)  # of a Cholesky and the gradients
            return 8.0 * m * m * (n_features + 3), n_folds * steps * (m**3 / 3 + 2.0 * m * m * (n_features + 2)), m
        fit_rows = m * 2 // 3  # kernel ridge: 3-fold grid search of 7 x 7 settings, plus the refit
        per_fit = fit_rows**3 / 3 + 2.0 * fit_rows**2 * n_features + fit_rows**2 * n_outputs
        return 8.0 * m * m * 3, n_folds * (147 + 1) * per_fit, m
    m = min(n_train, BASELINE_TRAINING_ROWS)
    degree = int(re.search(r"poly(\d+)", name).group(1)) if re.search(r"poly(\d+)", name) else 1
    width = math.comb(n_features + degree, degree)
    small = min(m, width)
    # the ridge decomposes the smaller of X^T X (width^2) and X X^T (rows^2)
    return 8.0 * m * width * 3 + 8.0 * small * small, n_folds * (2.0 * m * width * small + small**3), m


def _baseline_skip_reason(name: str, estimator: Any, n_train: int, n_features: int, n_outputs: int,
                          n_folds: int, at_once: int = 1) -> str | None:
    """Why a stock baseline is not fitted here (over ftcal's memory limit, or the report's work budget), or None;
    ``at_once`` folds fitted at the same time (in worker processes) each take its memory."""
    from ..core._memory import MemoryLimitError, check_allocation

    n_bytes, flops, _ = baseline_cost(name, estimator, n_train, n_features, n_outputs, n_folds)
    try:
        check_allocation(n_bytes * at_once, f"{name} on {n_train} rows x {n_features} channels"
                         + (f" ({at_once} folds at once)" if at_once > 1 else ""), "leave it out of the report")
    except MemoryLimitError as exc:
        return f"skipped: {exc}"
    if flops > BASELINE_WORK_BUDGET:
        return (f"skipped: about {flops:.1e} floating-point operations over {n_folds} folds ({n_train} rows x "
                f"{n_features} channels), beyond the report's budget of {BASELINE_WORK_BUDGET:.0e} per baseline")
    return None


def _png(fig) -> str:
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    FigureCanvasAgg(fig)
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode("ascii")


def _figures(y: NDArray, pred: NDArray, names: list[str], units: list[str], fs: NDArray, band: NDArray,
             band_label: str) -> dict[str, str]:
    """The report's pictures, as PNG data URIs."""
    from ._plots import error_vs_load_figure, residual_direction_figure, residual_magnitude_figure

    err = pred - y
    force = [i for i, u in enumerate(units) if u == "N"]
    torque = [i for i, u in enumerate(units) if u != "N"]
    out = {"error_vs_load": _png(error_vs_load_figure(y, 100 * err / fs, axis_names=names, units=units,
                                                      band_pct_fs=band, band_label=band_label)),
           "residuals_vs_magnitude": _png(residual_magnitude_figure(y, err, force_columns=force,
                                                                    torque_columns=torque))}
    xyz = [names.index(a) for a in ("Fx", "Fy", "Fz") if a in names]
    if len(xyz) == 3:
        out["residuals_vs_direction"] = _png(residual_direction_figure(y[:, xyz], err[:, xyz]))
    return out


def _load_cases(y: NDArray, pred: NDArray, groups: NDArray | None, fs: NDArray) -> dict:
    """The applied-vs-indicated table: one case per group and applied load (rows of one pose or one load
    configuration under the same load are averaged, as a certificate averages its readings), worst first."""
    n, k = y.shape
    grid = np.where(np.isfinite(fs), fs, np.nanmax(np.abs(y), axis=0) + 1.0) * 1e-6
    key = np.round(y / np.where(grid > 0, grid, 1.0))
    if groups is not None:
        _, glabel = np.unique(groups, return_inverse=True)
        key = np.column_stack([glabel, key])
    _, case, count = np.unique(key, axis=0, return_inverse=True, return_counts=True)
    case = case.ravel()
    if count.size == n:  # every row its own case: no averaging needed
        applied, indicated, first = y, pred, np.arange(n)
        count = np.ones(n, dtype=np.int64)
    else:
        applied = np.zeros((count.size, k))
        indicated = np.zeros((count.size, k))
        np.add.at(applied, case, y)
        np.add.at(indicated, case, pred)
        applied /= count[:, None]
        indicated /= count[:, None]
        first = np.full(count.size, n)
        np.minimum.at(first, case, np.arange(n))
    err_pct = 100 * (indicated - applied) / fs
    worst = np.nanmax(np.abs(err_pct), axis=1)
    order = np.lexsort((first, -worst))
    return {"applied": applied[order], "indicated": indicated[order], "error_pct_fs": err_pct[order],
            "worst_pct_fs": worst[order], "rows": count[order], "first_row": first[order],
            "group": None if groups is None else np.asarray(groups)[first[order]]}


def _round(a: NDArray, digits: int = 6) -> list:
    """Floats to ``digits`` significant digits (a compact JSON); NaN becomes None.

    Examples
    --------
    >>> _round(np.array([[123.456789, float("nan")], [-0.000123456789, 0.0]]), 3)
    [[123.0, None], [-0.000123, 0.0]]
    """
    a = np.asarray(a, dtype=float)
    finite = np.isfinite(a)
    magnitude = np.floor(np.log10(np.abs(np.where(finite & (a != 0), a, 1.0))))
    scale = 10.0 ** (digits - 1 - magnitude)
    rounded = np.where(finite, np.round(np.where(finite, a, 0.0) * scale) / scale, np.nan)
    if finite.all():
        return rounded.tolist()
    out = rounded.astype(object)
    out[~finite] = None
    return out.tolist()


def _parse_interval(text: str) -> tuple[int, str] | None:
    """``"12 months"``, ``"1 year"``, ``"90 days"``, ``"6 weeks"``, or a bare whole number (months) -> ``(count,
    "months" | "days")``; None for anything else (fractions included: a due date is a calendar date)."""
    found = re.fullmatch(r"\s*(\d+)\s*(?:(day|week|month|year)s?)?\s*", str(text).lower())
    if not found:
        return None
    count, unit = int(found.group(1)), found.group(2) or "month"
    return {"day": (count, "days"), "week": (7 * count, "days"), "month": (count, "months"),
            "year": (12 * count, "months")}[unit]


def add_interval(start: _dt.date, interval: str) -> _dt.date:
    """The date ``interval`` after ``start``: the recalibration due date of a calibration made on ``start``.

    The rule: days and weeks are counted as days; months and years (12 months) as calendar months, keeping the
    day of the month, or the last day of the month when it has no such day (Jan 31 + 1 month = Feb 28, or Feb 29
    in a leap year; Feb 29 + 12 months = Feb 28).

    Examples
    --------
    >>> import datetime as dt
    >>> add_interval(dt.date(2025, 1, 15), "12 months"), add_interval(dt.date(2024, 1, 31), "1 month")
    (datetime.date(2026, 1, 15), datetime.date(2024, 2, 29))
    """
    import calendar

    parsed = _parse_interval(interval)
    if parsed is None:
        raise CalibrationInputError(f"recalibration_interval {interval!r}: give a number and a unit (a "
                                    "whole number), e.g. '12 months', '1 year', '90 days'.")
    count, unit = parsed
    if unit == "days":
        return start + _dt.timedelta(days=count)
    months = start.year * 12 + (start.month - 1) + count
    year, month = divmod(months, 12)
    month += 1
    return _dt.date(year, month, min(start.day, calendar.monthrange(year, month)[1]))


def _iso_date(text: str) -> _dt.date | None:
    """``"2025-01-15"`` (or an ISO date and time) -> the date; None for any other text."""
    try:
        return _dt.date.fromisoformat(str(text).strip()[:10])
    except ValueError:
        return None


def _unit_temperature(text: str) -> str:
    """An ambient temperature with its unit: a bare number is in °C (``"22.5"`` -> ``"22.5 °C"``)."""
    return f"{text} °C" if re.fullmatch(r"[+-]?\d+(\.\d+)?", text) else text


def check_conditions(conditions: dict | None) -> dict[str, str | None]:
    """The condition fields of a report (:data:`CONDITION_FIELDS`), each a string or None (not stated).

    Raises
    ------
    CalibrationInputError
        A field that is not one of :data:`CONDITION_FIELDS`, or a value that is not text or a number.

    Examples
    --------
    >>> check_conditions({"operator": "A. Tester"})["operator"]
    'A. Tester'
    """
    from ..core._fields import celsius_field, number_field

    conditions = dict(conditions or {})
    unknown = sorted(set(conditions) - set(CONDITION_FIELDS))
    if unknown:
        raise CalibrationInputError(f"conditions field {unknown[0]!r} is not known; the fields are "
                                    f"{', '.join(CONDITION_FIELDS)}.")
    out: dict[str, str | None] = {}
    for key in CONDITION_FIELDS:
        value = conditions.get(key)
        if value is not None and (isinstance(value, bool) or not isinstance(value, (str, int, float, _dt.date))):
            raise CalibrationInputError(f"conditions field {key!r} must be text or a number; got "
                                        f"{type(value).__name__} {value!r}.")
        if isinstance(value, (int, float)):  # a finite number a float holds (NaN, inf, 10**400 refused)
            number_field(value, f"conditions field {key!r}")
        out[key] = None if value is None or str(value).strip() == "" else str(value).strip()
    interval = out["recalibration_interval"]
    if interval is not None and _parse_interval(interval) is None:
        raise CalibrationInputError(f"recalibration_interval {interval!r}: give a number and a unit (a "
                                    "whole number), e.g. '12 months', '1 year', '90 days'.")
    when = out["calibration_date"]
    if interval is not None and out["recalibration_due"] is None and when is not None and _iso_date(when) is None:
        raise CalibrationInputError(f"calibration_date {when!r}: give the date as YYYY-MM-DD (the recalibration "
                                    "due date is counted from it).")
    if out["ambient_temperature"] is not None:  # in °C, within an ambient range (296 is kelvin, not °C)
        out["ambient_temperature"] = f"{celsius_field(conditions['ambient_temperature'], 'ambient_temperature'):g} °C"
    return out


def _per_axis(value: ArrayLike | None, k: int, what: str) -> NDArray | None:
    if value is None:
        return None
    a = np.broadcast_to(np.asarray(value, dtype=float), (k,)) if np.ndim(value) == 0 else np.asarray(value, float)
    if a.shape != (k,) or not np.all(np.isfinite(a)) or np.any(a <= 0):
        raise CalibrationInputError(f"{what} must hold {k} finite positive values (one per output axis); got "
                                    f"{np.asarray(value).tolist()!r}.")
    return np.array(a, dtype=float)


def _reused_auto_choice(model: Any, X: NDArray, y: NDArray, groups: NDArray | None, cv: int, n_folds: int,
                        random_state: int) -> dict | None:
    """``auto``'s own comparison (its stock baselines on the same folds), when ``model`` is an AutoCalibrator
    fitted on these data with these folds: the report then refits only the chosen model, not the baselines."""
    results = getattr(model, "comparison_", None) if calibration_tags(model).chooses_model else None
    fitted_range = getattr(model, "calibrated_range_", None)
    # (folds other than plain grouped or shuffled ones: auto replaced folds that could not judge; not these)
    if not isinstance(results, dict) or "kind" not in results or getattr(model, "cv", None) != cv \
            or results.get("n_splits") != n_folds or fitted_range is None \
            or results.get("folds") not in ("group", "kfold") \
            or (getattr(model, "random_state", None) or 0) != random_state:  # auto's folds are seeded by it
        return None
    # the very rows auto scored its comparison on (a hash of the arrays, not only their extremes)
    return results if results.get("training_sha256") == training_data_sha256(X, y, groups) else None


def calibration_certificate(
    model: Any,
    dataset: CalibrationDataset,
    *,
    model_path: str | Path | None = None,
    model_sha256: str | None = None,
    dataset_path: str | Path | None = None,
    dataset_sha256: str | None = None,
    sensor: str | None = None,
    cv: int = 5,
    baselines: bool = True,
    full_scale: ArrayLike | None = None,
    rated: ArrayLike | None = None,
    spec: ArrayLike | float | None = None,
    conditions: dict | None = None,
    tool: Any = None,
    alpha: float | None = None,
    random_state: int = 0,
    figures: bool = True,
    n_jobs: int | None = None,
    command: str | None = None,
) -> dict:
    """The facts of a calibration report: summary verdict, identity, data, held-out accuracy, cases, model choice.

    Parameters
    ----------
    model : fitted calibrator
        The calibration (e.g. from :func:`ftcal.load_model`); cloned and refitted on each fold for the
        held-out figures (its parameters, not its fitted state, are judged). An
        :class:`~ftcal.AutoCalibrator` fitted on these rows with the same ``cv`` and seed lends its comparison
        (the stock baselines on the same folds) instead of the baselines being fitted again, and its chosen row's
        out-of-fold predictions (``held_out_predictions_``, kept in its model file) instead of a refit of the
        choice; a choice that gives a standard deviation (the GP) is refitted on every fold, for its std.
    dataset : CalibrationDataset
        The calibration data (the training data of ``model``); ``k`` output axes (named by the dataset).
    model_path, dataset_path : path, optional
        File names shown on the page.
    model_sha256, dataset_sha256 : str, optional
        SHA-256 of the bytes written / read (the identity of exactly that model and data); default the hash of
        the file at ``model_path`` / ``dataset_path`` now.
    sensor : str, optional
        Sensor name / serial number; default the dataset's ``meta['sensor']``.
    cv : int
        Folds: whole groups held out when the dataset has groups, else shuffled rows (contiguous blocks for a
        load-history model, which reads its rows in time order).
    baselines : bool
        Also cross-validate :func:`ftcal.calibrators.stock_baselines` on the same folds (each within ftcal's memory
        limit and :data:`BASELINE_WORK_BUDGET`, else listed as skipped with the reason).
    rated : array-like of shape (k,), optional
        Rated capacity per axis [N, N·m]: the full scale of every % FS figure. Default the largest absolute
        reference load per axis (the page says so). ``full_scale`` is its older name.
    spec : float or array-like of shape (k,), optional
        Largest U95 allowed per axis [% FS]; each axis PASSES or FAILS against it.
    conditions : dict, optional
        Conditions and traceability (:data:`CONDITION_FIELDS`), printed when given, "not stated" otherwise.
    tool : ToolLoad, optional
        A tool's identified parameters, to print.
    alpha : float, optional
        Torque scale [1/m] of the whole-wrench RMSE; default the model's ``alpha_``, else from the wrenches.
    figures : bool
        Include the plots (PNG data URIs).
    n_jobs : int, optional
        Processes that fit the folds at once (the stock baselines', and the model's own when they are not light
        work; ``None``: 1); the figures do not depend on it.
    command : str, optional
        The command that made the report, printed on the page.

    Returns
    -------
    dict
        JSON-able; ``render_report_html`` shows it.

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import CalibrationDataset, LinearCalibrator
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(80, 6)) * [50, 50, 50, 1, 1, 1]; raw = w @ rng.normal(size=(6, 6)) / 50
    >>> data = CalibrationDataset(raw=raw + 1e-4 * rng.normal(size=raw.shape), wrench=w)
    >>> facts = calibration_certificate(LinearCalibrator().fit(data.raw, w), data, baselines=False, figures=False,
    ...                                 rated=[500, 500, 900, 20, 20, 20], spec=1.0)
    >>> facts["verdict"], [a["verdict"] for a in facts["accuracy"]][:2]
    ('PASS', ['PASS', 'PASS'])
    """
    from sklearn.base import clone

    import ftcal
    from ..calibrators._baselines import stock_baselines

    X = model_inputs(model, dataset)
    y = np.asarray(dataset.wrench, dtype=float)
    n, k = y.shape
    names = _axis_names(dataset, k)
    n_outputs = getattr(model, "n_outputs_", None)
    if n_outputs is not None and int(n_outputs) != k:
        raise CalibrationInputError(
            f"the model gives {int(n_outputs)} output axis(es) but the dataset has {k} ({', '.join(names)}); a report "
            "certifies the model's own axes on data of those axes. Fix: select the model's axes from the data "
            "(the wrench mapping naming their columns only, e.g. Fz), or report a model of all these axes.")
    units = axis_units(names)
    torque = np.array([u != "N" for u in units])
    groups = dataset.group
    if groups is not None and np.unique(groups).size < 2:
        groups = None
    ordered = reads_history(model)  # a load-history model reads its rows as a time series: never shuffle them
    folds = calibration_folds(n, groups, cv, random_state, shuffle=not ordered)
    if rated is None:
        rated = full_scale
    rated_fs = _per_axis(rated, k, "rated")
    spec_pct = _per_axis(spec, k, "spec")
    conditions = check_conditions(conditions)
    data_max = np.max(np.abs(y), axis=0)
    fs = rated_fs if rated_fs is not None else np.where(data_max > 0, data_max, np.nan)
    if torque.any() and (~torque).any():
        alpha = float(alpha or getattr(model, "alpha_", None) or alpha_from_wrenches(y))
    else:
        alpha = float(alpha or getattr(model, "alpha_", None) or 1.0)
    scale = np.where(torque, alpha, 1.0)
    name = type(model).__name__
    label = f"{name} (this calibration)"
    reused = None if ordered else _reused_auto_choice(model, X, y, groups, cv, len(folds), random_state)
    template = clone(model)
    if reused is not None:  # a model that chose by cross-validation (its tags): best_estimator_, best_name_
        template = clone(model.best_estimator_)  # auto chose on these folds: refit its choice, not the whole search
        label = f"{name}: {model.best_name_} (this calibration)"
    choice: list[dict] = []
    n_train = min(len(tr) for tr, _ in folds)
    workers = 1
    if n_jobs not in (None, 1) and min(len(tr) for tr, _ in folds) > LIGHT_KERNEL_ROWS:
        from joblib import effective_n_jobs

        workers = min(effective_n_jobs(n_jobs), len(folds))

    def scored(lbl: str, pred: NDArray, kind: str, note: str | None = None) -> dict:
        sq = np.sum(((pred - y) * scale) ** 2, axis=1)
        rmse, se = rmse_and_se(sq / k, groups)
        row = {"model": lbl, "kind": kind, "status": "scored", "rmse": rmse, "rmse_se": se,
               "axis_rmse": np.sqrt(np.mean((pred - y) ** 2, axis=0)).tolist()}
        if note:
            row["note"] = note
        return row

    main = None
    if reused is not None and not provides_std(template):  # auto's own out-of-fold predictions of its choice
        known = getattr(model, "held_out_predictions_", None)
        if known is not None and np.shape(known) == y.shape and np.all(np.isfinite(known)):
            main = {"pred": np.asarray(known, dtype=float), "std": None}
    if main is None:  # the folds of the model's own refits share the cores, unless light work (its tags' cost)
        main = _held_out(template, X, y, groups, folds, seed=random_state,
                         n_jobs=workers if workers > 1 and not is_light(template, n_train) else None)
    choice.append(scored(label, main["pred"], "calibration"))
    if baselines and reused is not None:
        for i, kind in enumerate(reused["kind"]):
            if kind not in ("baseline", "stock"):  # auto's stock models are candidates now: the same rows
                continue
            if reused["rmse"][i] is None:
                choice.append({"model": reused["name"][i], "kind": "baseline", "status": reused["status"][i]})
            else:
                choice.append({"model": reused["name"][i], "kind": "baseline", "status": "scored",
                               "rmse": reused["rmse"][i], "rmse_se": reused["rmse_se"][i],
                               "axis_rmse": list(reused["axis_rmse"][i]),
                               "note": "from auto's comparison on the same folds"})
    elif baselines:
        for bname, est in stock_baselines(X.shape[1], random_state=random_state).items():
            skip = _baseline_skip_reason(bname, est, n_train, X.shape[1], k, len(folds))
            if skip is not None:
                choice.append({"model": bname, "kind": "baseline", "status": skip})
                continue
            # folds in parallel only when their memory fits the limit together; else one after the other
            at_once = workers if workers > 1 and _baseline_skip_reason(bname, est, n_train, X.shape[1], k,
                                                                       len(folds), workers) is None else None
            rows_used = baseline_cost(bname, est, n_train, X.shape[1], k, len(folds))[2]
            try:
                # no groups for a stock model (the folds hold them out; RidgeCV's routing cannot be asked)
                out = _held_out(est, X, y, None, folds, want_std=False, seed=random_state, n_jobs=at_once,
                                max_rows=None if bname in ("sk_kernel_ridge", "sk_gp") else BASELINE_TRAINING_ROWS)
            except Exception as exc:  # a baseline that cannot fit these data is reported, not fatal
                choice.append({"model": bname, "kind": "baseline",
                               "status": f"failed: {type(exc).__name__}: {' '.join(str(exc).split())[:160]}"})
                continue
            note = f"fitted on {rows_used} of {n_train}+ rows per fold" if rows_used < n_train else None
            choice.append(scored(bname, out["pred"], "baseline", note))

    pred = main["pred"]
    err = pred - y
    rms = np.sqrt(np.mean(err**2, axis=0))
    u95 = COVERAGE_FACTOR * rms
    max_err = np.max(np.abs(err), axis=0)
    accuracy = []
    for j in range(k):
        a = {"axis": names[j], "unit": units[j], "full_scale": fs[j], "rated": None if rated_fs is None else rated_fs[j],
             "data_max": data_max[j], "rms": rms[j], "max": max_err[j],
             "rms_pct_fs": 100 * rms[j] / fs[j], "max_pct_fs": 100 * max_err[j] / fs[j],
             "u95": u95[j], "u95_pct_fs": 100 * u95[j] / fs[j],
             "coverage_u95": float(np.mean(np.abs(err[:, j]) <= u95[j])),
             "coverage_std": (None if main["std"] is None
                              else float(np.mean(np.abs(err[:, j]) <= COVERAGE_FACTOR * main["std"][:, j]))),
             "spec_pct_fs": None if spec_pct is None else spec_pct[j], "verdict": None}
        if spec_pct is not None:
            a["verdict"] = "PASS" if np.isfinite(a["u95_pct_fs"]) and a["u95_pct_fs"] <= spec_pct[j] else "FAIL"
        accuracy.append(a)
    verdict = None if spec_pct is None else ("PASS" if all(a["verdict"] == "PASS" for a in accuracy) else "FAIL")

    comparison = _comparison(choice)
    cases = _load_cases(y, pred, groups, fs)
    temperature = None if dataset.temperature is None else [float(dataset.temperature.min()),
                                                            float(dataset.temperature.max())]
    coefficients = None
    if calibration_tags(model).temperature_column:  # the temperature wrapper's drift coefficients
        coefficients = {"reference_temperature": float(model.reference_temperature),
                        "gain_per_deg": np.asarray(model.gain_per_deg_).tolist(),
                        "offset_per_deg": np.asarray(model.offset_per_deg_).tolist()}
    date = _dt.datetime.now(_dt.timezone.utc)
    interval = conditions["recalibration_interval"]
    overdue = None
    if conditions["recalibration_due"] is None and interval is not None:
        measured = None if conditions["calibration_date"] is None else _iso_date(conditions["calibration_date"])
        due_date = add_interval(measured or date.date(), interval)  # from the measurements, else from the issue
        overdue = due_date < date.date()
        conditions["recalibration_due"] = f"{due_date.isoformat()} (" + (
            f"calibration date {measured.isoformat()}" if measured else "issue date") + f" + {interval})" + (
            ": OVERDUE on the date of issue" if overdue else "")
    warn = _warnings(accuracy, comparison, X, y, folds, groups, rated_fs, n, X.shape[1], dataset)
    if overdue:
        warn.insert(0, {"kind": "recalibration overdue", "text": (
            f"The recalibration was due {conditions['recalibration_due'].split(' ')[0]} ({interval} after the "
            f"calibration of {conditions['calibration_date']}), before this report's date of issue: these figures "
            "describe the sensor as it was then, not now.")})
    report = {
        "format": "ftcal-calibration-report", "format_version": 2,
        "date_utc": date.strftime("%Y-%m-%d %H:%M:%S UTC"),
        "ftcal_version": getattr(ftcal, "__version__", "unknown"),
        "command": command,
        "sensor": sensor or str(dataset.meta.get("sensor", "not named (give the sensor's name or serial number)")),
        "axes": [{"name": a, "unit": u} for a, u in zip(names, units)],
        "model": {"type": name, "file": None if model_path is None else Path(model_path).name,
                  "path": None if model_path is None else str(model_path),
                  "sha256": model_sha256 or (None if model_path is None else file_sha256(model_path)),
                  "params": {p: v for p, v in model.get_params(deep=False).items() if not hasattr(v, "fit")},
                  "alpha": alpha, "chosen": getattr(model, "best_name_", None),
                  "matrix": _matrix(model, names, units, X.shape[1])},
        "data": {"file": None if dataset_path is None else str(dataset_path),
                 "sha256": dataset_sha256 or (None if dataset_path is None else file_sha256(dataset_path)),
                 "rows": dataset.n_samples, "channels": dataset.n_channels,
                 "groups": None if dataset.group is None else int(np.unique(dataset.group).size),
                 "wrench_min": y.min(axis=0).tolist(), "wrench_max": y.max(axis=0).tolist(),
                 "max_force_norm": float(np.linalg.norm(y[:, ~torque], axis=1).max()) if (~torque).any() else None,
                 "max_torque_norm": float(np.linalg.norm(y[:, torque], axis=1).max()) if torque.any() else None,
                 "temperature_range": temperature,
                 "units": {u: dataset.meta[u] for u in ("source_force_unit", "source_torque_unit") if u in dataset.meta}},
        "validation": {"folds": len(folds), "split": "whole groups held out (GroupKFold)" if groups is not None
                       else "contiguous blocks of rows (KFold, time order kept: a load-history model)" if ordered
                       else "shuffled rows (KFold; no group column)", "coverage_factor": COVERAGE_FACTOR,
                       "reused_auto_comparison": reused is not None},
        "full_scale_source": "rated capacity" if rated_fs is not None else
        "the largest absolute load of the calibration data per axis (no rated capacity given)",
        "spec_pct_fs": None if spec_pct is None else spec_pct.tolist(),
        "verdict": verdict,
        "accuracy": accuracy,
        "comparison": comparison,
        "warnings": warn,
        "conditions": conditions,
        "recalibration_overdue": overdue,
        "model_choice": choice,
        "calibrated_range": {"raw_min": dataset.raw.min(axis=0).tolist(), "raw_max": dataset.raw.max(axis=0).tolist(),
                             "wrench_abs_max": data_max.tolist()},
        "temperature_coefficients": coefficients,
        "tool": None if tool is None else tool.to_dict(),
    }
    report = plain_json(report)
    report["cases"] = _cases_json(cases, names, k)  # already plain (and large): kept out of plain_json's walk
    band = spec_pct if spec_pct is not None else 100 * u95 / fs
    report["figures"] = _figures(y, pred, names, units, fs, band, "spec" if spec_pct is not None else "U95") \
        if figures else {}
    report["_cases"] = cases  # the full table as arrays, for the CSV (not in the JSON)
    report["_held_out_pred"] = pred  # the model's held-out predictions (not in the JSON): what ``ftcal fit`` checks
    return report


def _cases_json(cases: dict, names: list[str], k: int) -> dict:
    total = cases["applied"].shape[0]
    keep = slice(0, min(total, CASES_IN_JSON))
    return {"by": "load case (rows of one group under one applied load, averaged)" if cases["rows"].max() > 1
            else "row", "count": total, "in_json": min(total, CASES_IN_JSON), "order": "worst first",
            "axes": names, "applied": _round(cases["applied"][keep]), "indicated": _round(cases["indicated"][keep]),
            "error_pct_fs": _round(cases["error_pct_fs"][keep], 4), "rows": cases["rows"][keep].tolist(),
            "first_row": cases["first_row"][keep].tolist(),
            "group": None if cases["group"] is None else [str(g) for g in cases["group"][keep]]}


def _matrix(model: Any, names: list[str], units: list[str], n_inputs: int) -> dict | None:
    """The calibration matrix of a model whose prediction is affine in the readings, else None."""
    from ..core._exceptions import ExportError
    from ..persistence._matrix import linear_calibration_matrix

    try:
        matrix, offset = linear_calibration_matrix(model)
    except (ExportError, ValueError, TypeError, AttributeError):
        return None
    if matrix.shape[0] != len(names):
        return None
    return {"matrix": matrix.tolist(), "offset": offset.tolist(),
            "rows": [f"{a} [{u} per raw unit]" for a, u in zip(names, units)],
            "columns": [f"s{i}" for i in range(n_inputs)],
            "equation": "wrench = matrix @ raw + offset (raw in the sensor's own unit, in the data file's channel order)"}


def _comparison(choice: list[dict]) -> dict:
    """This calibration against the best stock model, in numbers and one sentence."""
    this = choice[0]
    stock = [c for c in choice[1:] if c.get("status") == "scored" and c.get("rmse") is not None]
    if not stock:
        return {"best_stock": None, "sentence": "No stock model was compared (the stock baselines were left out "
                "or could not be fitted)."}
    best = min(stock, key=lambda c: c["rmse"])
    r, rb = this["rmse"], best["rmse"]
    se = float(np.hypot(this.get("rmse_se") or 0.0, best.get("rmse_se") or 0.0))
    ratio = r / rb if rb > 0 else float("inf")
    if abs(ratio - 1) < 0.005:
        outcome = "equal"
        sentence = (f"This calibration's held-out RMSE, {r:.4g} N, equals the best stock model's ({best['model']}, "
                    f"{rb:.4g} N) on the same folds (within 0.5 %).")
    elif r <= rb:
        outcome = "better"
        sentence = (f"This calibration's held-out RMSE, {r:.4g} N, is {100 * (1 - ratio):.0f} % below the best stock "
                    f"model's ({best['model']}, {rb:.4g} N) on the same folds.")
    elif r - rb <= se:
        outcome = "stock within noise"
        sentence = (f"The best stock model, {best['model']}, scores {rb:.4g} N against this calibration's {r:.4g} N "
                    f"({100 * (ratio - 1):.0f} % better), within one standard error ({se:.2g} N): as good within "
                    "noise.")
    else:
        outcome = "stock better"
        sentence = (f"The best stock model, {best['model']}, scores {rb:.4g} N against this calibration's {r:.4g} N: "
                    f"{100 * (ratio - 1):.0f} % better, beyond one standard error ({se:.2g} N). Consider it"
                    + (f" (the calibrator stock with baseline={best['model']})" if best["model"] in STOCK_BASELINE_NAMES
                       else "") + ", or the auto model, which chooses among them.")
    return {"best_stock": best["model"], "best_stock_rmse": rb, "rmse": r, "ratio": ratio, "combined_se": se,
            "outcome": outcome, "sentence": sentence}


def _warnings(accuracy: list[dict], comparison: dict, X: NDArray, y: NDArray, folds: list, groups, rated_fs,
              n: int, n_channels: int, dataset: CalibrationDataset) -> list[dict]:
    """What a reader must know before trusting the figures, each ``{"kind", "text"}``."""
    out: list[dict] = []
    for a in accuracy:
        if a["rated"] is not None and a["data_max"] > a["rated"]:
            out.append({"kind": "beyond rated capacity", "text": (
                f"{a['axis']}: the calibration data hold loads up to {a['data_max']:.4g} {a['unit']}, beyond the rated "
                f"capacity of {a['rated']:.4g} {a['unit']} ({100 * a['data_max'] / a['rated']:.0f} %).")})
        if np.isfinite(a["max_pct_fs"]) and a["max_pct_fs"] >= 100:
            out.append({"kind": "error beyond full scale", "text": (
                f"{a['axis']}: the largest held-out error, {a['max']:.4g} {a['unit']}, is {a['max_pct_fs']:.0f} % of "
                f"full scale ({a['full_scale']:.4g} {a['unit']}): as large as the loads themselves.")})
    if comparison.get("outcome") in ("stock within noise", "stock better"):
        out.append({"kind": comparison["outcome"], "text": comparison["sentence"]})
    outside = np.zeros(n, dtype=bool)
    for train, test in folds:  # held-out readings beyond the range their fold's model was trained on
        lo, hi = X[train].min(axis=0), X[train].max(axis=0)
        outside[test] |= np.any((X[test] < lo) | (X[test] > hi), axis=1)
    if outside.mean() > 0.05:
        out.append({"kind": "extrapolation", "text": (
            f"{100 * outside.mean():.0f} % of the held-out rows lie beyond the readings their fold's model was trained "
            "on: their errors are extrapolation (hold-out by group leaves whole load cases unseen). Loads beyond the "
            "calibrated range will show similar errors.")})
    if rated_fs is not None:
        short = [a for a in accuracy if a["data_max"] < 0.5 * a["rated"]]
        if short:
            listed = ", ".join(f"{a['axis']} to {100 * a['data_max'] / a['rated']:.0f} %" for a in short)
            out.append({"kind": "extrapolation", "text": (
                f"The data cover less than half of the rated capacity on {listed}: loads beyond the calibrated range "
                "(see Calibrated range) are extrapolation, and these figures do not cover them.")})
    need = 10 * (n_channels + 1)
    units_held = n if groups is None else int(np.unique(groups).size)
    if n < need or (groups is not None and units_held < 5):
        what = f"{n} rows for {n_channels} channels (an affine map alone has {n_channels + 1} parameters per axis)" \
            if n < need else f"{units_held} groups"
        out.append({"kind": "few rows", "text": (
            f"Only {what}: the held-out figures rest on little data and may be far off. Record at least {need} rows "
            "in at least 5 groups (poses or load configurations).")})
    for a in accuracy:
        if a["coverage_u95"] < 0.9:
            out.append({"kind": "coverage", "text": (
                f"{a['axis']}: only {100 * a['coverage_u95']:.0f} % of the held-out errors fall within ±U95 (95 % "
                "expected): the errors are not normal (a few large ones); read U95 with care.")})
    if rated_fs is None:
        out.append({"kind": "no rated capacity", "text": (
            "No rated capacity was given: every % FS figure is against the largest load of the data. Give the "
            "sensor's rated capacity per axis (N, N·m; rated=, or the rated option of ftcal report) for figures "
            "against it.")})
    return out


def _fmt(value: Any, digits: int = 3) -> str:
    if value is None or (isinstance(value, float) and not np.isfinite(value)):
        return "–"
    if isinstance(value, float):
        return f"{value:.{digits}g}"
    return html.escape(str(value))


_CSS = """
body{font-family:system-ui,-apple-system,'Segoe UI',Roboto,sans-serif;margin:1.5em auto;max-width:60em;color:#222;
line-height:1.4;padding:0 1em}h1{font-size:1.55em;margin:0 0 .2em}h2{font-size:1.2em;border-bottom:1px solid #ccc;
margin-top:1.4em}h3{font-size:1.02em;margin:1em 0 .3em}table{border-collapse:collapse;margin:.5em 0;font-size:.9em}
th,td{border:1px solid #bbb;padding:.2em .55em;text-align:right}th{background:#eee}
td:first-child,th:first-child{text-align:left}.note{color:#444;font-size:.88em}img{max-width:100%;height:auto}
code{background:#f3f3f3;padding:0 .2em;word-break:break-all}.best{font-weight:bold}
.PASS{color:#0a6b2a;font-weight:bold}.FAIL{color:#b00020;font-weight:bold}
.verdict{font-size:1.25em;padding:.35em .7em;border:2px solid;display:inline-block;margin:.3em 0}
.verdict.PASS{border-color:#0a6b2a}.verdict.FAIL{border-color:#b00020}.verdict.none{border-color:#888;color:#444}
.warnings li{margin:.15em 0}.warn-kind{font-weight:bold}.summary-grid td:first-child{width:11em}
.not-stated{color:#8a5a00;font-style:italic}table.kv td{text-align:left}table.kv thead{display:none}
section{margin-top:1em}
@page{size:A4;margin:14mm 12mm 16mm 12mm;
@bottom-right{content:"page " counter(page) " of " counter(pages);font-size:9pt;color:#444}
@bottom-left{content:"ftcal calibration report";font-size:9pt;color:#444}}
.cases{overflow-x:auto}.cases table{font-size:.8em}.cases td,.cases th{padding:.15em .3em}
@page wide{size:A4 landscape;margin:12mm 12mm 16mm 12mm;
@bottom-right{content:"page " counter(page) " of " counter(pages);font-size:9pt;color:#444}
@bottom-left{content:"ftcal calibration report";font-size:9pt;color:#444}}
@media print{body{margin:0;max-width:none;font-size:10pt}section#cases{page:wide}.cases{overflow:visible}
.cases table{font-size:7pt}section{break-before:page;margin-top:0}
section.first{break-before:auto}h2{break-after:avoid}table,img,figure{break-inside:avoid}
table.long{break-inside:auto}thead{display:table-header-group}tr{break-inside:avoid}}
"""


def _table(head: list[str], rows: list[list[str]], classes: list[str] | None = None, long: bool = False) -> str:
    kinds = (["long"] if long else []) + (["kv"] if head == ["", ""] else [])
    cls_table = f' class="{" ".join(kinds)}"' if kinds else ""
    out = [f"<table{cls_table}><thead><tr>" + "".join(f"<th>{h}</th>" for h in head) + "</tr></thead><tbody>"]
    for i, row in enumerate(rows):
        cls = f' class="{classes[i]}"' if classes and classes[i] else ""
        out.append(f"<tr{cls}>" + "".join(f"<td>{c}</td>" for c in row) + "</tr>")
    out.append("</tbody></table>")
    return "\n".join(out)


#: Rows of the applied-vs-indicated table printed on the page (the worst; all are in the JSON and CSV).
CASES_ON_PAGE = 30


def _not_stated(value: Any, how: str = "") -> str:
    if value is None:
        return f'<span class="not-stated">not stated</span>{(" — " + how) if how else ""}'
    return _fmt(value)


def render_report_html(report: dict) -> str:
    """The report as one self-contained HTML page (inline CSS, pictures as data URIs, no script, no network)."""
    m, d, v = report["model"], report["data"], report["validation"]
    acc = report["accuracy"]
    axes = report.get("axes") or [{"name": a, "unit": u} for a, u in zip(WRENCH_LABELS, axis_units(WRENCH_LABELS))]
    names = [a["name"] for a in axes]
    units = [a["unit"] for a in axes]
    cond = report.get("conditions") or {}
    verdict = report.get("verdict")
    spec = report.get("spec_pct_fs")
    rated = acc[0].get("rated") is not None if acc else False
    title = f"Calibration report: {_fmt(report['sensor'])}"
    parts = [
        "<!DOCTYPE html>", '<html lang="en"><head><meta charset="utf-8">',
        '<meta http-equiv="Content-Security-Policy" content="default-src \'none\'; img-src data:; '
        'style-src \'unsafe-inline\'">',
        f"<title>{title}</title><style>{_CSS}</style></head><body>",
        '<section class="first" id="summary">',
        f"<h1>{title}</h1>",
        f"<p class=\"note\">Issued {_fmt(report['date_utc'])} by ftcal {_fmt(report['ftcal_version'])}. "
        "Every accuracy figure is <b>held out</b>: errors on data the fitted calibration did not see.</p>",
        _table(["", ""], [
            ["sensor", _fmt(report["sensor"])],
            ["model", f"{_fmt(m['type'])}" + (f" (chose {_fmt(m['chosen'])})" if m.get("chosen") else "")
             + (f", file <code>{_fmt(m['file'])}</code>" if m.get("file") else "")],
            ["date of issue", _fmt(report["date_utc"])],
            ["data", f"{_fmt(d['rows'])} rows, {_fmt(d['channels'])} channels"
             + (f", {_fmt(d['groups'])} groups" if d.get("groups") else "")
             + (f", <code>{_fmt(Path(d['file']).name)}</code>" if d.get("file") else "")],
            ["full scale", _fmt(report.get("full_scale_source", "largest load of the data"))],
            ["specification", "none given (a spec of e.g. 1 % FS gives a PASS/FAIL per axis)" if spec is None else
             "U95 ≤ " + ", ".join(f"{a['axis']} {_fmt(a['spec_pct_fs'])} %" for a in acc) + " of full scale"],
            ["recalibration due", _not_stated(cond.get("recalibration_due"), "give a recalibration interval")],
        ]),
    ]
    if verdict is None:
        parts.append('<p class="verdict none">No specification given: no PASS/FAIL verdict.</p>')
    else:
        failed = [a["axis"] for a in acc if a["verdict"] == "FAIL"]
        parts.append(f'<p class="verdict {verdict}">{verdict}: ' + (
            f"every axis within its specification at 95 %." if verdict == "PASS" else
            f"{', '.join(failed)} beyond the specification at 95 %.") + "</p>")
    parts.append(_table(
        ["axis", "full scale", "U95", "U95 [% FS]", "spec [% FS]", "result", "max error [% FS]"],
        [[f"{a['axis']}", f"{_fmt(a['full_scale'])} {a['unit']}", f"{_fmt(a['u95'])} {a['unit']}",
          _fmt(a["u95_pct_fs"]), _fmt(a.get("spec_pct_fs")),
          "–" if a.get("verdict") is None else f'<span class="{a["verdict"]}">{a["verdict"]}</span>',
          _fmt(a["max_pct_fs"])] for a in acc]))
    parts.append(f"<p><b>Against the stock models:</b> {_fmt(report.get('comparison', {}).get('sentence'))}</p>")
    warns = report.get("warnings") or []
    if warns:
        parts.append("<h3>Warnings</h3><ul class=\"warnings\">" + "".join(
            f'<li><span class="warn-kind">{_fmt(w["kind"])}:</span> {_fmt(w["text"])}</li>' for w in warns) + "</ul>")
    else:
        parts.append("<h3>Warnings</h3><p>None.</p>")
    parts.append("</section>")

    # the calibration itself
    parts.append('<section id="calibration"><h2>The calibration</h2>')
    ident = [["model type", _fmt(m["type"])], ["model file", _not_stated(m.get("file"))],
             ["model SHA-256", f"<code>{_fmt(m['sha256'])}</code>"],
             ["load it (Python)", f"<code>ftcal.load_model({_fmt(repr(m.get('file') or 'MODEL.model.npz'))})</code>"],
             ["use it (command line)", f"<code>ftcal predict {_fmt(m.get('file') or 'MODEL.model.npz')} "
                                       "readings.csv</code>"],
             ["torque scale alpha", f"{_fmt(m['alpha'])} 1/m"],
             ["data file", _not_stated(d.get("file"))], ["data SHA-256", f"<code>{_fmt(d.get('sha256'))}</code>"]]
    parts.append(_table(["", ""], ident))
    mx = m.get("matrix")
    if mx is not None:
        parts.append(f"<h3>Calibration matrix</h3><p class=\"note\">{_fmt(mx['equation'])}. Row units: the axis unit "
                     "per raw unit; offset in the axis unit.</p>")
        parts.append(_table(["axis [unit per raw unit]"] + mx["columns"] + ["offset"],
                            [[_fmt(r)] + [_fmt(c, 5) for c in row] + [_fmt(o, 5)]
                             for r, row, o in zip(mx["rows"], mx["matrix"], mx["offset"])]))
    else:
        parts.append("<p class=\"note\">No calibration matrix could be read from this model (its prediction is "
                     "not affine in the readings, or not a matrix of these axes). Its identity is the model file and "
                     "its SHA-256 above; load it with the command shown.</p>")
    has_force, has_torque = any(n.startswith("F") for n in names), any(n.startswith("T") for n in names)
    kinds = ", ".join([k for k, has in (("forces in N", has_force),
                                         ("torques in N·m about the sensor frame's origin", has_torque)) if has])
    over = "<code>[F, alpha·T]</code> in N" if has_force and has_torque else "the axes above, in their unit"
    parts.append("<h3>Frames and units</h3><p>Outputs are <code>[" + ", ".join(names) + "]</code> in the <b>sensor "
                 f"frame</b>: {kinds or 'in the units of the data'}. Raw channels are in the "
                 "sensor's own unit, in the channel order of the data file. The RMSE of the whole wrench is over "
                 f"{over} (thesis eq. 18)."
                 + (f" The data file declared {_fmt(', '.join(f'{k[7:]}: {u}' for k, u in d['units'].items()))}; "
                    "values were converted to N and N·m." if d.get("units") else "") + "</p>")
    parts.append("</section>")

    # accuracy
    parts.append(
        f"<section id=\"accuracy\"><h2>Held-out accuracy per axis</h2><p class=\"note\">{v['folds']}-fold "
        f"cross-validation, {_fmt(v['split'])}: every error below is on data the fitted calibration did not see. "
        f"Full scale (FS): {_fmt(report.get('full_scale_source', 'the largest load of the data'))}. "
        f"U95 = k·u, k = {v['coverage_factor']:g}, u the held-out RMS error; <i>coverage</i> is the fraction of held-out "
        "errors within ±U95." + (" auto chose its model on these same folds, so the figures of its choice are "
                                  "slightly optimistic." if v.get("reused_auto_comparison") else "") + "</p>")
    parts.append(_table(["axis", "full scale", "RMS error", "RMS [% FS]", "max error", "max [% FS]", "U95",
                         "U95 [% FS]", "coverage of U95", "coverage of ±2 std"],
                        [[a["axis"], f"{_fmt(a['full_scale'])} {a['unit']}", f"{_fmt(a['rms'])} {a['unit']}",
                          _fmt(a["rms_pct_fs"]), f"{_fmt(a['max'])} {a['unit']}", _fmt(a["max_pct_fs"]),
                          f"{_fmt(a['u95'])} {a['unit']}", _fmt(a["u95_pct_fs"]), f"{100 * a['coverage_u95']:.1f} %",
                          "model gives no std" if a["coverage_std"] is None else f"{100 * a['coverage_std']:.1f} %"]
                         for a in acc]))
    figs = report.get("figures") or {}
    if "error_vs_load" in figs:
        band = "the specification" if spec is not None else "±U95 (no specification given)"
        parts.append(f"<h3>Held-out error against applied load</h3><p class=\"note\">Shaded: {band}; errors beyond it "
                     "in red, the largest drawn last (on top).</p>"
                     f"<img alt=\"Held-out error against applied load\" src=\"{figs['error_vs_load']}\">")
    parts.append("</section>")

    # applied vs indicated
    cases = report.get("cases")
    if cases:
        shown = min(CASES_ON_PAGE, len(cases["applied"]))
        head = ["#", "group"] if cases.get("group") is not None else ["#", "row"]
        head = head + [f"{a} applied [{u}]" for a, u in zip(names, units)] + \
            [f"{a} indicated [{u}]" for a, u in zip(names, units)] + [f"{a} error [% FS]" for a in names]
        rows = []
        for i in range(shown):
            where = cases["group"][i] if cases.get("group") is not None else cases["first_row"][i]
            rows.append([str(i + 1), _fmt(where)] + [_fmt(x, 4) for x in cases["applied"][i]]
                        + [_fmt(x, 4) for x in cases["indicated"][i]] + [_fmt(x, 3) for x in cases["error_pct_fs"][i]])
        parts.append(
            "<section id=\"cases\"><h2>Applied against indicated load (held out), worst first</h2>"
            f"<p class=\"note\">One row per {_fmt(cases['by'])}: the applied (reference) load, the load the "
            "calibration indicated when that case was held out, and the error in % of full scale; sorted by the "
            f"largest error of any axis. {shown} of {cases['count']} cases shown; all are in the JSON and in the CSV "
            "beside this page.</p>")
        parts.append('<div class="cases">' + _table(head, rows, long=True) + "</div></section>")

    # model choice
    parts.append("<section id=\"choice\"><h2>Model choice (same folds)</h2><p class=\"note\">This calibration beside "
                 "the stock scikit-learn models a user would try first (<code>ftcal.calibrators.stock_baselines</code>). "
                 "Held-out RMSE of the torque-scaled wrench [N], ± its standard error over groups. A baseline over "
                 "ftcal's memory limit or the report's work budget is skipped, with the reason.</p>"
                 f"<p>{_fmt(report.get('comparison', {}).get('sentence'))}</p>")
    scored = [c for c in report["model_choice"] if c["status"] == "scored"]
    best = min((c["rmse"] for c in scored), default=None)
    rows, classes = [], []
    for c in report["model_choice"]:
        if c["status"] != "scored":
            rows.append([_fmt(c["model"]), _fmt(c["status"])] + [""] * (len(names) + 1))
            classes.append("")
            continue
        rows.append([_fmt(c["model"]) + (f' <span class="note">({_fmt(c["note"])})</span>' if c.get("note") else ""),
                     _fmt(c["rmse"]), _fmt(c["rmse_se"], 2)] + [_fmt(x) for x in c["axis_rmse"]])
        classes.append("best" if c["rmse"] == best else "")
    parts.append(_table(["model", "RMSE [N]", "± SE"] + [f"{a} [{u}]" for a, u in zip(names, units)], rows, classes))
    parts.append("</section>")

    # range, conditions
    r = report["calibrated_range"]
    parts += [
        "<section id=\"range\"><h2>Calibrated range</h2><p class=\"note\">Readings or loads beyond these were not "
        "calibrated (the range check of <code>ftcal predict</code> flags them).</p>",
        _table(["axis", "min", "max", "|max|"] + (["rated capacity"] if rated else []),
               [[f"{a} [{u}]", _fmt(lo), _fmt(hi), _fmt(mm)] + ([_fmt(ac["rated"])] if rated else [])
                for a, u, lo, hi, mm, ac in zip(names, units, d["wrench_min"], d["wrench_max"], r["wrench_abs_max"],
                                                acc)]),
        _table(["raw channel", "min", "max"], [[f"s{i}", _fmt(lo), _fmt(hi)] for i, (lo, hi) in
                                               enumerate(zip(r["raw_min"], r["raw_max"]))], long=True),
    ]
    temp_data = None if d["temperature_range"] is None else \
        f"{_fmt(d['temperature_range'][0])} to {_fmt(d['temperature_range'][1])} °C (the data's temperature column)"
    ambient = cond.get("ambient_temperature")
    how_temp = ("the data have no temperature column: add one named <code>temperature</code> [°C] to the data file, "
                "or state the ambient temperature (<code>ambient_temperature: 23 °C</code> in the conditions file, "
                "or the ambient temperature option of <code>ftcal report</code>)")
    cond_rows = []
    for key, label_ in CONDITION_FIELDS.items():
        if key == "ambient_temperature":
            value = temp_data if ambient is None and temp_data is not None else ambient
            cond_rows.append([label_, _not_stated(value, how_temp if value is None else "")])
        elif key in ("location", "notes") and cond.get(key) is None:
            continue
        elif key == "calibration_date" and cond.get(key) is None:
            cond_rows.append([label_, _not_stated(None, "issue date " + _fmt(report["date_utc"]))])
        else:
            cond_rows.append([label_, _not_stated(cond.get(key))])
    if ambient is not None and temp_data is not None:
        cond_rows.append(["sensor temperature (data)", temp_data])
    parts += ["<h2>Conditions and traceability</h2><p class=\"note\">From the conditions file beside the data "
              "(<code>DATA.conditions.yaml</code> or <code>.json</code>), a conditions file named on the command "
              "line, or the options of the same names.</p>", _table(["", ""], cond_rows),
              "<h3>Data</h3>",
              _table(["", ""], [
                  ["rows", _fmt(d["rows"])], ["raw channels", _fmt(d["channels"])],
                  ["groups (poses / load configurations)", _fmt(d["groups"])],
                  ["largest |F|", f"{_fmt(d['max_force_norm'])} N"]]
                  + ([["largest |T|", f"{_fmt(d['max_torque_norm'])} N·m"]] if d.get("max_torque_norm") is not None
                     else [])
                  + [["command", f"<code>{_fmt(report.get('command'))}</code>"]]),
              "</section>"]
    pics = [(key, t) for key, t in (("residuals_vs_magnitude", "Held-out error against load magnitude"),
                                     ("residuals_vs_direction", "Held-out error against load direction"))
            if key in figs]
    if pics:
        parts.append("<section id=\"residuals\"><h2>Residuals</h2>" + "".join(
            f"<h3>{t}</h3><img alt=\"{t}\" src=\"{figs[key]}\">" for key, t in pics) + "</section>")
    tc = report["temperature_coefficients"]
    tool = report["tool"]
    if tc is not None or tool is not None:
        parts.append("<section id=\"extras\">")
        if tc is not None:
            parts += [f"<h2>Temperature coefficients</h2><p class=\"note\">raw = f(w)(1 + g ΔT) + o ΔT, ΔT from "
                      f"{_fmt(tc['reference_temperature'])} °C.</p>",
                      _table(["channel", "gain g [1/°C]", "offset o [unit/°C]"],
                             [[f"s{i}", _fmt(g), _fmt(o)] for i, (g, o) in
                              enumerate(zip(tc["gain_per_deg"], tc["offset_per_deg"]))])]
        if tool is not None:
            parts += ["<h2>Tool</h2>", _table(["", "value"], [
                ["mass", f"{_fmt(tool['mass_kg'])} ± {_fmt(tool['mass_std_error_kg'], 2)} kg"],
                ["centre of mass (sensor frame)", f"{', '.join(_fmt(c) for c in tool['center_of_mass_m'])} m"],
                ["bias", ", ".join(_fmt(b) for b in tool["bias"]) + " [N, N·m]"]])]
        parts.append("</section>")
    parts.append("</body></html>")
    return "\n".join(parts)


def report_cases_csv(report: dict) -> str:
    """The applied-vs-indicated table (every case, worst first) as CSV text."""
    cases = report.get("_cases")
    names = [a["name"] for a in report["axes"]]
    units = [a["unit"] for a in report["axes"]]
    out = io.StringIO()
    writer = csv.writer(out, lineterminator="\n")
    writer.writerow(["rank", "group", "first_row", "rows"] + [f"{a}_applied [{u}]" for a, u in zip(names, units)]
                    + [f"{a}_indicated [{u}]" for a, u in zip(names, units)] + [f"{a}_error [%FS]" for a in names])
    if cases is None:  # a report read back from JSON: the cases it holds
        c = report["cases"]
        applied, indicated, err = (np.asarray(c[key], dtype=float) for key in ("applied", "indicated", "error_pct_fs"))
        group, first, rows = c["group"], np.asarray(c["first_row"]), np.asarray(c["rows"])
    else:
        applied, indicated, err = cases["applied"], cases["indicated"], cases["error_pct_fs"]
        group, first, rows = cases["group"], cases["first_row"], cases["rows"]
    block = np.column_stack([applied, indicated, err])
    for i in range(block.shape[0]):
        writer.writerow([i + 1, "" if group is None else group[i], int(first[i]), int(rows[i])]
                        + [f"{x:.7g}" for x in block[i]])
    return out.getvalue()


def write_calibration_report(report: dict, html_path: str | Path, *, overwrite: bool = False
                             ) -> tuple[Path, Path, Path]:
    """Write the page (``.html``), its facts (``.json``) and its cases (``.csv``) beside it; return the paths."""
    html_path = Path(html_path)
    if html_path.suffix.lower() != ".html":
        raise CalibrationInputError(f"report path {html_path} must end in .html")
    paths = (html_path, html_path.with_suffix(".json"), html_path.with_suffix(".csv"))
    texts = (render_report_html(report), report_json(report), report_cases_csv(report))
    for path, text in zip(paths, texts):
        with atomic_output(path, overwrite=overwrite, error=CalibrationInputError) as tmp:
            tmp.write_text(text, encoding="utf-8")
    return paths


def report_json(report: dict) -> str:
    """The report's facts as JSON text (the pictures left out)."""
    facts = plain_json({k: v for k, v in report.items() if k != "figures" and k != "cases" and not k.startswith("_")})
    text = json.dumps(facts, indent=1, default=str, allow_nan=False)
    if "cases" not in report:
        return text + "\n"
    # plain already (rounded lists) and large: written compactly, by the C encoder (indentation would take the
    # pure-Python one, ten times slower on a hundred thousand cases)
    cases = json.dumps(report["cases"], separators=(",", ":"), allow_nan=False)
    return text[:-1].rstrip() + (",\n" if facts else "") + f' "cases": {cases}\n}}\n'

