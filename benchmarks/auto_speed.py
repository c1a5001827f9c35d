"""``auto``'s time targets: a soft sensor's 334 rows in <= 10x one stock GP fit (the same process, medians of
3), and 80 000 rows (networks and stock candidates) in <= 5 min.

Usage::

    python benchmarks/auto_speed.py [--rows 334] [--repeats 3] [--jobs 2] [--skip-large | --skip-small]
        [--race | --no-race]
        [--out benchmarks/results/auto_speed.json]

``AutoCalibrator`` with its defaults (every candidate, networks on the short schedule, the stack, the five
stock baselines) and ``n_jobs=--jobs``:

* **small** (``--rows``, default 334): the first rows of :func:`ftcal.simulation.make_soft_sensor_dataset`
  (8 channels), shuffled 5-fold; the median of ``--repeats`` fits after one warm-up fit (the first fit also
  starts the worker processes and imports torch in them, reported apart); its table (which candidates were
  raced out, and why) is kept;
* **80 000 rows**: :func:`ftcal.simulation.make_robot_held_dataset` (80 000 rows, 41 poses, pose-grouped 5-fold), one
  fit; the stock baselines are candidates (the kernel ones on 1000-row subsamples), and the seconds each
  row of the comparison took (all folds) are recorded.

Beside each, in the same process, the stock scikit-learn GP fitted once on the same rows (on
1000 of them for the large set, as ``auto`` does): the ratio says how the time compares with what a user
would run instead, whatever the machine's speed. The load average before and after is recorded, and beside each
wall time the CPU seconds of this process and its joblib workers (what the fit cost, however busy the shared
machine was); the small set's auto and stock GP fits are interleaved.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import statistics
import time
import warnings
from pathlib import Path

import ftcal
from ftcal.calibrators import stock_baselines

from _output import single_output


def timed(fn) -> float:
    start = time.perf_counter()
    fn()
    return time.perf_counter() - start


def cpu_seconds() -> float:
    """CPU seconds (user + system) of this process and its live children (joblib's worker processes, which stay
    alive between fits): on a shared machine the wall time says how busy it was, the CPU time what the fit cost."""
    import psutil

    me = psutil.Process()
    total = sum(me.cpu_times()[:2])
    for child in me.children(recursive=True):
        try:
            total += sum(child.cpu_times()[:2])
        except psutil.Error:
            pass
    return total


def timed_cpu(fn) -> tuple[float, float]:
    """(wall seconds, CPU seconds of this process and its workers) of ``fn()``."""
    cpu = cpu_seconds()
    wall = timed(fn)
    return wall, cpu_seconds() - cpu


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    def count(low: int, high: int, negative: bool = False):
        def parse(text: str) -> int:
            value = int(text)
            if not (low <= value <= high or (negative and -high <= value <= -1)):
                raise argparse.ArgumentTypeError(f"{text} is not in {low}..{high}" + (" or -1..-64" if negative else ""))
            return value
        return parse

    parser.add_argument("--repeats", type=count(1, 100), default=3)
    parser.add_argument("--jobs", type=count(1, 64, negative=True), default=2, help="auto's n_jobs (-1: all cores)")
    parser.add_argument("--skip-large", action="store_true")
    parser.add_argument("--skip-small", action="store_true", help="only the 80 000-row case")
    parser.add_argument("--rows", type=count(50, 418), default=334, help="rows of the small set (default 334)")
    parser.add_argument("--race", action=argparse.BooleanOptionalAction, default=True,
                        help="race the costly candidates (AutoCalibrator(race=...); default on)")
    parser.add_argument("--out", default="benchmarks/results/auto_speed.json")
    parser.add_argument("--force", action="store_true", help="replace an --out file this script did not write")
    args = parser.parse_args()
    out = single_output(parser, args.out, args.force)
    warnings.simplefilter("ignore")
    result: dict = {"load_average_before": os.getloadavg(), "jobs": args.jobs, "rows": args.rows, "race": args.race,
                    "machine": {"platform": platform.platform(), "cpus": os.cpu_count(),
                                "python": platform.python_version()}}
    soft = ftcal.simulation.make_soft_sensor_dataset()
    X, y = soft.raw[:args.rows], soft.wrench[:args.rows]

    def fit_small():
        auto = ftcal.AutoCalibrator(random_state=0, n_jobs=args.jobs, race=args.race).fit(X, y)
        result["small_choice"] = auto.best_name_
        result["small_table"] = auto.summary()
        result["small_seconds_by_row"] = dict(zip(auto.comparison_["name"], auto.comparison_["fit_seconds"]))

    if not args.skip_small:
        result["small_first_fit_s"] = timed(fit_small)
        gp = stock_baselines(8)["sk_gp"]
        runs, gp_runs = [], []
        for _ in range(args.repeats):  # interleaved: a slow spell of the shared machine hits both alike
            runs.append(timed_cpu(fit_small))
            gp_runs.append(timed_cpu(lambda: gp.fit(X, y)))
            print(f"auto {runs[-1][0]:.1f} s (CPU {runs[-1][1]:.1f} s), sk_gp {gp_runs[-1][0]:.1f} s (CPU "
                  f"{gp_runs[-1][1]:.1f} s), load {os.getloadavg()[0]:.1f}", flush=True)
        result["small_fit_s"] = [w for w, _ in runs]
        result["small_fit_cpu_s"] = [c for _, c in runs]
        result["small_fit_median_s"] = statistics.median(result["small_fit_s"])
        result["small_sk_gp_fit_runs_s"] = [w for w, _ in gp_runs]
        result["small_sk_gp_fit_cpu_s"] = [c for _, c in gp_runs]
        result["small_sk_gp_fit_s"] = statistics.median(result["small_sk_gp_fit_runs_s"])
        result["small_ratio_to_sk_gp"] = result["small_fit_median_s"] / result["small_sk_gp_fit_s"]
        result["small_cpu_ratio_to_sk_gp"] = statistics.median(result["small_fit_cpu_s"]) / statistics.median(
            result["small_sk_gp_fit_cpu_s"])
        print(json.dumps(result, indent=1), flush=True)
    if not args.skip_large:
        robot = ftcal.simulation.make_robot_held_dataset(80_000, n_poses=41)

        def fit_large():
            auto = ftcal.AutoCalibrator(random_state=0, n_jobs=args.jobs, race=args.race).fit(robot.raw, robot.wrench,
                                                                               groups=robot.group)
            result["large_choice"] = auto.best_name_
            result["large_table"] = auto.summary()
            result["large_seconds_by_row"] = dict(zip(auto.comparison_["name"], auto.comparison_["fit_seconds"]))

        result["large_load_before"] = os.getloadavg()
        result["large_fit_s"], result["large_fit_cpu_s"] = timed_cpu(fit_large)
        result["large_load_after"] = os.getloadavg()
        gp = stock_baselines(8, max_kernel_samples=1000)["sk_gp"]
        result["large_sk_gp_fit_s"] = timed(lambda: gp.fit(robot.raw, robot.wrench))
        result["large_ratio_to_sk_gp"] = result["large_fit_s"] / result["large_sk_gp_fit_s"]
    result["load_average_after"] = os.getloadavg()
    out.write_text(json.dumps(result, indent=1))
    print(json.dumps({k: v for k, v in result.items() if k not in ("large_table", "small_table")}, indent=1))


if __name__ == "__main__":
    main()
