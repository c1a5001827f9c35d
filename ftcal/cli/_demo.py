"""``ftcal demo``: the main job on built-in defaults, no files of the user's needed."""

from __future__ import annotations

import argparse

from ._common import Console, OutputPlan, finish_command
from ._training import fit_with_progress

EXAMPLE = """\
examples:
  ftcal demo                       # about 2-4 minutes on 2 cores; results in ./ftcal-demo/
  ftcal demo --preset asymmetric --seed 1 --out demo_asym
  ftcal demo --quick               # seconds: a smoke test of the whole pipeline

simulates one artificial dataset of the thesis (2000 training samples on 4 spheres in
the torque-scaled wrench space, 1250 continuous test samples, creep / noise / crosstalk /
nonlinearity errors), fits the linear, comparative and directional calibrators with the
short training schedule, prints the comparison table on stdout and writes the datasets,
model files, metrics.json/.md and PNG plots to DIR.
"""


def register(sub: argparse._SubParsersAction) -> None:
    from ..simulation import ERROR_PRESETS

    p = sub.add_parser("demo", help="simulate, fit the three calibrators, print the comparison, write plots",
                       description="The whole calibration job on built-in defaults: no input files needed.",
                       epilog=EXAMPLE)
    p.add_argument("--preset", default="thesis", choices=sorted(ERROR_PRESETS), help="error preset of the sensor")
    p.add_argument("--quick", action="store_true", help="tiny data and a few epochs (seconds; numbers meaningless)")
    finish_command(p, run, "ftcal-demo")


def run(args: argparse.Namespace) -> int:
    from ..benchmark import demo_files, run_demo

    console = Console(args.quiet)
    plan = OutputPlan(args.out, demo_files(), args.force)  # refuse before any work
    with plan.as_one_set(), plan.staging() as stage:  # the demo's files as one set
        result = run_demo(stage, preset=args.preset, quick=args.quick, random_state=args.seed, overwrite=True,
                          fit=lambda est, X, y, name: fit_with_progress(est, X, y, console, label=name),
                          log=console.info)
    print(f"ftcal demo: '{args.preset}' preset, seed {args.seed}, test set of {result.test.n_samples} samples, "
          f"alpha = {result.info['alpha']:.3g} 1/m\n\n{result.table}\n")
    console.info(f"plots, models and metrics in {args.out}/ (rmse_distribution.png, axis_rmse.png, errors_*.png)")
    return 0
