#!/usr/bin/env python
"""The crossover: where does the directional DNN start to beat the LTM, the comparative DNN and
the hybrid, as the sign-dependent gain grows?

Every level is the ``thesis`` error model plus a sign-dependent gain ``1 ± a/2`` on all six axes
(``ErrorModel(asymmetry=a, asymmetry_axes=6)``; ``a = 0.2`` is the ``reconstructed`` preset), test loads
from the ``ball`` distribution, several datasets per level (the same dataset seeds at every level). It
runs :func:`ftcal.benchmark.run_artificial_benchmark` with one custom preset per level, so every fit is cached
under ``OUT/cache`` and the same command resumes; ``--aggregate-only`` builds the table and the plot from
whatever is cached.

Outputs in ``OUT``: ``crossover.md`` (RMSE per level and model, wins per pair, the interpolated crossover
levels), ``crossover.json`` and ``crossover.png``.

Examples::

    python benchmarks/crossover.py --quick --out /tmp/crossover-quick
    python benchmarks/crossover.py --datasets 5 --schedule short --out benchmarks/results/crossover
    python benchmarks/crossover.py --datasets 5 --schedule short --out benchmarks/results/crossover --aggregate-only
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from ftcal.simulation import ERROR_PRESETS
from ftcal import FtcalError
from ftcal.benchmark import run_artificial_benchmark
from ftcal.cli import cli_message

from _output import int_at_least, jobs, output_files

#: Sign-dependent gain levels (fractions): 0 ... 20 %, denser where the LTM's error starts to exceed the noise.
LEVELS = (0.0, 0.02, 0.04, 0.07, 0.10, 0.15, 0.20)
MODELS = ("linear", "directional", "comparative", "axis_nonlinear", "sk_poly2")
#: The directional DNN against these.
RIVALS = ("linear", "comparative", "axis_nonlinear", "sk_poly2")
DEFAULT_OUT = Path(__file__).resolve().parent / "out" / "crossover"


def level_name(a: float) -> str:
    """Preset name of a level, e.g. ``asym0.070``."""
    return f"asym{a:.3f}"


def level_presets(levels) -> dict:
    """Name -> ``thesis`` error model plus a sign-dependent gain ``a`` on all six axes."""
    return {level_name(a): replace(ERROR_PRESETS["thesis"], asymmetry=float(a), asymmetry_axes=6) for a in levels}


def crossover_level(levels, diff) -> float | None:
    """First level where ``diff`` (rival minus directional, per level) turns positive, linearly interpolated.

    ``None`` when it never does; the first level when it always does.

    >>> crossover_level([0.0, 0.1, 0.2], [-2.0, 2.0, 5.0])
    0.05
    """
    for i, d in enumerate(diff):
        if d > 0:
            if i == 0:
                return float(levels[0])
            d0 = diff[i - 1]
            return float(levels[i - 1] + (levels[i] - levels[i - 1]) * (-d0) / (d - d0))
    return None


def summarise(result: dict, levels, models) -> dict:
    """Per level: mean ± std RMSE per model, noise floor, per-pair wins of the directional DNN; crossovers."""
    summary = result["summary"]
    rows = []
    for a in levels:
        s = summary[level_name(a)]
        row = {"asymmetry": a, "noise_floor": s["noise_floor"]["mean"], "models": {}, "wins": {}}
        for m in models:
            row["models"][m] = {k: s["models"][m]["rmse"][k] for k in ("mean", "std", "n")}
        per_ds = {m: s["models"][m]["rmse_per_dataset"] for m in models}
        for rival in RIVALS:
            if "directional" in per_ds and rival in per_ds:
                common = sorted(set(per_ds["directional"]) & set(per_ds[rival]))
                row["wins"][rival] = [sum(per_ds["directional"][i] < per_ds[rival][i] for i in common), len(common)]
                # paired: the mean difference over the datasets both models ran on
                row.setdefault("paired_diff", {})[rival] = (
                    float(np.mean([per_ds[rival][i] - per_ds["directional"][i] for i in common])) if common else None)
        rows.append(row)
    crossing = {}
    for rival in RIVALS:
        if rival in models and "directional" in models:
            usable = [r for r in rows if r.get("paired_diff", {}).get(rival) is not None]
            diff = [r["paired_diff"][rival] for r in usable]
            crossing[rival] = crossover_level([r["asymmetry"] for r in usable], diff) if usable else "no data yet"
    return {"levels": rows, "crossover": crossing}


def markdown(table: dict, meta: dict, models) -> str:
    lines = [
        f"Crossover sweep: schedule `{meta['schedule']}`, {meta['n_datasets']} datasets per level, "
        f"{meta['n_per_sphere']} points per sphere, {meta['n_test']} ball test points; "
        f"{meta['n_complete']}/{meta['n_expected']} fits complete.",
        "",
        "| sign-dependent gain | noise floor [N] | " + " | ".join(models) + " | directional wins (of datasets) |",
        "|---" * (len(models) + 3) + "|",
    ]
    for r in table["levels"]:
        cells = [f"{r['models'][m]['mean']:.2f} ± {r['models'][m]['std']:.2f}" if r["models"][m]["n"] else "—"
                 for m in models]
        wins = ", ".join(f"vs {k}: {w}/{n}" for k, (w, n) in r["wins"].items())
        lines.append(f"| {100 * r['asymmetry']:.0f} % | {r['noise_floor']:.2f} | " + " | ".join(cells) + f" | {wins} |")
    lines += ["", "Directional DNN better than (mean RMSE difference over the datasets both ran on, linearly "
              "interpolated between levels) from a gain of:", ""]
    for rival, a in table["crossover"].items():
        lines.append(f"- {rival}: " + ("never in the sweep" if a is None else a if isinstance(a, str)
                                       else f"{100 * a:.1f} %"))
    return "\n".join(lines) + "\n"


def plot(table: dict, models, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5))
    x = [100 * r["asymmetry"] for r in table["levels"]]
    for m in models:
        pts = [(xi, r["models"][m]["mean"], r["models"][m]["std"]) for xi, r in zip(x, table["levels"]) if r["models"][m]["n"]]
        if pts:
            xs, mu, sd = map(np.asarray, zip(*pts))
            ax.errorbar(xs, mu, yerr=sd, marker="o", capsize=3, label=m)
    ax.plot(x, [r["noise_floor"] for r in table["levels"]], "k--", label="noise floor")
    for rival, a in table["crossover"].items():
        if isinstance(a, float) and rival == "linear":
            ax.axvline(100 * a, color="grey", lw=0.8, ls=":")
    ax.set_xlabel("sign-dependent gain a on all six axes [%]  (reconstructed preset: 20 %)")
    ax.set_ylabel("test RMSE, eq. 18 [N]")
    ax.set_yscale("log")
    ax.set_title("Where the directional DNN pays (thesis errors + sign-dependent gain, ball loads)", fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--levels", nargs="+", type=float, default=list(LEVELS), help="sign-dependent gains (fractions)")
    p.add_argument("--datasets", type=int_at_least(1, 1000), default=5, help="datasets per level (default 5)")
    p.add_argument("--models", nargs="+", default=list(MODELS), help="calibrators and stock baselines")
    p.add_argument("--schedule", default="short", choices=["thesis", "short"], help="network training schedule")
    p.add_argument("--n-per-sphere", type=int_at_least(1, 1_000_000), help="training points per sphere (default 1250)")
    p.add_argument("--n-test", type=int_at_least(1, 1_000_000), help="test points (default 1250)")
    p.add_argument("--seed", type=int_at_least(0), default=0)
    p.add_argument("--jobs", type=jobs, default=1, help="worker processes (-1: one per core)")
    p.add_argument("--stack", type=int_at_least(1), default=5, help="network fits of one level trained together")
    p.add_argument("--quick", action="store_true", help="smoke mode: small data, few epochs, 3 levels")
    p.add_argument("--out", default=str(DEFAULT_OUT))
    p.add_argument("--aggregate-only", action="store_true", help="only summarise the cached results")
    p.add_argument("--force", action="store_true", help="replace output files this script did not write")
    return p


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if args.quick and (args.n_per_sphere or args.n_test):
        parser.error("--quick sets its own small sizes: drop --n-per-sphere / --n-test, or --quick")
    levels = sorted(set(args.levels))[:: max(1, len(args.levels) // 3)] if args.quick else sorted(set(args.levels))
    files = output_files(parser, args.out, args.force, ["crossover.md", "crossover.json", "crossover.png"])
    out = files.out_dir
    start = time.perf_counter()

    def progress(done: int, total: int, rec: dict) -> None:
        print(f"[{done}/{total}] {rec['preset']} dataset {rec['dataset']} {rec['model']}: RMSE {rec['rmse']:.2f} N "
              f"(elapsed {time.perf_counter() - start:.0f} s)", flush=True)

    try:
        result = run_artificial_benchmark(
            n_datasets=args.datasets, presets=level_presets(levels), models=args.models, schedule=args.schedule,
            seed=args.seed, n_jobs=args.jobs, out_dir=out, quick=args.quick, progress=progress,
            compute=not args.aggregate_only, test_distribution="ball", plot=False, stack=args.stack,
            n_per_sphere=None if args.quick else args.n_per_sphere or 1250,
            n_test=None if args.quick else args.n_test or 1250, force=args.force,
        )
    except FtcalError as exc:
        print(f"error: {cli_message(exc)}", file=sys.stderr)
        return 2
    table = summarise(result, levels, args.models)
    meta = result["meta"]
    text = markdown(table, meta, args.models)
    files.write_text("crossover.md", text)
    files.write_text("crossover.json", json.dumps({"meta": meta, **table}, indent=1))
    with files.write("crossover.png") as tmp:
        plot(table, args.models, tmp)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
