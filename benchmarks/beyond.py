#!/usr/bin/env python
"""The "beyond the thesis" benchmark: the polynomial, the axis-nonlinear hybrid and seed ensembles
against the thesis' three models, on the artificial presets (and optionally the virtual robot experiment).

A thin layer over :func:`ftcal.benchmark.run_artificial_benchmark` (models by registry
name; every (preset, dataset, model) result cached, so re-running the same
command resumes) and :func:`ftcal.benchmark.run_real_world_benchmark`. Two passes share
one cache: the closed-form models on ``--datasets`` datasets, the network
models (slow on a CPU) on the first ``--network-datasets`` of them. Then it
checks the issue's targets on the datasets both have in common and writes
``beyond_summary.md`` / ``.json`` into ``--out``:

* hybrid mean RMSE vs. the best of linear / comparative / directional, per preset;
* hybrid RMSE / noise floor (target <= 1.15 on ``thesis`` and ``asymmetric``);
* hybrid / LTM on ``stress`` (target <= 0.8);
* across-dataset RMSE std of the directional ensemble / directional (target <= 0.5), and the same ratio for
  the excess over the noise floor (RMSE - floor per dataset), which removes the datasets' own spread;
* Wilcoxon signed-rank p-values of the hybrid against every other model.

Examples::

    python benchmarks/beyond.py --datasets 3 --network-datasets 0 --out /tmp/beyond-smoke
    python benchmarks/beyond.py --datasets 30 --network-datasets 6 --presets thesis asymmetric stress \\
        --schedule short --jobs 2
    python benchmarks/beyond.py --datasets 30 --network-datasets 0 --real-world
    python benchmarks/beyond.py --datasets 30 --network-datasets 6 --aggregate-only   # tables from the cache
"""

from __future__ import annotations

import argparse
import json
import math
import platform
import sys
import time
from pathlib import Path

import numpy as np

from ftcal import FtcalError
from ftcal.benchmark import run_artificial_benchmark, run_real_world_benchmark
from ftcal.core import plain_json
from ftcal.benchmark import wilcoxon_pvalue
from ftcal.cli import cli_message

from _output import output_files

DEFAULT_OUT = Path(__file__).resolve().parent / "out" / "beyond"
HYBRID = "axis_nonlinear"
CLOSED_FORM = ("linear", "polynomial", HYBRID)
NETWORKS = ("comparative", "directional", "directional_ensemble")
THESIS_MODELS = ("linear", "comparative", "directional")


def build_parser() -> argparse.ArgumentParser:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    p.add_argument("--datasets", type=int, default=30, help="datasets per preset for the closed-form models")
    p.add_argument("--network-datasets", type=int, default=6, help="datasets per preset for the network models")
    p.add_argument("--networks", nargs="*", default=list(NETWORKS), help="network models (registry names)")
    p.add_argument("--presets", nargs="+", default=["thesis", "asymmetric", "stress"], help="error presets")
    p.add_argument("--schedule", default="short", choices=["thesis", "short"], help="network training schedule")
    p.add_argument("--seed", type=int, default=0, help="master seed of data and models")
    p.add_argument("--jobs", type=int, default=1, help="joblib workers")
    p.add_argument("--out", default=str(DEFAULT_OUT), help=f"output and cache folder (default {DEFAULT_OUT})")
    p.add_argument("--real-world", action="store_true", help="also run the virtual robot experiment")
    p.add_argument("--aggregate-only", action="store_true", help="no new fits: summarise what the cache holds")
    p.add_argument("--force", action="store_true", help="replace output files this script did not write")
    return p


def _per_dataset(summary: dict, preset: str, model: str) -> dict[int, float]:
    table = summary[preset]["models"].get(model)
    return {} if table is None else {int(k): v for k, v in table["rmse_per_dataset"].items()}


def _stats(values: list[float]) -> dict:
    v = np.asarray(values, dtype=float)
    return {"mean": float(v.mean()) if v.size else math.nan,
            "std": float(v.std(ddof=1)) if v.size > 1 else math.nan, "n": int(v.size)}


def targets(summary: dict, results: list[dict], models: list[str]) -> dict:
    """The issue's targets per preset, every comparison on the datasets both models have."""
    out = {}
    for preset, s in summary.items():
        hyb = _per_dataset(summary, preset, HYBRID)
        floors = {r["dataset"]: r["noise_floor"] for r in results if r["preset"] == preset}
        row: dict = {"noise_floor": s["noise_floor"], "hybrid_over_floor": _stats(
            [hyb[i] / floors[i] for i in hyb])}
        comparisons = {}
        for m in models:
            other = _per_dataset(summary, preset, m)
            common = sorted(set(hyb) & set(other))
            if m == HYBRID or not common:
                continue
            p, note = wilcoxon_pvalue([hyb[i] for i in common], [other[i] for i in common])
            comparisons[m] = {"n": len(common), "hybrid": _stats([hyb[i] for i in common]),
                              "other": _stats([other[i] for i in common]), "wilcoxon_p": p, "note": note}
        row["vs"] = comparisons
        best = [comparisons[m]["other"]["mean"] - comparisons[m]["hybrid"]["mean"] for m in THESIS_MODELS
                if m in comparisons]
        row["hybrid_no_worse_than_thesis_models"] = bool(best) and min(best) >= 0
        if "linear" in comparisons:
            row["hybrid_over_ltm"] = comparisons["linear"]["hybrid"]["mean"] / comparisons["linear"]["other"]["mean"]
        d, e = _per_dataset(summary, preset, "directional"), _per_dataset(summary, preset, "directional_ensemble")
        common = sorted(set(d) & set(e))
        if len(common) > 1:
            sd, se = _stats([d[i] for i in common]), _stats([e[i] for i in common])
            # the across-dataset std of any model near the floor is bounded by the floor's own spread; the
            # excess over the floor (RMSE - floor, per dataset) isolates what the model itself adds
            xd, xe = _stats([d[i] - floors[i] for i in common]), _stats([e[i] - floors[i] for i in common])
            row["ensemble"] = {"n": len(common), "directional": sd, "directional_ensemble": se,
                               "std_ratio": se["std"] / sd["std"] if sd["std"] > 0 else math.nan,
                               "noise_floor": _stats([floors[i] for i in common]),
                               "excess_directional": xd, "excess_directional_ensemble": xe,
                               "excess_std_ratio": xe["std"] / xd["std"] if xd["std"] > 0 else math.nan}
            # seed-to-seed spread of a single directional net on one dataset: the std of the 5 members' RMSEs
            spread = [float(np.std(r["member_rmse"], ddof=1)) for r in results
                      if r["preset"] == preset and r["model"] == "directional_ensemble" and r.get("member_rmse")]
            row["ensemble"]["member_seed_std"] = _stats(spread)
        out[preset] = row
    return out


def markdown(meta: dict, tgt: dict, real_world: dict | None) -> str:
    f = lambda st, d=2: "—" if st["n"] == 0 else f"{st['mean']:.{d}f} ± {st['std']:.{d}f} (n={st['n']})"  # noqa: E731
    lines = [f"Command: `{meta['command']}`", f"Machine: {meta['machine']}; wall time {meta['wall_seconds']:.0f} s.", ""]
    for preset, row in tgt.items():
        lines += [f"#### Preset `{preset}`", "",
                  f"Noise floor {f(row['noise_floor'])} N; hybrid / noise floor {f(row['hybrid_over_floor'], 3)}; "
                  f"hybrid no worse than every thesis model: **{row['hybrid_no_worse_than_thesis_models']}**"
                  + (f"; hybrid / LTM = {row['hybrid_over_ltm']:.3f}" if "hybrid_over_ltm" in row else "") + ".", "",
                  "| other model | datasets | hybrid RMSE [N] | other RMSE [N] | Wilcoxon p (hybrid vs other) |",
                  "|---|---|---|---|---|"]
        for m, c in row["vs"].items():
            p = "NaN (" + c["note"] + ")" if math.isnan(c["wilcoxon_p"]) else f"{c['wilcoxon_p']:.3g}"
            lines.append(f"| {m} | {c['n']} | {f(c['hybrid'])} | {f(c['other'])} | {p} |")
        if "ensemble" in row:
            e = row["ensemble"]
            lines += ["", f"Ensemble: directional {f(e['directional'])}, directional_ensemble "
                          f"{f(e['directional_ensemble'])}; std ratio {e['std_ratio']:.3f} (target <= 0.5). "
                          f"Noise floor on the same datasets {f(e['noise_floor'])}. Excess over the floor "
                          f"(RMSE - floor): directional {f(e['excess_directional'], 3)}, directional_ensemble "
                          f"{f(e['excess_directional_ensemble'], 3)}; std ratio {e['excess_std_ratio']:.3f}."
                          + ("" if not e["member_seed_std"]["n"] else
                             f" Seed-to-seed std of one directional net on one dataset (its 5 members), mean over "
                             f"datasets: {f(e['member_seed_std'], 3)}.")]
        lines.append("")
    if real_world is not None:
        lines += ["#### Virtual robot experiment", "", "| split | model | RMSE [N] | rel. force | rel. torque |",
                  "|---|---|---|---|---|"]
        for split, by_model in real_world["splits"].items():
            for m, r in by_model.items():
                lines.append(f"| {split} | {m} | {r['rmse_mean']:.4f} | {r['rel_force_mean']:.4f} | "
                             f"{r['rel_torque_mean']:.4f} |")
        lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    t0 = time.perf_counter()
    files = output_files(parser, args.out, args.force, ["beyond_summary.json", "beyond_summary.md"])
    out = files.out_dir
    common = dict(presets=args.presets, schedule=args.schedule, seed=args.seed, n_jobs=args.jobs, out_dir=out,
                  plot=False, compute=not args.aggregate_only, force=args.force)

    def progress(done, total, rec):
        print(f"[{done}/{total}] {rec['preset']} ds{rec['dataset']} {rec['model']}: RMSE {rec['rmse']:.3f} N "
              f"({rec['fit_seconds']:.1f} s)", file=sys.stderr, flush=True)

    try:
        run_artificial_benchmark(n_datasets=args.datasets, models=CLOSED_FORM, progress=progress, **common)
        if args.network_datasets > 0 and args.networks:
            run_artificial_benchmark(n_datasets=args.network_datasets, models=args.networks, progress=progress,
                                     **common)
        models = list(CLOSED_FORM) + list(args.networks)
        n_all = max(args.datasets, args.network_datasets)
        payload = run_artificial_benchmark(n_datasets=n_all, models=models, **{**common, "compute": False})
        real_world = None
        if args.real_world:
            real_world = run_real_world_benchmark(models=CLOSED_FORM, schedule=args.schedule,
                                                  grouped_schedule=args.schedule, random_state=args.seed)
    except FtcalError as exc:
        print(f"beyond: error: {cli_message(exc)}", file=sys.stderr)
        return 2
    tgt = targets(payload["summary"], payload["results"], models)
    meta = {"command": "python benchmarks/beyond.py " + " ".join(argv if argv is not None else sys.argv[1:]),
            "machine": f"{platform.node()} {platform.processor() or platform.machine()}, Python "
                       f"{platform.python_version()}", "wall_seconds": time.perf_counter() - t0}
    rw = None if real_world is None else {"splits": {
        s: {m: {k: r.get(k) for k in ("rmse_mean", "rel_force_mean", "rel_torque_mean")} for m, r in by.items()}
        for s, by in real_world["splits"].items()}}
    files.write_text("beyond_summary.json", json.dumps(plain_json({"meta": meta, "targets": tgt, "real_world": rw}),
                                                       indent=1))
    text = markdown(meta, tgt, rw)
    files.write_text("beyond_summary.md", text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
