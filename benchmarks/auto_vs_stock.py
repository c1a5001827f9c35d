"""``auto`` and ftcal's GP against the stock scikit-learn baselines, on data where those are strong or made to break auto.

Usage::

    nice -n 19 python benchmarks/auto_vs_stock.py [--out benchmarks/results/auto_vs_stock] [--case NAME ...]

Cases (each written to ``<case>.json`` in ``--out`` and skipped when that file exists, so a run resumes):

``soft``
    :func:`ftcal.simulation.make_soft_sensor_dataset` (418 rows, 8 channels), outer 5-fold
    shuffled CV: ``auto`` (default candidates, networks included) fitted on each outer training fold, the
    stock baselines and the LTM on the same folds; held-out RMSE (eq. 18), the GP's 2-std coverage, fit time.
    Its floor is not the reference noise: the readings depend on the load history, which no static map can
    undo. ``static_floor`` estimates what a static map can reach: flexible models fitted on 20 000 rows of
    the *same* sensor (same seed, more presses), scored on the 418 rows; the best of them. Shuffled folds
    put rows of one press (the same load history) on both sides of a split, so they can score below it.
``soft_grouped``
    The same with press-grouped 5-fold CV (``GroupKFold`` on the dataset's press column, given to ``auto``
    too): every press is scored by models that never saw it, as on a new recording.
``robot_held``
    :func:`ftcal.simulation.make_robot_held_dataset` (90 000 rows, 47 poses), outer pose-grouped 5-fold
    (``--robot-folds`` of them, default all 5): ``auto`` with the groups, baselines, LTM. Its floor is not
    the reference noise either: every pose has its own offset (mounting, thermal state) that no model can
    learn across poses. ``robot_static_floor`` measures what a static map reaches: flexible models fitted
    on the 90 000 rows of the *same* sensor recorded without the per-pose offsets (same seed,
    ``pose_offset=0``), scored on the held-out rows, offsets included; the best of them.
``thesis``, ``asymmetric``, ``reconstructed``
    :func:`ftcal.make_artificial_dataset` (5000 training rows, 1250 test rows), noise floor from the dataset.
``dead_weight_15``, ``dead_weight_30``, ``dead_weight_50``
    :func:`ftcal.simulation.make_dead_weight_dataset`: ``auto`` vs the LTM on a validation set
    with loads up to 2x the calibrated range (target: auto <= 1.1x the LTM), and the stock baselines fitted on
    the same rows: the best of them at 2x (an oracle: known only from the validation rows) and the one the same
    5 folds choose (what scikit-learn gives for free); added to an earlier run's JSON without refitting auto.

Cases made to break ``auto`` (each failure seen on a real sensor, reproduced on data made here):

``soft_nmm``
    A GP likelihood that overfits: the soft sensor's 418 rows with its 8 channels mixed into strongly
    correlated ones (each channel 0.8 of the mean of all plus 0.2 of its own) and the torques in N·mm (the
    file's unit, as a user who does not convert them), shuffled outer 5-fold.
``dead_weight_axis_groups``
    15 dead-weight rows of a 3-axis load cell (3 channels) and of a 6-axis sensor, one group per loaded axis
    (:func:`ftcal.simulation.make_dead_weight_dataset` with ``loaded_axes``), given to ``auto`` as groups: auto vs the
    LTM and the stock baselines at 2x the range, 3 seeds (target: auto <= 1.1x the LTM, never constant).
``robot_small``
    A robot-held grouped set where the stock kernel ridge is strong: 8000 rows of 41 poses
    (:func:`ftcal.simulation.make_robot_held_dataset`), outer pose-grouped 5-fold, auto given the groups.

Since the stock baselines became ``auto``'s candidates, ``auto / best stock`` <= 1.0 (or within its SE) is
what the design promises; the cases above test it where it failed.

Every RMSE is eq. 18 (all 6 n torque-scaled values, [N]). ``summary.md`` is rewritten from the parts found.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import time
from pathlib import Path

import numpy as np
from sklearn.model_selection import GroupKFold, KFold

import ftcal
from ftcal.core import alpha_from_wrenches
from ftcal.simulation import make_dead_weight_dataset, make_robot_held_dataset, make_soft_sensor_dataset
from ftcal.benchmark import read_json_record
from ftcal.benchmark import OutputFiles
from ftcal.calibrators import STOCK_BASELINE_NAMES, stock_baselines

from _output import output_files, table_or_stop

JOBS = 2  # processes of auto's candidate scoring (--jobs)
FILES: OutputFiles | None = None  # the output folder (--out), set by main; the static floors' caches go there
#: Rows the stock kernel baselines are fitted on (a random subset): ftcal's GP's default max_samples, as in auto.
#: (Cases run before this line was added used 2000; each case's JSON records its value.)
KERNEL_ROWS = 1000
ROBOT_FOLDS = 5  # outer pose-grouped folds of robot_held (--robot-folds)
CASES = ("dead_weight_axis_groups", "soft_nmm", "robot_small", "dead_weight_15", "dead_weight_30", "dead_weight_50",
         "soft", "soft_grouped", "thesis", "asymmetric", "reconstructed", "robot_held")


def rmse(y, pred, alpha):
    """Eq. 18: over all 6 n torque-scaled values [N]."""
    return ftcal.core.wrench_rmse(y, pred, alpha)


def outer(raw, wrench, groups, splits, alpha, seed=0, predictions: dict | None = None):
    """Fit auto, the LTM, ftcal's GP and the stock baselines on each outer split; held-out predictions (also put in
    ``predictions``, by model name, when given)."""
    names = ["auto", "linear", "gaussian_process", *stock_baselines(raw.shape[1])]
    jobs = JOBS
    pred = {n: np.full(wrench.shape, np.nan) for n in names}
    if predictions is not None:
        predictions.update(pred)
    seconds = {n: 0.0 for n in names}
    inside = []
    covered, counted = 0, 0
    for train, test in splits:
        g = None if groups is None else groups[train]
        models = {"auto": ftcal.AutoCalibrator(alpha=alpha, random_state=seed, n_jobs=jobs),
                  "linear": ftcal.LinearCalibrator(alpha=alpha),
                  "gaussian_process": ftcal.GaussianProcessCalibrator(alpha=alpha, random_state=seed),
                  **stock_baselines(raw.shape[1], max_kernel_samples=KERNEL_ROWS, random_state=seed)}
        for name, model in models.items():
            t0 = time.perf_counter()
            if name == "auto":
                model.fit(raw[train], wrench[train], groups=g)
                inside.append({"chosen": model.best_name_, "table": model.summary()})
            else:
                model.fit(raw[train], wrench[train])
            seconds[name] += time.perf_counter() - t0
            if name == "gaussian_process":
                pred[name][test], std = model.predict(raw[test], return_std=True)
                covered += int((np.abs(pred[name][test] - wrench[test]) <= 2 * std).sum())
                counted += std.size
            else:
                pred[name][test] = model.predict(raw[test])
            print(f"  {name}: {seconds[name]:.1f} s so far", flush=True)
    done = ~np.isnan(pred["auto"]).any(axis=1)
    scores = {n: rmse(wrench[done], p[done], alpha) for n, p in pred.items()}
    best_stock = min(v for n, v in scores.items() if n.startswith("sk_"))
    return {"rmse": scores, "fit_seconds_total": seconds, "n_outer_splits": len(inside),
            "auto_over_best_stock": scores["auto"] / best_stock, "auto_over_linear": scores["auto"] / scores["linear"],
            "gp_over_sk_gp": scores["gaussian_process"] / scores["sk_gp"],
            "gp_coverage_2std": covered / max(counted, 1), "auto_choices": [i["chosen"] for i in inside],
            "auto_table_first_split": inside[0]["table"], "n_train": int(len(splits[0][0]))}


def best_model(scores: dict) -> str:
    """The name of the least RMSE in ``scores``, a model that could not be scored (NaN, or ``null`` in a cached
    JSON) never counted as the best (``min`` over NaN depends on the order)."""
    finite = {name: value for name, value in scores.items() if value is not None and np.isfinite(value)}
    if not finite:
        raise SystemExit(f"auto_vs_stock.py: no model of {sorted(scores)} could be scored")
    return min(finite, key=finite.get)


def best_static_map(cache: str | None, setup) -> dict:
    """The best held-out RMSE of the models ``setup()`` gives, ``(models, known, test_raw, test_wrench, alpha,
    info)``, fitted on ``known`` (a large recording of the same sensor); kept in the output folder as ``cache``
    (a JSON file, written through :data:`FILES` so that its manifest knows it) once computed, so that a resumed
    run neither builds the data nor fits the models again."""
    cache = None if FILES is None else cache
    # a cache this script did not write (or one edited since) is not reused: it is computed again
    earlier = None if cache is None or not FILES.is_own(cache) else read_json_record(FILES.out_dir / cache,
                                                                                     numbers=("rmse",))
    if earlier is not None:
        return earlier
    models, known, test_raw, test_wrench, alpha, info = setup()
    scores = {n: rmse(test_wrench, m.fit(known.raw, known.wrench).predict(test_raw), alpha) for n, m in models.items()}
    result = {"rmse": scores[best_model(scores)], "by_model": scores, "n_rows": known.n_samples, **info}
    if cache is not None:
        FILES.write_text(cache, json.dumps(result, indent=1, default=float))
    return result


def static_floor(small, cache: str | None = None) -> dict:
    """What a static map reaches on ``small`` when fitted on 20 000 rows of the same soft sensor (best of three)."""
    def setup():
        big = make_soft_sensor_dataset(20000, n_zero=2300, n_presses=1770, random_state=small.meta["random_state"])
        alpha = small.meta["alpha"]
        models = {"sk_poly3": stock_baselines(8)["sk_poly3"],
                  "gaussian_process(max_samples=2000)": ftcal.GaussianProcessCalibrator(
                      alpha=alpha, max_samples=2000, selection_samples=500, per_output=False, random_state=0),
                  "axis_nonlinear": ftcal.AxisNonlinearCalibrator(alpha=alpha)}
        return models, big, small.raw, small.wrench, alpha, {}

    return best_static_map(cache, setup)


def robot_static_floor(d, splits, cache: str | None = None) -> dict:
    """What a static map reaches on the held-out rows of ``splits`` of the robot-held dataset ``d`` (best of three).

    The maps are fitted on all rows of the same sensor recorded without per-pose offsets (``pose_offset=0`` with
    the same seed: the same loads, sensor and noise), so they know the sensor's map as well as 90 000 rows tell;
    what is left on the held-out rows is the reference noise plus the held-out poses' own offsets.
    """
    def setup():
        clean = make_robot_held_dataset(d.n_samples, n_poses=int(np.unique(d.group).size),
                                        random_state=d.meta["random_state"], pose_offset=0.0)
        alpha = d.meta["alpha"]
        test = np.concatenate([t for _, t in splits])
        models = {"sk_poly2": stock_baselines(8)["sk_poly2"], "sk_poly3": stock_baselines(8)["sk_poly3"],
                  "axis_nonlinear": ftcal.AxisNonlinearCalibrator(alpha=alpha)}
        return models, clean, d.raw[test], d.wrench[test], alpha, {"n_test_rows": int(test.size)}

    return best_static_map(cache, setup)


def ratio_interval(wrench: np.ndarray, pred_a: np.ndarray, pred_b: np.ndarray, groups: np.ndarray, alpha: float,
                   n_boot: int = 2000, seed: int = 0) -> list[float]:
    """95 % interval of RMSE(a) / RMSE(b) (eq. 18) over the rows of ``groups`` resampled whole (a pose-level
    bootstrap: rows of one pose share its offset and are not independent)."""
    scale = np.r_[np.ones(3), np.full(3, alpha)]
    _, inverse = np.unique(groups, return_inverse=True)
    count = np.bincount(inverse)
    sums = [np.bincount(inverse, weights=(((p - wrench) * scale) ** 2).mean(axis=1)) for p in (pred_a, pred_b)]
    draws = np.random.default_rng(seed).integers(0, count.size, size=(n_boot, count.size))
    ratio = np.sqrt(sums[0][draws].sum(axis=1) / sums[1][draws].sum(axis=1))
    return [float(v) for v in np.percentile(ratio, [2.5, 97.5])]


def robot_floor_predictions(d, splits: list, floor: dict) -> np.ndarray:
    """The held-out predictions of the static floor's best map (fitted again on the offset-free recording)."""
    clean = make_robot_held_dataset(d.n_samples, n_poses=int(np.unique(d.group).size),
                                    random_state=d.meta["random_state"], pose_offset=0.0)
    best = best_model(floor["by_model"])
    model = stock_baselines(8)[best] if best.startswith("sk_") else ftcal.AxisNonlinearCalibrator(alpha=d.meta["alpha"])
    model.fit(clean.raw, clean.wrench)
    pred = np.full(d.wrench.shape, np.nan)
    for _, test in splits:
        pred[test] = model.predict(d.raw[test])
    return pred


def dead_weight_data(case: str, seed: int):
    """Calibration rows, validation rows (loads up to 2x the calibrated range) and alpha of a dead-weight case."""
    cal, val = make_dead_weight_dataset(int(case.rsplit("_", 1)[1]), random_state=seed)
    return cal, val, alpha_from_wrenches(cal.wrench)


def dead_weight_stock(case: str, result: dict) -> dict:
    """``result`` (a dead-weight case) with, per seed, the stock baselines' RMSE at 2x the range, fitted on the same
    rows, and the stock model a user would choose for free: the best on the calibration rows' 5 folds (the folds
    auto uses); added to an earlier run's JSON without refitting auto.

    The best stock model at 2x the range is known only from the validation rows themselves (an oracle): the
    stock model the folds choose is what scikit-learn gives for free."""
    from sklearn.base import clone

    from ftcal.model_selection import calibration_folds, held_out_predictions

    for o in result["seeds"]:
        if "stock_chosen_on_folds" in o:
            continue
        cal, val, alpha = dead_weight_data(case, o["seed"])
        models = stock_baselines(cal.raw.shape[1], random_state=o["seed"])
        o["stock_rmse_2x"] = {name: rmse(val.wrench, clone(model).fit(cal.raw, cal.wrench).predict(val.raw), alpha)
                              for name, model in models.items()}
        o["auto_over_best_stock"] = o["auto_rmse_2x"] / min(o["stock_rmse_2x"].values())
        folds = calibration_folds(len(cal.raw), None, 5, o["seed"])  # auto's (the sets repeat no row)
        o["stock_fold_rmse"] = {name: rmse(cal.wrench, held_out_predictions(model, cal.raw, cal.wrench,
                                                                            folds=folds)[1], alpha)
                                for name, model in models.items()}
        chosen = best_model(o["stock_fold_rmse"])
        o["stock_chosen_on_folds"] = chosen
        o["auto_over_fold_chosen_stock"] = o["auto_rmse_2x"] / o["stock_rmse_2x"][chosen]
    return result


def run_case(case: str) -> dict:
    if case == "dead_weight_axis_groups":
        out = []
        for axes, channels in ((3, 3), (6, 6)):
            for seed in range(3):
                cal, val = make_dead_weight_dataset(15, loaded_axes=axes, n_channels=channels, random_state=seed)
                alpha = alpha_from_wrenches(cal.wrench)
                t0 = time.perf_counter()
                try:
                    auto = ftcal.AutoCalibrator(alpha=alpha, random_state=seed, n_jobs=JOBS).fit(
                        cal.raw, cal.wrench, groups=cal.group)
                except ftcal.core.CalibrationInputError as exc:  # a clear refusal is an allowed outcome
                    out.append({"axes": axes, "seed": seed, "refused": str(exc)})
                    continue
                fit_s = time.perf_counter() - t0
                pred = auto.predict(val.raw)
                ltm = ftcal.LinearCalibrator(alpha=alpha).fit(cal.raw, cal.wrench)
                r_auto, r_ltm = rmse(val.wrench, pred, alpha), rmse(val.wrench, ltm.predict(val.raw), alpha)
                stock = {name: rmse(val.wrench, model.fit(cal.raw, cal.wrench).predict(val.raw), alpha)
                         for name, model in stock_baselines(channels, random_state=seed).items()}
                out.append({"axes": axes, "seed": seed, "chosen": auto.best_name_, "folds": auto.comparison_["folds"],
                            "auto_rmse_2x": r_auto, "linear_rmse_2x": r_ltm, "auto_over_linear": r_auto / r_ltm,
                            "stock_rmse_2x": stock, "auto_over_best_stock": r_auto / min(stock.values()),
                            "constant": bool((np.ptp(pred, axis=0)[:axes] == 0).any()), "fit_seconds": fit_s,
                            "why": auto.comparison_["why"]})
        scored = [o for o in out if "auto_over_linear" in o]
        return {"seeds": out, "worst_auto_over_linear": max((o["auto_over_linear"] for o in scored), default=None),
                "any_constant": any(o["constant"] for o in scored)}
    if case == "soft_nmm":
        d = make_soft_sensor_dataset()
        raw = 0.8 * d.raw.mean(axis=1, keepdims=True) + 0.2 * d.raw  # strongly correlated channels
        wrench = d.wrench * np.r_[np.ones(3), np.full(3, 1000.0)]  # torques in N·mm, as the file had them
        splits = list(KFold(5, shuffle=True, random_state=0).split(raw))
        return {**outer(raw, wrench, None, splits, alpha_from_wrenches(wrench)), "n_samples": d.n_samples,
                "noise_floor": d.meta["noise_floor_rmse"]}
    if case == "robot_small":
        d = make_robot_held_dataset(8000, n_poses=41, random_state=0)
        splits = list(GroupKFold(5).split(d.raw, groups=d.group))
        return {**outer(d.raw, d.wrench, d.group, splits, d.meta["alpha"]), "n_samples": d.n_samples,
                "n_poses": 41, "noise_floor": d.meta["noise_floor_rmse"]}
    if case.startswith("dead_weight_"):
        out = []
        for seed in range(3):
            cal, val, alpha = dead_weight_data(case, seed)
            t0 = time.perf_counter()
            auto = ftcal.AutoCalibrator(alpha=alpha, random_state=seed, n_jobs=JOBS).fit(cal.raw, cal.wrench)
            fit_s = time.perf_counter() - t0
            ltm = ftcal.LinearCalibrator(alpha=alpha).fit(cal.raw, cal.wrench)
            r_auto, r_ltm = rmse(val.wrench, auto.predict(val.raw), alpha), rmse(val.wrench, ltm.predict(val.raw), alpha)
            out.append({"seed": seed, "chosen": auto.best_name_, "auto_rmse_2x": r_auto, "linear_rmse_2x": r_ltm,
                        "auto_over_linear": r_auto / r_ltm, "fit_seconds": fit_s,
                        "out_of_range_flagged": float(np.mean(auto.out_of_range(val.raw)))
                        if hasattr(auto, "out_of_range") else None})
        return dead_weight_stock(case, {"seeds": out, "worst_auto_over_linear": max(o["auto_over_linear"] for o in out)})
    if case == "soft":
        d = make_soft_sensor_dataset()
        splits = list(KFold(5, shuffle=True, random_state=0).split(d.raw))
        return {**outer(d.raw, d.wrench, None, splits, d.meta["alpha"]), "noise_floor": d.meta["noise_floor_rmse"],
                "static_floor": static_floor(d, "soft_static_floor.json"), "n_samples": d.n_samples}
    if case == "soft_grouped":
        d = make_soft_sensor_dataset()
        splits = list(GroupKFold(5).split(d.raw, groups=d.group))
        return {**outer(d.raw, d.wrench, d.group, splits, d.meta["alpha"]), "noise_floor": d.meta["noise_floor_rmse"],
                "static_floor": static_floor(d, "soft_static_floor.json"), "n_samples": d.n_samples}
    if case == "robot_held":
        d = make_robot_held_dataset()
        splits = list(GroupKFold(5).split(d.raw, groups=d.group))[:ROBOT_FOLDS]
        pred = {}
        res = outer(d.raw, d.wrench, d.group, splits, d.meta["alpha"], predictions=pred)
        floor = robot_static_floor(d, splits, f"robot_static_floor_{len(splits)}.json")
        rows = np.concatenate([t for _, t in splits])
        best_stock = min((n for n in res["rmse"] if n.startswith("sk_")), key=res["rmse"].get)
        interval = {"auto / static floor": (pred["auto"], robot_floor_predictions(d, splits, floor)),
                    f"auto / best stock ({best_stock})": (pred["auto"], pred[best_stock])}
        return {**res, "noise_floor": d.meta["noise_floor_rmse"], "static_floor": floor,
                "ratio_95_interval_pose_bootstrap": {
                    name: ratio_interval(d.wrench[rows], a[rows], b[rows], d.group[rows], d.meta["alpha"])
                    for name, (a, b) in interval.items()},
                "n_samples": d.n_samples, "n_poses": int(np.unique(d.group).size)}
    train, test, info = ftcal.make_artificial_dataset(case, random_state=0)
    raw = np.vstack([train.raw, test.raw])
    wrench = np.vstack([train.wrench, test.wrench])
    n = train.n_samples
    alpha = alpha_from_wrenches(train.wrench)
    res = outer(raw, wrench, None, [(np.arange(n), np.arange(n, n + test.n_samples))], alpha)
    return {**res, "info": {k: v for k, v in info.items() if isinstance(v, (int, float, str))}}


def case_training_set(case: str) -> tuple:
    """``(raw, wrench, groups, alpha)`` of the rows ``auto`` is fitted on first in ``case`` (its first outer
    training fold, or its calibration rows with seed 0)."""
    if case == "dead_weight_axis_groups":
        cal, _ = make_dead_weight_dataset(15, loaded_axes=6, n_channels=6, random_state=0)
        return cal.raw, cal.wrench, cal.group, alpha_from_wrenches(cal.wrench)
    if case.startswith("dead_weight_"):
        cal, _, alpha = dead_weight_data(case, 0)
        return cal.raw, cal.wrench, None, alpha
    if case in ("soft", "soft_grouped", "soft_nmm"):
        d = make_soft_sensor_dataset()
        raw, wrench, groups = d.raw, d.wrench, d.group if case == "soft_grouped" else None
        if case == "soft_nmm":
            raw = 0.8 * d.raw.mean(axis=1, keepdims=True) + 0.2 * d.raw
            wrench = d.wrench * np.r_[np.ones(3), np.full(3, 1000.0)]
        splits = GroupKFold(5).split(raw, groups=groups) if groups is not None else \
            KFold(5, shuffle=True, random_state=0).split(raw)
        train = next(iter(splits))[0]
        return raw[train], wrench[train], None if groups is None else groups[train], alpha_from_wrenches(wrench)
    if case in ("robot_small", "robot_held"):
        d = make_robot_held_dataset(8000, n_poses=41, random_state=0) if case == "robot_small" else \
            make_robot_held_dataset()
        train = next(iter(GroupKFold(5).split(d.raw, groups=d.group)))[0]
        return d.raw[train], d.wrench[train], d.group[train], d.meta["alpha"]
    train, _, _ = ftcal.make_artificial_dataset(case, random_state=0)
    return train.raw, train.wrench, None, alpha_from_wrenches(train.wrench)


def race_check(case: str) -> dict:
    """``auto`` raced (the default) and in full (``race=False``) on the same rows, seed and fold plan: the two
    choices, the raced choice against the full choice on the full comparison's folds (paired SE, symmetric
    words: the race must not cost more than noise), which candidates the race stopped and why, and both times."""
    raw, wrench, groups, alpha = case_training_set(case)
    out = {"n_train": int(len(raw)), "groups": None if groups is None else int(np.unique(groups).size)}
    fits = {}
    for race in (True, False):
        t0 = time.perf_counter()
        fits[race] = ftcal.AutoCalibrator(alpha=alpha, random_state=0, n_jobs=JOBS, race=race).fit(
            raw, wrench, groups=groups)
        out["raced_seconds" if race else "full_seconds"] = time.perf_counter() - t0
        print(f"  race={race}: {out['raced_seconds' if race else 'full_seconds']:.1f} s, chose "
              f"{fits[race].best_name_}", flush=True)
    raced, full = fits[True].comparison_, fits[False].comparison_
    assert raced.plan.same_folds(full.plan)
    out.update(raced_choice=raced.chosen, full_choice=full.chosen,
               stopped={r.name: r.reason for r in raced.rows if r.status.name == "STOPPED"},
               raced_table=raced.table(), full_table=full.table())
    if raced.chosen == full.chosen:
        out.update(verdict="equivalent", words=f"the same choice ({raced.chosen})")
    elif raced.chosen in [r.name for r in full.scored()]:
        d = full.paired(raced.chosen, full.chosen)
        out.update(verdict=d.verdict, words=d.words(), difference=d.difference, paired_se=d.paired_se)
    else:  # the raced choice is a stack of other members than the full one's: compare on held-out figures
        out.update(verdict="not comparable", words=f"{raced.chosen} is not a row of the full comparison")
    return out


def race_summary(out: Path) -> str:
    rows = ["| case | rows | raced choice | full choice | raced vs full (paired SE) | stopped early | raced s | full s |",
            "|---|---|---|---|---|---|---|---|"]
    for case in CASES:
        r = read_json_record(out / f"race_{case}.json")
        if r is None:
            rows.append(f"| {case} | not run | | | | | | |")
            continue
        rows.append(f"| {case} | {r['n_train']} | {r['raced_choice']} | {r['full_choice']} | {r['words']} | "
                    f"{', '.join(r['stopped']) or 'none'} | {r['raced_seconds']:.0f} | {r['full_seconds']:.0f} |")
    return "\n".join(rows)


def summary(out: Path) -> str:
    """The table of every case result in ``out`` (see :func:`table_or_stop`)."""
    return table_or_stop("auto_vs_stock.py", out, _summary)


def _summary(out: Path) -> str:
    lines = ["| case | training rows | auto | LTM | ftcal GP | sk_gp | best stock | auto / best stock | floor | "
             "auto / floor | ftcal GP / sk_gp | GP 2-std coverage | auto choices | auto fit [s] a fold |",
             "|" + "---|" * 14]
    for case in CASES:
        path = out / f"{case}.json"
        r = read_json_record(path)
        if r is None or case.startswith("dead_weight"):
            continue
        s = r["rmse"]
        best = min(v for n, v in s.items() if n.startswith("sk_"))
        # the soft and robot-held sensors' floor is what a static map reaches (history, per-pose offsets);
        # the others' the reference noise
        floor = r["static_floor"]["rmse"] if "static_floor" in r else r.get("noise_floor", r.get("info", {}).get("noise_floor"))
        floor_cells = ("", "") if floor is None else (f"{floor:.4g}", f"{s['auto'] / floor:.3f}")
        lines.append(f"| {case} | {r['n_train']} | {s['auto']:.4g} | {s['linear']:.4g} | {s['gaussian_process']:.4g} | "
                     f"{s['sk_gp']:.4g} | {best:.4g} | {r['auto_over_best_stock']:.3f} | {floor_cells[0]} | "
                     f"{floor_cells[1]} | {r['gp_over_sk_gp']:.3f} | "
                     f"{r['gp_coverage_2std']:.3f} | {', '.join(sorted(set(r['auto_choices'])))} | "
                     f"{r['fit_seconds_total']['auto'] / r['n_outer_splits']:.0f} |")
    lines += ["", "| dead-weight rows | seed | auto chose | auto RMSE at 2x range | LTM | auto / LTM | "
              + " | ".join(STOCK_BASELINE_NAMES) + " | auto / best stock at 2x (an oracle) | stock model the folds "
              "choose | auto / it | fit [s] |", "|" + "---|" * 15]
    for case in CASES:
        path = out / f"{case}.json"
        r = read_json_record(path)
        if r is not None and case.startswith("dead_weight") and case != "dead_weight_axis_groups":
            for o in r["seeds"]:
                stock = o.get("stock_rmse_2x", {})
                lines.append(f"| {case.rsplit('_', 1)[1]} | {o['seed']} | {o['chosen']} | {o['auto_rmse_2x']:.4g} | "
                             f"{o['linear_rmse_2x']:.4g} | {o['auto_over_linear']:.3f} | "
                             + " | ".join(f"{stock[n]:.4g}" if n in stock else "" for n in STOCK_BASELINE_NAMES)
                             + f" | {o.get('auto_over_best_stock', float('nan')):.3f} | "
                             f"{o.get('stock_chosen_on_folds', '')} | {o.get('auto_over_fold_chosen_stock', float('nan')):.3f} | "
                             f"{o['fit_seconds']:.1f} |")
    axis = read_json_record(out / "dead_weight_axis_groups.json")
    if axis is not None:
        lines += ["", "| one group per loaded axis (15 rows) | seed | auto chose | folds used | auto RMSE at 2x | LTM | "
                  "auto / LTM | auto / best stock | constant? |", "|" + "---|" * 9]
        for o in axis["seeds"]:
            if "refused" in o:
                lines.append(f"| {o['axes']} axes | {o['seed']} | refused: {o['refused'][:80]} | | | | | | |")
                continue
            lines.append(f"| {o['axes']} axes | {o['seed']} | {o['chosen']} | {o['folds'].split(':')[0]} | "
                         f"{o['auto_rmse_2x']:.4g} | {o['linear_rmse_2x']:.4g} | {o['auto_over_linear']:.3f} | "
                         f"{o['auto_over_best_stock']:.3f} | {'yes' if o['constant'] else 'no'} |")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="benchmarks/results/auto_vs_stock",
                        help="folder of the case JSON files and summary.md (a case already written there is skipped, "
                        "so the command resumes)")
    parser.add_argument("--case", action="append", choices=CASES)
    parser.add_argument("--jobs", type=int, default=2, help="auto's n_jobs (default: 2, the machine's cores)")
    parser.add_argument("--robot-folds", type=int, default=5, choices=range(1, 6),
                        help="outer pose-grouped folds of robot_held to run (1-5, default 5)")
    parser.add_argument("--force", action="store_true",
                        help="replace files in --out this script did not write, or that were edited since (their "
                        "cases run again)")
    parser.add_argument("--race-check", action="store_true",
                        help="instead: auto raced and in full on each case's first training fold, the choices "
                        "compared (race_<case>.json, race_summary.md)")
    args = parser.parse_args()
    if args.race_check:
        files = output_files(parser, args.out, args.force, ["race_summary.md",
                                                            *(f"race_{c}.json" for c in args.case or CASES)])
        global JOBS
        JOBS = args.jobs
        for case in args.case or CASES:
            path = files.out_dir / f"race_{case}.json"
            if files.is_own(path.name) and read_json_record(path) is not None:
                continue
            print(f"race check {case} ...", flush=True)
            result = race_check(case)
            result.update(case=case, load_average=os.getloadavg(), auto_jobs=JOBS)
            files.write_text(path.name, json.dumps(result, indent=1, default=float))
            files.write_text("race_summary.md", race_summary(files.out_dir) + "\n")
        print(race_summary(files.out_dir), flush=True)
        return
    # a case's JSON (written once, then skipped) and the summary: a user's file of those names stops the run now
    files = output_files(parser, args.out, args.force, ["summary.md", *(f"{c}.json" for c in args.case or CASES),
                                                        "soft_static_floor.json",  # the static floors' caches
                                                        f"robot_static_floor_{args.robot_folds}.json"])
    global FILES, ROBOT_FOLDS
    JOBS, ROBOT_FOLDS, FILES = args.jobs, args.robot_folds, files
    out = files.out_dir
    for case in args.case or CASES:
        path = out / f"{case}.json"
        # an unreadable file, or one this script did not write or that was edited since (--force lets the run
        # replace it), is not a result: the case runs again
        earlier = read_json_record(path) if files.is_own(path.name) else None
        if earlier is not None and case.startswith("dead_weight") and case != "dead_weight_axis_groups":
            # an earlier run's JSON: add the stock baselines
            files.write_text(path.name, json.dumps(dead_weight_stock(case, earlier), indent=1, default=float))
            files.write_text("summary.md", summary(out) + "\n")
        if earlier is not None:
            continue
        print(f"{case} ...", flush=True)
        t0 = time.perf_counter()
        result = run_case(case)
        result.update(case=case, wall_seconds=time.perf_counter() - t0, load_average=os.getloadavg(),
                      kernel_baseline_rows=KERNEL_ROWS, auto_jobs=JOBS,
                      machine={"platform": platform.platform(), "cpus": os.cpu_count(),
                               "python": platform.python_version()})
        files.write_text(path.name, json.dumps(result, indent=1, default=float))
        files.write_text("summary.md", summary(out) + "\n")
        print(summary(out), flush=True)


if __name__ == "__main__":
    main()
