"""The GP calibrator's predictive std on held-out data, 2-std coverage per case (target 90-97 %).

Usage::

    python benchmarks/gp_coverage.py [--out benchmarks/results/gp_coverage] [--case NAME ...]

The cases and outer folds of ``benchmarks/auto_vs_stock.py`` (soft: shuffled 5-fold; soft_grouped and robot_held:
group 5-fold, the groups also given to ``fit`` so the std is calibrated leaving whole groups out; the artificial
presets: their test set). Per case: the share of held-out errors within 2 std (all six components), per
component, and with the uncalibrated std (``std / std_scale_``), and the factors; beside it the stock scikit-learn
GP's (``sk_gp`` of :func:`ftcal.calibrators.stock_baselines`, its ``predict(return_std=True)``, same folds), added to
an earlier run's JSON without refitting ftcal's GP. One JSON per case (resumable).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import numpy as np
from sklearn.model_selection import GroupKFold, KFold

import ftcal
from ftcal.calibrators import stock_baselines
from ftcal.benchmark import read_json_record

from _output import output_files

CASES = ("soft", "soft_grouped", "thesis", "asymmetric", "reconstructed", "robot_held")


def folds(case: str):
    if case in ("soft", "soft_grouped"):
        d = ftcal.simulation.make_soft_sensor_dataset()
        split = KFold(5, shuffle=True, random_state=0).split(d.raw) if case == "soft" else GroupKFold(5).split(
            d.raw, groups=d.group)
        return d.raw, d.wrench, (d.group if case == "soft_grouped" else None), list(split), d.meta["alpha"]
    if case == "robot_held":
        d = ftcal.simulation.make_robot_held_dataset()
        return d.raw, d.wrench, d.group, list(GroupKFold(5).split(d.raw, groups=d.group)), d.meta["alpha"]
    train, test, _ = ftcal.make_artificial_dataset(case, random_state=0)
    n = train.n_samples
    return (np.vstack([train.raw, test.raw]), np.vstack([train.wrench, test.wrench]), None,
            [(np.arange(n), np.arange(n, n + test.n_samples))], ftcal.core.alpha_from_wrenches(train.wrench))


def run(case: str) -> dict:
    raw, wrench, groups, splits, alpha = folds(case)
    within, raw_within, scales, t0 = [], [], [], time.perf_counter()
    for train, test in splits:
        gp = ftcal.GaussianProcessCalibrator(alpha=alpha, random_state=0).fit(
            raw[train], wrench[train], groups=None if groups is None else groups[train])
        pred, std = gp.predict(raw[test], return_std=True)
        err = np.abs(pred - wrench[test])
        within.append(err <= 2 * std)
        raw_within.append(err <= 2 * std / gp.std_scale_)
        scales.append(gp.std_scale_.tolist())
    within, raw_within = np.vstack(within), np.vstack(raw_within)
    return {"case": case, "coverage_2std": float(within.mean()), "per_component": within.mean(axis=0).tolist(),
            "uncalibrated_coverage_2std": float(raw_within.mean()), "std_scale_per_fold": scales,
            "groups_given": groups is not None, "seconds": time.perf_counter() - t0}


def stock_coverage(case: str) -> float:
    """The stock GP's 2-std coverage on the case's held-out folds (fitted on its 1000-row subset, as everywhere)."""
    raw, wrench, _, splits, _ = folds(case)
    within = []
    for train, test in splits:
        model = stock_baselines(raw.shape[1], random_state=0)["sk_gp"].fit(raw[train], wrench[train])
        pred, std = model.estimator_.predict(raw[test], return_std=True)  # the pipeline (scaler + GP) on the subset
        within.append(np.abs(pred - wrench[test]) <= 2 * std)
    return float(np.vstack(within).mean())


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", default="benchmarks/results/gp_coverage")
    parser.add_argument("--case", action="append", choices=CASES)
    parser.add_argument("--force", action="store_true", help="replace a case file this script did not write")
    args = parser.parse_args()
    files = output_files(parser, args.out, args.force, [f"{case}.json" for case in args.case or CASES])
    for case in args.case or CASES:
        name = f"{case}.json"
        r = read_json_record(files.out_dir / name, numbers=("uncalibrated_coverage_2std", "coverage_2std"))
        if r is None:  # not run yet, or a file that is not this script's result
            r = run(case)
            files.write_text(name, json.dumps(r, indent=1))
        if "stock_gp_coverage_2std" not in r:
            r["stock_gp_coverage_2std"] = stock_coverage(case)
            files.write_text(name, json.dumps(r, indent=1))
        print(f"| {case} | {r['uncalibrated_coverage_2std']:.3f} | {r['coverage_2std']:.3f} | "
              f"{' '.join(f'{c:.2f}' for c in r['per_component'])} | {r['stock_gp_coverage_2std']:.3f} |", flush=True)


if __name__ == "__main__":
    main()
