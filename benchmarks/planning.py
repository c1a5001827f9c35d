"""Figures of pose planning: fewer poses for the same accuracy (optimal plans, "which poses next").

On the virtual robot (KUKA iiwa 14, :func:`ftcal.experiment.simulate_experiment`, thesis load configurations and
robot errors), for each sensor preset and seed: one virtual sensor (its error parameters drawn from
the seed), a held-out set of poses, and training plans of several sizes --

* ``geodesic``: the thesis' spheres, 12 / 42 / 155 poses (icosphere levels 0, 1, 2);
* ``random``: N reachable directions of the level-3 candidate sphere, uniformly;
* ``d-optimal``: N of them by ``plan_calibration_poses(strategy="d-optimal")``;
* ``next``: sequential rounds, starting from the D-optimal plan of the smallest size and adding
  ``--next-step`` poses per round by :func:`ftcal.experiment.propose_next_poses` with a Gaussian-process model
  fitted on the data so far.

Each plan is run as a load / no-load experiment with all seven load configurations and paired by
:func:`ftcal.experiment.prepare_dataset` exactly as real logs would be; the LTM (``linear``) and ``auto`` are fitted
and scored on the held-out poses (torque-scaled RMSE [N], ``alpha`` of the sensor). The held-out poses
are 100 directions of the level-4 sphere that are not level-3 vertices (so no candidate of any plan is a
test pose), all reachable, run with all load configurations.

``auto`` here is :class:`ftcal.AutoCalibrator` over its closed-form candidates (linear, polynomials,
axis-nonlinear, Gaussian process), without the network candidates, and without a time budget (no
result may depend on the machine's speed): training networks for every plan of every seed does not fit
in a shared 2-core session.

Usage::

    nice -n 19 python benchmarks/planning.py [--sensors thesis,reconstructed,soft] [--seeds 0,1,2]
        [--sizes 12,24,52] [--models linear,auto] [--out benchmarks/results/planning]

``--sensors`` takes error-preset names of :func:`ftcal.simulation.error_preset` (``ftcal.simulation.ERROR_PRESETS``); presets
added later (``reconstructed``, the soft-sensor preset) are used by name once they exist. Every fit
is cached as one JSON file in ``<out>/cache/`` (out of git), so an interrupted run resumes; the LTM pass
runs over every seed before the (much slower) ``auto`` pass. The
summary (``summary.json``, ``summary.md``) and the plot ``benchmarks/figures/planning_rmse.png`` are
rewritten from the cache at the end (``--report-only`` does only that).
"""

from __future__ import annotations

import argparse
import json
import platform
import tempfile
import time
import warnings
from pathlib import Path

import numpy as np

import ftcal
from ftcal.benchmark import read_json_record
from ftcal.core import write_json
from ftcal.compose import default_candidates

from _output import output_files, single_output

HERE = Path(__file__).resolve().parent
GEODESIC = {12: 0, 42: 1, 155: 2}
NETWORKS = ("directional", "comparative", "directional_ensemble", "comparative_ensemble")


def make_sensor(name: str, seed: int) -> "ftcal.simulation.VirtualSensor":
    """The virtual sensor of a preset name, error parameters and tare drawn from ``seed``."""
    if name not in ftcal.simulation.ERROR_PRESETS:
        raise SystemExit(f"planning.py: unknown sensor preset {name!r}; known: {sorted(ftcal.simulation.ERROR_PRESETS)}")
    rng = np.random.default_rng(1000 + seed)
    sensor = ftcal.simulation.VirtualSensor(errors=name, random_state=rng)
    fs = np.array([sensor.profile.fmax] * 3 + [sensor.profile.tmax] * 3)
    sensor.zero_offset = sensor.profile.reading_from_wrench((rng.normal(0.0, 0.005, 6) * fs)[None])[0]
    return sensor


#: Recorded in every ``auto`` result: the AutoCalibrator settings of this script since auto's rewrite with stock baselines
#: (stacking on by default, candidates scored by ``n_jobs``). Rows without it were measured with the earlier auto.
AUTO_SETTINGS = "closed-form candidates, stack=True, baselines=False, n_jobs=1"


def auto_calibrator(seed: int):
    """``auto`` over the closed-form candidates; one process (the figures are the same for any ``n_jobs``), and
    no stock baselines (they are never chosen, so they change no figure here, only the fit time)."""
    candidates = [(n, c) for n, c in default_candidates() if n not in NETWORKS]
    return ftcal.AutoCalibrator(candidates=candidates, stack=True, baselines=False, n_jobs=1, random_state=seed)


def run_plan(robot, plan, sensor, seed: int):
    with tempfile.TemporaryDirectory() as tmp:
        paths = ftcal.experiment.simulate_experiment(tmp, robot=robot, plan=plan, sensor=sensor, random_state=seed)
        return ftcal.experiment.prepare_dataset(paths, robot)


def held_out_plan(robot, cache: Path):
    """100 reachable level-4 directions that are not level-3 vertices (fixed, cached)."""
    path = cache / "held_out_plan.npz"
    if path.exists():
        d = np.load(path)
        return d["g"], d["q"]
    fine = ftcal.robot.reachable_candidates(robot, subdivisions=4)
    coarse = ftcal.robot.gravity_directions_in_sensor(3, excluded_cap_deg=0)
    new = np.max(fine.gravity_in_sensor @ coarse.T, axis=1) < 1 - 1e-9
    idx = np.sort(np.random.default_rng(2024).choice(np.flatnonzero(new), 100, replace=False))
    np.savez(path, g=fine.gravity_in_sensor[idx], q=fine.q[idx])
    return fine.gravity_in_sensor[idx], fine.q[idx]


def as_plan(robot, g, q, name: str) -> "ftcal.robot.CalibrationPlan":
    pitch, yaw = ftcal.robot.pitch_yaw_from_gravity_in_sensor(g)
    return ftcal.robot.CalibrationPlan(q=q, gravity_in_sensor=g, pitch=pitch, yaw=yaw, unreachable=np.zeros((0, 3)),
                                 anchor_position_in_base=np.zeros(3), robot_name=robot.name,
                                 sensor_frame=robot.sensor_frame, anchor_frame=robot.anchor_frame,
                                 n_candidates=len(g), settings={"strategy": name})


def score(model_name: str, train, test, alpha: float, seed: int) -> dict:
    model = ftcal.LinearCalibrator(alpha=alpha) if model_name == "linear" else auto_calibrator(seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        t0 = time.perf_counter()
        if model_name == "auto":
            model.fit(train.raw, train.wrench, groups=train.group)
        else:
            model.fit(train.raw, train.wrench)
        seconds = time.perf_counter() - t0
    out = {"rmse": ftcal.core.wrench_rmse(test.wrench, model.predict(test.raw), alpha=alpha), "fit_seconds": seconds}
    if model_name == "auto":
        out["chosen"] = str(model.best_name_)
        out["auto_settings"] = AUTO_SETTINGS
    return out


def cached(path: Path, compute) -> dict:
    result = read_json_record(path)
    if result is not None:
        return result
    result = compute()
    write_json(path, result, indent=1)
    return result


def load_candidates(robot, cache: Path):
    path = cache / "candidates_level3.npz"
    if path.exists():
        d = np.load(path, allow_pickle=False)
        return ftcal.robot.CandidatePoses(gravity_in_sensor=d["g"], q=d["q"], unreachable=d["u"],
                                    anchor_position_in_base=d["a"], n_candidates=int(d["n"]),
                                    settings=json.loads(str(d["s"])))
    c = ftcal.robot.reachable_candidates(robot, subdivisions=3)
    np.savez(path, g=c.gravity_in_sensor, q=c.q, u=c.unreachable, a=c.anchor_position_in_base, n=c.n_candidates,
             s=json.dumps(c.settings))
    return c


def run(sensors, seeds, sizes, next_step: int, models, out: Path) -> None:
    """One pass per model (the cheap LTM first, over every seed; then ``auto``), every result cached."""
    cache = out / "cache"
    cache.mkdir(parents=True, exist_ok=True)
    robot = ftcal.robot.load_robot()
    candidates = load_candidates(robot, cache)
    g_test, q_test = held_out_plan(robot, cache)
    for model_name in models:
        for seed in seeds:
            for sensor_name in sensors:
                sensor = make_sensor(sensor_name, seed)
                alpha = float(sensor.profile.alpha)
                test = run_plan(robot, as_plan(robot, g_test, q_test, "held-out"), sensor, 10_000 + seed)
                # largest first: the geodesic reference and the plans of the target size come before the rest
                jobs = sorted([("geodesic", n) for n in GEODESIC] +
                              [(s, n) for s in ("d-optimal", "random") for n in sizes],
                              key=lambda job: (-job[1], ("geodesic", "d-optimal", "random").index(job[0])))
                for strategy, n in jobs:
                    def compute(strategy=strategy, n=n):
                        if strategy == "geodesic":
                            plan = ftcal.robot.plan_calibration_poses(robot, subdivisions=GEODESIC[n],
                                                                excluded_cap_deg=0 if n == 12 else 20)
                        else:
                            plan = ftcal.robot.plan_calibration_poses(robot, strategy=strategy, n_poses=n,
                                                                candidates=candidates, random_state=seed)
                        train = run_plan(robot, plan, sensor, 100 * seed + n)
                        return {"sensor": sensor_name, "seed": seed, "strategy": strategy, "n_poses": plan.n_poses,
                                "model": model_name, "d_criterion": ftcal.robot.d_criterion(plan.gravity_in_sensor),
                                **score(model_name, train, test, alpha, seed)}
                    r = cached(cache / f"{sensor_name}_s{seed}_{strategy}_{n}_{model_name}.json", compute)
                    print(f"{model_name:6s} {sensor_name} seed {seed} {strategy:9s} {r['n_poses']:4d} poses: "
                          f"{r['rmse']:.4f} N", flush=True)
                # sequential "next" rounds from the smallest D-optimal plan, a GP telling where to measure
                plan = ftcal.robot.plan_calibration_poses(robot, strategy="d-optimal", n_poses=min(sizes),
                                                    candidates=candidates)
                g, q = plan.gravity_in_sensor, plan.q
                train = run_plan(robot, plan, sensor, 100 * seed + len(g))
                while len(g) + next_step <= max(sizes):
                    key = cache / f"{sensor_name}_s{seed}_next_{len(g) + next_step}_{model_name}.json"
                    poses = cache / f"{sensor_name}_s{seed}_next_{len(g) + next_step}_poses.npz"
                    if not poses.exists():  # the proposals of a round, shared by the model passes
                        gp = ftcal.GaussianProcessCalibrator(alpha=alpha, random_state=seed).fit(train.raw, train.wrench)
                        prop = ftcal.experiment.propose_next_poses(robot, train, gp, next_step, candidates=candidates)
                        np.savez(poses, g=prop.gravity_in_sensor, q=prop.q, gain=prop.expected_gain.sum())
                    d = np.load(poses)
                    g, q, gain = np.vstack([g, d["g"]]), np.vstack([q, d["q"]]), float(d["gain"])
                    train = run_plan(robot, as_plan(robot, g, q, "next"), sensor, 100 * seed + len(g) + 7)
                    r = cached(key, lambda: {"sensor": sensor_name, "seed": seed, "strategy": "next",
                                             "n_poses": len(g), "model": model_name,
                                             "d_criterion": ftcal.robot.d_criterion(g),
                                             "expected_gain": gain,
                                             **score(model_name, train, test, alpha, seed)})
                    print(f"{model_name:6s} {sensor_name} seed {seed} next      {len(g):4d} poses: {r['rmse']:.4f} N",
                          flush=True)


def report(out: Path, files, figure) -> None:
    rows = [read_json_record(p, numbers=("rmse", "d_criterion", "n_poses", "seed"))
            for p in sorted((out / "cache").glob("*_s*_*_*.json"))]  # a record of another kind is left out
    rows = [r for r in rows if r is not None and all(isinstance(r.get(k), str) for k in ("model", "sensor", "strategy"))]
    if not rows:
        return
    by: dict = {}
    for r in rows:
        by.setdefault((r["sensor"], r["model"], r["strategy"], r["n_poses"]), {})[r["seed"]] = r
    summary = []
    lines = ["| sensor | model | plan | poses | seeds | held-out RMSE [N], mean | ratio to geodesic 155 (same seeds), mean [min, max] | log det M | auto chose |",
             "|---|---|---|---|---|---|---|---|---|"]
    order = {"geodesic": 0, "d-optimal": 1, "random": 2, "next": 3}
    for (sensor, model, strategy, n), rs in sorted(by.items(), key=lambda kv: (kv[0][0], kv[0][1], order[kv[0][2]], kv[0][3])):
        ref = by.get((sensor, model, "geodesic", 155), {})
        ratios = [rs[s]["rmse"] / ref[s]["rmse"] for s in rs if s in ref]
        entry = {"sensor": sensor, "model": model, "strategy": strategy, "n_poses": n, "seeds": sorted(rs),
                 "rmse_mean": float(np.mean([r["rmse"] for r in rs.values()])),
                 "ratio_mean": float(np.mean(ratios)) if ratios else None,
                 "ratio_min": float(np.min(ratios)) if ratios else None,
                 "ratio_max": float(np.max(ratios)) if ratios else None,
                 "d_criterion_mean": float(np.mean([r["d_criterion"] for r in rs.values()])),
                 "auto_chosen": sorted({r.get("chosen", "") for r in rs.values()} - {""}),
                 # auto rows measured before this script recorded its settings came from the earlier auto
                 "earlier_auto": sorted(s for s, r in rs.items() if model == "auto" and "auto_settings" not in r)}
        summary.append(entry)
        ratio = "-" if not ratios else f"{entry['ratio_mean']:.3f} [{entry['ratio_min']:.3f}, {entry['ratio_max']:.3f}]"
        chose = ", ".join(entry["auto_chosen"]) + (" (earlier auto)" if entry["earlier_auto"] else "")
        lines.append(f"| {sensor} | {model} | {strategy} | {n} | {len(rs)} | {entry['rmse_mean']:.4f} | {ratio} "
                     f"| {entry['d_criterion_mean']:.2f} | {chose} |")
    files.write_text("summary.json", json.dumps({"rows": summary, "machine": platform.platform(),
                                                  "note": "machine NOT idle (helpers and the lead's benchmarks share 2 cores); "
                                                          "no figure depends on speed"}, indent=1))
    files.write_text("summary.md", "\n".join(lines) + "\n")
    print("\n".join(lines))
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    panels = [(sensor, model) for sensor in sorted({e["sensor"] for e in summary}) for model in ("linear", "auto")
              if any(e["sensor"] == sensor and e["model"] == model and e["ratio_mean"] is not None
                     and e["strategy"] != "geodesic" for e in summary)]
    if not panels:
        return
    sensors = sorted({sensor for sensor, _ in panels})
    fig, axes = plt.subplots(len(sensors), 2, figsize=(9.2, 3.6 * len(sensors)), squeeze=False)
    for ax in axes.ravel():
        ax.set_visible(False)
    for sensor, model in panels:
        ax = axes[sensors.index(sensor), ("linear", "auto").index(model)]
        ax.set_visible(True)
        for k, (strategy, style) in enumerate((("geodesic", "o-"), ("random", "s--"), ("d-optimal", "^-"),
                                               ("next", "d-."))):
            pts = sorted((e["n_poses"], e["ratio_mean"], e["ratio_min"], e["ratio_max"], len(e["seeds"]))
                         for e in summary if e["sensor"] == sensor and e["model"] == model
                         and e["strategy"] == strategy and e["ratio_mean"] is not None)
            if pts:
                n, mean, lo, hi, seeds = map(np.array, zip(*pts))
                x = n * (1 + 0.02 * (k - 1.5))  # a small offset so the bars do not hide each other
                ax.errorbar(x, mean, yerr=[mean - lo, hi - mean], fmt=style, capsize=2,
                            label=f"{strategy} ({seeds.min()}-{seeds.max()} seeds)" if seeds.min() != seeds.max()
                            else f"{strategy} ({seeds.min()} seed{'s' if seeds.min() > 1 else ''})")
        ax.axhline(1.05, color="gray", lw=0.8, ls=":", label="goal: 1.05")
        ax.axvline(155 / 3, color="gray", lw=0.6, ls="--")
        ax.set_xscale("log")
        ax.set_xticks([12, 24, 41, 52, 155])
        ax.set_xticklabels(["12", "24", "41", "52", "155"])
        ax.minorticks_off()
        ax.set_xlabel("poses (each x 7 load configurations)")
        ax.set_ylabel("held-out RMSE / geodesic-155 RMSE")
        ax.set_title(f"{sensor}: {'LTM' if model == 'linear' else 'auto (closed-form)'}", fontsize=10)
        ax.legend(fontsize=7)
    fig.tight_layout()
    with figure.write() as tmp:
        fig.savefig(tmp, format="png", dpi=110)
    print(f"plot -> {figure}")


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--sensors", default="thesis")
    ap.add_argument("--seeds", default="0,1,2")
    ap.add_argument("--sizes", default="12,24,52", help="poses of the random and d-optimal plans")
    ap.add_argument("--next-step", type=int, default=20, help="poses added per 'next' round")
    ap.add_argument("--models", default="linear,auto", help="one pass per model, in this order")
    ap.add_argument("--out", default=str(HERE / "results" / "planning"))
    ap.add_argument("--report-only", action="store_true")
    ap.add_argument("--figure", default=str(HERE / "figures" / "planning_rmse.png"),
                    help="the plot's file (default: benchmarks/figures/planning_rmse.png, where RESULTS.md shows it)")
    ap.add_argument("--force", action="store_true", help="replace summaries and the figure this script did not write")
    a = ap.parse_args(argv)
    files = output_files(ap, a.out, a.force, ["summary.json", "summary.md"])
    figure = single_output(ap, a.figure, a.force)
    if not a.report_only:
        run(a.sensors.split(","), [int(s) for s in a.seeds.split(",")], [int(s) for s in a.sizes.split(",")],
            a.next_step, a.models.split(","), files.out_dir)
    report(files.out_dir, files, figure)


if __name__ == "__main__":
    main()
