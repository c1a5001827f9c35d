#!/usr/bin/env python
"""Artificial-data benchmark of the thesis (Tables II-III, Fig. 5): thin wrapper of
:func:`ftcal.benchmark.run_artificial_benchmark`.

Resumable: every (preset, dataset, model) result is cached under ``OUT/cache``;
run the same command again to continue an interrupted run.

Examples::

    python benchmarks/artificial.py --quick --out /tmp/ftcal-quick
    python benchmarks/artificial.py --datasets 30 --aggregate-only   # tables from whatever is cached
    python benchmarks/artificial.py --datasets 5 --presets thesis asymmetric stress --schedule short
    python benchmarks/artificial.py --datasets 30 --presets thesis asymmetric stress --schedule thesis \
        --stack 15 --jobs 2 --out benchmarks/out/artificial_thesis
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from ftcal.compose import CALIBRATOR_NAMES
from ftcal.simulation import ERROR_PRESETS
from ftcal import FtcalError
from ftcal.benchmark import run_artificial_benchmark
from ftcal.calibrators import STOCK_BASELINE_NAMES
from ftcal.cli import cli_message

#: Default output folder (git-ignored): benchmarks/out/artificial.
DEFAULT_OUT = Path(__file__).resolve().parent / "out" / "artificial"


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0], formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--datasets", type=int, default=30, help="datasets per preset (default 30)")
    p.add_argument("--presets", nargs="+", default=["thesis"], choices=sorted(ERROR_PRESETS), help="error presets")
    p.add_argument("--models", nargs="+", default=None,
                   help=f"registered calibrators ({', '.join(CALIBRATOR_NAMES)}) or stock baselines "
                        f"({', '.join(STOCK_BASELINE_NAMES)}); default: linear comparative directional")
    p.add_argument("--baselines", action=argparse.BooleanOptionalAction, default=None,
                   help="also fit every stock scikit-learn baseline on the same data "
                        "(default: yes unless --models is given)")
    p.add_argument("--schedule", default="thesis", choices=["thesis", "short"], help="network training schedule")
    p.add_argument("--seed", type=int, default=0, help="master seed of data and model initialisation")
    p.add_argument("--jobs", type=int, default=1, help="parallel joblib workers (-1: all cores)")
    p.add_argument("--stack", type=int, default=1,
                   help="network fits of one preset and model trained together as one stacked module")
    p.add_argument("--out", default=str(DEFAULT_OUT), help=f"output and cache folder (default {DEFAULT_OUT})")
    p.add_argument("--quick", action="store_true", help="smoke mode: 3 small datasets, a few epochs")
    p.add_argument("--test-distribution", default=None, choices=["radial", "box", "ball"],
                   help="test-set sampling (default: the preset's own: 'ball' for reconstructed, else 'radial')")
    p.add_argument("--aggregate-only", action="store_true", help="only summarise the cached results")
    p.add_argument("--no-plot", action="store_true", help="skip the PNG")
    p.add_argument("--force", action="store_true", help="overwrite existing summary files not written by the benchmark")
    return p


def _models(args: argparse.Namespace) -> list[str]:
    """The models asked for, plus the stock baselines unless only named models were asked for."""
    models = args.models or ["linear", "comparative", "directional"]
    baselines = args.models is None if args.baselines is None else args.baselines
    return list(dict.fromkeys(models + (list(STOCK_BASELINE_NAMES) if baselines else [])))


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    start = time.perf_counter()

    def progress(done: int, total: int, rec: dict) -> None:
        print(f"[{done}/{total}] {rec['preset']} dataset {rec['dataset']} {rec['model']}: RMSE {rec['rmse']:.2f} N "
              f"(fit {rec['fit_seconds']:.1f} s, elapsed {time.perf_counter() - start:.0f} s)", flush=True)

    try:
        result = run_artificial_benchmark(
            n_datasets=args.datasets, presets=args.presets, schedule=args.schedule,
            models=_models(args),
            seed=args.seed, n_jobs=args.jobs, out_dir=args.out, quick=args.quick, progress=progress,
            force=args.force, compute=not args.aggregate_only, test_distribution=args.test_distribution,
            plot=not args.no_plot, stack=args.stack,
        )
    except FtcalError as exc:
        print(f"error: {cli_message(exc)}", file=sys.stderr)
        return 2
    meta = result["meta"]
    print(open(result["files"]["markdown"], encoding="utf-8").read())
    print(f"{meta['n_complete']}/{meta['n_expected']} results ({meta['n_from_cache']} from cache), "
          f"wall {meta['wall_seconds']:.1f} s; files: {', '.join(result['files'].values())}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
