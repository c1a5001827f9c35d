"""ftcal's GP engine against scikit-learn's on the same model: the stock GP structure fitted both ways, same process.

Usage::

    python benchmarks/gp_gradient.py [--repeats 3] [--out benchmarks/results/gp_gradient.json]

``GaussianProcessCalibrator(mean="none", kernel="rbf", per_output=False, kernel_bounds="stock")`` *is* the stock
GP (``StandardScaler`` + ``ConstantKernel() * RBF(ones(N)) + WhiteKernel()``, ``normalize_y=True``; the parity
test checks their predictions agree): fitted by ftcal, each step of its optimiser computes the
log-marginal-likelihood gradient from ``m x m`` matrices and one matrix product; fitted by scikit-learn
(``StockCalibrator(baseline="sk_gp")``), from the ``(m, m, n_theta)`` kernel-gradient tensor. For each size
(rows of an 8-channel smooth sensor with six outputs), the median fit time of each, interleaved, their ratio and
the largest difference of their predictions relative to the wrench's spread. ftcal's fit also computes its
closed-form left-out errors and calibrates its std (work the stock fit does not do). The load average before and
after is recorded.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import time

import numpy as np

from ftcal.calibrators import GaussianProcessCalibrator, StockCalibrator

from _output import single_output

SIZES = (250, 500, 1000)  # rows (8 channels, 6 outputs)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3, choices=range(1, 51), metavar="1..50")
    parser.add_argument("--out", default="benchmarks/results/gp_gradient.json")
    parser.add_argument("--force", action="store_true", help="replace an --out file this script did not write")
    args = parser.parse_args()
    out = single_output(parser, args.out, args.force)
    results = {"load_average_before": os.getloadavg(), "repeats": args.repeats, "rows": []}
    rng = np.random.default_rng(0)
    for m in SIZES:
        load = rng.uniform(-1, 1, size=(m, 6))
        raw = np.tanh(load @ rng.normal(size=(6, 8)) / 2) + 0.01 * rng.normal(size=(m, 8))
        models = {"ftcal": GaussianProcessCalibrator(mean="none", kernel="rbf", per_output=False,
                                                     kernel_bounds="stock", max_samples=m, alpha=1.0, random_state=0),
                  "scikit-learn": StockCalibrator(baseline="sk_gp", max_kernel_samples=m, alpha=1.0, random_state=0)}
        times: dict = {name: [] for name in models}
        for _ in range(args.repeats):
            for name, model in models.items():
                t0 = time.perf_counter()
                model.fit(raw, load)
                times[name].append(time.perf_counter() - t0)
        difference = np.abs(models["ftcal"].predict(raw) - models["scikit-learn"].predict(raw)).max() / load.std()
        row = {"rows": m, "channels": 8, "outputs": 6,
               **{f"{name}_median_s": statistics.median(t) for name, t in times.items()},
               "max_prediction_difference_over_spread": float(difference)}
        row["ftcal_over_scikit_learn"] = row["ftcal_median_s"] / row["scikit-learn_median_s"]
        results["rows"].append(row)
        print(json.dumps(row), flush=True)
    results["load_average_after"] = os.getloadavg()
    out.write_text(json.dumps(results, indent=1) + "\n")


if __name__ == "__main__":
    main()
