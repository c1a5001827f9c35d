"""Real-world benchmark (thesis V-B, Tables IV-V, Fig. 6) on the simulated robot experiment.

Thin wrapper around :func:`ftcal.benchmark.run_real_world_benchmark`: runs it, prints the
tables as Markdown beside the thesis' values, writes the results as JSON and
the Fig. 6-like plot as PNG.

    python benchmarks/real_world.py                       # thesis schedule on random20, short on 7-fold
    python benchmarks/real_world.py --schedule short      # quick run
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path

import torch

from ftcal.compose import CALIBRATOR_NAMES
from ftcal.benchmark import run_real_world_benchmark
from ftcal.benchmark import SPLIT_NAMES

from _output import single_output

HERE = Path(__file__).resolve().parent


def markdown_tables(res: dict) -> str:
    """Tables IV (per-sample RMSE) and V (relative errors) per split, with the thesis' values."""
    lines = []
    th = res["thesis"]
    for split, per_model in res["splits"].items():
        lines += [f"**Split `{split}`** (n_test = {next(iter(per_model.values()))['n_test']})", "",
                  "| model | schedule | RMSE mean ± std [N] | thesis IV | rel. force | thesis V force "
                  "| rel. torque | thesis V torque | fit time [s] |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for name, r in per_model.items():
            t = th.get(name)
            tiv = f"{t['rmse_mean']} ± {t['rmse_std']}" if t else "-"
            tvf = f"{t['rel_force_mean']} ± {t['rel_force_std']}" if t else "-"
            tvt = f"{t['rel_torque_mean']} ± {t['rel_torque_std']}" if t else "-"
            lines.append(
                f"| {name} | {r['schedule']} | {r['rmse_mean']:.3f} ± {r['rmse_std']:.3f} | {tiv} "
                f"| {r['rel_force_mean']:.4f} ± {r['rel_force_std']:.4f} | {tvf} "
                f"| {r['rel_torque_mean']:.4f} ± {r['rel_torque_std']:.4f} | {tvt} | {r['fit_seconds']:.1f} |"
            )
        lines.append("")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> dict:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--models", nargs="+", default=["linear", "comparative", "directional"],
                   choices=list(CALIBRATOR_NAMES))
    p.add_argument("--splits", nargs="+", default=list(SPLIT_NAMES), choices=list(SPLIT_NAMES))
    p.add_argument("--schedule", default="thesis", help="schedule on the random20 split")
    p.add_argument("--grouped-schedule", default="short", help="schedule on the 7-fold leave-one-config-out split")
    p.add_argument("--load-mass", type=float, default=2.0, help="external load [kg]")
    p.add_argument("--subdivisions", type=int, default=2, help="icosphere level (2: 155 poses per sphere)")
    p.add_argument("--random-state", type=int, default=0)
    p.add_argument("--threads", type=int, default=1, help="torch CPU threads")
    p.add_argument("--log-dir", type=Path, default=None, help="keep the simulated run logs here")
    p.add_argument("--out", default=str(HERE / "out" / "real_world.json"))
    p.add_argument("--plot", type=Path, default=HERE / "real_world_fig6.png")
    p.add_argument("--force", action="store_true", help="replace --out / --plot files this script did not write")
    args = p.parse_args(argv)
    out, figure = single_output(p, args.out, args.force), single_output(p, args.plot, args.force)
    torch.set_num_threads(args.threads)
    t0 = time.perf_counter()
    with figure.write() as tmp:
        res = run_real_world_benchmark(models=args.models, splits=args.splits, schedule=args.schedule,
                                       grouped_schedule=args.grouped_schedule, load_mass=args.load_mass,
                                       subdivisions=args.subdivisions, random_state=args.random_state,
                                       log_dir=args.log_dir, plot_path=tmp)
    wall = time.perf_counter() - t0
    res["plot"] = str(figure.path)  # not the temporary file it was drawn to
    out.write_text(json.dumps(res, indent=1))
    d = res["dataset"]
    print(f"dataset: {d['n_samples']} samples x {d['n_channels']} channels, {d['n_configurations']} load "
          f"configurations, alpha = {d['alpha']:.3f} 1/m, |F| <= {d['force_norm_max_N']:.2f} N, "
          f"|T| <= {d['torque_norm_max_Nm']:.2f} N·m, max pair rotation {d['pair_rotation_deg_max']:.2f} deg")
    print(markdown_tables(res))
    print(f"wall time {wall:.0f} s; results {out}; plot {figure}")
    return res


if __name__ == "__main__":
    main()
