"""How long ``ftcal fit --model linear --report`` takes on large data, as users run it (the CLI, one process).

Cases (a smooth 8-channel sensor with a mild nonlinearity, groups of rows as poses):

* ``fit --model linear --report`` on 80 000 rows x 8 channels (target: under a minute on 2 cores), against
  ``fit --model linear --report --no-baselines`` in the same run (the report's own cross-validation alone);
* ``fit --model auto --report`` on the same 80 000 rows (case ``80k_auto``; target: under 5 minutes on 2 cores):
  every candidate, the networks and the stock models scored on the pose-grouped folds, the chosen one refitted,
  the report from auto's own comparison;
* ``report`` of a linear model on 1 000 000 rows x 8 channels (must finish: the stock baselines subsampled and
  budgeted);
* ``fit --model linear --report`` on 1 200 rows x 500 channels (must finish: no baseline may ask for more memory
  than ftcal's limit; the skipped ones are named).

Each case runs ``--repeats`` times (the median is reported) as a subprocess of the ``ftcal`` command, timed
from start to exit (imports and file writing included). The machine is shared: the load average at the start
and end is printed with the figures.

Run::

    nice -n 10 python benchmarks/report_speed.py --repeats 1 --cases 80k,wide,million
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from ftcal import CalibrationDataset


def sensor(n_rows: int, n_channels: int, n_groups: int, seed: int = 0) -> CalibrationDataset:
    rng = np.random.default_rng(seed)
    wrench = rng.uniform(-1, 1, size=(n_rows, 6)) * [300, 300, 600, 10, 10, 10]
    gains = rng.normal(size=(n_channels, 6)) / [300, 300, 600, 10, 10, 10]
    raw = np.tanh(0.8 * wrench @ gains.T) + 0.002 * rng.normal(size=(n_rows, n_channels))
    return CalibrationDataset(raw=raw, wrench=wrench, group=np.repeat(np.arange(n_groups), -(-n_rows // n_groups))[
        :n_rows], meta={"sensor": "benchmark sensor"})


def timed(argv: list[str], repeats: int) -> dict:
    """Median wall time [s] of ``ftcal ARGV`` and the CPU time [s] it and its worker processes used (user + system:
    what an idle machine would need at least, divided by the cores it keeps busy)."""
    walls, cpus = [], []
    for _ in range(repeats):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.perf_counter()
        done = subprocess.run([sys.executable, "-m", "ftcal", *argv], capture_output=True, text=True)
        walls.append(time.perf_counter() - t0)
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpus.append(after.ru_utime - before.ru_utime + after.ru_stime - before.ru_stime)
        if done.returncode != 0:
            raise SystemExit(f"ftcal {' '.join(argv)} failed:\n{done.stderr[-2000:]}")
    return {"wall_s": round(statistics.median(walls), 1), "cpu_s": round(statistics.median(cpus), 1),
            "load_average_after": os.getloadavg()[0]}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=1)
    parser.add_argument("--cases", default="80k,80k_auto,wide,million",
                        help="comma-separated: 80k, 80k_auto, wide, million")
    args = parser.parse_args()
    results = {"load_average_start": os.getloadavg(), "cores": os.cpu_count()}
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        cases = args.cases.split(",")
        sensor(80_000, 8, 40).save(work / "big.csv")
        base = ["fit", str(work / "big.csv"), "--model", "linear", "--report", "--force", "-q", "--out"]
        if "80k" in cases:
            results["fit_linear_report_80k_no_baselines"] = timed(base + [str(work / "a"), "--no-baselines"],
                                                                  args.repeats)
            print(json.dumps(results, indent=1), flush=True)
            results["fit_linear_report_80k"] = timed(base + [str(work / "b")], args.repeats)
            facts = json.loads((work / "b" / "linear.report.json").read_text())
            results["80k_model_choice"] = {c["model"]: c["status"] if c.get("rmse") is None else c["rmse"] for c in facts["model_choice"]}
            print(json.dumps(results, indent=1), flush=True)
        if "80k_auto" in cases:
            results["fit_auto_report_80k"] = timed(["fit", str(work / "big.csv"), "--model", "auto", "--report",
                                                    "--force", "-q", "--out", str(work / "c")], args.repeats)
            facts = json.loads((work / "c" / "auto.report.json").read_text())
            results["80k_auto_model_choice"] = {c["model"]: c["status"] if c.get("rmse") is None else c["rmse"] for c in facts["model_choice"]}
            print(json.dumps(results, indent=1), flush=True)
        if "wide" in cases:
            sensor(1200, 500, 12, seed=1).save(work / "wide.npz")
            results["fit_linear_report_1200x500"] = timed(["fit", str(work / "wide.npz"), "--model", "linear",
                                                           "--report", "--force", "-q", "--out", str(work / "w")],
                                                          args.repeats)
            facts = json.loads((work / "w" / "linear.report.json").read_text())
            results["1200x500_model_choice"] = {c["model"]: c["status"] if c.get("rmse") is None else c["rmse"]
                                                for c in facts["model_choice"]}
            print(json.dumps(results, indent=1), flush=True)
        if "million" in cases:
            sensor(1_000_000, 8, 100, seed=2).save(work / "million.npz")
            subprocess.run([sys.executable, "-m", "ftcal", "fit", str(work / "million.npz"), "--model", "linear",
                            "-q", "--out", str(work / "mm")], check=True)
            results["report_linear_1e6"] = timed(["report", str(work / "mm" / "linear.model.npz"),
                                                  str(work / "million.npz"), "--force", "-q", "--out",
                                                  str(work / "mr")], args.repeats)
            facts = json.loads((work / "mr" / "linear.report.json").read_text())
            results["1e6_model_choice"] = {c["model"]: c["status"] if c.get("rmse") is None else c["rmse"] for c in facts["model_choice"]}
    results["load_average_end"] = os.getloadavg()
    print(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
