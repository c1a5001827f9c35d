"""``ftcal retare``: re-zero a saved calibration from zero-load readings, without refitting."""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from ._common import CliError, Console, OutputPlan, existing_file, finish_command, positive_float
from ..core import check_allocation
from ._data_options import add_channel_option, model_reading, readings_input
from ._models import MODEL_SUFFIX, model_label
from ._tool_drift import RETARE_EXAMPLE, TOOL_SUFFIX, add_retare_tool_options

EXAMPLE = """\
examples:
  ftcal retare models/directional.model.npz zero_readings.csv
  my_sensor_reader --samples 200 | ftcal retare models/linear.model.npz - --output models/linear-today.model.npz

READINGS: raw readings taken now with nothing attached (the format of 'ftcal predict': one reading per
line, optional s0..s{N-1} header, or a .npz with array 'raw'). The new model file holds the same
calibration with the zero-load reading replaced by their mean; no input file is ever replaced, --force
or not. The readings must be quiet (each channel's spread at most --max-spread times the noise seen in
training, which counts as at least 1e-4 of the channel's training span) and lie near the training
readings (within half their span beyond them), else the run stops.
""" + RETARE_EXAMPLE


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("retare", help="re-zero a model from zero-load readings (no refit) -> a new model file",
                       description="Replace a model's zero-load reading by the mean of new zero-load readings.",
                       epilog=EXAMPLE)
    p.add_argument("model", type=existing_file,
                   help="model file written by 'ftcal fit', or a tool file (NAME.tool.json) of 'ftcal identify-load'")
    p.add_argument("readings", help="zero-load raw readings: a text file, a .npz with array 'raw', or '-' (stdin)")
    p.add_argument("--output", metavar="FILE", help="new model file (default: MODEL with '-retared' before the suffix)")
    p.add_argument("-f", "--force", action="store_true", help="overwrite --output if it exists (never one of the inputs)")
    p.add_argument("--max-spread", type=positive_float, default=5.0,
                   help="largest per-channel std of the readings, in units of the training noise (a tool file: of its "
                   "identification's residual RMS)")
    add_retare_tool_options(p)
    add_channel_option(p)
    finish_command(p, run, seed=False)


def run(args: argparse.Namespace) -> int:
    import ftcal
    from ..persistence import model_data
    from ._predict import raw_chunks

    console = Console(args.quiet)
    args.readings = readings_input(args, args.readings, "the zero-load readings")  # --columns: a headerless file
    tool = args.model.name.endswith(TOOL_SUFFIX)
    stem, suffix = (args.model.name.removesuffix(TOOL_SUFFIX), TOOL_SUFFIX) if tool else \
        (model_label(args.model), MODEL_SUFFIX)
    output = Path(args.output) if args.output else args.model.with_name(f"{stem}-retared{suffix}")
    if tool:
        from ._tool_drift import run_retare_tool

        return run_retare_tool(args, output)
    if args.time is not None or args.temperature is not None or args.orientation or args.tool_off or \
            args.force_unit is not None or args.torque_unit is not None:
        raise CliError("--time, --temperature, --orientation, --tool-off, --force-unit and --torque-unit re-tare a "
                       f"tool file (NAME.tool.json); {args.model} is a model file (its readings are raw)")
    plan = OutputPlan.single_file(output, args.force)
    model = ftcal.load_model(args.model)
    n_channels = int(model.n_features_in_)
    stored, _, _ = model_reading(args.model)  # the channel mapping the model was fitted with
    channels = args.channels if args.channels is not None else (stored.channels if stored is not None else None)
    chunks, n_bytes = [], 0.0
    # a stream of readings may be endless: bounded as they come
    for chunk, _ in raw_chunks(args.readings, n_channels, 4096, channels=channels):
        n_bytes += chunk.nbytes
        check_allocation(2 * n_bytes, f"the zero-load readings of {args.readings} ({n_bytes / chunk.itemsize / n_channels:.0f}"
                         " so far)", "a few hundred readings are enough; pass fewer")
        chunks.append(chunk)
    if not chunks:
        raise CliError(f"{args.readings}: no readings; record some zero-load readings first")
    readings = np.vstack(chunks)
    model.retare(readings, max_spread=args.max_spread)
    with plan.writing(output.name) as tmp:
        # the data description of the model file (its mapping, units, axes) is kept in the re-tared one
        ftcal.save_model(model, tmp, overwrite=True, data=model_data(args.model) or None)
    shift = ftcal.calibrators.retare_shift(model)
    console.info(f"re-tared from {len(readings)} readings: zero-load reading moved by "
                 f"[{', '.join(f'{v:.4g}' for v in shift)}] (raw units) -> {output}")
    return 0
