"""Figures of grouped model choice: the unbiased tare under sign-dependent gains, and what ``auto`` chooses on ftcal's own data.

Usage::

    python benchmarks/auto_choice.py [--out benchmarks/results/auto_choice] [--part tare|artificial|robot]
                                     [--schedule short|thesis]

Each part writes ``<part>.json`` in ``--out`` (the tare part ``tare_<schedule>.json``) and is skipped when that file exists (delete it to re-run),
so an interrupted run resumes. ``summary.md`` is rewritten from the parts found. Only public ftcal names
are used.
"""

from __future__ import annotations

import argparse
import json
import platform
import tempfile
import time
from pathlib import Path

import numpy as np

import ftcal
from ftcal.benchmark import read_json_record

from _output import output_files, table_or_stop

PARTS = ("tare", "artificial", "robot")


def sign_gain_case(seed: int = 0, n_train: int = 2500, n_test: int = 1000):
    """A positively homogeneous sensor with +/-8 % sign-dependent gains, trained on 4 load shells."""
    rng = np.random.default_rng(seed)
    matrix = rng.normal(size=(6, 8)) * 0.01
    zero = rng.normal(size=8) * 2.0

    def read(w):
        return (np.where(w > 0, 1.08, 0.92) * w) @ matrix + zero + 1e-3 * rng.normal(size=(len(w), 8))

    d = rng.normal(size=(n_train, 6))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    w_train = d * np.repeat([25.0, 50.0, 75.0, 100.0], n_train // 4)[:, None]
    d = rng.normal(size=(n_test, 6))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    w_test = d * rng.uniform(10.0, 100.0, size=(n_test, 1))
    return read(w_train), w_train, read(w_test), w_test, zero


def part_tare(schedule: str = "short") -> dict:
    raw, w, test_raw, test_w, zero = sign_gain_case()
    span = raw.max(axis=0) - raw.min(axis=0)
    out = {"case": "+/-8 % sign-dependent gains, 4 shells (25-100 N), 2500 train / 1000 test rows, 8 channels",
           "alpha": 1.0, "schedule": schedule}
    ltm = ftcal.LinearCalibrator(alpha=1.0).fit(raw, w)
    out["ltm_rmse"] = ftcal.core.wrench_rmse(test_w, ltm.predict(test_raw), alpha=1.0)
    for label, tare in (("estimated", None), ("true", zero)):
        t0 = time.perf_counter()
        model = ftcal.make_calibrator("directional", schedule=schedule, random_state=0, alpha=1.0, zero_reading=tare)
        model.fit(raw, w)
        out[f"directional_{label}_tare_rmse"] = ftcal.core.wrench_rmse(test_w, model.predict(test_raw), alpha=1.0)
        out[f"directional_{label}_fit_seconds"] = time.perf_counter() - t0
        if tare is None:
            out["tare_error_pct_of_span_max"] = float(np.max(np.abs(model.zero_reading_ - zero) / span) * 100)
    out["ratio_estimated_to_ltm"] = out["directional_estimated_tare_rmse"] / out["ltm_rmse"]
    return out


def _auto_record(auto: ftcal.AutoCalibrator, test_rmse: float | None, seconds: float) -> dict:
    return {"chosen": auto.best_name_, "cv_results": auto.comparison_, "test_rmse": test_rmse,
            "fit_seconds": seconds, "table": auto.summary()}


def part_artificial() -> dict:
    out = {}
    for preset in ("thesis", "asymmetric", "stress"):
        train, test, info = ftcal.make_artificial_dataset(preset=preset, random_state=0)
        t0 = time.perf_counter()
        auto = ftcal.AutoCalibrator(alpha=info["alpha"], random_state=0).fit(train.raw, train.wrench)
        seconds = time.perf_counter() - t0
        rmse = ftcal.core.wrench_rmse(test.wrench, auto.predict(test.raw), alpha=info["alpha"])
        out[preset] = {**_auto_record(auto, rmse, seconds), "noise_floor": info["noise_floor"]}
        print(f"{preset}: auto chose {auto.best_name_}, test RMSE {rmse:.3f} N in {seconds:.0f} s", flush=True)
    return out


def part_robot() -> dict:
    with tempfile.TemporaryDirectory() as tmp:
        paths = ftcal.experiment.simulate_experiment(tmp, random_state=0)
        data = ftcal.experiment.prepare_dataset(paths)
    t0 = time.perf_counter()
    auto = ftcal.AutoCalibrator(random_state=0).fit(data.raw, data.wrench, groups=data.group)
    seconds = time.perf_counter() - t0
    print(f"robot: auto chose {auto.best_name_} in {seconds:.0f} s", flush=True)
    return {**_auto_record(auto, None, seconds), "n_samples": data.n_samples,
            "groups": "load configuration (7), leave-groups-out folds"}


def summary(out: Path) -> str:
    """The summary of the part results in ``out`` (see :func:`table_or_stop`)."""
    return table_or_stop("auto_choice.py", out, _summary)


def _summary(out: Path) -> str:
    lines = [f"machine: {platform.machine()}, {platform.python_version()}, ftcal {ftcal.__version__}", ""]
    for tare in sorted(out.glob("tare_*.json")):
        t = json.loads(tare.read_text())
        lines += [f"## Tare under sign-dependent gains ({t['schedule']} schedule)", "", f"case: {t['case']}", "",
                  "| model | test RMSE [N] |", "|---|---|",
                  f"| LTM | {t['ltm_rmse']:.3f} |",
                  f"| directional, true tare | {t['directional_true_tare_rmse']:.3f} |",
                  f"| directional, estimated (sign-gated) tare | {t['directional_estimated_tare_rmse']:.3f} |", "",
                  f"ratio directional (estimated tare) / LTM: {t['ratio_estimated_to_ltm']:.3f} (target <= 0.35); "
                  f"largest tare error {t['tare_error_pct_of_span_max']:.3f} % of the reading span (target <= 0.5 %)",
                  ""]
    art = out / "artificial.json"
    if art.exists():
        a = json.loads(art.read_text())
        lines += ["## auto on the artificial presets (dataset 0, 5-fold CV, default 150 s budget)", ""]
        for preset, r in a.items():
            lines += [f"### {preset}: chose {r['chosen']}, test RMSE {r['test_rmse']:.3f} N "
                      f"(noise floor {r['noise_floor']:.3f} N), {r['fit_seconds']:.0f} s", "", r["table"], ""]
    rob = out / "robot.json"
    if rob.exists():
        r = json.loads(rob.read_text())
        lines += [f"## auto on the virtual robot experiment ({r['n_samples']} rows; {r['groups']})", "",
                  f"chose {r['chosen']} in {r['fit_seconds']:.0f} s", "", r["table"], ""]
    return "\n".join(lines)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default=str(Path(__file__).parent / "results" / "auto_choice"))
    parser.add_argument("--part", action="append", choices=PARTS)
    parser.add_argument("--schedule", default="short", choices=("short", "thesis"),
                        help="training schedule of the directional model in the tare part")
    parser.add_argument("--force", action="store_true", help="replace a summary.md this script did not write")
    args = parser.parse_args(argv)
    parts = {name: f"tare_{args.schedule}.json" if name == "tare" else f"{name}.json" for name in args.part or PARTS}
    files = output_files(parser, args.out, args.force, ["summary.md", *parts.values()])  # checked before any work
    for name in args.part or PARTS:
        path = files.out_dir / parts[name]
        if read_json_record(path) is not None:
            print(f"{name}: done before ({path}); delete it to re-run", flush=True)
            continue
        result = part_tare(args.schedule) if name == "tare" else {"artificial": part_artificial,
                                                                    "robot": part_robot}[name]()
        files.write_text(path.name, json.dumps(result, indent=2, default=float) + "\n")
    files.write_text("summary.md", summary(files.out_dir) + "\n")
    print(summary(files.out_dir))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
