"""auto / LTM per pose-grouped outer fold and pooled on a simulated robot-held recording.

Usage::

    python benchmarks/robot_pose_folds.py [--rows 8000] [--poses 41] [--folds 0 1 2 3 4] [--jobs 2] --out FILE

Each outer fold holds out whole poses; ``make_calibrator("auto")`` (given the training poses as groups) and the
LTM are fitted on the rest and scored on the held-out poses (eq. 18's torque-scaled RMSE [N]); the paired SE of
the RMSE difference is over the held-out poses (delta method). Written after every fold.

``--closed-forms`` (a diagnosis, seconds a fold): auto over the closed-form candidates only (no stock models, no
GP, no networks), and for every candidate its inner (comparison) RMSE beside its outer RMSE on the held-out poses
when refitted on all training poses (``candidates`` of each fold in the JSON): whether the inner estimate
predicts the outer error.
"""

from __future__ import annotations

import argparse
import json
import os
import time
import warnings

import numpy as np
from sklearn.base import clone

import ftcal
from ftcal.core import scale_torques
from ftcal.compose import default_candidates
from ftcal.model_selection import calibration_folds, mean_and_se, model_cost


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--rows", type=int, default=8000)
    parser.add_argument("--poses", type=int, default=41)
    parser.add_argument("--folds", type=int, nargs="+", default=[0, 1, 2, 3, 4])
    parser.add_argument("--jobs", type=int, default=2)
    parser.add_argument("--out", required=True)
    parser.add_argument("--closed-forms", action="store_true", help="auto over the closed forms; inner vs outer")
    args = parser.parse_args()
    warnings.simplefilter("ignore")
    d = ftcal.simulation.make_robot_held_dataset(args.rows, n_poses=args.poses, random_state=0)
    X, y, g = d.raw, d.wrench, d.group
    folds = calibration_folds(len(X), g, 5)
    result = {"rows": args.rows, "poses": args.poses, "load_before": os.getloadavg(), "folds": []}
    errs_auto, errs_ltm, units = [], [], []
    for k in args.folds:
        train, test = folds[k]
        t0 = time.perf_counter()
        if args.closed_forms:
            closed = [(n, c) for n, c in default_candidates(grouped=True) if model_cost(c) == "closed_form"]
            auto = ftcal.AutoCalibrator(candidates=closed, baselines=False, n_jobs=1, random_state=0)
        else:
            auto = ftcal.make_calibrator("auto", n_jobs=args.jobs, random_state=0)
        auto.fit(X[train], y[train], groups=g[train])
        seconds = time.perf_counter() - t0
        ltm = ftcal.make_calibrator("linear").fit(X[train], y[train])
        alpha = auto.alpha_
        e = lambda m: np.mean((scale_torques(m.predict(X[test]), alpha) - scale_torques(y[test], alpha)) ** 2, 1)  # noqa: E731
        ea, el = e(auto), e(ltm)
        ra, rl = float(np.sqrt(ea.mean())), float(np.sqrt(el.mean()))
        d_se = mean_and_se(ea - el, g[test])[1] / (ra + rl)
        result["folds"].append({"fold": k, "auto_rmse": ra, "ltm_rmse": rl, "ratio": ra / rl,
                                "paired_se_of_difference": d_se, "chosen": auto.best_name_, "fit_s": seconds,
                                "why": auto.comparison_.why, "load": os.getloadavg()})
        if args.closed_forms:
            outer = {n: float(np.sqrt(e(clone(c).set_params(alpha=alpha).fit(X[train], y[train], **(
                {"groups": g[train]} if c.get_params().get("group_offsets") else {}))).mean()))
                for n, c in closed}
            result["folds"][-1]["candidates"] = [{"name": r.name, "inner_rmse": r.rmse, "outer_rmse": outer.get(r.name),
                                                  "verdict": r.verdict} for r in auto.comparison_.rows]
        errs_auto.append(ea), errs_ltm.append(el), units.append(g[test])
        ea_all, el_all = np.concatenate(errs_auto), np.concatenate(errs_ltm)
        result["pooled_ratio"] = float(np.sqrt(ea_all.mean() / el_all.mean()))
        print(json.dumps(result["folds"][-1]), flush=True)
        with open(args.out, "w") as fh:
            json.dump(result, fh, indent=1)


if __name__ == "__main__":
    main()
