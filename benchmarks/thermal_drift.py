"""Thermal drift figures: how much of a simulated thermal drift's error temperature compensation removes.

Usage::

    python benchmarks/thermal_drift.py [--datasets 5] [--out benchmarks/results/thermal_drift]

For each preset and dataset: the calibration and test data are read at random temperatures in a 20 deg C
range (15-35 deg C) by a sensor with data-sheet drift (``ftcal.core.ThermalDrift.typical``: zero 0.03 % FS/deg C,
span 0.02 %/deg C, and the upper bound 0.05 / 0.03), then the LTM and the hybrid are fitted without and
with ``TemperatureCompensatedCalibrator``. The share of the drift's error removed is
``1 - (MSE_compensated - MSE_no_drift) / (MSE_drift - MSE_no_drift)``. Only public ftcal names are used.
"""

from __future__ import annotations

import argparse
import json
import platform
from pathlib import Path

import numpy as np

import ftcal

from _output import int_at_least, output_files

MAGNITUDES = {"typical": (0.03, 0.02), "upper": (0.05, 0.03)}


def run(n_datasets: int) -> dict:
    out: dict = {}
    for preset in ("thesis", "asymmetric", "stress"):
        for label, (zero_pct, span_pct) in MAGNITUDES.items():
            rows = []
            for seed in range(n_datasets):
                train, test, info = ftcal.make_artificial_dataset(preset=preset, random_state=seed)
                rng = np.random.default_rng(1000 + seed)
                drift = ftcal.core.ThermalDrift.typical(np.abs(train.raw).max(axis=0), zero_pct_per_deg=zero_pct,
                                                   span_pct_per_deg=span_pct, random_state=rng)
                t_train = rng.uniform(15, 35, train.n_samples)
                t_test = rng.uniform(15, 35, test.n_samples)
                alpha = info["alpha"]
                row = {}
                for name, cls in (("linear", ftcal.LinearCalibrator), ("axis_nonlinear", ftcal.AxisNonlinearCalibrator)):
                    def mse(model, X_train, X_test):
                        model.fit(X_train, train.wrench)
                        return ftcal.core.wrench_rmse(test.wrench, model.predict(X_test), alpha=alpha) ** 2

                    clean = mse(cls(alpha=alpha), train.raw, test.raw)
                    drifted = mse(cls(alpha=alpha), drift.apply(train.raw, t_train), drift.apply(test.raw, t_test))
                    comp = mse(ftcal.TemperatureCompensatedCalibrator(cls(), alpha=alpha),
                               np.column_stack([drift.apply(train.raw, t_train), t_train]),
                               np.column_stack([drift.apply(test.raw, t_test), t_test]))
                    row[name] = {"rmse_no_drift": clean ** 0.5, "rmse_drift": drifted ** 0.5,
                                 "rmse_compensated": comp ** 0.5,
                                 "removed": 1 - (comp - clean) / (drifted - clean)}
                rows.append(row)
            out[f"{preset}/{label}"] = rows
            print(preset, label, {m: round(float(np.mean([r[m]["removed"] for r in rows])), 3) for m in rows[0]},
                  flush=True)
    return out


def summary(results: dict) -> str:
    lines = [f"machine: {platform.machine()}, Python {platform.python_version()}, ftcal {ftcal.__version__}", "",
             "| preset / drift | model | RMSE no drift [N] | RMSE with drift | compensated | drift error removed (mean, min) |",
             "|---|---|---|---|---|---|"]
    for key, rows in results.items():
        for model in rows[0]:
            v = {k: np.array([r[model][k] for r in rows]) for k in rows[0][model]}
            lines.append(f"| {key} | {model} | {v['rmse_no_drift'].mean():.3f} | {v['rmse_drift'].mean():.3f} | "
                         f"{v['rmse_compensated'].mean():.3f} | {100 * v['removed'].mean():.1f} %, "
                         f"{100 * v['removed'].min():.1f} % |")
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--datasets", type=int_at_least(1, 1000), default=5)
    parser.add_argument("--out", default=str(Path(__file__).parent / "results" / "thermal_drift"))
    parser.add_argument("--force", action="store_true", help="replace output files this script did not write")
    args = parser.parse_args(argv)
    files = output_files(parser, args.out, args.force, ["thermal_drift.json", "summary.md"])
    results = run(args.datasets)
    files.write_text("thermal_drift.json", json.dumps(results, indent=2) + "\n")
    files.write_text("summary.md", summary(results) + "\n")
    print(summary(results))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
