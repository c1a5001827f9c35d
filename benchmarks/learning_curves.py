#!/usr/bin/env python
"""Learning curves: held-out RMSE against the amount of calibration data — the thesis' central
claim (accuracy from limited calibration data), tested where it can hold.

Datasets come from the table :data:`FACTORIES` (name -> :class:`Factory`): each makes one full dataset per
seed (a train pool and a fixed test set) and a grid of training *sizes*, each a subset of the pool, so every
size of one seed is scored on the same test set. Adding a dataset is one line in that table, e.g. the
soft-sensor preset (its last 8 presses are the test set, :func:`soft_split`)::

    "soft": rows_factory(soft_split, sizes=(25, 50, 100, 200, 300)),

Artificial presets (``reconstructed``, ``asymmetric``): the size is (spheres, points per sphere); spheres
are the outermost of the thesis' four (``n_spheres`` of :func:`ftcal.make_artificial_dataset`), points the
first ``p`` of each sphere (the points of a sphere are independent draws, so that is a random subset).
The virtual robot (``robot_poses``, ``robot_configs``): the thesis' KUKA iiwa experiment (7 load
configurations x 155 poses, Pinocchio FK, 2 kg load, sensor errors of the ``reconstructed`` preset);
configurations 5 and 6 are the test set, the size is (configurations, poses per configuration) out of
configurations 0-4.

Every fit is cached as one JSON file under ``OUT/cache`` as soon as it ends (keyed by a hash of its
configuration, and holding a fingerprint of its training and test data,
:func:`ftcal.benchmark.data_fingerprint`: a record whose data the current code no longer makes is fitted again),
so the same command resumes; ``--aggregate-only`` writes the tables and plots from whatever is cached.
A fingerprint cannot tell older model code on the same data: ``--verify K`` fits again, with the current code,
the K cached records of each model and dataset with the fewest training rows (networks in the stack they
were trained in) and reports whether they reproduce (a record that does not is replaced by the new fit), as
the cache spans sessions and code versions.
Work is ordered so that the most informative results come first: the first seed of every dataset and size
with the closed-form models, then the networks, then further seeds, the kernel models, the ensembles, and
last ``auto`` (its fits are the longest: minutes each on thousands of rows). Network fits of one dataset,
seed and model (all sizes) train together as one stacked module (:func:`ftcal.networks.fit_stacked`).

Outputs in ``OUT``: ``learning_curves.md``, ``learning_curves.json``, ``learning_curves_<dataset>.png``.

Examples::

    python benchmarks/learning_curves.py --quick --out /tmp/lc-quick
    python benchmarks/learning_curves.py --seeds 3 --schedule short --out benchmarks/results/learning_curves
    python benchmarks/learning_curves.py --seeds 3 --schedule short --out benchmarks/results/learning_curves --aggregate-only
"""

from __future__ import annotations

import argparse
import hashlib
import itertools
import json
import sys
import time
import traceback
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ftcal.compose import CALIBRATOR_NAMES
from ftcal import make_artificial_dataset
from ftcal.core import wrench_rmse
from ftcal.benchmark import make_model
from ftcal.benchmark import data_fingerprint, package_versions, read_json_record
from ftcal.core import is_finite_number, plain_json, write_json
from ftcal.calibrators import STOCK_BASELINE_NAMES

from _output import int_at_least, jobs, output_files

DEFAULT_OUT = Path(__file__).resolve().parent / "out" / "learning_curves"
_FORMAT = 1

#: Models in the order they run (cheapest first): tiers 0-4 (see the module notes).
TIERS = (
    ("linear", "polynomial", "axis_nonlinear", "sk_linear", "sk_poly2", "sk_poly3"),
    ("directional", "comparative"),
    ("gaussian_process", "sk_kernel_ridge", "sk_gp"),
    ("directional_ensemble", "comparative_ensemble"),
    ("auto",),
)


@dataclass
class Pool:
    """One seed's data: the training pool (with what selects a subset), the fixed test set."""

    X: np.ndarray
    y: np.ndarray
    select: Callable[[tuple], np.ndarray]  # size -> row indices into X
    X_test: np.ndarray
    y_test: np.ndarray
    alpha: float
    noise_floor: float | None = None


@dataclass
class Factory:
    """A dataset of the learning curves: ``make(seed) -> Pool`` and its grid of sizes."""

    make: Callable[[int], Pool]
    sizes: tuple
    size_label: str  # what a size is, for the tables


def artificial_factory(preset: str, spheres=(1, 2, 3, 4), points=(10, 25, 100, 400, 1250)) -> Factory:
    """Spheres x points-per-sphere of one artificial preset (1250 points per sphere, 1250 test points)."""

    def make(seed: int) -> Pool:
        train, test, info = make_artificial_dataset(preset, random_state=seed, n_per_sphere=max(points), n_test=1250)
        sphere = train.group
        n_total = int(sphere.max()) + 1

        def select(size):
            k, p = size
            keep = [np.flatnonzero(sphere == s)[:p] for s in range(n_total - k, n_total)]  # the outermost k
            return np.concatenate(keep)

        return Pool(train.raw, train.wrench, select, test.raw, test.wrench, info["alpha"], info["noise_floor"])

    return Factory(make, tuple(itertools.product(spheres, points)), "(spheres, points per sphere)")


def rows_factory(make_dataset: Callable[[int], tuple], sizes) -> Factory:
    """A dataset given as ``make_dataset(seed) -> (train, test)`` CalibrationDatasets (or ``(train, test, info)``);
    a size is a number of training rows, a random subset (nested: smaller sizes are subsets of larger ones)."""

    def make(seed: int) -> Pool:
        train, test, *rest = make_dataset(seed)
        order = np.random.default_rng(seed).permutation(train.n_samples)
        alpha = (train.meta or {}).get("alpha") or 1.0
        floor = rest[0].get("noise_floor") if rest and isinstance(rest[0], dict) else None
        return Pool(train.raw, train.wrench, lambda size: order[: min(size[0], order.size)], test.raw, test.wrench,
                    float(alpha), floor)

    return Factory(make, tuple((int(s),) for s in sizes), "(training rows,)")


_ROBOT_CACHE: dict[tuple, object] = {}


def _robot_dataset(seed: int, errors: str):
    """The thesis' virtual experiment (7 configurations x 155 poses), one row per pose; cached per process."""
    if (seed, errors) not in _ROBOT_CACHE:
        import tempfile

        from ftcal.robot import load_robot
        from ftcal.experiment import prepare_dataset, simulate_experiment

        robot = load_robot()
        with tempfile.TemporaryDirectory() as tmp:
            paths = simulate_experiment(tmp, robot=robot, random_state=seed, errors=errors)
            _ROBOT_CACHE[seed, errors] = prepare_dataset(paths, robot)
    return _ROBOT_CACHE[seed, errors]


def robot_factory(kind: str, errors: str = "reconstructed") -> Factory:
    """Configurations 0-4 train, 5-6 test; ``kind`` "poses": 5 configurations x m poses; "configs": k x all.

    The sensor's errors: the ``reconstructed`` preset by default (with ``thesis`` errors the LTM sits at the
    noise floor and no model has anything to learn, RESULTS.md, "beyond the thesis")."""
    from ftcal.simulation import SensorProfile

    def make(seed: int) -> Pool:
        ds = _robot_dataset(seed, errors)
        group = np.asarray(ds.group)
        train_rows, test_rows = np.flatnonzero(group <= 4), np.flatnonzero(group >= 5)
        rng = np.random.default_rng(seed)
        order = {g: rng.permutation(np.flatnonzero(group == g)) for g in range(5)}

        def select(size):
            k, m = size
            return np.concatenate([order[g][:m] for g in range(k)])

        # indices of select() are into the whole dataset: the pool is the whole dataset, the test rows never selected
        return Pool(ds.raw, ds.wrench, select, ds.raw[test_rows], ds.wrench[test_rows], SensorProfile.default().alpha)

    if kind == "poses":
        return Factory(make, tuple((5, m) for m in (5, 10, 20, 40, 80, 1000)), "(configurations, poses per configuration)")
    return Factory(make, tuple((k, 1000) for k in (1, 2, 3, 4, 5)), "(configurations, poses per configuration)")


def soft_split(seed: int, test_presses: int = 8):
    """The soft-sensor preset of ``seed``: its last ``test_presses`` presses are the test set (a new
    recording), the other presses' rows the training pool."""
    from ftcal.simulation import make_soft_sensor_dataset

    d = make_soft_sensor_dataset(random_state=seed)
    test = np.isin(d.group, np.unique(d.group)[-test_presses:])
    # no floor: the reference noise is not this sensor's floor (its readings depend on the load history; what a
    # static map reaches is estimated by benchmarks/auto_vs_stock.py on the whole recording)
    return d.subset(np.flatnonzero(~test)), d.subset(np.flatnonzero(test)), {"noise_floor": None}


#: The datasets of the learning curves: adding one is one line.
FACTORIES: dict[str, Factory] = {
    "reconstructed": artificial_factory("reconstructed"),
    "asymmetric": artificial_factory("asymmetric"),
    "robot_poses": robot_factory("poses"),
    "robot_configs": robot_factory("configs"),
    "soft": rows_factory(soft_split, sizes=(25, 50, 100, 200, 300)),
}


# --------------------------------------------------------------------------- tasks and cache
def _hash(config: dict) -> str:
    return hashlib.sha256(json.dumps(config, sort_keys=True).encode()).hexdigest()[:12]


def make_tasks(factories, models, seeds, schedule) -> list[dict]:
    """Every (dataset, size, seed, model), most informative first (see the module notes)."""
    tasks = []
    tier_of = {m: next((i for i, t in enumerate(TIERS) if m in t), len(TIERS)) for m in models}
    tiers = sorted(set(tier_of.values()))
    for tier, seed in itertools.chain(((t, 0) for t in tiers[:2]), ((t, s) for t in tiers[:2] for s in seeds[1:]),
                                      ((t, s) for t in tiers[2:] for s in seeds)):
        if seed not in seeds:
            continue
        for name in factories:
            for size in FACTORIES[name].sizes:
                for model in (m for m in models if tier_of[m] == tier):
                    config = {"format": _FORMAT, "dataset": name, "size": list(size), "seed": seed, "model": model,
                              "schedule": schedule}
                    tasks.append({**config, "hash": _hash(config)})
    return tasks


def _cache_path(cache: Path, task: dict) -> Path:
    size = "x".join(str(s) for s in task["size"])
    return cache / task["dataset"] / f"{size}_s{task['seed']}_{task['model']}_{task['hash']}.json"


def data_key(pool: Pool, rows) -> str:
    """Fingerprint of what a fit of ``rows`` sees and is scored on (training rows, test set, torque scale)."""
    return data_fingerprint(pool.X[rows], pool.y[rows], pool.X_test, pool.y_test, [pool.alpha])


def _record(task, model, pool: Pool, rows, seconds: float, error: str | None = None) -> dict:
    rec = {k: task[k] for k in ("dataset", "size", "seed", "model", "schedule", "hash")}
    rec.update(n_train=int(len(rows)), fit_seconds=seconds, noise_floor=pool.noise_floor, error=error,
               data=data_key(pool, rows), versions=package_versions())
    if error is None:
        pred = model.predict(pool.X_test)
        rec["rmse"] = wrench_rmse(pool.y_test, pred, pool.alpha)
        rec["rmse_axes"] = np.sqrt(np.mean((pool.y_test - pred) ** 2, axis=0)).tolist()
        choice = getattr(model, "best_name_", None) or getattr(model, "chosen_", None)
        rec["auto_choice"] = None if choice is None else str(choice)
    else:
        rec["rmse"] = None
    return rec


def load_cached(cache: Path, tasks: list[dict]) -> tuple[list[dict], list[dict], int]:
    """The cached records of ``tasks`` that hold their fit's current data, the tasks still to fit, and how many of
    those have a record of other data.

    A record is used only if it is complete (:func:`_complete`) and its data fingerprint (``data``) is that of
    the rows the current code makes for its dataset, seed and size; a record from other data (an older
    simulator or robot model, another package version) or without a fingerprint is fitted again.
    """
    pools: dict[tuple, Pool] = {}
    records, pending, stale = [], [], 0
    for t in tasks:
        rec = read_json_record(_cache_path(cache, t), numbers=("n_train",), hash=t["hash"],
                               dataset=t["dataset"], size=t["size"], seed=t["seed"], model=t["model"])
        if rec is not None and _complete(rec):
            key = (t["dataset"], t["seed"])
            if key not in pools:
                pools[key] = FACTORIES[t["dataset"]].make(t["seed"])
            if rec.get("data") == data_key(pools[key], pools[key].select(tuple(t["size"]))):
                records.append(rec)
                continue
            stale += 1
        pending.append(t)
    return records, pending, stale


#: Relative RMSE difference up to which a refit reproduces a cached record (rounding, BLAS summation order).
REPRODUCED = 1e-4


def verify(records: list[dict], tasks: list[dict], per_group: int, n_jobs: int, stack: int,
           save) -> tuple[list[dict], dict, list[dict]]:
    """Fit again, with the current code, the ``per_group`` cached records of each model and dataset with the fewest
    training rows (then size and seed order), failed fits included.

    A record whose RMSE the refit does not reproduce (within :data:`REPRODUCED`, relative), or a failure whose
    refit succeeds, is replaced by the refit; a success whose refit fails (or gives no finite RMSE) is kept and
    counted as failed. A network is refitted in the stack it was trained in (``stacked_with``; records written
    before stacks were recorded: the stack :func:`_units` makes of the whole grid), as :func:`ftcal.networks.fit_stacked`
    rounds a stacked step otherwise than a lone one and training can amplify that. The other members of such a
    stack are fitted too: those not cached yet are returned as new records (and saved), the others left alone.
    Returns the records, per model the counts and the largest relative difference (None: none compared), and
    the new records.
    """
    from joblib import Parallel, delayed

    order = {t["hash"]: i for i, t in enumerate(tasks)}
    by_hash = {t["hash"]: t for t in tasks}
    chosen = []
    for group in dict.fromkeys((r["model"], r["dataset"]) for r in records):
        mine = sorted((r for r in records if (r["model"], r["dataset"]) == group),
                      key=lambda r: (r["n_train"], order[r["hash"]]))
        chosen += mine[:per_group]
    grid = {t["hash"]: tuple(u_t["hash"] for u_t in u) for u in _units(tasks, stack) for t in u}
    units = {}
    for r in chosen:
        stored = r.get("stacked_with")
        unit = tuple(stored) if isinstance(stored, list) and r["hash"] in stored and \
            all(isinstance(h, str) and h in by_hash for h in stored) else grid[r["hash"]]
        units[unit] = None
    refit = {rec["hash"]: rec for recs in Parallel(n_jobs=n_jobs)(
        delayed(run_unit)([by_hash[h] for h in unit]) for unit in units) for rec in recs}
    cached = {r["hash"] for r in records}
    new_records = [rec for h, rec in refit.items() if h not in cached and _complete(rec)]
    for rec in new_records:
        save(rec)
    report: dict = {}
    replaced = {}
    for old in chosen:
        new = refit[old["hash"]]
        entry = report.setdefault(old["model"], {"verified": 0, "reproduced": 0, "replaced": 0, "failed": 0,
                                                 "largest": None})
        entry["verified"] += 1
        where = f"{old['dataset']} {tuple(old['size'])} seed {old['seed']} {old['model']}"
        ok_new = new["error"] is None and is_finite_number(new["rmse"])
        if old["error"] is not None:  # a failure: reproduced if it fails again, replaced if it now fits
            entry["reproduced" if not ok_new else "replaced"] += 1
            if ok_new:
                save(new)
                replaced[old["hash"]] = new
            print(f"verify {where}: cached failure, refit {'fitted' if ok_new else 'failed again'}", flush=True)
            continue
        if not ok_new:
            entry["failed"] += 1
            why = new["error"] or f"RMSE {new['rmse']}"
            print(f"verify {where}: cached {old['rmse']:.6g}, refit failed ({why}): kept", flush=True)
            continue
        diff = abs(new["rmse"] - old["rmse"]) / old["rmse"]  # a cached RMSE is > 0 (_complete)
        entry["largest"] = max(entry["largest"] or 0.0, diff)
        if diff <= REPRODUCED:
            entry["reproduced"] += 1
        else:
            entry["replaced"] += 1
            save(new)
            replaced[old["hash"]] = new
        print(f"verify {where}: cached {old['rmse']:.6g}, refit {new['rmse']:.6g} ({diff:.1e})", flush=True)
    return [replaced.get(r["hash"], r) for r in records], report, new_records


def read_verification(path: Path, scope: dict) -> dict | None:
    """The last ``--verify`` report kept in ``path``, if it is one this script wrote for the same datasets, models,
    seeds and schedule (``scope``); None otherwise (missing, edited into something else, another run's)."""
    report = read_json_record(path, scope=scope)
    checked = None if report is None else report.get("models")
    if not isinstance(checked, dict) or not checked or not set(checked) <= set(scope["models"]) or \
            not is_finite_number(report.get("per_model")) or not is_finite_number(report.get("tolerance")):
        return None
    for entry in checked.values():
        counts = [entry.get(k) if isinstance(entry, dict) else None
                  for k in ("verified", "reproduced", "replaced", "failed")]
        largest = entry.get("largest") if isinstance(entry, dict) else None
        if not all(isinstance(c, int) and not isinstance(c, bool) and 0 <= c <= 10**6 for c in counts) or \
                counts[0] != sum(counts[1:]) or not (largest is None or is_finite_number(largest) and largest >= 0):
            return None
    if not (isinstance(report["per_model"], int) and report["per_model"] >= 1 and 0 < report["tolerance"] < 1):
        return None
    return report


def _complete(rec: dict) -> bool:
    """Whether a cached record is one this script wrote: a finite positive RMSE, or a failure with its message and
    no RMSE (None, or NaN in records written before failures had None); a noise floor that is a number or None."""
    scored = rec.get("error") is None and is_finite_number(rec.get("rmse")) and rec["rmse"] > 0
    failed = isinstance(rec.get("error"), str) and not is_finite_number(rec.get("rmse")) and \
        (rec.get("rmse") is None or isinstance(rec.get("rmse"), float))
    floor = rec.get("noise_floor")
    return (scored or failed) and isinstance(rec.get("size"), list) and \
        (floor is None or is_finite_number(floor) and floor >= 0)


def run_unit(unit: list[dict]) -> list[dict]:
    """Fit and score a unit of tasks (one fit, or several nets of one kind stacked). Runs in a worker."""
    import torch

    torch.set_num_threads(1)
    first = unit[0]
    pool = FACTORIES[first["dataset"]].make(first["seed"])
    n_channels = pool.X.shape[1]
    prepared = []
    for task in unit:
        rows = pool.select(tuple(task["size"]))
        seed = int(np.random.SeedSequence([task["seed"], len(rows)]).generate_state(1)[0] % (2**31 - 1))
        prepared.append((task, make_model(task["model"], n_channels=n_channels, alpha=pool.alpha,
                                          schedule=task["schedule"], random_state=seed), rows))
    start = time.perf_counter()
    try:
        if len(unit) == 1:
            task, model, rows = prepared[0]
            model.fit(pool.X[rows], pool.y[rows])
        else:
            from ftcal.networks import fit_stacked

            fit_stacked([m for _, m, _ in prepared], [pool.X[r] for _, _, r in prepared],
                        [pool.y[r] for _, _, r in prepared])
    except Exception as exc:  # a model that cannot fit this little data is a result too
        error = f"{type(exc).__name__}: {exc}"[:300]
        if len(unit) > 1:  # retry one by one so that one failure does not hide the others
            return [rec for task, _, _ in prepared for rec in run_unit([task])]
        traceback.print_exc(limit=1)
        return [_record(prepared[0][0], None, pool, prepared[0][2], time.perf_counter() - start, error)]
    share = (time.perf_counter() - start) / len(unit)
    records = [_record(task, model, pool, rows, share) for task, model, rows in prepared]
    if len(unit) > 1:  # the stack it was trained in: --verify refits it in the same one (fit_stacked's rounding)
        for rec in records:
            rec["stacked_with"] = [task["hash"] for task in unit]
    return records


def _units(pending: list[dict], stack: int) -> list[list[dict]]:
    """Network fits of one dataset, seed and model grouped (up to ``stack``), in task order; others alone."""
    nets = {"directional", "comparative"}
    units, open_groups = [], {}
    for task in pending:
        if stack > 1 and task["model"] in nets:
            key = (task["dataset"], task["seed"], task["model"])
            if key not in open_groups or len(open_groups[key]) >= stack:
                open_groups[key] = []
                units.append(open_groups[key])
            open_groups[key].append(task)
        else:
            units.append([task])
    return units


# --------------------------------------------------------------------------- summary
def summarise(records: list[dict], factories, models) -> dict:
    out = {}
    for name in factories:
        rows = []
        for size in FACTORIES[name].sizes:
            recs = [r for r in records if r["dataset"] == name and tuple(r["size"]) == tuple(size)]
            cell = {"size": list(size), "n_train": max((r["n_train"] for r in recs), default=None), "models": {}}
            floors = [r["noise_floor"] for r in recs if r["noise_floor"] is not None]
            cell["noise_floor"] = float(np.mean(floors)) if floors else None
            for m in models:
                vals = [r["rmse"] for r in recs if r["model"] == m]
                ok = [v for v in vals if is_finite_number(v)]
                cell["models"][m] = {"mean": float(np.mean(ok)) if ok else None,
                                     "std": float(np.std(ok, ddof=1)) if len(ok) > 1 else 0.0 if ok else None,
                                     "n": len(ok), "failed": len(vals) - len(ok),
                                     "choices": sorted({r.get("auto_choice") for r in recs
                                                        if r["model"] == m and r.get("auto_choice")})}
            done = {m: c["mean"] for m, c in cell["models"].items() if c["mean"] is not None}
            cell["best"] = min(done, key=done.get) if done else None
            rows.append(cell)
        out[name] = rows
    return out


def environments(records: list[dict]) -> dict:
    """How many records hold the package versions they were fitted with, and how many distinct sets of them."""
    kept = [json.dumps(r["versions"], sort_keys=True) for r in records if isinstance(r.get("versions"), dict)]
    return {"recorded": len(kept), "distinct": len(set(kept))}


def markdown(summary: dict, meta: dict, models) -> str:
    env = meta.get("environments") or {"recorded": 0, "distinct": 0}
    lines = [f"Learning curves: schedule `{meta['schedule']}`, seeds {meta['seeds']}; "
             f"{meta['n_complete']}/{meta['n_expected']} fits complete. RMSE eq. 18 [N] on the fixed test set, "
             "mean ± std over seeds (n = seeds done); **bold** = best mean; `x` = fit failed. Package versions "
             f"recorded with {env['recorded']} of the {meta['n_complete']} records ({env['distinct']} distinct sets; "
             "the other records predate the recording).", ""]
    for name, rows in summary.items():
        present = [m for m in models if any(r["models"][m]["n"] or r["models"][m]["failed"] for r in rows)]
        if not present:
            continue
        lines += [f"### `{name}` — size = {FACTORIES[name].size_label}", "",
                  "| size | train rows | noise floor | " + " | ".join(present) + " |", "|---" * (len(present) + 3) + "|"]
        for r in rows:
            cells = []
            for m in present:
                c = r["models"][m]
                if c["mean"] is None:
                    cells.append("x" if c["failed"] else "—")
                    continue
                txt = f"{c['mean']:.1f} ± {c['std']:.1f} ({c['n']})"
                cells.append(f"**{txt}**" if m == r["best"] else txt)
            nf = "—" if r["noise_floor"] is None else f"{r['noise_floor']:.1f}"
            lines.append(f"| {tuple(r['size'])} | {r['n_train'] or '—'} | {nf} | " + " | ".join(cells) + " |")
        choices = {tuple(r["size"]): r["models"].get("auto", {}).get("choices") for r in rows}
        if any(choices.values()):
            lines += ["", "auto's choices: " + "; ".join(f"{k}: {', '.join(v)}" for k, v in choices.items() if v)]
        lines.append("")
    check = meta.get("verification")
    if check:  # read_verification's checks: counts are integers, the largest difference a finite number or None
        lines += [f"Verification (`--verify {check['per_model']:g}`): the cached records of each model and dataset with "
                  f"the fewest training rows refitted with the current code; reproduced = RMSE within "
                  f"{check['tolerance']:g} (relative), or a failure that fails again; replaced = not reproduced (or a "
                  "failure that now fits), the refit kept instead; failed = the refit failed, the record kept. "
                  "Networks are refitted in the stack they were trained in (recorded since session 8; older records: "
                  "the stack a run of the whole grid makes).", "",
                  "| model | refitted | reproduced | replaced | failed | largest relative difference |",
                  "|---|---|---|---|---|---|"]
        for model, c in check["models"].items():
            largest = "—" if c["largest"] is None else f"{c['largest']:.1e}"
            lines.append(f"| {model} | {c['verified']} | {c['reproduced']} | {c['replaced']} | {c['failed']} | {largest} |")
        lines.append("")
    return "\n".join(lines)


def plot(name: str, rows: list[dict], models, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    first = sorted({r["size"][0] for r in rows})
    panels = first if len(first) > 1 and len({r["size"][1] for r in rows if len(r["size"]) > 1}) > 1 else [None]
    fig, axes = plt.subplots(1, len(panels), figsize=(4.2 * len(panels), 4.2), sharey=True, squeeze=False)
    for ax, panel in zip(axes[0], panels):
        sub = [r for r in rows if panel is None or r["size"][0] == panel]
        for m in models:
            pts = [(r["n_train"], r["models"][m]["mean"], r["models"][m]["std"]) for r in sub
                   if r["models"][m]["mean"] is not None]
            if pts:
                x, mu, sd = map(np.asarray, zip(*sorted(pts)))
                ls = "--" if m.startswith("sk_") else "-"
                ax.plot(x, mu, ls, marker="o", ms=3, label=m)
                ax.fill_between(x, mu - sd, mu + sd, alpha=0.15)
        floors = [(r["n_train"], r["noise_floor"]) for r in sub if r["noise_floor"] is not None and r["n_train"]]
        if floors:
            x, f = zip(*sorted(floors))
            ax.plot(x, f, "k:", label="noise floor")
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("training rows")
        ax.set_title(f"{name}" + ("" if panel is None else f", {panel} sphere(s)"), fontsize=9)
    axes[0][0].set_ylabel("held-out RMSE, eq. 18 [N]")
    axes[0][-1].legend(fontsize=6, ncol=2)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


# --------------------------------------------------------------------------- driver
def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--datasets", nargs="+", default=list(FACTORIES), choices=list(FACTORIES))
    p.add_argument("--models", nargs="+", default=[m for t in TIERS for m in t],
                   help=f"calibrators ({', '.join(CALIBRATOR_NAMES)}) and stock baselines ({', '.join(STOCK_BASELINE_NAMES)})")
    p.add_argument("--seeds", type=int_at_least(1, 100), default=3, help="seeds (datasets and model initialisations) per size")
    p.add_argument("--schedule", default="short", choices=["thesis", "short"])
    p.add_argument("--jobs", type=jobs, default=1, help="worker processes (-1: one per core)")
    p.add_argument("--stack", type=int_at_least(1), default=10, help="network fits of one dataset, seed and model trained together")
    p.add_argument("--quick", action="store_true", help="smoke mode: 1 seed, the smallest sizes, closed forms only")
    p.add_argument("--out", default=str(DEFAULT_OUT))
    p.add_argument("--aggregate-only", action="store_true")
    p.add_argument("--verify", type=int_at_least(0), default=0, metavar="K",
                   help="fit again the K cached records of each model and dataset with the fewest rows; replace "
                        "those that differ")
    p.add_argument("--force", action="store_true", help="replace output files this script did not write")
    return p


def main(argv: list[str] | None = None) -> int:
    from joblib import Parallel, delayed

    parser = build_parser()
    args = parser.parse_args(argv)
    seeds = list(range(1 if args.quick else args.seeds))
    unknown = [m for m in args.models if m not in tuple(CALIBRATOR_NAMES) + STOCK_BASELINE_NAMES]
    if unknown:
        parser.error(f"unknown models {unknown}; choose from {', '.join((*CALIBRATOR_NAMES, *STOCK_BASELINE_NAMES))}")
    models = [m for m in args.models if m in TIERS[0]] if args.quick else list(args.models)
    if not models:
        parser.error(f"--quick runs the closed-form models only ({', '.join(TIERS[0])}): name at least one of them")
    if args.verify and args.aggregate_only:
        parser.error("--verify fits again, --aggregate-only fits nothing: choose one")
    files = output_files(parser, args.out, args.force, ["learning_curves.md", "learning_curves.json"]
                         + [f"learning_curves_{name}.png" for name in args.datasets])
    out, cache = files.out_dir, files.out_dir / "cache"
    tasks = make_tasks(args.datasets, models, seeds, args.schedule)
    if args.quick:
        tasks = [t for t in tasks if t["size"][-1] <= 25 or t["size"] == [5, 5]]
    records, pending, stale = load_cached(cache, tasks)
    if stale:
        print(f"{stale} cached records are of other data than the current code makes: not used"
              + (" (run without --aggregate-only to fit them again)" if args.aggregate_only else ", fitted again"),
              flush=True)
    start = time.perf_counter()

    def write(path: Path, obj) -> None:
        try:
            write_json(path, obj, indent=None)
        except (OSError, FileExistsError) as exc:
            parser.error(f"cannot write the cache file {path}: {getattr(exc, 'strerror', None) or exc}")

    def save(rec: dict) -> None:
        write(_cache_path(cache, rec), rec)

    # the last --verify's report, kept with the cache and shown while the run's scope stays the same
    verification_file = cache / "verification.json"
    scope = {"datasets": list(args.datasets), "models": models, "seeds": seeds, "schedule": args.schedule,
             "quick": args.quick}
    verification = read_verification(verification_file, scope)
    if args.verify:
        records, checked, fitted = verify(records, tasks, args.verify, args.jobs, args.stack, save)
        records += fitted  # members of a verified stack that were not cached yet: fitted once, not again below
        done = {r["hash"] for r in fitted}
        pending = [t for t in pending if t["hash"] not in done]
        if checked:  # nothing cached to verify: the last report stays
            verification = {"per_model": args.verify, "tolerance": REPRODUCED, "scope": scope, "models": checked}
            write(verification_file, verification)
    if pending and not args.aggregate_only:
        gen = Parallel(n_jobs=args.jobs, return_as="generator")(delayed(run_unit)(u) for u in _units(pending, args.stack))
        for rec in itertools.chain.from_iterable(gen):
            save(rec)
            records.append(rec)
            score = "FAILED" if rec["error"] else f"RMSE {rec['rmse']:.2f}"
            print(f"[{len(records)}/{len(tasks)}] {rec['dataset']} {tuple(rec['size'])} seed {rec['seed']} "
                  f"{rec['model']}: {score} ({rec['n_train']} rows, {rec['fit_seconds']:.1f} s, "
                  f"elapsed {time.perf_counter() - start:.0f} s)" + (f" {rec['error']}" if rec["error"] else ""),
                  flush=True)
    summary = summarise(records, args.datasets, models)
    meta = {"schedule": args.schedule, "seeds": seeds, "models": models, "datasets": args.datasets,
            "n_expected": len(tasks), "n_complete": len(records), "quick": args.quick, "verification": verification,
            "environments": environments(records)}
    text = markdown(summary, meta, models)
    files.write_text("learning_curves.md", text)
    files.write_text("learning_curves.json", json.dumps(plain_json({"meta": meta, "summary": summary, "records": records})))
    for name, rows in summary.items():
        if any(r["models"][m]["n"] for r in rows for m in models):
            with files.write(f"learning_curves_{name}.png") as tmp:
                plot(name, rows, models, tmp)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
