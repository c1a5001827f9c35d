#!/usr/bin/env python
"""The figures a sensor maker reports: per-axis RMSE and maximum error in % of full scale, and the
error against load magnitude, including loads beyond the largest training sphere (extrapolation).

Each model is fitted on the four-sphere train set of an artificial dataset (outer sphere 0.8 Fmax = 1600 N
torque-scaled) and scored on two test sets of the same sensor pooled: the ``ball`` set (force in the 2000 N
ball, torque in the 40 N·m ball: torque-scaled norms up to 2828 N, most points beyond the outer sphere) and
the ``radial`` set (norm uniform in 0-2000 N, so small loads are covered too), 1250 points each. Full scale: Fmax for the
forces, Tmax for the torques. The test predictions of every fit are cached (``OUT/cache/*.npz``, keyed by the data's fingerprint too), so the same
command resumes and ``--aggregate-only`` only redraws.

Outputs in ``OUT``: ``sensor_maker.md`` (per-axis tables), ``sensor_maker_axes.png`` (per-axis RMSE and max
error, % FS), ``sensor_maker_magnitude.png`` (RMSE per load-magnitude bin, the training spheres marked).

Examples::

    python benchmarks/sensor_maker.py --datasets 3 --schedule short --out benchmarks/results/sensor_maker
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import zipfile
import zlib
from pathlib import Path

import numpy as np

from ftcal.compose import CALIBRATOR_NAMES
from ftcal.simulation import ERROR_PRESETS, SensorProfile
from ftcal import make_artificial_dataset
from ftcal.core import scale_torques
from ftcal.benchmark import dataset_seeds, make_model
from ftcal.benchmark import data_fingerprint
from ftcal.core import atomic_output
from ftcal.calibrators import STOCK_BASELINE_NAMES

from _output import int_at_least, output_files

MODELS = ("linear", "sk_poly2", "axis_nonlinear", "directional", "comparative", "gaussian_process", "sk_gp")
AXES = ("Fx", "Fy", "Fz", "Tx", "Ty", "Tz")
DEFAULT_OUT = Path(__file__).resolve().parent / "out" / "sensor_maker"
BINS = np.arange(0.0, 3000.0, 250.0)  # torque-scaled load norm [N]


def _fit_predict(preset: str, index: int, model: str, schedule: str, cache: Path, fit: bool = True) -> dict | None:
    """Test predictions of one fit with what scores them; from the cache when it holds this fit's (same
    configuration and data), else fitted and cached, or None with ``fit=False`` (aggregating only)."""
    data_seed, model_seed = dataset_seeds(0, index)
    profile = SensorProfile.default()
    # the same seed gives the same sensor errors and train set; only the test loads differ
    train, test, info = make_artificial_dataset(preset, random_state=data_seed, test_distribution="ball")
    _, radial, _ = make_artificial_dataset(preset, random_state=data_seed, test_distribution="radial")
    test_raw, test_wrench = np.vstack([test.raw, radial.raw]), np.vstack([test.wrench, radial.wrench])
    # the key holds the data's fingerprint: predictions made on data the current code no longer makes are not reused
    config = {"preset": preset, "index": index, "model": model, "schedule": schedule, "test": "ball+radial",
              "data": data_fingerprint(train.raw, train.wrench, test_raw, test_wrench, [profile.alpha])}
    key = hashlib.sha256(json.dumps(config, sort_keys=True).encode()).hexdigest()[:12]
    path = cache / f"{preset}_ds{index:03d}_{model}_{key}.npz"
    pred = _cached_prediction(path, test_wrench.shape)
    if pred is None and not fit:
        return None
    if pred is None:  # not cached, or a file that is not this script's prediction: fit again
        est = make_model(model, n_channels=profile.n_channels, alpha=profile.alpha, schedule=schedule,
                         random_state=model_seed)
        est.fit(train.raw, train.wrench)
        pred = est.predict(test_raw)
        path.parent.mkdir(parents=True, exist_ok=True)
        with atomic_output(path, overwrite=True, error=FileExistsError) as tmp:
            np.savez(tmp, pred=pred)
        print(f"{preset} dataset {index} {model}: fitted", flush=True)
    return {"true": test_wrench, "pred": pred, "noise_floor": info["noise_floor"], "radii": info["sphere_radii"]}


def _cached_prediction(path: Path, shape: tuple) -> np.ndarray | None:
    """The cached test predictions, or None when missing, unreadable or not of the test set's shape."""
    try:
        with np.load(path, allow_pickle=False) as data:
            pred = np.asarray(data["pred"], dtype=float)
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile, zlib.error):  # missing, truncated, foreign
        return None
    return pred if pred.shape == shape and np.isfinite(pred).all() else None


def axis_table(runs: list[dict], fmax: float, tmax: float) -> dict:
    """Per axis, over all datasets' test points: RMSE and max |error| in % of full scale."""
    fs = np.array([fmax] * 3 + [tmax] * 3)
    err = np.vstack([r["pred"] - r["true"] for r in runs])
    return {"rmse_pct_fs": (100 * np.sqrt(np.mean(err ** 2, axis=0)) / fs).tolist(),
            "max_pct_fs": (100 * np.abs(err).max(axis=0) / fs).tolist()}


def magnitude_curve(runs: list[dict], alpha: float) -> dict:
    """RMSE (eq. 18, torque-scaled) per bin of the torque-scaled load norm."""
    norm = np.concatenate([np.linalg.norm(scale_torques(r["true"], alpha), axis=1) for r in runs])
    sq = np.concatenate([np.mean(scale_torques(r["pred"] - r["true"], alpha) ** 2, axis=1) for r in runs])
    idx = np.digitize(norm, BINS) - 1
    rmse = [float(np.sqrt(sq[idx == b].mean())) if np.any(idx == b) else None for b in range(len(BINS))]
    return {"bin_left": BINS.tolist(), "rmse": rmse, "count": [int(np.sum(idx == b)) for b in range(len(BINS))]}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--presets", nargs="+", default=["reconstructed", "thesis"], choices=sorted(ERROR_PRESETS))
    p.add_argument("--datasets", type=int_at_least(1, 1000), default=3)
    p.add_argument("--models", nargs="+", default=list(MODELS), choices=[*CALIBRATOR_NAMES, *STOCK_BASELINE_NAMES])
    p.add_argument("--schedule", default="short", choices=["thesis", "short"])
    p.add_argument("--out", default=str(DEFAULT_OUT))
    p.add_argument("--aggregate-only", action="store_true")
    p.add_argument("--force", action="store_true", help="replace output files this script did not write")
    args = p.parse_args(argv)
    files = output_files(p, args.out, args.force, ["sensor_maker.md", "sensor_maker.json", "sensor_maker_axes.png",
                                                    "sensor_maker_magnitude.png"])
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = files.out_dir
    cache = out / "cache"
    profile = SensorProfile.default()
    results: dict = {}
    for preset in args.presets:
        for model in args.models:
            runs = []
            for i in range(args.datasets):  # --aggregate-only: only the fits cached for this configuration and data
                run = _fit_predict(preset, i, model, args.schedule, cache, fit=not args.aggregate_only)
                if run is not None:
                    runs.append(run)
            if runs:
                results.setdefault(preset, {})[model] = {
                    "n_datasets": len(runs), **axis_table(runs, profile.fmax, profile.tmax),
                    "magnitude": magnitude_curve(runs, profile.alpha),
                    "noise_floor": float(np.mean([r["noise_floor"] for r in runs])), "radii": runs[0]["radii"]}
    if not results:
        p.error(f"nothing to aggregate: no cached fit in {cache} (run without --aggregate-only first)")
    lines = [f"Sensor-maker figures: schedule `{args.schedule}`, ball + radial test loads (2 x 1250 per dataset), "
             f"full scale {profile.fmax:g} N / {profile.tmax:g} N·m. Errors pooled over the datasets' test points.", ""]
    for preset, per_model in results.items():
        lines += [f"### Preset `{preset}`", "",
                  "| model | datasets | " + " | ".join(f"{a} RMSE" for a in AXES) + " | " + " | ".join(f"{a} max" for a in AXES) + " |",
                  "|---" * 14 + "|"]
        for m, r in per_model.items():
            lines.append(f"| {m} | {r['n_datasets']} | " + " | ".join(f"{v:.2f}" for v in r["rmse_pct_fs"]) + " | "
                         + " | ".join(f"{v:.2f}" for v in r["max_pct_fs"]) + " |")
        lines += ["", "(% of full scale.) RMSE [N, eq. 18] by torque-scaled load norm (training spheres at "
                  + ", ".join(f"{x:g}" for x in next(iter(per_model.values()))["radii"]) + " N):", "",
                  "| model | " + " | ".join(f"{int(b)}-{int(b + 250)}" for b in BINS) + " |", "|---" * (len(BINS) + 1) + "|"]
        for m, r in per_model.items():
            lines.append(f"| {m} | " + " | ".join("—" if v is None else f"{v:.1f}" for v in r["magnitude"]["rmse"]) + " |")
        first = next(iter(per_model.values()))["magnitude"]["count"]
        lines += [f"| (test points) | " + " | ".join(str(c) for c in first) + " |", ""]
    files.write_text("sensor_maker.md", "\n".join(lines))
    files.write_text("sensor_maker.json", json.dumps(results))

    fig, axes = plt.subplots(len(results), 2, figsize=(11, 3.8 * len(results)), squeeze=False)
    for row, (preset, per_model) in enumerate(results.items()):
        width = 0.8 / max(1, len(per_model))
        for k, (m, r) in enumerate(per_model.items()):
            x = np.arange(6) + k * width
            axes[row][0].bar(x, r["rmse_pct_fs"], width, label=m)
            axes[row][1].bar(x, r["max_pct_fs"], width, label=m)
        for col, title in enumerate(("RMSE", "maximum |error|")):
            ax = axes[row][col]
            ax.set_xticks(np.arange(6) + 0.4 - width / 2, AXES)
            ax.set_ylabel("% of full scale")
            ax.set_title(f"{title} per axis, preset '{preset}'", fontsize=9)
        axes[row][1].legend(fontsize=7)
    fig.tight_layout()
    files.save_figure("sensor_maker_axes.png", fig, dpi=110)
    plt.close(fig)

    fig, axes = plt.subplots(1, len(results), figsize=(5.5 * len(results), 4.2), squeeze=False)
    for ax, (preset, per_model) in zip(axes[0], results.items()):
        centres = BINS + 125
        for m, r in per_model.items():
            y = np.array([np.nan if v is None else v for v in r["magnitude"]["rmse"]])
            ax.plot(centres, y, "--" if m.startswith("sk_") else "-", marker="o", ms=3, label=m)
        radii = next(iter(per_model.values()))["radii"]
        for rad in radii:
            ax.axvline(rad, color="grey", lw=0.6, ls=":")
        ax.axvspan(max(radii), BINS[-1] + 250, color="orange", alpha=0.08, label="beyond the outer sphere")
        ax.set_yscale("log")
        ax.set_xlabel("torque-scaled load norm [N] (training spheres dotted)")
        ax.set_ylabel("RMSE, eq. 18 [N]")
        ax.set_title(f"Error vs load magnitude, preset '{preset}'", fontsize=9)
        ax.legend(fontsize=7)
    fig.tight_layout()
    files.save_figure("sensor_maker_magnitude.png", fig, dpi=110)
    plt.close(fig)
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
