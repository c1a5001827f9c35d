"""The demo job: one artificial dataset, the three calibrators, their comparison and plots.

This is what ``ftcal demo`` runs, as a function for notebooks and scripts. It
needs no files of the user's: it simulates a dataset of the thesis' kind
(section IV-A, default ``thesis`` error preset) with 2000 training samples on
the four spheres (the thesis uses 5000; 2000 keeps the demo near a minute on
2 cores) and 1250 continuous test samples, fits ``linear``,
``comparative`` and ``directional`` from the calibrator registry with the
``short`` training schedule, and compares them on the test set with the
torque scale of the sensor (alpha = 2000 N / 40 N·m = 50 m⁻¹).

``quick=True`` shrinks everything (100 training samples, a handful of epochs)
so the whole pipeline runs in seconds; its numbers mean nothing.
"""

from __future__ import annotations

import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from ..io._dataset import CalibrationDataset
from ..core._exceptions import FtcalError
from ..core._metrics import CalibrationMetrics, calibration_metrics

__all__ = ["DEMO_MODELS", "DemoResult", "demo_files", "run_demo"]

#: The calibrators the demo compares, in table order.
DEMO_MODELS: tuple[str, ...] = ("linear", "comparative", "directional")

#: Sizes of the demo dataset: (training points per sphere, test points).
_FULL_SIZES = (500, 1250)
_QUICK_SIZES = (25, 60)
#: Network parameters of the quick mode (on top of the short schedule).
_QUICK_PARAMS = dict(phase1_epochs=4, plateau_epochs=1, max_recover_epochs=1, hidden_layer_sizes=(16, 16))


@dataclass
class DemoResult:
    """What :func:`run_demo` produced.

    Attributes
    ----------
    train, test : CalibrationDataset
    info : dict
        The simulated dataset's facts (error parameters, ``noise_floor`` [N], ``alpha``).
    models : dict
        Name -> fitted calibrator.
    predictions : dict
        Name -> predicted test wrenches (n_test, 6) [N, N·m].
    reports : dict
        Name -> :class:`~ftcal.core.CalibrationMetrics` on the test set.
    fit_seconds : dict
        Name -> training wall time [s].
    table : str
        The comparison table (markdown).
    files : list of Path
        Files written (empty when ``out_dir`` was None).
    """

    train: CalibrationDataset
    test: CalibrationDataset
    info: dict
    models: dict = field(default_factory=dict)
    predictions: dict = field(default_factory=dict)
    reports: dict[str, CalibrationMetrics] = field(default_factory=dict)
    fit_seconds: dict = field(default_factory=dict)
    table: str = ""
    files: list[Path] = field(default_factory=list)


def demo_files(models: tuple[str, ...] = DEMO_MODELS) -> list[str]:
    """Names (relative to the output directory) of every file :func:`run_demo` writes."""
    from ..core._files import model_file_name
    from ..reporting._evaluation import EVALUATION_PLOTS, predicted_plot_name

    return (
        ["train.csv", "test.csv", "coverage.png", "metrics.json", "metrics.md"]
        + [f"models/{model_file_name(m)}" for m in models]
        + list(EVALUATION_PLOTS)
        + [predicted_plot_name(m) for m in models]
    )


def run_demo(
    out_dir: str | Path | None = None,
    *,
    preset: str = "thesis",
    quick: bool = False,
    random_state: int = 0,
    overwrite: bool = False,
    fit: Callable[[Any, np.ndarray, np.ndarray, str], Any] | None = None,
    log: Callable[[str], None] | None = None,
) -> DemoResult:
    """Simulate a dataset, fit the three calibrators, compare them, and write files and plots.

    Parameters
    ----------
    out_dir : str or Path, optional
        Where to write the datasets, model files, metrics and plots (see
        :func:`demo_files`); nothing is written when None.
    preset : str, default="thesis"
        Error preset of the simulated sensor.
    quick : bool, default=False
        Tiny data and a few epochs: a smoke test of the pipeline.
    random_state : int, default=0
        Seeds the data and every model.
    overwrite : bool, default=False
        Replace existing files in ``out_dir``; without it an existing file is an error
        raised before any work.
    fit : callable, optional
        ``fit(estimator, X, y, name)`` used to train each model (the CLI passes
        one with a progress bar); default ``estimator.fit(X, y)``.
    log : callable, optional
        Receives one status line per step.

    Returns
    -------
    DemoResult

    Examples
    --------
    The files it writes (``run_demo`` itself trains three models, so it is not
    run here; ``run_demo(quick=True).table`` takes a few seconds):

    >>> demo_files()[:3]
    ['train.csv', 'test.csv', 'coverage.png']
    """
    import ftcal

    from ..reporting._evaluation import comparison_table

    fit = fit or (lambda estimator, X, y, name: estimator.fit(X, y))
    log = log or (lambda message: None)
    out = None if out_dir is None else Path(out_dir)
    if out is not None and not overwrite:
        taken = [n for n in demo_files() if (out / n).exists()]
        if taken:
            raise FtcalError(f"{out / taken[0]} already exists.", parameter="out", value=str(out),
                             fix="pass {overwrite}, or another directory", settings={"overwrite": True})
    n_per_sphere, n_test = _QUICK_SIZES if quick else _FULL_SIZES
    log(f"simulating a '{preset}' dataset: {4 * n_per_sphere} training samples on 4 spheres, {n_test} test samples")
    train, test, info = ftcal.make_artificial_dataset(
        preset, random_state=random_state, n_per_sphere=n_per_sphere, n_test=n_test
    )
    result = DemoResult(train=train, test=test, info=info)
    alpha = float(info["alpha"])
    for name in DEMO_MODELS:
        estimator = ftcal.make_calibrator(name, schedule="short", random_state=random_state)
        if quick and "phase1_epochs" in estimator.get_params():
            estimator.set_params(**_QUICK_PARAMS)
        start = time.perf_counter()
        result.models[name] = fit(estimator, train.raw, train.wrench, name)
        result.fit_seconds[name] = time.perf_counter() - start
        result.predictions[name] = np.asarray(estimator.predict(test.raw), dtype=float)
        result.reports[name] = calibration_metrics(test.wrench, result.predictions[name], alpha=alpha)
        log(f"{name}: fitted in {result.fit_seconds[name]:.1f} s, test RMSE {result.reports[name].rmse:.3g} N")
    result.table = comparison_table(result.reports, info["noise_floor"])
    if out is not None:
        result.files = _write(out, result, alpha)
    return result


def _write(out: Path, result: DemoResult, alpha: float) -> list[Path]:
    import ftcal

    from ..reporting import _plots
    from ..core._files import model_file_name, write_json
    from ..reporting._evaluation import axis_table, predicted_plot_name, write_evaluation_plots, EVALUATION_PLOTS

    (out / "models").mkdir(parents=True, exist_ok=True)
    result.train.save(out / "train.csv", overwrite=True)  # the caller (ftcal demo) checked --force
    result.test.save(out / "test.csv", overwrite=True)
    _plots.plot_wrench_coverage(
        result.train.wrench, out / "coverage.png", alpha=alpha, title="Demo training wrenches (4 spheres)"
    )
    for name, model in result.models.items():
        ftcal.save_model(model, out / "models" / model_file_name(name), overwrite=True)
    write_json(out / "metrics.json", {
        "alpha": alpha,
        "noise_floor": result.info["noise_floor"],
        "preset": result.info["preset"],
        "fit_seconds": result.fit_seconds,
        "models": {name: r.to_dict() for name, r in result.reports.items()},
    })
    (out / "metrics.md").write_text(
        f"# ftcal demo (alpha = {alpha:.4g} 1/m)\n\n{result.table}\n\nRMSE per axis:\n\n{axis_table(result.reports)}\n",
        encoding="utf-8",
    )
    paths = {"distribution": out / EVALUATION_PLOTS[0], "axis": out / EVALUATION_PLOTS[1],
             **{name: out / predicted_plot_name(name) for name in result.models}}
    write_evaluation_plots(
        paths, result.test.wrench, result.predictions, alpha, result.info["noise_floor"], dataset_name="demo test set"
    )
    return [out / n for n in demo_files(tuple(result.models))]
