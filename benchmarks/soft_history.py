"""The soft sensor's load history, and ftcal's ``HistoryCalibrator`` against the stock baselines.

Usage::

    python benchmarks/soft_history.py [--out benchmarks/results/auto_vs_stock/soft_history.json] [--force]

The press-grouped 5-fold of ``benchmarks/auto_vs_stock.py``'s ``soft_grouped`` case
(:func:`ftcal.simulation.make_soft_sensor_dataset`, 418 rows in recording order, whole presses held out). Every model
is fitted on the training presses (in recording order) and predicts the held-out presses as one recording
(in recording order, starting at rest: what ``cross_val_predict`` gives; no reading of a training press
feeds the history of a held-out one). Scored with eq. 18:

* the static models: ftcal's ``polynomial(degree=3, ridge=0.01)`` (what ``auto`` chooses here), ``auto``
  itself and the five stock scikit-learn baselines;
* **ftcal's history term** (:class:`ftcal.HistoryCalibrator`, ``ftcal fit --history``): the static model
  plus a linear map of :func:`ftcal.compose.reading_history` of the readings (their moving average over the rows
  before each row, minus the row: readings only, nothing a deployed sensor lacks), fitted jointly by
  backfitting, its time constant chosen from ``(1, 2, 4, 8, 16)`` rows by an inner press-grouped CV on the
  training presses alone (the simulator's own, 3 rows, is not given), or no term when it does not pay;
  on the polynomial, and on ``auto`` (``HistoryCalibrator(AutoCalibrator())``: ``auto`` chooses the static
  model once, then the history term is fitted with it);
* **the stock baselines given the same history columns** (``[X, reading_history(X, tau)]`` with the ``tau``
  ftcal chose in that fold): what a user who thought of the feature would get for free.
"""

from __future__ import annotations

import json
import time

import numpy as np
from sklearn.model_selection import GroupKFold

import ftcal
from ftcal.calibrators import stock_baselines

from _output import parse_output


def main() -> None:
    out = parse_output(__doc__, "benchmarks/results/auto_vs_stock/soft_history.json")
    d = ftcal.simulation.make_soft_sensor_dataset()
    raw, wrench, groups, alpha = d.raw, d.wrench, d.group, d.meta["alpha"]
    stock = list(stock_baselines(raw.shape[1]))
    names = ["polynomial(degree=3, ridge=0.01)", "auto", *stock, "history(polynomial(degree=3, ridge=0.01))",
             "history(auto)", *[f"{s} + history columns" for s in stock]]
    pred = {n: np.empty_like(wrench) for n in names}
    chosen: dict[str, list] = {"history(polynomial)": [], "history(auto)": [], "auto": [], "history(auto) static": []}
    seconds: dict[str, list] = {n: [] for n in ("auto", "history(auto)", "history(polynomial)")}
    for train, test in GroupKFold(5).split(raw, groups=groups):
        X, y, g = raw[train], wrench[train], groups[train]

        def poly():
            return ftcal.PolynomialCalibrator(degree=3, ridge=0.01, alpha=alpha)

        pred[names[0]][test] = poly().fit(X, y).predict(raw[test])
        start = time.perf_counter()
        auto = ftcal.AutoCalibrator(alpha=alpha, n_jobs=2, random_state=0).fit(X, y, groups=g)
        seconds["auto"].append(time.perf_counter() - start)
        pred["auto"][test] = auto.predict(raw[test])
        chosen["auto"].append(auto.best_name_)
        start = time.perf_counter()
        hp = ftcal.HistoryCalibrator(poly(), alpha=alpha).fit(X, y, groups=g)
        seconds["history(polynomial)"].append(time.perf_counter() - start)
        pred[names[len(stock) + 2]][test] = hp.predict(raw[test])
        chosen["history(polynomial)"].append(hp.tau_rows_)
        start = time.perf_counter()
        ha = ftcal.HistoryCalibrator(ftcal.AutoCalibrator(n_jobs=2, random_state=0), alpha=alpha).fit(X, y, groups=g)
        seconds["history(auto)"].append(time.perf_counter() - start)
        pred["history(auto)"][test] = ha.predict(raw[test])
        chosen["history(auto)"].append(ha.tau_rows_)
        chosen["history(auto) static"].append(ha.static_choice_)
        tau = hp.tau_rows_ or 2.0  # the stock models get the time constant ftcal chose (2 rows if it chose none)
        with_history = (np.c_[X, ftcal.compose.reading_history(X, tau)],
                        np.c_[raw[test], ftcal.compose.reading_history(raw[test], tau)])
        for name, model in stock_baselines(raw.shape[1], random_state=0).items():
            pred[name][test] = model.fit(X, y).predict(raw[test])
        for name, model in stock_baselines(2 * raw.shape[1], random_state=0).items():
            pred[f"{name} + history columns"][test] = model.fit(with_history[0], y).predict(with_history[1])
    rmse = {n: ftcal.core.wrench_rmse(wrench, p, alpha=alpha) for n, p in pred.items()}
    best_stock = min(rmse[s] for s in stock)
    best_stock_history = min(rmse[f"{s} + history columns"] for s in stock)
    result = {"rmse": rmse, "best_stock": best_stock, "best_stock_with_history_columns": best_stock_history,
              "chosen_per_fold": chosen, "fit_seconds_per_fold": seconds,
              "history_auto_over_best_stock": rmse["history(auto)"] / best_stock,
              "auto_over_best_stock": rmse["auto"] / best_stock,
              "load_average": list(__import__("os").getloadavg())}
    out.write_text(json.dumps(result, indent=1))
    print("| model | RMSE (eq. 18) [N] | / best stock (static) | / best stock with history columns |\n|---|---|---|---|")
    for name, value in rmse.items():
        print(f"| {name} | {value:.4f} | {value / best_stock:.3f} | {value / best_stock_history:.3f} |")
    print(f"\nchosen per outer fold: {chosen}\nfit seconds per fold: {seconds}")


if __name__ == "__main__":
    main()
