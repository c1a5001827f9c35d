"""The shared pieces of the calibration certificate (:mod:`ftcal.reporting._certificate`): file identities, the
model's inputs, the axes' units, the held-out engine call, the load cases, the conditions and their due dates,
the calibration matrix, the warnings and the writer of the certificate's three files.

The certificate itself (:class:`~ftcal.reporting._certificate.CalibrationCertificate`,
:func:`~ftcal.reporting._certificate.calibration_certificate`) opens with a one-page summary (sensor, model, date,
per-axis expanded uncertainty with its budget, PASS/FAIL against a specification, the comparison with the best
stock model, warnings), then the calibration (matrix or model identity), the held-out applied-vs-indicated table,
the comparison, the calibrated range, conditions and traceability. The page needs no network and prints to a
multi-page PDF.
"""

from __future__ import annotations

import base64
import datetime as _dt
import hashlib
import io
import re
import warnings
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import CalibrationInputError
from ..core._files import atomic_output
from ..calibrators._base import calibration_tags
from ..compose._history import reads_history
from ..model_selection._selection import held_out_predictions
from ..core._wrench import WRENCH_LABELS
from ..io._dataset import CalibrationDataset
from ..compose._auto import provides_std

__all__ = ["model_inputs", "write_calibration_report", "file_sha256", "bytes_sha256", "axis_units",
           "CONDITION_FIELDS", "COVERAGE_FACTOR", "CASES_IN_JSON", "load_case_labels", "dataset_axis_names"]

#: k of the check of a model's own standard deviation (the coverage of ±2 std); U95 itself has the budget's k.
COVERAGE_FACTOR = 2.0
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
    with open(path, "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()


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


def dataset_axis_names(dataset: CalibrationDataset, k: int) -> list[str]:
    """The dataset's output axis names (``axis_names``, or its meta's), else ``Fx..Tz`` for 6 columns.

    Examples
    --------
    >>> import numpy as np
    >>> dataset_axis_names(CalibrationDataset(raw=np.zeros((2, 6)), wrench=np.zeros((2, 6))), 6)
    ['Fx', 'Fy', 'Fz', 'Tx', 'Ty', 'Tz']
    """
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


def _held_out(template: Any, X: NDArray, y: NDArray, groups: NDArray | None, folds: list, *, seed: int = 0,
              n_jobs: int | None = None) -> tuple[NDArray, NDArray | None]:
    """``(out-of-fold predictions, their std or None)`` on ``folds`` (the std where the model gives one in every
    fold), from ftcal's one held-out engine (:func:`~ftcal.model_selection._selection.held_out_predictions`):
    ``groups`` reach the model through its metadata routing; the test folds predicted in blocks (one stream for a
    model that reads the load history); the fits' BLAS on one thread where no other thread sees it."""
    from ..core._threads import limit_threads_here

    with limit_threads_here(1), warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        _, pred, std = held_out_predictions(
            template, X, y, groups=groups, folds=folds, random_state=seed, n_jobs=n_jobs, has_std=provides_std,
            chunk_rows=None if reads_history(template) else PREDICT_CHUNK_ROWS)
    return pred.reshape(y.shape), None if std is None else std.reshape(y.shape)


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
    out = {"error_vs_load": _png(error_vs_load_figure(y, 100 * err / fs, axis_names=names, units=units,
                                                      band_pct_fs=band, band_label=band_label)),
           "residuals_vs_magnitude": _png(residual_magnitude_figure(
               y, err, force_columns=force, torque_columns=[i for i in range(len(units)) if i not in force]))}
    xyz = [names.index(a) for a in ("Fx", "Fy", "Fz") if a in names]
    if len(xyz) == 3:
        out["residuals_vs_direction"] = _png(residual_direction_figure(y[:, xyz], err[:, xyz]))
    return out


def load_case_labels(y: NDArray, pred: NDArray, groups: NDArray | None, fs: NDArray) -> tuple[NDArray, dict]:
    """The load case of each row (one group under one applied load: its rows are read again under the same load)
    and the applied-vs-indicated table of the cases (rows averaged, as a certificate averages its readings),
    worst first: ``(case of each row, {applied, indicated, error_pct_fs, worst_pct_fs, rows, first_row})``.

    Examples
    --------
    >>> y = np.array([[1.0], [1.0], [2.0]]); case, table = load_case_labels(y, y + [[0.1], [0.3], [0.0]], None,
    ...                                                                     np.array([2.0]))
    >>> case.tolist(), table["rows"].tolist(), np.round(table["indicated"].ravel(), 3).tolist()
    ([0, 0, 1], [2, 1], [1.2, 2.0])
    """
    k = y.shape[1]
    grid = np.where(np.isfinite(fs), fs, np.nanmax(np.abs(y), axis=0) + 1.0) * 1e-6
    key = np.round(y / np.where(grid > 0, grid, 1.0))
    if groups is not None:
        _, glabel = np.unique(groups, return_inverse=True)
        key = np.column_stack([glabel.ravel(), key])
    _, first, case, count = np.unique(key, axis=0, return_index=True, return_inverse=True, return_counts=True)
    case = case.ravel()
    sums = np.zeros((count.size, 2 * k))
    np.add.at(sums, case, np.hstack([y, pred]))
    applied, indicated = np.hsplit(sums / count[:, None], 2)
    err_pct = 100 * (indicated - applied) / fs
    worst = np.nanmax(np.abs(err_pct), axis=1)
    order = np.lexsort((first, -worst))
    return case, {"applied": applied[order], "indicated": indicated[order], "error_pct_fs": err_pct[order],
                  "worst_pct_fs": worst[order], "rows": count[order], "first_row": first[order]}


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


def _parse_interval(text: str) -> tuple[int, str]:
    """``"12 months"``, ``"1 year"``, ``"90 days"``, ``"6 weeks"``, or a bare whole number (months) -> ``(count,
    "months" | "days")``; anything else is refused (fractions included: a due date is a calendar date)."""
    found = re.fullmatch(r"\s*(\d+)\s*(?:(day|week|month|year)s?)?\s*", str(text).lower())
    if not found:
        raise CalibrationInputError(f"recalibration_interval {text!r}: give a number and a unit (a "
                                    "whole number), e.g. '12 months', '1 year', '90 days'.")
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

    count, unit = _parse_interval(interval)
    if unit == "days":
        return start + _dt.timedelta(days=count)
    year, month = divmod(start.year * 12 + start.month - 1 + count, 12)  # month counted from 0
    return _dt.date(year, month + 1, min(start.day, calendar.monthrange(year, month + 1)[1]))


def _iso_date(text: str) -> _dt.date | None:
    """``"2025-01-15"`` (or an ISO date and time) -> the date; None for any other text."""
    try:
        return _dt.date.fromisoformat(str(text).strip()[:10])
    except ValueError:
        return None


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
    if interval is not None:
        _parse_interval(interval)
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


def _matrix(model: Any, names: list[str], units: list[str], channels: list[str]) -> dict | None:
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
            "columns": list(channels[:matrix.shape[1]]),
            "equation": "wrench = matrix @ raw + offset (raw in the sensor's own unit, in the data file's channel order)"}


def _warnings(accuracy: list[dict], comparison: dict, X: NDArray, folds: list, groups, rated_fs) -> list[dict]:
    """What a reader must know before trusting the figures, each ``{"kind", "text"}``."""
    n, n_channels = X.shape
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
    if comparison.get("outcome") == "stock better":
        out.append({"kind": comparison["outcome"], "text": comparison["sentence"]})
    outside = np.zeros(n, dtype=bool)
    for train, test in folds:  # held-out readings beyond the range their fold's model was trained on
        lo, hi = X[train].min(axis=0), X[train].max(axis=0)
        outside[test] |= np.any((X[test] < lo) | (X[test] > hi), axis=1)
    if outside.mean() > 0.05:
        out.append({"kind": "extrapolation", "text": (
            f"{100 * outside.mean():.0f} % of the held-out rows lie beyond the readings their fold's model was trained "
            "on: their errors are extrapolation" + (" (holding out whole groups leaves their load cases unseen)"
                                                    if groups is not None else "")
            + ". Loads beyond the calibrated range will show similar errors.")})
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




def write_calibration_report(certificate: Any, html_path: str | Path, *, overwrite: bool = False
                             ) -> tuple[Path, Path, Path]:
    """Write a :class:`~ftcal.reporting._certificate.CalibrationCertificate` as its page (``.html``), its facts
    (``.json``) and its cases (``.csv``) beside each other; return the paths."""
    html_path = Path(html_path)
    if html_path.suffix.lower() != ".html":
        raise CalibrationInputError(f"report path {html_path} must end in .html")
    paths = (html_path, html_path.with_suffix(".json"), html_path.with_suffix(".csv"))
    texts = (certificate.to_html(), certificate.to_json(), certificate.to_csv())
    for path, text in zip(paths, texts):
        with atomic_output(path, overwrite=overwrite, error=CalibrationInputError) as tmp:
            tmp.write_text(text, encoding="utf-8")
    return paths
