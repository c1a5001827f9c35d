"""The real-world benchmark (thesis V-B, Tables IV-V, Fig. 6) on the virtual experiment.

Pipeline: :func:`ftcal.experiment.simulate_experiment` writes the 7 x 155 load / no-load
run logs; :func:`ftcal.experiment.prepare_dataset` turns them into a dataset exactly as it
would real logs; each calibrator (built only through
:func:`ftcal.make_calibrator`) is fitted and scored on two splits a
practitioner would use:

``random20``
    A random 20 % of the poses held out (``ShuffleSplit``), the thesis' split
    ratio. Train and test share load configurations, so this measures how well
    the sphere is interpolated.
``leave-one-config-out``
    Seven folds, each holding out one whole load configuration
    (``LeaveOneGroupOut`` on the dataset's group). Every pose is predicted once
    by a model that never saw its load position: the honest test for a sensor
    later used with other tools.

Metrics (thesis IV-C) on the held-out predictions: the RMSE of eq. 18 (``rmse``, over all 6n
torque-scaled values: the figure every ftcal table prints), the per-sample RMSE of the
torque-scaled wrench (eq. 18 per row, ``alpha`` from the whole dataset so
that every model is scored alike), its mean and std over the samples (Table
IV's "within the dataset"), and relative force and torque errors (eq. 19,
Table V). The figure shows the distribution of per-sample RMSE per model
(histogram and the normal density of its mean and std, as Fig. 6).
"""

from __future__ import annotations

import contextlib
import platform
import tempfile
import time
from pathlib import Path
from typing import Sequence

import numpy as np
from sklearn.model_selection import LeaveOneGroupOut, ShuffleSplit

from ..io._dataset import CalibrationDataset
from ..experiment._experiment import prepare_dataset
from ..core._metrics import mean_std, per_sample_rmse, relative_errors, wrench_rmse
from ..calibrators._baselines import STOCK_BASELINE_NAMES
from ..compose._registry import training_schedule
from ._artificial import make_model
from ..robot._robot import load_robot
from ..experiment._virtual_experiment import DEFAULT_LOAD_MASS_KG, simulate_experiment
from ..core._wrench import alpha_from_wrenches

__all__ = ["run_real_world_benchmark", "real_world_markdown", "SPLIT_NAMES", "THESIS_TABLES_IV_V"]

#: Splits evaluated by :func:`run_real_world_benchmark`.
SPLIT_NAMES: tuple[str, ...] = ("random20", "leave-one-config-out")

#: The thesis' real-world results: model -> (RMSE mean, std, rel. force mean, std, rel. torque mean, std).
THESIS_TABLES_IV_V: dict[str, tuple[float, float, float, float, float, float]] = {
    "directional": (0.49, 0.24, 0.029, 0.026, 0.022, 0.020),
    "comparative": (0.69, 0.29, 0.021, 0.020, 0.045, 0.050),
    "linear": (0.78, 0.42, 0.041, 0.036, 0.0090, 0.0077),
}


def _folds(dataset: CalibrationDataset, split: str, random_state: int):
    if split == "random20":
        return ShuffleSplit(n_splits=1, test_size=0.2, random_state=random_state).split(dataset.raw)
    if split == "leave-one-config-out":
        return LeaveOneGroupOut().split(dataset.raw, groups=dataset.group)
    raise ValueError(f"unknown split {split!r}; choose from {SPLIT_NAMES}.")


def _evaluate(dataset, model_name, split, schedule, random_state, alpha):
    """Held-out predictions of one model (a registry name or a stock baseline's name) on one split."""
    y_true, y_pred, fit_s = [], [], 0.0
    for train, test in _folds(dataset, split, random_state):
        # alpha=None (every calibrator's default): the torque scale derived from the training wrenches
        est = make_model(model_name, n_channels=dataset.n_channels, alpha=None, schedule=schedule,
                         random_state=random_state)
        t0 = time.perf_counter()
        est.fit(dataset.raw[train], dataset.wrench[train])
        fit_s += time.perf_counter() - t0
        y_true.append(dataset.wrench[test])
        y_pred.append(est.predict(dataset.raw[test]))
    yt, yp = np.vstack(y_true), np.vstack(y_pred)
    rmse = per_sample_rmse(yt, yp, alpha)
    rf, rt = relative_errors(yt, yp)
    return {
        # only models with a training schedule (the networks) show it; stock baselines and closed forms do not
        "schedule": schedule if model_name not in STOCK_BASELINE_NAMES and training_schedule("short", model_name)
        else "-",
        "n_test": int(yt.shape[0]),
        "rmse": wrench_rmse(yt, yp, alpha),
        **{f"{name}_{k}": stat[k] for name, values in (("rmse", rmse), ("rel_force", rf), ("rel_torque", rt))
           for stat in [mean_std(values, ddof=0)] for k in ("mean", "std")},
        "fit_seconds": fit_s,
        "per_sample_rmse": rmse.tolist(),
    }


def _plot(results: dict, path: Path) -> Path:
    from matplotlib.figure import Figure

    from ..reporting._plots import model_color

    splits = list(results["splits"])
    fig = Figure(figsize=(6 * len(splits), 4))
    axes = fig.subplots(1, len(splits), squeeze=False)
    for ax, split in zip(axes[0], splits):
        per_model = results["splits"][split]
        top = max(max(r["per_sample_rmse"]) for r in per_model.values())
        grid = np.linspace(0, top, 400)
        for name, r in per_model.items():
            c = model_color(name)
            data = np.asarray(r["per_sample_rmse"])
            ax.hist(data, bins=40, range=(0, top), density=True, alpha=0.25, color=c)
            mu, sd = r["rmse_mean"], max(r["rmse_std"], 1e-12)
            ax.plot(grid, np.exp(-0.5 * ((grid - mu) / sd) ** 2) / (sd * np.sqrt(2 * np.pi)), color=c,
                    label=f"{name}: {mu:.3f} ± {r['rmse_std']:.3f}")
        ax.set(title=f"per-sample RMSE, split {split}", xlabel="RMSE of the torque-scaled wrench [N]", ylabel="density")
        ax.legend()
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=120)
    return path


def run_real_world_benchmark(
    *,
    models: Sequence[str] = ("linear", "comparative", "directional"),
    baselines: bool = True,
    splits: Sequence[str] = SPLIT_NAMES,
    schedule: str = "thesis",
    grouped_schedule: str = "short",
    load_mass: float = DEFAULT_LOAD_MASS_KG,
    subdivisions: int = 2,
    errors: str = "thesis",
    random_state: int = 0,
    log_dir: str | Path | None = None,
    plot_path: str | Path | None = None,
) -> dict:
    """Simulate the thesis' robot experiment, build the dataset from its logs, score the calibrators.

    Parameters
    ----------
    models : sequence of str
        Registry names (:data:`ftcal.compose.CALIBRATOR_NAMES`).
    baselines : bool, default=True
        Also score the stock scikit-learn baselines (:data:`ftcal.calibrators.STOCK_BASELINE_NAMES`) on the same
        splits: what every table compares ftcal with.
    splits : sequence of str
        Any of :data:`SPLIT_NAMES`.
    schedule : str, default="thesis"
        Training schedule on the ``random20`` split.
    grouped_schedule : str, default="short"
        Schedule on the 7-fold ``leave-one-config-out`` split (7 fits per model).
    load_mass : float, default=2.0
        External load [kg].
    subdivisions : int, default=2
        Icosphere level (2: 155 poses per sphere).
    errors : str, default="thesis"
        Error preset of the virtual sensor.
    random_state : int, default=0
        Seeds the experiment, the split and the models.
    log_dir : path, optional
        Where the run logs go (kept); default a temporary folder (removed).
    plot_path : path, optional
        PNG of the per-sample RMSE distributions (Fig. 6).

    Returns
    -------
    dict
        ``dataset`` (sizes, alpha), ``splits`` -> model -> metrics (including
        ``per_sample_rmse``), ``timing`` [s], ``machine``, ``settings``,
        ``thesis`` (Tables IV-V) and ``plot`` (path or None).

    Examples
    --------
    Icosahedron (12 directions, the tool-face-up one excluded) x 7 configurations:

    >>> res = run_real_world_benchmark(models=("linear",), splits=("random20",), subdivisions=0, baselines=False)
    >>> res["dataset"]["n_samples"], sorted(res["splits"]["random20"])
    (77, ['linear'])
    """
    t_start = time.perf_counter()
    timing = {}
    # no log_dir: a temporary folder, removed once the dataset is read
    with (tempfile.TemporaryDirectory(prefix="ftcal_real_world_") if log_dir is None
          else contextlib.nullcontext(log_dir)) as log_dir:
        robot = load_robot("kuka_iiwa14")
        t0 = time.perf_counter()
        paths = simulate_experiment(log_dir, robot=robot, load_mass=load_mass, subdivisions=subdivisions,
                                    errors=errors, random_state=random_state, overwrite=True)
        timing["simulate_s"] = time.perf_counter() - t0
        t0 = time.perf_counter()
        dataset = prepare_dataset(paths, robot, load_mass)
        timing["prepare_s"] = time.perf_counter() - t0
    alpha = alpha_from_wrenches(dataset.wrench)
    results: dict = {"splits": {}}
    for split in splits:
        sched = schedule if split == "random20" else grouped_schedule
        results["splits"][split] = {}
        for name in (*models, *(STOCK_BASELINE_NAMES if baselines else ())):
            t0 = time.perf_counter()
            results["splits"][split][name] = _evaluate(dataset, name, split, sched, random_state, alpha)
            timing[f"{split}/{name}_s"] = time.perf_counter() - t0
    timing["total_s"] = time.perf_counter() - t_start
    results.update(
        dataset={"n_samples": dataset.n_samples, "n_channels": dataset.n_channels, "alpha": alpha,
                 "n_configurations": int(len(set(dataset.group.tolist()))),
                 "pair_rotation_deg_max": dataset.meta["pair_rotation_deg_max"],
                 "force_norm_max_N": float(np.linalg.norm(dataset.wrench[:, :3], axis=1).max()),
                 "torque_norm_max_Nm": float(np.linalg.norm(dataset.wrench[:, 3:], axis=1).max())},
        timing=timing,
        machine={"platform": platform.platform(), "processor": platform.processor() or platform.machine(),
                 "python": platform.python_version()},
        settings={"models": list(models), "splits": list(splits), "schedule": schedule,
                  "grouped_schedule": grouped_schedule, "load_mass_kg": load_mass, "subdivisions": subdivisions,
                  "errors": errors, "random_state": random_state},
        thesis={k: dict(zip(("rmse_mean", "rmse_std", "rel_force_mean", "rel_force_std", "rel_torque_mean",
                             "rel_torque_std"), v)) for k, v in THESIS_TABLES_IV_V.items()},
        plot=str(_plot(results, Path(plot_path))) if plot_path is not None else None,
    )
    return results


def real_world_markdown(result: dict) -> str:
    """Tables IV-V of a :func:`run_real_world_benchmark` result as Markdown: per split, each model's per-sample RMSE
    and relative errors (mean ± std over the test samples) beside the thesis' values.

    Examples
    --------
    >>> result = {"dataset": {"n_samples": 60, "n_configurations": 4, "alpha": 10.0}, "splits": {"random20": {
    ...     "linear": {"schedule": "-", "n_test": 12, "rmse_mean": 0.5, "rmse_std": 0.1, "rel_force_mean": 0.02,
    ...                "rel_force_std": 0.01, "rel_torque_mean": 0.03, "rel_torque_std": 0.01}}}}
    >>> print(real_world_markdown(result).splitlines()[-1])
    | linear | - | 12 | 0.5 ± 0.1 | — | 0.02 ± 0.01 | — | 0.03 ± 0.01 | — |
    """
    ds = result["dataset"]
    lines = [
        f"Real-world benchmark (virtual experiment): {ds['n_samples']} samples, {ds['n_configurations']} load "
        f"configurations, alpha = {ds['alpha']:.4g} 1/m.",
    ]
    thesis = result.get("thesis", {})
    for split, per_model in result["splits"].items():
        lines += [
            "",
            f"### Split `{split}`",
            "",
            "| model | schedule | test samples | RMSE [N] | thesis T. IV | rel. force | thesis T. V | rel. torque | thesis T. V |",
            "|---|---|---|---|---|---|---|---|---|",
        ]
        for name, r in per_model.items():
            t = thesis.get(name)
            cells = [f"{r[key + '_mean']:.3g} ± {r[key + '_std']:.2g} | "  # ours, then the thesis'
                     + ("—" if t is None else f"{t[key + '_mean']:.3g} ± {t[key + '_std']:.2g}")
                     for key in ("rmse", "rel_force", "rel_torque")]
            lines.append(f"| {name} | {r['schedule']} | {r['n_test']} | {' | '.join(cells)} |")
    return "\n".join(lines)
