"""One offset per pose (``PolynomialCalibrator(group_offsets=True)``) on the simulated robot-held sensor.

Usage::

    python benchmarks/group_offsets.py [--out benchmarks/results/auto_vs_stock/group_offsets.json] [--force]

:func:`ftcal.simulation.make_robot_held_dataset` (90 000 rows, 47 poses, each pose shifting all readings by an offset of
its own), the pose-grouped 5-fold of ``benchmarks/auto_vs_stock.py``'s ``robot_held`` case: the LTM and the
quadratic (ridge 0.01) with and without one offset per pose (fitted with the training poses as ``groups``),
beside the stock baselines a user would try first (the kernel ones on 1000 rows) and the static floor that
``auto_vs_stock.py`` caches (``robot_static_floor_5.json``, if present). RMSE: eq. 18 over all held-out rows.

Two checks of that floor and of ``auto``'s choice, on the same folds: the stock polynomials fitted per fold on the
training poses of the same sensor recorded without offsets (``pose_offset=0``, same seed; is the floor, fitted on
all 90 000 rows, flattered by fitting in sample?), and in every fold ``AutoCalibrator`` with the closed-form
candidates (the LTM, the quadratics, the twins; no stack, no baselines): its inner-CV table and choice.
"""

from __future__ import annotations

import json

import numpy as np
from sklearn.model_selection import GroupKFold

import ftcal
from ftcal.benchmark import read_json_record
from ftcal.compose import default_candidates
from ftcal.calibrators import stock_baselines

from _output import parse_output


def main() -> None:
    out = parse_output(__doc__, "benchmarks/results/auto_vs_stock/group_offsets.json")
    d = ftcal.simulation.make_robot_held_dataset()
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
    rmse = {n: ftcal.core.wrench_rmse(wrench, p, alpha=alpha) for n, p in pred.items()}
    clean = ftcal.simulation.make_robot_held_dataset(d.n_samples, n_poses=int(np.unique(groups).size),
                                          random_state=d.meta["random_state"], pose_offset=0.0)
    per_fold = {n: np.empty_like(wrench) for n in ("sk_poly2", "sk_poly3")}
    inner = []
    closed_forms = [c for c in default_candidates(grouped=True) if c[0].startswith(("linear", "polynomial(degree=2"))]
    for train, test in GroupKFold(5).split(raw, groups=groups):
        for name in per_fold:
            per_fold[name][test] = stock_baselines(raw.shape[1])[name].fit(
                clean.raw[train], clean.wrench[train]).predict(raw[test])
        auto = ftcal.AutoCalibrator(candidates=closed_forms, alpha=alpha, stack=False, baselines=False)
        auto.fit(raw[train], wrench[train], groups=groups[train])
        inner.append({"chosen": auto.best_name_, "table": auto.summary()})
        print(f"fold checked: auto (closed forms) chose {auto.best_name_}", flush=True)
    floor_per_fold = {n: ftcal.core.wrench_rmse(wrench, p, alpha=alpha) for n, p in per_fold.items()}
    floor_record = read_json_record(out.path.parent / "robot_static_floor_5.json", numbers=("rmse",))
    floor = None if floor_record is None else floor_record["rmse"]
    best_stock = min(v for n, v in rmse.items() if n.startswith("sk_"))
    out.write_text(json.dumps({"rmse": rmse, "best_stock": best_stock, "static_floor": floor,
                               "static_floor_fitted_per_fold": floor_per_fold, "auto_closed_forms_per_fold": inner},
                              indent=1))
    print("| model | RMSE (eq. 18) [N] | / best stock | / static floor |\n|---|---|---|---|")
    for name, value in rmse.items():
        print(f"| {name} | {value:.4f} | {value / best_stock:.3f} | "
              f"{'' if floor is None else f'{value / floor:.3f}'} |")
    print("static floor fitted per fold on the offset-free training poses:", floor_per_fold)
    print("auto (closed forms) per fold:", [i["chosen"] for i in inner])


if __name__ == "__main__":
    main()
