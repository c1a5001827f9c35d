"""Issue 19: how much of the soft sensor's remaining error is its load history, i.e. out of reach of any static map.

Usage::

    python benchmarks/soft_history.py [--out benchmarks/results/auto_vs_stock/soft_history.json] [--force]

The press-grouped 5-fold of ``benchmarks/auto_vs_stock.py``'s ``soft_grouped`` case
(:func:`ftcal.make_soft_sensor_dataset`, 418 rows in recording order, whole presses held out). Every model
is fitted on the training presses and scored (eq. 18) on the held-out ones:

* the static models: ftcal's ``polynomial(degree=3, ridge=0.01)`` (what ``auto`` chooses here) and the five
  stock scikit-learn baselines;
* **a first-order history term** on top of that polynomial: the readings' exponential moving average over the
  rows *before* each row (time constant ``tau`` rows, in recording order; readings only, no reference
  wrench, so nothing a deployed sensor would not have), minus the current reading, mapped linearly onto
  the polynomial's residual. ``tau`` is chosen from ``(1, 2, 4, 8, 16)`` rows by an inner press-grouped
  5-fold on the training presses alone, so the simulator's own time constant (3 rows) is not given.

This is an experiment, not an ftcal model: a history-aware calibrator needs readings in time order at
``predict`` (a stream with state, no ONNX graph), an API decision left to the owner (``benchmarks/RESULTS.md``).
"""

from __future__ import annotations

import json

import numpy as np
from sklearn.model_selection import GroupKFold

import ftcal
from ftcal.models import stock_baselines

from _output import parse_output

TAUS = (1.0, 2.0, 4.0, 8.0, 16.0)


def history(raw: np.ndarray, tau: float) -> np.ndarray:
    """Each row's exponential moving average of the readings before it (the first row: itself), minus the row."""
    mean, out = raw[0].copy(), np.empty_like(raw)
    for i, row in enumerate(raw):
        out[i] = mean - row
        mean += (row - mean) / tau
    return out


class WithHistory:
    """``PolynomialCalibrator(3, 0.01)`` plus a linear map of ``history(raw, tau)`` onto its residual."""

    def __init__(self, tau: float, alpha: float):
        self.tau, self.alpha = tau, alpha

    def fit(self, raw, wrench, lagged):
        self.static_ = ftcal.PolynomialCalibrator(degree=3, ridge=0.01, alpha=self.alpha).fit(raw, wrench)
        design = np.c_[lagged, np.ones(len(raw))]
        self.coef_ = np.linalg.lstsq(design, wrench - self.static_.predict(raw), rcond=None)[0]
        return self

    def predict(self, raw, lagged):
        return self.static_.predict(raw) + np.c_[lagged, np.ones(len(raw))] @ self.coef_


def main() -> None:
    out = parse_output(__doc__, "benchmarks/results/auto_vs_stock/soft_history.json")
    d = ftcal.make_soft_sensor_dataset()
    raw, wrench, groups, alpha = d.raw, d.wrench, d.group, d.meta["alpha"]
    lagged = {tau: history(raw, tau) for tau in TAUS}  # over the whole recording, as a deployed sensor would see it
    names = ["polynomial(degree=3, ridge=0.01)", *stock_baselines(raw.shape[1]), "polynomial + history"]
    pred, chosen = {n: np.empty_like(wrench) for n in names}, []
    for train, test in GroupKFold(5).split(raw, groups=groups):
        inner = list(GroupKFold(5).split(raw[train], groups=groups[train]))

        def inner_rmse(tau):
            p = np.empty_like(wrench[train])
            for a, b in inner:
                model = WithHistory(tau, alpha).fit(raw[train][a], wrench[train][a], lagged[tau][train][a])
                p[b] = model.predict(raw[train][b], lagged[tau][train][b])
            return ftcal.wrench_rmse(wrench[train], p, alpha=alpha)

        tau = min(TAUS, key=inner_rmse)
        chosen.append(tau)
        pred["polynomial + history"][test] = WithHistory(tau, alpha).fit(
            raw[train], wrench[train], lagged[tau][train]).predict(raw[test], lagged[tau][test])
        static = ftcal.PolynomialCalibrator(degree=3, ridge=0.01, alpha=alpha).fit(raw[train], wrench[train])
        pred[names[0]][test] = static.predict(raw[test])
        for name, model in stock_baselines(raw.shape[1], random_state=0).items():
            pred[name][test] = model.fit(raw[train], wrench[train]).predict(raw[test])
    rmse = {n: ftcal.wrench_rmse(wrench, p, alpha=alpha) for n, p in pred.items()}
    best_stock = min(v for n, v in rmse.items() if n.startswith("sk_"))
    result = {"rmse": rmse, "best_stock": best_stock, "tau_chosen_per_fold": chosen,
              "history_over_best_stock": rmse["polynomial + history"] / best_stock,
              "static_over_best_stock": rmse[names[0]] / best_stock}
    out.write_text(json.dumps(result, indent=1))
    print("| model | RMSE (eq. 18) [N] | / best stock |\n|---|---|---|")
    for name, value in rmse.items():
        print(f"| {name} | {value:.4f} | {value / best_stock:.3f} |")
    print(f"\ntau chosen per outer fold: {chosen}")


if __name__ == "__main__":
    main()
