"""Issue 19: one offset per pose (``PolynomialCalibrator(group_offsets=True)``) on the simulated robot-held sensor.

Usage::

    python benchmarks/group_offsets.py [--out benchmarks/results/auto_vs_stock/group_offsets.json] [--force]

:func:`ftcal.make_robot_held_dataset` (90 000 rows, 47 poses, each pose shifting all readings by an offset of
its own), the pose-grouped 5-fold of ``benchmarks/auto_vs_stock.py``'s ``robot_held`` case: the LTM and the
quadratic (ridge 0.01) with and without one offset per pose (fitted with the training poses as ``groups``),
beside the stock baselines a user would try first (the kernel ones on 1000 rows) and the static floor that
``auto_vs_stock.py`` caches (``robot_static_floor_5.json``, if present). RMSE: eq. 18 over all held-out rows.
"""

from __future__ import annotations

import json

import numpy as np
from sklearn.model_selection import GroupKFold

import ftcal
from ftcal.models import stock_baselines

from _output import parse_output


def main() -> None:
    out = parse_output(__doc__, "benchmarks/results/auto_vs_stock/group_offsets.json")
    d = ftcal.make_robot_held_dataset()
    raw, wrench, groups, alpha = d.raw, d.wrench, d.group, d.meta["alpha"]
    models = {f"polynomial(degree={k}{', ridge=0.01' if k > 1 else ''}{', group offsets' if offsets else ''})":
              ftcal.PolynomialCalibrator(degree=k, ridge=0.01, group_offsets=offsets, alpha=alpha)
              for k in (1, 2) for offsets in (False, True)}
    names = [*models, *stock_baselines(raw.shape[1])]
    pred = {n: np.empty_like(wrench) for n in names}
    for train, test in GroupKFold(5).split(raw, groups=groups):
        for name, model in {**models, **stock_baselines(raw.shape[1], random_state=0)}.items():
            kwargs = {"groups": groups[train]} if name in models else {}
            pred[name][test] = model.fit(raw[train], wrench[train], **kwargs).predict(raw[test])
        print(f"fold done ({len(test)} held-out rows)", flush=True)
    rmse = {n: ftcal.wrench_rmse(wrench, p, alpha=alpha) for n, p in pred.items()}
    floor_file = out.parent / "robot_static_floor_5.json"
    floor = json.loads(floor_file.read_text())["rmse"] if floor_file.exists() else None
    best_stock = min(v for n, v in rmse.items() if n.startswith("sk_"))
    out.write_text(json.dumps({"rmse": rmse, "best_stock": best_stock, "static_floor": floor}, indent=1))
    print("| model | RMSE (eq. 18) [N] | / best stock | / static floor |\n|---|---|---|---|")
    for name, value in rmse.items():
        print(f"| {name} | {value:.4f} | {value / best_stock:.3f} | "
              f"{'' if floor is None else f'{value / floor:.3f}'} |")


if __name__ == "__main__":
    main()
