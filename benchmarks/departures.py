#!/usr/bin/env python
"""Measured effects of ftcal's departures from the thesis (RESULTS.md "Departures from the thesis").

1. Nonlinearity γ: 1 % of full scale (ftcal) against the printed 1e-3 (0.1 %), LTM RMSE and noise floor on
   ``thesis`` data (the LTM is the model eq. 14 hurts).
2. eq. 18 per component (ftcal) against per sample (the norm of the 6-component error): the same predictions
   scored both ways.
3. Table II's "± std": how much of the LTM's spread across datasets the per-dataset noise floor explains (R²),
   from the cached study results.
4. The best-weights restore: the same net (same seed, same data) with and without restoring the weights of
   the best epoch at the end of training (the restore switched off for the measurement only).

Examples::

    python benchmarks/departures.py --out benchmarks/results/departures
    python benchmarks/departures.py --out benchmarks/results/departures --restore-schedule thesis
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import replace
from pathlib import Path

import numpy as np

from ftcal.simulation import ERROR_PRESETS, SensorProfile
from ftcal import LinearCalibrator, make_artificial_dataset
from ftcal.core import per_sample_rmse, wrench_rmse
from ftcal.benchmark import read_json_record
from ftcal.benchmark import dataset_seeds, make_model

from _output import int_at_least, output_files

ROOT = Path(__file__).resolve().parent


def gamma_effect(n: int) -> dict:
    out = {}
    for gamma in (0.001, 0.01):
        model = replace(ERROR_PRESETS["thesis"], nonlinearity=gamma)
        ltm, floor = [], []
        for i in range(n):
            train, test, info = make_artificial_dataset(model, random_state=dataset_seeds(0, i)[0])
            ltm.append(wrench_rmse(test.wrench, LinearCalibrator().fit(train.raw, train.wrench).predict(test.raw), 50.0))
            floor.append(info["noise_floor"])
        out[f"gamma={gamma:g}"] = {"ltm_rmse": float(np.mean(ltm)), "noise_floor": float(np.mean(floor)), "n": n}
    return out


def eq18_effect(n: int) -> dict:
    out = {}
    for preset in ("thesis", "reconstructed"):
        comp, sample = [], []
        for i in range(n):
            train, test, _ = make_artificial_dataset(preset, random_state=dataset_seeds(0, i)[0])
            pred = LinearCalibrator().fit(train.raw, train.wrench).predict(test.raw)
            comp.append(wrench_rmse(test.wrench, pred, 50.0))
            # per sample: RMSE over samples of the 6-D error norm = sqrt(6) x the per-component RMSE
            sample.append(float(np.sqrt(np.mean((np.sqrt(6) * per_sample_rmse(test.wrench, pred, 50.0)) ** 2))))
        out[preset] = {"ltm_per_component": float(np.mean(comp)), "ltm_per_sample_norm": float(np.mean(sample)),
                       "ratio": float(np.mean(sample) / np.mean(comp)), "n": n}
    return out


def spread_explained(cache: Path) -> dict | None:
    recs = [r for r in (read_json_record(p, numbers=("rmse", "noise_floor"), model="linear")
                        for p in cache.glob("ds*_linear_*.json")) if r is not None]
    if len(recs) < 3:
        return None
    rmse = np.array([r["rmse"] for r in recs])
    floor = np.array([r["noise_floor"] for r in recs])
    r = np.corrcoef(rmse, floor)[0, 1]
    return {"n": len(recs), "r2": float(r**2), "ltm_std": float(rmse.std(ddof=1)), "floor_std": float(floor.std(ddof=1))}


def restore_effect(models, presets, schedule: str = "short") -> dict:
    """Test RMSE with the best epoch's weights (ftcal) and with the last epoch's, from one fit: the last weights are
    copied aside just before :class:`~ftcal.networks.RestoreBestWeights` loads the best ones."""
    import torch

    from ftcal.networks import RestoreBestWeights

    out = {}
    original = RestoreBestWeights.on_train_end
    last = {}

    def keep_last_then_restore(self, net, **kwargs):
        last["state"] = [p.detach().clone() for p in net.module_.parameters()]
        original(self, net, **kwargs)

    profile = SensorProfile.default()
    for preset in presets:
        data_seed, model_seed = dataset_seeds(0, 0)
        train, test, _ = make_artificial_dataset(preset, random_state=data_seed)
        for name in models:
            RestoreBestWeights.on_train_end = keep_last_then_restore
            try:
                est = make_model(name, n_channels=6, alpha=profile.alpha, schedule=schedule, random_state=model_seed)
                est.fit(train.raw, train.wrench)
            finally:
                RestoreBestWeights.on_train_end = original
            row = {"schedule": schedule, "with_restore": wrench_rmse(test.wrench, est.predict(test.raw), 50.0)}
            with torch.no_grad():
                for p, value in zip(est.net_.module_.parameters(), last["state"]):
                    p.copy_(value)
            est.__dict__.pop("_numpy_layers_cache", None)  # predict's numpy copy of the weights
            row["last_epoch"] = wrench_rmse(test.wrench, est.predict(test.raw), 50.0)
            row["epochs"], row["best_epoch"] = int(est.n_epochs_), int(est.best_epoch_)
            out[f"{preset}/{name}" + ("" if schedule == "short" else f"/{schedule}")] = row
            print(preset, name, row, flush=True)
    return out


def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--datasets", type=int_at_least(1, 1000), default=5, help="datasets of the closed-form measurements")
    p.add_argument("--out", default=str(ROOT / "out" / "departures"))
    p.add_argument("--restore-schedule", choices=["short", "thesis"],
                   help="only measure the best-weights restore, with this schedule, and add it to departures.json")
    p.add_argument("--force", action="store_true", help="replace a departures.json this script did not write")
    args = p.parse_args(argv)
    files = output_files(p, args.out, args.force, ["departures.json"])
    path = files.out_dir / "departures.json"
    if args.restore_schedule:
        result = read_json_record(path) or {}
        result.setdefault("restore", {}).update(
            restore_effect(("directional", "comparative"), ("reconstructed", "thesis"), args.restore_schedule))
        files.write_text("departures.json", json.dumps(result, indent=1))
        return 0
    result = {"gamma": gamma_effect(args.datasets), "eq18": eq18_effect(args.datasets),
              "spread_thesis": spread_explained(ROOT / "results" / "artificial_thesis" / "cache" / "thesis"),
              "spread_reconstructed": spread_explained(ROOT / "results" / "artificial_reconstructed" / "cache" / "reconstructed")}
    files.write_text("departures.json", json.dumps(result, indent=1))
    print(json.dumps(result, indent=1), flush=True)
    result["restore"] = restore_effect(("directional", "comparative"), ("reconstructed", "thesis"))
    files.write_text("departures.json", json.dumps(result, indent=1))
    print(json.dumps(result["restore"], indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())
