"""``ftcal predict``: a saved model applied to raw readings, wrenches out; made for pipelines."""

from __future__ import annotations

import argparse
import inspect
import sys
from pathlib import Path

import numpy as np

from ._models import load_model_file
from ..core._files import same_file
from ._common import CliError, Console, OutputPlan, add_run_options, existing_file, positive_int, int_in_range
from ._readings import iter_reading_chunks, read_readings_npz, write_wrench_rows
from ..core._wrench import WRENCH_LABELS

EXAMPLE = """\
input: one raw reading per line (comma or space separated; an optional header
naming the channels s0..s{N-1}; '#' comments). output: CSV Fx,Fy,Fz [N],Tx,Ty,Tz [N·m].

examples:
  ftcal predict models/directional.model.npz readings.csv --output wrench.csv
  my_sensor_reader | ftcal predict models/directional.model.npz --line-buffered | my_controller
  ftcal predict models/linear.model.npz data/test.csv --no-header | head -3
  ftcal predict models/gaussian_process.model.npz readings.csv --std     # + std_Fx..std_Tz columns
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "predict",
        help="apply a saved model to raw readings (file or stdin) -> wrenches (file or stdout)",
        description="Apply a saved calibration model to raw readings. Nothing but the wrenches goes to stdout.",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=existing_file, help="model file written by 'ftcal fit'")
    p.add_argument(
        "input", nargs="?", default="-",
        help="raw readings: a CSV / whitespace text file, a .npz with array 'raw', or '-' for stdin",
    )
    p.add_argument("--output", default="-", metavar="FILE", help="where the wrenches go; '-' is stdout")
    p.add_argument("-f", "--force", action="store_true", help="overwrite --output FILE if it exists")
    p.add_argument("--no-header", action="store_true", help="do not write the Fx,...,Tz header line")
    p.add_argument(
        "--chunk-size", type=int_in_range(1, 1_000_000, "rows per chunk"), default=4096,
        help="readings predicted together (memory vs. latency)",
    )
    p.add_argument(
        "--line-buffered", action="store_true",
        help="answer each input line at once and flush (live streams; same as --chunk-size 1)",
    )
    p.add_argument(
        "--std", action="store_true",
        help="also write each component's predictive standard deviation (std_Fx..std_Tz; Gaussian-process "
             "models, also when auto chose one)",
    )
    add_run_options(p, seed=False)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    console = Console(args.quiet)
    plan = OutputPlan.single_file(args.output, args.force)
    if args.input != "-" and not Path(args.input).is_file():
        raise FileNotFoundError(2, "No such file (the raw readings to predict)", args.input)
    if args.output != "-":
        for role, other in (("input", args.input), ("model", args.model)):
            if other != "-" and same_file(args.output, other):
                raise CliError(f"--output {args.output} is the {role} file; writing there would destroy it. "
                               "Choose another --output")
    model = load_model_file(args.model)
    n_channels = int(model.n_features_in_)
    chunk = 1 if args.line_buffered else args.chunk_size
    if args.std and "return_std" not in inspect.signature(getattr(model, "best_estimator_", model).predict).parameters:
        chosen = getattr(model, "best_name_", type(model).__name__)
        raise CliError(f"--std: {args.model} holds {chosen}, which gives no standard deviation; only Gaussian-process "
                       "models do (ftcal fit --model gaussian_process). Drop --std")

    def emit(out) -> int:
        header = not args.no_header
        total = 0
        for raw in raw_chunks(args.input, n_channels, chunk):
            if args.std:
                wrench, std = model.predict(raw, return_std=True)
                if header:
                    out.write(",".join([*WRENCH_LABELS, *(f"std_{a}" for a in WRENCH_LABELS)]) + "\n")
                write_wrench_rows(out, np.hstack([wrench, std]), False)
                wrench = np.asarray(wrench)
            else:
                wrench = np.asarray(model.predict(raw), dtype=float)
                write_wrench_rows(out, wrench, header)
            header = False
            total += len(wrench)
            if chunk == 1 or out is sys.stdout:
                out.flush()
        if header:  # no data at all: still a valid (empty) table
            write_wrench_rows(out, np.empty((0, 6)), True)
        return total

    if plan is None:
        emit(sys.stdout)
        sys.stdout.flush()
        return 0
    with plan.writing(Path(args.output).name) as tmp, open(tmp, "w", encoding="utf-8") as fh:
        total = emit(fh)
    console.info(f"wrote {total} wrenches to {args.output}")
    return 0


def raw_chunks(source: str, n_channels: int, chunk: int):
    if source == "-":
        if sys.stdin.isatty():
            print("ftcal predict: reading raw readings from the terminal; end with Ctrl-D", file=sys.stderr)
        yield from iter_reading_chunks(sys.stdin, "stdin", n_channels, chunk)
    elif source.endswith(".npz"):
        raw = read_readings_npz(source, n_channels)
        for start in range(0, len(raw), chunk):
            yield raw[start:start + chunk]
    else:
        with open(source, encoding="utf-8") as fh:
            yield from iter_reading_chunks(fh, source, n_channels, chunk)
