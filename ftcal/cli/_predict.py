"""``ftcal predict``: a saved model applied to raw readings, wrenches out; made for pipelines."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from ._models import load_model_file
from ._common import CliError, Console, OutputPlan, add_run_options, existing_file, int_in_range, path_problem
from ._readings import iter_reading_chunks, located_error, read_readings_npz, takes_temperature, write_wrench_rows

EXAMPLE = """\
input: one raw reading per line (comma or space separated; an optional header
naming the channels s0..s{N-1}; '#' comments). output: CSV Fx,Fy,Fz [N],Tx,Ty,Tz [N·m].

examples:
  ftcal predict models/directional.model.npz readings.csv --output wrench.csv
  my_sensor_reader | ftcal predict models/directional.model.npz --line-buffered | my_controller
  ftcal predict models/linear.model.npz data/test.csv --no-header | head -3
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
    add_run_options(p, seed=False)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    console = Console(args.quiet)
    plan = OutputPlan.single_file(args.output, args.force)
    problem = None if args.input == "-" else path_problem(args.input, streams=True)
    if problem is not None:
        raise CliError(f"{problem} (the raw readings to predict)")
    model = load_model_file(args.model)
    n_channels = int(model.n_features_in_)
    temperature = takes_temperature(model)
    chunk = 1 if args.line_buffered else args.chunk_size

    def emit(out) -> int:
        header = not args.no_header
        total = 0
        for raw, lines in raw_chunks(args.input, n_channels, chunk, with_lines=True, temperature=temperature):
            try:
                wrench = np.asarray(model.predict(raw), dtype=float)
            except ValueError as exc:  # name the input's line, not the row inside a chunk
                raise located_error(exc, "stdin" if args.input == "-" else args.input, lines) from None
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


def raw_chunks(source: str, n_channels: int, chunk: int, *, with_lines: bool = False, temperature: bool = False):
    """Arrays of at most ``chunk`` readings of ``source`` (``(array, line numbers)`` with ``with_lines``; the
    rows of a ``.npz`` are numbered from 0)."""
    if source == "-":
        if sys.stdin.isatty():
            print("ftcal predict: reading raw readings from the terminal; end with Ctrl-D", file=sys.stderr)
        yield from iter_reading_chunks(sys.stdin, "stdin", n_channels, chunk, with_lines=with_lines,
                                       temperature=temperature)
    elif source.endswith(".npz"):
        raw = read_readings_npz(source, n_channels)
        for start in range(0, len(raw), chunk):
            yield (raw[start:start + chunk], np.arange(start, min(start + chunk, len(raw)))) if with_lines \
                else raw[start:start + chunk]
    else:
        with open(source, encoding="utf-8") as fh:
            yield from iter_reading_chunks(fh, source, n_channels, chunk, with_lines=with_lines,
                                           temperature=temperature)
