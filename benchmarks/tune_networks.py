#!/usr/bin/env python
"""Hyperparameter search of the network calibrators, and whether the tuned setting wins.

For each preset:

1. **search** -- :func:`ftcal.compose.search_calibrator` (scikit-learn's randomized search over
   :data:`ftcal.compose._search.DEFAULT_SEARCH_SPACES`, k-fold cross-validated torque-scaled RMSE, eq. 18) on a *tuning*
   dataset whose seed is not one of the benchmark's (``--tuning-seed``), so the validation below is not
   scored on data the search has seen;
2. **validate** -- the documented defaults and the search's best setting are trained on the first
   ``--validate`` datasets of the artificial benchmark (the same seeds as ``benchmarks/beyond.py``) and
   scored on their continuous test sets; mean ± std, ratio and Wilcoxon signed-rank p-value (paired by
   dataset). A tuned setting replaces a default only where it wins here, on every preset.

Writes ``tune_networks.json`` and ``tune_networks.md`` into ``--out`` (refuses to overwrite them without
``--force``).

Examples::

    python benchmarks/tune_networks.py --models directional --n-iter 2 --validate 1 --n-per-sphere 100 \\
        --out /tmp/tune-smoke --force
    python benchmarks/tune_networks.py --models directional --n-iter 6 --validate 6 --jobs 2
    python benchmarks/tune_networks.py --models directional --setting '{"lr": 0.003}' --validate 6 --jobs 2
"""

from __future__ import annotations

import argparse
import json
import platform
import shlex
import sys
import time
from pathlib import Path

import numpy as np
from joblib import Parallel, delayed

from ftcal.simulation import SensorProfile
from ftcal import make_artificial_dataset, make_calibrator
from ftcal.compose import search_calibrator
from ftcal.core import wrench_rmse
from ftcal.core import mean_std, plain_json
from ftcal.benchmark import dataset_seeds, format_mean_std, wilcoxon_pvalue
from ftcal.compose import search_summary

from _output import output_files

DEFAULT_OUT = Path(__file__).resolve().parent / "out" / "tune_networks"
OUTPUTS = ("tune_networks.json", "tune_networks.md")


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    p.add_argument("--models", nargs="+", default=["directional"], help="network models (registry names)")
    p.add_argument("--presets", nargs="+", default=["thesis", "asymmetric", "stress"], help="error presets")
    p.add_argument("--n-iter", type=int, default=6, help="randomized-search candidates per model and preset")
    p.add_argument("--cv", type=int, default=3, help="cross-validation folds of the search")
    p.add_argument("--validate", type=int, default=6, help="benchmark datasets for default-vs-tuned")
    p.add_argument("--schedule", default="short", choices=["thesis", "short"], help="starting training schedule")
    p.add_argument("--n-per-sphere", type=int, default=1250, help="training points per sphere")
    p.add_argument("--tuning-seed", type=int, default=1000, help="seed of the tuning datasets")
    p.add_argument("--seed", type=int, default=0, help="master seed of the benchmark datasets (as beyond.py)")
    p.add_argument("--jobs", type=int, default=2, help="joblib workers")
    p.add_argument("--setting", type=_setting, metavar="JSON",
                   help="skip the search and validate this setting, e.g. '{\"lr\": 0.003}' (isolates one factor)")
    p.add_argument("--out", default=str(DEFAULT_OUT), help="output directory")
    p.add_argument("--force", action="store_true", help="replace output files this script did not write")
    return p


def _setting(text: str) -> dict:
    try:
        value = json.loads(text)
    except json.JSONDecodeError as exc:
        raise argparse.ArgumentTypeError(f"--setting {text!r} is not JSON ({exc})") from None
    if not isinstance(value, dict) or not value:
        raise argparse.ArgumentTypeError(
            f"--setting {text!r}: give a JSON object of parameters, e.g. '{{\"lr\": 0.003}}'")
    return {k: tuple(v) if isinstance(v, list) else v for k, v in value.items()}


def _validate_one(preset: str, model: str, params: dict, index: int, args) -> float:
    """Test RMSE [N] of ``model`` with ``params`` on benchmark dataset ``index`` of ``preset``."""
    import torch

    torch.set_num_threads(1)
    data_seed, model_seed = dataset_seeds(args.seed, index)
    profile = SensorProfile.default()
    train, test, _ = make_artificial_dataset(preset, random_state=data_seed, profile=profile,
                                             n_per_sphere=args.n_per_sphere)
    calibrator = make_calibrator(model, schedule=args.schedule, random_state=model_seed, alpha=profile.alpha,
                                 **params)
    calibrator.fit(train.raw, train.wrench)
    return wrench_rmse(test.wrench, calibrator.predict(test.raw), profile.alpha)


def tune_one(preset: str, model: str, args) -> dict:
    if args.setting is not None:  # no search: validate the given setting
        best, search_seconds = dict(args.setting), 0.0
        summary = {"best_params": {k: plain_json(v) for k, v in best.items()},
                   "best_rmse": float("nan"), "n_folds": 0, "candidates": []}
    else:
        profile = SensorProfile.default()
        train, _, _ = make_artificial_dataset(preset, random_state=args.tuning_seed, profile=profile,
                                              n_per_sphere=args.n_per_sphere)
        start = time.perf_counter()
        search = search_calibrator(model, train.raw, train.wrench, n_iter=args.n_iter, cv=args.cv,
                                   schedule=args.schedule, random_state=args.tuning_seed, n_jobs=args.jobs,
                                   alpha=profile.alpha)
        search_seconds = time.perf_counter() - start
        summary = search_summary(search)
        best = dict(search.best_params_)
    start = time.perf_counter()
    runs = Parallel(n_jobs=args.jobs)(
        delayed(_validate_one)(preset, model, params, i, args)
        for params in ({}, best) for i in range(args.validate))
    default_rmse, tuned_rmse = runs[:args.validate], runs[args.validate:]
    p_value, note = wilcoxon_pvalue(tuned_rmse, default_rmse)
    default, tuned = mean_std(default_rmse, ddof=1), mean_std(tuned_rmse, ddof=1)
    return {
        "preset": preset, "model": model, "search": summary, "search_seconds": search_seconds,
        "validate_seconds": time.perf_counter() - start,
        "default_rmse": default_rmse, "tuned_rmse": tuned_rmse, "default": default, "tuned": tuned,
        "tuned_over_default": tuned["mean"] / default["mean"], "wilcoxon_p": p_value, "wilcoxon_note": note,
        "tuned_wins": bool(tuned["mean"] < default["mean"] and np.isfinite(p_value) and p_value < 0.05),
    }


def _fmt(stat: dict) -> str:
    return f"{format_mean_std(stat, 3)} (n={stat['n']})"


def markdown(rows: list[dict], command: str, seconds: float) -> str:
    lines = [f"Command: `{command}`",
             f"Machine: {platform.node() or 'unknown'} {platform.machine()}, Python {platform.python_version()}; "
             f"wall time {seconds:.0f} s.", "",
             "| model | preset | best setting (CV RMSE [N]) | default RMSE [N] | tuned RMSE [N] | tuned / default "
             "| Wilcoxon p | tuned wins |", "|---|---|---|---|---|---|---|---|"]
    for r in rows:
        best = ", ".join(f"{k}={v}" for k, v in r["search"]["best_params"].items())
        cv = f"{r['search']['best_rmse']:.3f}" if r["search"]["candidates"] else "given, not searched"
        lines.append(f"| {r['model']} | {r['preset']} | {best} ({cv}) | {_fmt(r['default'])} "
                     f"| {_fmt(r['tuned'])} | {r['tuned_over_default']:.3f} | {r['wilcoxon_p']:.3g} "
                     f"| {'yes' if r['tuned_wins'] else 'no'} |")
    lines.append("")
    for r in rows:
        if not r["search"]["candidates"]:
            continue
        lines.append(f"Candidates, {r['model']} on `{r['preset']}` ({r['search']['n_folds']}-fold CV RMSE [N], "
                     f"search {r['search_seconds']:.0f} s):")
        for c in r["search"]["candidates"]:
            lines.append(f"- rank {c['rank']}: {c['params']} -> {c['rmse_mean']:.3f} ± {c['rmse_std']:.3f} "
                         f"({c['fit_seconds_mean']:.0f} s per fit)")
        lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    for name, value, low in (("--n-iter", args.n_iter, 1), ("--cv", args.cv, 2), ("--validate", args.validate, 1),
                             ("--n-per-sphere", args.n_per_sphere, 10), ("--jobs", args.jobs, 1)):
        if value < low:
            print(f"error: {name} must be >= {low}; got {value}", file=sys.stderr)
            return 2
    files = output_files(parser, args.out, args.force, list(OUTPUTS))  # before any work
    command = shlex.join(["python", "benchmarks/tune_networks.py", *(argv if argv is not None else sys.argv[1:])])
    start = time.perf_counter()
    rows = []
    for model in args.models:
        for preset in args.presets:
            rows.append(tune_one(preset, model, args))
            r = rows[-1]
            print(f"{model} on {preset}: best {r['search']['best_params']}, tuned / default "
                  f"{r['tuned_over_default']:.3f} (p={r['wilcoxon_p']:.3g})", file=sys.stderr, flush=True)
    seconds = time.perf_counter() - start
    text = markdown(rows, command.strip(), seconds)
    files.write_text("tune_networks.json", json.dumps(plain_json(
        {"command": command.strip(), "wall_seconds": seconds, "rows": rows}), indent=2) + "\n")
    files.write_text("tune_networks.md", text + "\n")
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
