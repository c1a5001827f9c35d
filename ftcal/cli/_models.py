"""Datasets and model files as the subcommands use them (thin wrappers that add context)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

import numpy as np

from ..io import CalibrationDataset
from ..core import alpha_from_wrenches
from ..core import MODEL_SUFFIX, model_file_name
from ._common import CliError, note_dataset, path_problem

__all__ = ["MODEL_SUFFIX", "model_file_name", "model_label", "load_dataset",
           "parse_param", "dataset_alpha", "evaluation_alpha", "calibrator_params", "check_fold_count"]

def model_label(path: Path) -> str:
    """Short name of a model file for tables and plots (its name without the suffix)."""
    name = Path(path).name
    return name[: -len(MODEL_SUFFIX)] if name.endswith(MODEL_SUFFIX) else Path(path).stem


def load_dataset(path: str | Path, role: str = "dataset", columns=None) -> CalibrationDataset:
    """A :class:`~ftcal.CalibrationDataset` from ``.csv`` / ``.npz`` / ``.mat``; ``role`` names it in errors;
    ``columns`` (a :class:`~ftcal.io.ColumnMap`) maps other layouts and units."""
    path = Path(path)
    problem = None if path.is_dir() else path_problem(path)  # a folder of files (one per pose) is one dataset
    if problem is not None:
        raise CliError(f"{problem} (the {role})")
    from ..core import MAX_TRAINING_MAGNITUDE  # scikit-learn behind it: not at `ftcal --help`

    dataset = CalibrationDataset.load(path, columns=columns)
    note_dataset(path)
    for array, name, labels in ((dataset.raw, "raw reading", [f"s{k}" for k in range(dataset.n_channels)]),
                                (dataset.wrench, "wrench", list(dataset.axes))):
        big = np.abs(array) > MAX_TRAINING_MAGNITUDE
        if big.any():
            row, col = (int(v) for v in np.argwhere(big)[0])
            where = f"line {dataset.row_sources().where(row)[1]}" if path.suffix == ".csv" else \
                f"row {row} (rows counted from 0)"  # a .csv's rows are named by their lines
            raise CliError(f"{path}: {where}: a {name} of {array[row, col]:.6g} (column "
                           f"{labels[col]}), beyond the {MAX_TRAINING_MAGNITUDE:g} a calibration can square without "
                           "overflow; check the units and that line")
    return dataset


def parse_param(text: str) -> tuple[str, Any]:
    """argparse type of ``--param KEY=VALUE``: the value is read as JSON, else kept as text.

    Examples
    --------
    >>> parse_param("phase1_epochs=20"), parse_param("hidden_layer_sizes=[64, 64]")
    (('phase1_epochs', 20), ('hidden_layer_sizes', (64, 64)))
    """
    key, sep, value = text.partition("=")
    key = key.strip()
    if not sep or not key.isidentifier():
        raise argparse.ArgumentTypeError(f"{text!r} is not KEY=VALUE (e.g. phase1_epochs=50)")
    try:
        parsed = json.loads(value)
    except json.JSONDecodeError:
        parsed = value
    return key, tuple(parsed) if isinstance(parsed, list) else parsed


def dataset_alpha(dataset: CalibrationDataset, alpha: float | None) -> float | None:
    """``--alpha``, else the dataset's ``meta['alpha']`` (the sensor's Fmax / Tmax), else None."""
    if alpha is not None:
        return float(alpha)
    meta_alpha = dataset.meta.get("alpha")
    if meta_alpha is None:
        return None
    try:
        value = float(meta_alpha)
    except (TypeError, ValueError):
        value = float("nan")
    if not (value > 0 and value != float("inf")):
        raise CliError(f"dataset meta 'alpha' is {meta_alpha!r}, not a positive number; pass --alpha")
    return value


def calibrator_params(args: argparse.Namespace, dataset: CalibrationDataset) -> dict:
    """The calibrator's parameters of ``--param KEY=VALUE``, with the torque scale of :func:`dataset_alpha` unless a
    ``--param alpha=...`` gives one."""
    params = dict(args.param)
    alpha = dataset_alpha(dataset, args.alpha)
    if alpha is not None and "alpha" not in params:
        params["alpha"] = alpha
    return params


def evaluation_alpha(dataset: CalibrationDataset, alpha: float | None) -> float:
    """Torque scale for metrics: ``--alpha``, else the dataset's ``meta['alpha']``, else from its wrenches."""
    value = dataset_alpha(dataset, alpha)
    return alpha_from_wrenches(dataset.wrench, dataset.axes) if value is None else value


def check_fold_count(dataset: CalibrationDataset, cv: int, path) -> None:
    """Refuse ``--cv`` folds a dataset cannot fill (one sample per fold at least), before scikit-learn does in its
    own terms (``n_splits``)."""
    if dataset.n_samples < cv:
        raise CliError(f"{path} has {dataset.n_samples} sample(s), fewer than the {cv} folds of --cv; record more "
                       "load cases or lower --cv (each fold also needs enough samples left to fit on)")
