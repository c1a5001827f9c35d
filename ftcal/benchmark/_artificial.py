"""The artificial-data benchmark of the thesis (section IV-A, results V-A, Tables II-III, Fig. 5).

For every preset and dataset index ``0 .. n_datasets-1`` a dataset is drawn
with :func:`~ftcal.make_artificial_dataset`, every model is built with
:func:`~ftcal.make_calibrator`, fitted on the four-sphere train set and
scored on the continuous test set.

Resumable cache
---------------
Each (preset, dataset, model) result is one small JSON file
``<out_dir>/cache/<preset>/ds<index>_<model>_<config hash>.json``, written as
soon as that fit ends. A later call with the same configuration skips every
result already there, so a long run can be spread over many sessions (or
killed and restarted); results of another configuration (schedule, seed,
sizes, preset definition) have another hash and are never mixed in, and a
result holds a fingerprint of its data (:func:`~ftcal.benchmark.data_fingerprint`)
and the package versions it was fitted with, so one computed on data the
current code no longer makes is fitted again (results written before
fingerprints: when their sampled sensor errors or noise floor differ; a
change of the raw readings that leaves both alone goes unseen in those). The
summary is built from whatever is complete and reports the counts.

Outputs (in ``out_dir``)
------------------------
``artificial_results.json`` (everything), ``artificial_results.md`` (the
tables) and ``artificial_rmse_<preset>.png`` (Fig. 5). These are rewritten
only if the benchmark wrote them itself and nobody changed them since (a
manifest keeps their hashes); any other existing file of that name stops the
run with :class:`BenchmarkOutputExistsError` unless ``force=True``.

Statistics
----------
* RMSE (Table II): eq. 18 on the torque-scaled test wrench [N], per dataset;
  mean ± std (sample std, ``ddof=1``) across datasets.
* Relative errors (Table III): eq. 19 per test sample, averaged per dataset;
  mean ± std across datasets.
* Wilcoxon signed-rank test (two-sided) of the per-dataset RMSE of every
  model pair (but no pair of two stock baselines), paired by dataset. With fewer than 6 pairs even the most
  extreme outcome has p >= 0.0625, so the test cannot show a difference:
  p is reported as NaN with a note; likewise when every difference is zero.
* Noise floor: per dataset (see :mod:`ftcal.simulation._artificial`); mean ± std.
"""

from __future__ import annotations

import functools
import hashlib
import itertools
import json
import math
import time
import warnings
from collections.abc import Callable, Mapping, Sequence
from numbers import Integral
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed, effective_n_jobs
from sklearn.utils._param_validation import Interval

from ..simulation._artificial import make_artificial_dataset
from ..core._files import plain_json, write_json
from ._records import data_fingerprint, package_versions, read_json_record
from ..core._exceptions import CalibrationInputError
from ..core._metrics import calibration_metrics, mean_std, wrench_rmse
from ..core._validation import check_arguments, check_bool
from ._outputs import OutputFiles, check_file_name
from ..simulation._error_models import ErrorModel
from ..simulation._presets import MAX_DATASETS, default_test_distribution, error_preset
from ..simulation._sampling import check_dataset_arguments
from ..simulation._sensor import SensorProfile

__all__ = ["run_artificial_benchmark", "summarize_results", "wilcoxon_pvalue", "format_mean_std", "dataset_seeds",
           "THESIS_TABLES", "make_model"]

_FORMAT = 1
#: Sizes and epoch caps of ``quick=True`` (the smoke mode): 3 datasets, 100 points per sphere, 200 test points,
#: networks capped at 60 + 10 + 10 epochs.
QUICK = {"n_datasets": 3, "n_per_sphere": 100, "n_test": 200, "phase1_epochs": 60, "plateau_epochs": 10, "max_recover_epochs": 10}

#: The thesis' Tables II and III (mean, std), by our model names.
THESIS_TABLES = {
    "directional": {"rmse": (36.9, 3.44), "rel_force": (0.040, 0.0037), "rel_torque": (0.038, 0.0044)},
    "comparative": {"rmse": (48.3, 4.47), "rel_force": (0.044, 0.0042), "rel_torque": (0.042, 0.0043)},
    "linear": {"rmse": (62.3, 0.76), "rel_force": (0.070, 0.0007), "rel_torque": (0.062, 0.0005)},
}


# ----------------------------------------------------------------- statistics
def wilcoxon_pvalue(a: Sequence[float], b: Sequence[float]) -> tuple[float, str]:
    """Two-sided Wilcoxon signed-rank p-value of paired samples, with a note when it cannot be computed.

    Returns ``(nan, note)`` for fewer than 6 pairs or all-zero differences.

    Examples
    --------
    >>> wilcoxon_pvalue([1, 2, 3, 4, 5, 6], [2, 3, 4, 5, 6, 7])
    (0.03125, '')
    >>> wilcoxon_pvalue([1.0, 2.0], [1.5, 2.5])[1]
    'only 2 paired datasets; the signed-rank test needs at least 6 to reach p < 0.05'
    """
    from scipy.stats import wilcoxon

    a, b = np.asarray(a, dtype=float), np.asarray(b, dtype=float)
    if a.size < 6:
        return float("nan"), f"only {a.size} paired datasets; the signed-rank test needs at least 6 to reach p < 0.05"
    if np.all(a == b):
        return float("nan"), "all paired differences are zero; the test is undefined"
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        try:
            p = float(wilcoxon(a, b, alternative="two-sided").pvalue)
        except ValueError as exc:
            return float("nan"), f"scipy could not compute the test ({exc})"
    return p, ""


def summarize_results(results: list[dict], models: Sequence[str], presets: Sequence[str]) -> dict:
    """Tables II/III, noise floors and Wilcoxon p-values from per-result records.

    Each record needs ``preset``, ``dataset``, ``model``, ``rmse``,
    ``rel_force_mean``, ``rel_torque_mean`` and ``noise_floor``.

    Examples
    --------
    >>> recs = [dict(preset="p", dataset=i, model=m, rmse=r, rel_force_mean=0.1, rel_torque_mean=0.2,
    ...              noise_floor=1.0) for i, (m, r) in enumerate([("a", 2.0), ("a", 4.0)])]
    >>> s = summarize_results(recs, ["a"], ["p"])
    >>> s["p"]["models"]["a"]["rmse"]
    {'mean': 3.0, 'std': 1.414..., 'n': 2}
    """
    out: dict = {}
    across_datasets = functools.partial(mean_std, ddof=1)
    for preset in presets:
        recs = [r for r in results if r["preset"] == preset]
        by_model = {m: {r["dataset"]: r for r in recs if r["model"] == m} for m in models}
        floors = {r["dataset"]: r["noise_floor"] for r in recs}
        table = {}
        for m in models:
            rows = [by_model[m][i] for i in sorted(by_model[m])]
            table[m] = {
                **{name: across_datasets([r[key] for r in rows]) for name, key in
                   (("rmse", "rmse"), ("rel_force", "rel_force_mean"), ("rel_torque", "rel_torque_mean"))},
                "rmse_per_dataset": {str(r["dataset"]): r["rmse"] for r in rows},
                "n_datasets": len(rows),
            }
        pairs = {}
        for m1, m2 in itertools.combinations(models, 2):
            if m1.startswith("sk_") and m2.startswith("sk_"):
                continue  # the baselines are compared with ftcal's models, not with each other
            common = sorted(set(by_model[m1]) & set(by_model[m2]))
            p, note = wilcoxon_pvalue([by_model[m1][i]["rmse"] for i in common], [by_model[m2][i]["rmse"] for i in common])
            pairs[f"{m1} vs {m2}"] = {"p": p, "n": len(common), "note": note}
        out[preset] = {"models": table, "wilcoxon": pairs, "noise_floor": across_datasets(list(floors.values()))}
    return out


# ----------------------------------------------------------------- one result
def dataset_seeds(seed: int, index: int) -> tuple[int, int]:
    """(dataset seed, model seed) of dataset ``index`` under master ``seed``: the same data for every preset and model.

    Examples
    --------
    >>> dataset_seeds(0, 3) == dataset_seeds(0, 3) != dataset_seeds(0, 4)
    True
    """
    ss = np.random.SeedSequence(entropy=seed, spawn_key=(index,))
    data_seed, model_seed = ss.generate_state(2)
    return int(data_seed), int(model_seed % (2**31 - 1))


def _dataset(task: dict):
    """The task's dataset ``(train, test, info)`` and the sensor profile (the same for every model of the task's
    preset and dataset index)."""
    data_seed, _ = dataset_seeds(task["seed"], task["dataset"])
    profile = SensorProfile.default()
    return make_artificial_dataset(
        ErrorModel(**task["error_model"]), random_state=data_seed, profile=profile, n_per_sphere=task["n_per_sphere"],
        n_test=task["n_test"], test_distribution=task["test_distribution"], n_spheres=task.get("n_spheres", 4),
    ), profile


def _data_key(data, profile) -> str:
    """Fingerprint of a dataset ``(train, test, info)`` as a fit sees it (:func:`~ftcal.benchmark.data_fingerprint`)."""
    train, test, _ = data
    return data_fingerprint(train.raw, train.wrench, test.raw, test.wrench, [profile.alpha])


def _data_and_model(task: dict):
    """The task's dataset ``(train, test, info)``, its unfitted model and the sensor profile."""
    data, profile = _dataset(task)
    model = make_model(task["model"], n_channels=profile.n_channels, alpha=profile.alpha, schedule=task["schedule"],
                       random_state=dataset_seeds(task["seed"], task["dataset"])[1], overrides=task["overrides"])
    return data, model, profile


def make_model(name: str, *, n_channels: int, alpha: float, schedule: str = "thesis", random_state: int = 0,
               overrides: dict | None = None):
    """An unfitted model by name: a registered calibrator, or a stock scikit-learn baseline (``sk_*``).

    The stock baselines (:func:`~ftcal.calibrators.stock_baselines`) are what a
    user gets for free; every table shows them beside ftcal's calibrators.

    Examples
    --------
    >>> make_model("sk_linear", n_channels=6, alpha=50.0)
    LinearRegression()
    >>> make_model("linear", n_channels=6, alpha=50.0).alpha
    50.0
    """
    from ..calibrators._baselines import STOCK_BASELINE_NAMES, stock_baselines
    from ..compose._registry import make_calibrator

    if name in STOCK_BASELINE_NAMES:
        return stock_baselines(n_channels, random_state=random_state)[name]
    return make_calibrator(name, schedule=schedule, random_state=random_state, alpha=alpha, **(overrides or {}))


def _record(task: dict, data, model, profile, fit_seconds: float, stacked: int = 1) -> dict:
    """Score a fitted model on the task's test set: one cached result."""
    _, test, info = data
    report = calibration_metrics(test.wrench, model.predict(test.raw), alpha=profile.alpha)
    # ensembles: every member's own test RMSE, i.e. the seed-to-seed spread on this one dataset
    members = getattr(model, "estimators_", None)
    member_rmse = None if members is None else [
        wrench_rmse(test.wrench, m.predict(test.raw), profile.alpha) for m in members]
    history = getattr(getattr(model, "net_", None), "history", None)
    return {
        **{k: task[k] for k in ("preset", "dataset", "model", "config_hash")},
        "config": task["config"],
        **{k: getattr(report, k) for k in ("rmse", "rel_force_mean", "rel_torque_mean")},
        "report": report.to_dict(),
        "noise_floor": info["noise_floor"],
        "data": _data_key(data, profile),
        "errors": info["errors"],
        "fit_seconds": fit_seconds,
        "stacked": stacked,
        "epochs": None if history is None else len(history),
        "stop_reason": None if not history else history[-1].get("stop_reason"),
        "member_rmse": member_rmse,
        "versions": package_versions(),
    }


def _run_group(tasks: list[dict]) -> list[dict]:
    """Fit and score the tasks' models. Runs in a joblib worker.

    One task: one ordinary fit. Several (network models of one preset and
    model name on several datasets): the nets train together as one stacked
    module (:func:`~ftcal.networks.fit_stacked`); each record's ``fit_seconds`` is
    its share of that fit's wall time, ``stacked`` the number of nets.
    """
    # the networks limit their own threads during fit (n_threads, in the fitting thread): nothing process-wide
    prepared = [_data_and_model(task) for task in tasks]
    start = time.perf_counter()
    if len(tasks) == 1:
        (data, model, _), = prepared
        model.fit(data[0].raw, data[0].wrench)
    else:
        from ..networks._stacked import fit_stacked

        fit_stacked([m for _, m, _ in prepared], [d[0].raw for d, _, _ in prepared],
                    [d[0].wrench for d, _, _ in prepared])
    share = (time.perf_counter() - start) / len(tasks)
    return [_record(task, data, model, profile, share, len(tasks))
            for task, (data, model, profile) in zip(tasks, prepared)]


def _groups(pending: list[dict], stack: int) -> list[list[dict]]:
    """Pending tasks as work units: network fits of one preset and model in chunks of ``stack``; others alone."""
    from ..calibrators._base import calibration_tags
    from ..compose._registry import CALIBRATOR_NAMES, make_calibrator

    if stack <= 1:
        return [[t] for t in pending]
    groups, units = {}, []
    tags = {m: calibration_tags(make_calibrator(m)) for m in {t["model"] for t in pending} if m in CALIBRATOR_NAMES}
    stackable = {m: m in tags and tags[m].network and tags[m].stackable for m in {t["model"] for t in pending}}
    for task in pending:
        if stackable[task["model"]]:
            groups.setdefault((task["preset"], task["model"]), []).append(task)
        else:
            units.append([task])
    for chunk_of in groups.values():
        units += [chunk_of[i:i + stack] for i in range(0, len(chunk_of), stack)]
    return units


def format_mean_std(stat: dict, digits: int = 2) -> str:
    """``"mean ± std"`` of a :func:`~ftcal.core.mean_std` result, ``"—"`` when it counted nothing.

    Examples
    --------
    >>> format_mean_std({"mean": 36.91, "std": 3.444, "n": 30}, 1)
    '36.9 ± 3.4'
    >>> format_mean_std({"mean": 4.17, "std": 0.0, "n": 1}, 2)  # one value has no spread to show
    '4.17'
    """
    if stat["n"] == 0:
        return "—"
    if stat["n"] == 1:
        return f"{stat['mean']:.{digits}f}"
    return f"{stat['mean']:.{digits}f} ± {stat['std']:.{digits}f}"


def _thesis_cell(preset: str, model: str, key: str, digits: int) -> str:
    """The thesis' value for the presets meant to match its study (``thesis``, ``reconstructed``), else a dash."""
    ref = THESIS_TABLES.get(model, {}).get(key) if preset in ("thesis", "reconstructed") else None
    return "—" if ref is None else f"{ref[0]:.{digits}f} ± {ref[1]:.{digits + 1}g}"


def markdown_tables(summary: dict, meta: dict) -> str:
    """Markdown of Tables II-III (ours beside the thesis'), noise floors and Wilcoxon p-values."""
    lines = [
        f"Artificial benchmark: schedule `{meta['schedule']}`, seed {meta['seed']}, "
        f"{meta['n_per_sphere']} points per sphere, {meta['n_test']} test points"
        + (" (quick smoke mode)" if meta["quick"] else "") + ".",
        "",
    ]
    for preset, s in summary.items():
        nf = s["noise_floor"]
        distribution = meta.get("test_distributions", {}).get(preset, meta.get("test_distribution"))
        lines += [
            f"### Preset `{preset}`",
            "",
            f"Test loads: `{distribution}`. "
            f"Noise floor (perfect calibrator): {format_mean_std(nf, 2)} N over {nf['n']} datasets.",
            "",
            "| Model | datasets | RMSE [N] (ours) | RMSE (thesis T. II) | rel. force (ours) | rel. force (thesis T. III)"
            " | rel. torque (ours) | rel. torque (thesis T. III) |",
            "|---|---|---|---|---|---|---|---|",
        ]
        for m, t in s["models"].items():
            # ours beside the thesis', each with its digits
            cells = [f"{format_mean_std(t[key], ours)} | {_thesis_cell(preset, m, key, theirs)}"
                     for key, ours, theirs in (("rmse", 2, 1), ("rel_force", 4, 3), ("rel_torque", 4, 3))]
            lines.append(f"| {m} | {t['n_datasets']} | {' | '.join(cells)} |")
        lines += ["", "| Wilcoxon pair | paired datasets | p | note |", "|---|---|---|---|"]
        for pair, w in s["wilcoxon"].items():
            if w["n"] == 0:
                continue  # a model not run yet (the JSON keeps every pair)
            p = "NaN" if math.isnan(w["p"]) else f"{w['p']:.3g}"
            lines.append(f"| {pair} | {w['n']} | {p} | {w['note']} |")
        lines.append("")
    return "\n".join(lines)


# ----------------------------------------------------------------- driver
def _check_args(n_datasets, models, schedule, n_jobs, stack=1, **arguments) -> None:
    """Check the benchmark's arguments (``arguments``: ``seed``, ``n_per_sphere``, ``n_test``,
    ``test_distribution``, ``n_spheres``) before any work; the counts within the CLI's bounds."""
    from ..calibrators._baselines import STOCK_BASELINE_NAMES
    from ..compose._registry import CALIBRATOR_NAMES, SCHEDULE_NAMES

    seed = arguments.pop("seed")
    check_dataset_arguments("run_artificial_benchmark", **arguments)
    check_arguments("run_artificial_benchmark", {
        "n_datasets": [Interval(Integral, 1, MAX_DATASETS, closed="both")],
        # joblib's: None is 1, -1 every core, -2 all but one
        "n_jobs": [Interval(Integral, None, -1, closed="right"), Interval(Integral, 1, None, closed="left"), None],
        "stack": [Interval(Integral, 1, None, closed="left")],
        "seed": [Interval(Integral, 0, None, closed="left")],
    }, n_datasets=n_datasets, n_jobs=n_jobs, stack=stack, seed=seed)
    known = tuple(CALIBRATOR_NAMES) + STOCK_BASELINE_NAMES
    unknown = [m for m in models if m not in known]
    if unknown or not models:
        raise CalibrationInputError(f"unknown models {unknown or models}; choose from {known}.")
    if schedule not in SCHEDULE_NAMES:
        raise CalibrationInputError(f"unknown schedule {schedule!r}; choose one of {SCHEDULE_NAMES}.")


def _preset_models(presets: Sequence[str] | Mapping[str, ErrorModel]) -> dict[str, ErrorModel]:
    """Preset name -> error model: named presets looked up, a mapping's models checked."""
    if isinstance(presets, Mapping):
        bad = {k: v for k, v in presets.items() if not isinstance(v, ErrorModel)}
        if bad:
            raise CalibrationInputError(f"presets maps names to ErrorModel instances; got {bad!r:.120}.")
        chosen = dict(presets)
    else:
        chosen = {p: error_preset(p) for p in _names(presets, "presets", "('thesis',)")}
    if not chosen:
        raise CalibrationInputError("presets is empty: name at least one, e.g. ('thesis',).")
    for name in chosen:  # the name is a folder of the cache and part of the plot's file name
        check_file_name(name, "a preset name")
    return chosen


def _names(values, what: str, example: str) -> tuple:
    """``values`` as a tuple of names: one name alone counts as a list of one (not as its letters)."""
    if isinstance(values, str):
        return (values,)
    if not isinstance(values, (list, tuple)) or not all(isinstance(v, str) for v in values):
        raise CalibrationInputError(f"{what} must be a list of names, e.g. {example}; got {values!r:.120}.")
    return tuple(values)


def _tasks(n_datasets, presets: dict, models, schedule, seed, quick, n_per_sphere, n_test, test_distribution,
           n_spheres=4) -> list[dict]:
    from ..compose._registry import CALIBRATOR_NAMES, training_schedule

    tasks = []
    # dataset-major order: a run stopped early still covers every preset and model
    for index, preset, model in itertools.product(range(n_datasets), presets, models):
        overrides = {}
        if quick and model in CALIBRATOR_NAMES and training_schedule(schedule, model):
            overrides = {k: QUICK[k] for k in ("phase1_epochs", "plateau_epochs", "max_recover_epochs")}
        config = {
            "format": _FORMAT, "preset": preset, "error_model": presets[preset].to_dict(), "model": model,
            "schedule": schedule, "overrides": overrides, "seed": seed, "n_per_sphere": n_per_sphere,
            "n_test": n_test, "test_distribution": test_distribution or default_test_distribution(preset),
            **({} if n_spheres == 4 else {"n_spheres": int(n_spheres)}),  # 4: the hash of earlier caches
        }
        config_hash = hashlib.sha256(json.dumps(config, sort_keys=True).encode()).hexdigest()[:12]
        tasks.append({**config, "dataset": index, "config": config, "config_hash": config_hash})
    return tasks


def _cache_path(cache_dir: Path, task: dict) -> Path:
    """The cache file of a task or of its record (both hold ``preset``, ``dataset``, ``model``, ``config_hash``)."""
    return cache_dir / task["preset"] / f"ds{task['dataset']:03d}_{task['model']}_{task['config_hash']}.json"


def _load_cached(path: Path, task: dict, datasets: dict) -> dict | None:
    """The cached record of ``task``, or None: then the fit runs again.

    None when the file is missing, half-written, of another configuration, not a record this benchmark wrote
    (every figure it writes is a finite number), or of other data than the current code makes for the task: its
    fingerprint (``data``; records written before fingerprints have none), its sampled sensor errors
    (``errors``) or its noise floor (a figure of the test set's noise) differs. ``datasets`` keeps each ``(fingerprint, noise floor, sensor errors)`` computed, by dataset.
    """
    record = read_json_record(path, numbers=("rmse", "rel_force_mean", "rel_torque_mean", "noise_floor"),
                              config=task["config"], dataset=task["dataset"], preset=task["preset"], model=task["model"])
    if record is None:
        return None
    key = json.dumps({k: v for k, v in task["config"].items() if k not in ("model", "overrides", "schedule")},
                     sort_keys=True) + f"#{task['dataset']}"
    if key not in datasets:
        data, profile = _dataset(task)
        datasets[key] = (_data_key(data, profile), data[2]["noise_floor"], json.loads(json.dumps(data[2]["errors"])))
    fingerprint, floor, errors = datasets[key]
    same = record.get("data", fingerprint) == fingerprint and record.get("errors") == errors and \
        abs(record["noise_floor"] - floor) <= 1e-12 * max(abs(floor), 1e-300)
    return record if same else None


def _plot_presets(outputs: OutputFiles, summary: dict, presets: Sequence[str], models: Sequence[str]) -> dict:
    """Fig. 5 of each preset with results (``artificial_rmse_<preset>.png``): ``{"png_<preset>": path}``."""
    from ..reporting._plots import plot_error_distributions

    files = {}
    for preset in presets:
        per_model = {m: v for m in models if (v := list(summary[preset]["models"][m]["rmse_per_dataset"].values()))}
        if per_model:
            name = f"artificial_rmse_{preset}.png"
            with outputs.write(name) as tmp:
                plot_error_distributions(
                    per_model, tmp, noise_floor=summary[preset]["noise_floor"]["mean"],
                    title=f"RMSE across artificial datasets, preset '{preset}' (thesis Fig. 5)",
                )
            files[f"png_{preset}"] = str(outputs.out_dir / name)
    return files


def run_artificial_benchmark(
    n_datasets: int = 30,
    presets: Sequence[str] | Mapping[str, ErrorModel] = ("thesis",),
    models: Sequence[str] = ("linear", "comparative", "directional"),
    schedule: str = "thesis",
    seed: int = 0,
    n_jobs: int = 1,
    out_dir: str | Path = "benchmark-artificial",
    quick: bool = False,
    progress: Callable[[int, int, dict], None] | None = None,
    *,
    force: bool = False,
    compute: bool = True,
    n_per_sphere: int | None = None,
    n_test: int | None = None,
    test_distribution: str | None = None,
    plot: bool = True,
    stack: int = 1,
    n_spheres: int = 4,
) -> dict:
    """Run (or resume) the artificial benchmark and write its summary files.

    Parameters
    ----------
    n_datasets : int, default=30
        Datasets per preset (indices 0 .. n-1; the same data for every model).
    presets : sequence of str or mapping of str to ErrorModel, default=("thesis",)
        Error presets (:data:`~ftcal.simulation.ERROR_PRESETS`), or names mapped to
        error models of your own (e.g. a sweep of one parameter).
    models : sequence of str
        Registry names (:data:`~ftcal.compose.CALIBRATOR_NAMES`) and stock
        scikit-learn baselines (:data:`~ftcal.calibrators.STOCK_BASELINE_NAMES`,
        ``sk_linear`` ... ``sk_gp``), fitted on the same data.
    schedule : {"thesis", "short"}
        Training schedule of the networks.
    seed : int, default=0
        Master seed of datasets and model initialisations.
    n_jobs : int, default=1
        joblib workers. The backend is not fixed, so
        ``with joblib.parallel_config(backend=...)`` (e.g. a dask or ray
        cluster) takes effect.
    out_dir : str or Path
        Where the cache and the summary files go (created if missing).
    quick : bool, default=False
        Smoke mode: :data:`QUICK` sizes and epoch caps (well under a minute).
    progress : callable, optional
        ``progress(done, total, record)`` after each new result.
    force : bool, default=False
        Overwrite summary files the benchmark did not write itself.
    compute : bool, default=True
        ``False``: only aggregate what the cache already holds.
    n_per_sphere, n_test : int, optional
        Dataset sizes (default 1250 / 1250, or the quick sizes).
    test_distribution : {"radial", "box", "ball"}, optional
        See :mod:`ftcal.simulation._sampling`; default: each preset's own
        (``"ball"`` for ``reconstructed``, else ``"radial"``).
    plot : bool, default=True
        Write the Fig. 5 PNG per preset.
    stack : int, default=1
        Train up to ``stack`` network fits of one preset and model (on
        different datasets) together as one stacked module
        (:func:`~ftcal.networks.fit_stacked`): the same results up to float32
        rounding, about 10x less CPU time with 30. 1 fits one by one.
    n_spheres : int, default=4
        Training spheres, the outermost ones (see :func:`~ftcal.make_artificial_dataset`).

    Returns
    -------
    dict
        ``meta`` (configuration, counts, wall time), ``summary`` (per preset:
        ``models`` -> ``rmse`` / ``rel_force`` / ``rel_torque`` mean, std, n;
        ``wilcoxon``; ``noise_floor``), ``results`` (every record) and ``files``.
    """
    t0 = time.perf_counter()
    for name, flag in (("quick", quick), ("force", force), ("compute", compute), ("plot", plot)):
        check_bool(flag, name)  # force="no" must not mean yes
    if progress is not None and not callable(progress):
        raise CalibrationInputError(f"progress must be a function (done, total, record) or None; got {progress!r:.80}.")
    preset_models = _preset_models(presets)
    presets, models = tuple(preset_models), _names(models, "models", "('linear', 'directional')")
    _check_args(n_datasets, models, schedule, n_jobs, stack, seed=seed, n_per_sphere=n_per_sphere,
                n_test=n_test, test_distribution=test_distribution, n_spheres=n_spheres)
    if quick:
        n_datasets = min(int(n_datasets), QUICK["n_datasets"])
    n_per_sphere = int(n_per_sphere or (QUICK["n_per_sphere"] if quick else 1250))
    n_test = int(n_test or (QUICK["n_test"] if quick else 1250))
    outputs = OutputFiles(out_dir, force=force)
    out_dir = outputs.out_dir
    names = ["artificial_results.json", "artificial_results.md"] + (
        [f"artificial_rmse_{p}.png" for p in presets] if plot else [])
    outputs.check(names)  # fail before hours of work, not after

    cache_dir = out_dir / "cache"
    tasks = _tasks(int(n_datasets), preset_models, models, schedule, int(seed), quick, n_per_sphere, n_test,
                   test_distribution, n_spheres)
    results, pending, datasets = [], [], {}
    for task in tasks:
        rec = _load_cached(_cache_path(cache_dir, task), task, datasets)
        (results.append(rec) if rec is not None else pending.append(task))
    n_cached = len(results)
    if compute and pending:
        units = _groups(pending, int(stack))
        workers = min(effective_n_jobs(n_jobs), len(units))  # never a worker process without a fit to do
        gen = Parallel(n_jobs=workers, return_as="generator_unordered")(delayed(_run_group)(u) for u in units)
        for rec in itertools.chain.from_iterable(gen):
            write_json(_cache_path(cache_dir, rec), rec, indent=1)  # atomic: a killed run leaves no half file
            results.append(rec)
            if progress is not None:
                progress(len(results), len(tasks), rec)

    results.sort(key=lambda r: (presets.index(r["preset"]), r["dataset"], models.index(r["model"])))
    summary = summarize_results(results, models, presets)
    meta = {
        "n_datasets": int(n_datasets), "presets": list(presets), "models": list(models), "schedule": schedule,
        "seed": int(seed), "quick": bool(quick), "n_per_sphere": n_per_sphere, "n_spheres": int(n_spheres),
        "n_test": n_test, "test_distribution": test_distribution,
        "test_distributions": {p: test_distribution or default_test_distribution(p) for p in presets},
        "n_jobs": n_jobs, "stack": int(stack), "n_expected": len(tasks),
        "n_complete": len(results), "n_from_cache": n_cached, "n_computed": len(results) - n_cached,
    }
    files = _plot_presets(outputs, summary, presets, models) if plot else {}
    meta["wall_seconds"] = time.perf_counter() - t0
    files["markdown"] = str(outputs.write_text("artificial_results.md", markdown_tables(summary, meta)))
    files["json"] = str(out_dir / "artificial_results.json")
    payload = {"meta": meta, "summary": summary, "results": results, "files": files}
    outputs.write_text("artificial_results.json", json.dumps(plain_json(payload), indent=1))
    return payload


