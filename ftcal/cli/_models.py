"""Datasets and model files as the subcommands use them (thin wrappers that add context)."""

from __future__ import annotations

import argparse
import json
from pathlib import Path
from typing import Any

from ..io._dataset import CalibrationDataset
from ..core._wrench import alpha_from_wrenches
from ..core._files import MODEL_SUFFIX, model_file_name
from ._common import CliError

__all__ = [
    "MODEL_SUFFIX",
    "model_file_name",
    "model_label",
    "load_model_file",
    "load_dataset",
    "model_inputs",
    "parse_param",
    "dataset_alpha",
    "evaluation_alpha",
]

def model_label(path: Path) -> str:
    """Short name of a model file for tables and plots (its name without the suffix)."""
    name = Path(path).name
    return name[: -len(MODEL_SUFFIX)] if name.endswith(MODEL_SUFFIX) else Path(path).stem


def load_model_file(path: str | Path):
    """A fitted calibrator from a model file written by :func:`ftcal.save_model`."""
    import ftcal

    return ftcal.load_model(path)


def model_inputs(model, dataset: CalibrationDataset):
    """The ``X`` a fitted model takes from a dataset: the raw channels, plus the temperature column for a
    temperature-compensated model (one input more than the dataset has channels)."""
    from ..evaluation._calibration_report import model_inputs as library_model_inputs

    return library_model_inputs(model, dataset)


def load_dataset(path: str | Path, role: str = "dataset", columns=None) -> CalibrationDataset:
    """A :class:`~ftcal.CalibrationDataset` from ``.csv`` / ``.npz`` / ``.mat``; ``role`` names it in errors;
    ``columns`` (a :class:`~ftcal.io.ColumnMap`) maps other layouts and units."""
    path = Path(path)
    if not path.is_file():
        raise CliError(f"{path}: no such {role} file")
    return CalibrationDataset.load(path, columns=columns)


def parse_param(text: str) -> tuple[str, Any]:
    """argparse type of ``--param KEY=VALUE``: the value is read as JSON, else kept as text.

    Examples
    --------
    >>> parse_param("max_epochs=20"), parse_param("hidden_layer_sizes=[64, 64]")
    (('max_epochs', 20), ('hidden_layer_sizes', (64, 64)))
    """
    key, sep, value = text.partition("=")
    key = key.strip()
    if not sep or not key.isidentifier():
        raise argparse.ArgumentTypeError(f"{text!r} is not KEY=VALUE (e.g. max_epochs=50)")
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


def evaluation_alpha(dataset: CalibrationDataset, alpha: float | None) -> float:
    """Torque scale for metrics: ``--alpha``, else the dataset's ``meta['alpha']``, else from its wrenches."""
    value = dataset_alpha(dataset, alpha)
    return alpha_from_wrenches(dataset.wrench) if value is None else value
