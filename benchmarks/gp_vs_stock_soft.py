"""ftcal's GP against the stock scikit-learn GP on the simulated soft sensor (8 correlated channels, torques in N·mm),
5-fold, same folds: eq. 18 RMSE and the 2-std coverage of ftcal's calibrated std.

Usage: nice -n 10 python benchmarks/gp_vs_stock_soft.py [--rows 418] [--hysteresis 0.25 1.0] [--seed 0]

Rows: the LTM; ``GaussianProcessCalibrator()`` (mean, kernel, bounds and per-output chosen by held-out error);
ftcal's GP set to the stock structure (``mean="none", kernel="rbf", per_output=False, kernel_bounds="stock"``,
which must equal the stock GP); the stock GP (``StandardScaler + GaussianProcessRegressor(ConstantKernel() *
RBF(ones(8)) + WhiteKernel(), normalize_y=True)``). Each fit runs single-threaded (``threadpool_limits(1)``).
"""
import argparse
import time
import warnings

import numpy as np
from sklearn.model_selection import KFold
from threadpoolctl import threadpool_limits

import ftcal
from ftcal import GaussianProcessCalibrator, LinearCalibrator
from ftcal.simulation import make_soft_sensor_dataset
from ftcal.calibrators import stock_baselines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--rows", type=int, default=418)
    parser.add_argument("--hysteresis", type=float, nargs="+", default=[0.25, 1.0])
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    for hysteresis in args.hysteresis:
        d = make_soft_sensor_dataset(args.rows, hysteresis=hysteresis, random_state=args.seed)
        wrench = d.wrench * [1, 1, 1, 1000, 1000, 1000]  # torques in N·mm, as the real sensor's file
        alpha = float(np.abs(wrench[:, :3]).max() / np.abs(wrench[:, 3:]).max())
        models = [
            ("LTM", lambda: LinearCalibrator(alpha=alpha)),
            ("ftcal GP (held-out choice)", lambda: GaussianProcessCalibrator(alpha=alpha, random_state=0)),
            ("ftcal GP, stock structure", lambda: GaussianProcessCalibrator(
                alpha=alpha, mean="none", kernel="rbf", per_output=False, kernel_bounds="stock", random_state=0)),
            ("stock GP (sk_gp)", lambda: stock_baselines(8)["sk_gp"]),
        ]
        print(f"\nsoft sensor, {args.rows} rows, hysteresis {hysteresis}, seed {args.seed}, alpha {alpha:.4g} 1/mm\n")
        print("| model | 5-fold RMSE [N] (eq. 18) | / stock GP | 2-std coverage | choices (fold 1) | s per fit |")
        print("|---|---|---|---|---|---|")
        rows = []
        for name, make in models:
            pred, cover, choice, start = np.zeros_like(wrench), [], "", time.perf_counter()
            for fold, (train, test) in enumerate(KFold(5, shuffle=True, random_state=0).split(d.raw)):
                with threadpool_limits(1):
                    model = make().fit(d.raw[train], wrench[train])
                if isinstance(model, GaussianProcessCalibrator):
                    pred[test], std = model.predict(d.raw[test], return_std=True)
                    cover.append(np.abs(pred[test] - wrench[test]) <= 2 * std)
                    choice = choice or f"{model.mean_}/{model.kernel_}/{model.kernel_bounds_}" + (
                        ", per output" if model.per_output_ else "")
                else:
                    pred[test] = model.predict(d.raw[test])
            rows.append((name, ftcal.core.wrench_rmse(wrench, pred, alpha), np.mean(np.vstack(cover)) if cover else None,
                         choice, (time.perf_counter() - start) / 5))
        stock = rows[-1][1]
        for name, rmse, coverage, choice, seconds in rows:
            cov = f"{coverage:.3f}" if coverage is not None else "—"
            print(f"| {name} | {rmse:.4f} | {rmse / stock:.3f} | {cov} | {choice or '—'} | {seconds:.1f} |", flush=True)


if __name__ == "__main__":
    main()
