"""``ftcal export``: a saved model as an ONNX file, for a C++ / C# / embedded program with onnxruntime."""

from __future__ import annotations

import argparse
from pathlib import Path

from ._common import CliError, Console, OutputPlan, add_run_options, existing_file
from ._models import model_label

EXAMPLE = """\
examples:
  ftcal export models/directional.model.npz --format onnx
  ftcal export models/auto.model.npz --format onnx --output deploy/sensor.onnx

The ONNX graph holds the whole calibration (re-tare, zero-load reading, scaling, the networks,
torque scaling): input 'readings' float64 (n, N) raw channels in the training order (temperature
[deg C] last for a temperature-compensated model), output 'wrench' float64 (n, 6) Fx,Fy,Fz [N],
Tx,Ty,Tz [N·m]. Needs the onnx package: pip install "ftcal[onnx]".
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "export",
        help="write a saved model as an ONNX file (raw readings -> wrench) for deployment",
        description="Export a saved calibration model to ONNX, pre- and post-processing included.",
        epilog=EXAMPLE,
    )
    p.add_argument("model", type=existing_file, help="model file written by 'ftcal fit'")
    p.add_argument("--format", choices=("onnx",), default="onnx", help="export format (default onnx)")
    p.add_argument("--output", metavar="FILE", help="the exported file (default: MODEL with the suffix .onnx)")
    p.add_argument("-f", "--force", action="store_true", help="overwrite --output if it exists")
    add_run_options(p, seed=False)
    p.set_defaults(handler=run)


def run(args: argparse.Namespace) -> int:
    import ftcal

    console = Console(args.quiet)
    output = Path(args.output) if args.output else args.model.with_name(f"{model_label(args.model)}.onnx")
    plan = OutputPlan.single_file(output, args.force)  # first: never over an input, whatever its name
    if output.suffix.lower() != ".onnx":
        raise CliError(f"--output {output} should end in .onnx (the file is an ONNX model)")
    model = ftcal.load_model(args.model)
    with plan.writing(output.name) as tmp:
        ftcal.export_onnx(model, tmp, overwrite=True)
    console.info(f"exported {type(model).__name__} ({model.n_features_in_} inputs -> 6) to {output}")
    return 0
