"""``ftcal export``: a saved model as an ONNX file (C++ / C# / embedded with onnxruntime), or a linear model as its
6 x N matrix and offset (CSV or JSON) for a vendor driver."""

from __future__ import annotations

import argparse
from pathlib import Path

from ._common import CliError, Console, OutputPlan, existing_file, finish_command
from ._models import model_label

EXAMPLE = """\
examples:
  ftcal export models/directional.model.npz --format onnx
  ftcal export models/auto.model.npz --format onnx --output deploy/sensor.onnx
  ftcal export models/linear.model.npz --format matrix --output deploy/matrix.csv
  ftcal export models/linear.model.npz --format matrix --output deploy/matrix.json
  ftcal export tool/tool.tool.json --format ros --output deploy/gravity_compensation.yaml

The ONNX graph holds the whole calibration (re-tare, zero-load reading, scaling, the networks,
torque scaling): input 'readings' float64 (n, N) raw channels in the training order (temperature
[deg C] last for a temperature-compensated model), output 'wrench' float64 (n, k) of the model's
k axes: Fx,Fy,Fz [N],Tx,Ty,Tz [N·m] for a 6-axis sensor, Fx,Fy,Fz for a 3-axis load cell.
Needs the onnx package: pip install "ftcal[onnx]".

--format matrix (a linear model only): wrench = matrix @ raw + offset, the k x N matrix and the
offset (k) in N and N·m. CSV (any --output name but .json): a header 'axis,s0,...,s{N-1},offset'
(the channels the model was fitted on), one row per axis; it reads as it is with
pandas.read_csv(path, index_col=0) or numpy.loadtxt(path, delimiter=",", skiprows=1,
usecols=range(1, N + 2)). JSON (.json): keys equation, matrix, offset, inputs, outputs, units.
A nonlinear model has no such matrix and is refused.

--format ros (a tool file of 'ftcal identify-load'): the tool's gravity-compensation parameters as
YAML for ROS: force_torque_tools' keys (bias, gripper_mass, gripper_com_pose, ...) and a ROS 2
control_toolbox GravityCompensation filter block (CoG.pos, CoG.force, frames). Neither can express a bias
drift: the YAML holds the bias at the drift's reference time and says so in a comment.

--format onnx of a tool file: the tool's compensation as an ONNX graph, inputs 'rotation' float64
(n, 3, 3) (sensor to base), 'wrench' float64 (n, 6) [N, N·m] and, for a drifting bias, 'time' (n,) or
'temperature' (n,); output 'external' (n, 6). The graph extrapolates a drift silently beyond the span
it covers (metadata 'drift_span'); re-tare and export again.
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("export", help="write a saved model as an ONNX file (raw readings -> wrench) for deployment",
                       description="Export a saved calibration model to ONNX, pre- and post-processing included.",
                       epilog=EXAMPLE)
    p.add_argument("model", type=existing_file,
                   help="model file written by 'ftcal fit' (a tool file of 'ftcal identify-load' for --format ros)")
    p.add_argument("--format", choices=("onnx", "matrix", "ros"), default="onnx",
                   help="onnx: the whole model as an ONNX graph; matrix: a linear model's 6xN matrix and offset; "
                   "ros: a tool file as gravity-compensation YAML")
    p.add_argument("--sensor-frame", default="ft_sensor", help="--format ros: the sensor's frame name in your TF tree")
    p.add_argument("--world-frame", default="world", help="--format ros: the frame gravity is given in")
    p.add_argument("--output", metavar="FILE",
                   help="the exported file (default: MODEL with the suffix .onnx, or .matrix.csv for --format matrix)")
    p.add_argument("-f", "--force", action="store_true", help="overwrite --output if it exists")
    finish_command(p, run, seed=False)


def run(args: argparse.Namespace) -> int:
    import ftcal

    console = Console(args.quiet)
    default = {"onnx": ".onnx", "matrix": ".matrix.csv", "ros": ".ros.yaml"}[args.format]
    is_tool = args.model.name.endswith(".tool.json")
    stem = args.model.name.removesuffix(".tool.json") if args.format == "ros" or is_tool else model_label(args.model)
    output = Path(args.output) if args.output else args.model.with_name(f"{stem}{default}")
    plan = OutputPlan.single_file(output, args.force)  # first: never over an input, whatever its name
    # any output name is accepted with --format matrix (.json is JSON, any other name CSV: x.matrix, cal.txt); an
    # ONNX or YAML file keeps its suffix, which runtimes and ROS tools go by
    suffixes = {"onnx": (".onnx",), "ros": (".yaml", ".yml")}.get(args.format)
    if suffixes and output.suffix.lower() not in suffixes:
        raise CliError(f"--output {output} should end in {' or '.join(suffixes)} for --format {args.format}")
    if args.format == "ros" or (is_tool and args.format == "onnx"):
        from ..experiment import tool_gravity_compensation_yaml, tool_onnx_model

        tool = ftcal.experiment.ToolLoad.load(args.model)
        if args.format == "ros":
            text = tool_gravity_compensation_yaml(tool, sensor_frame=args.sensor_frame, world_frame=args.world_frame)
            plan.write_text(output.name, text)
            console.info(f"wrote the tool's gravity-compensation parameters (ROS YAML) to {output}")
            return 0
        with plan.writing(output.name) as tmp:
            tmp.write_bytes(tool_onnx_model(tool).SerializeToString())
        drift = "" if tool.drift is None else f" with its {tool.drift.description} bias drift"
        console.info(f"exported the tool's compensation{drift} (ONNX) to {output}")
        return 0
    model = ftcal.load_model(args.model)
    if args.format == "matrix":
        return _export_matrix(model, output, plan, console, args.model)
    with plan.writing(output.name) as tmp:
        ftcal.export_onnx(model, tmp, overwrite=True)
    console.info(f"exported {type(model).__name__} ({model.n_features_in_} inputs -> {getattr(model, 'n_outputs_', 6)} axes) to {output}")
    return 0


def _export_matrix(model, output: Path, plan: OutputPlan, console: Console, model_path) -> int:
    from ..io import parse_column_slice
    from ..persistence import matrix_export_dict
    from ._data_options import model_reading

    stored, axes, _ = model_reading(model_path)  # the axes and channel names the model was fitted with
    inputs = None if stored is None or stored.channels is None or parse_column_slice(stored.channels[0]) \
        else stored.channels
    facts = matrix_export_dict(model, axes=axes, inputs=inputs)
    if output.suffix.lower() == ".json":
        plan.write_json(output.name, facts)
    else:
        # no comment line: numpy.loadtxt(path, delimiter=",", skiprows=1, usecols=...) and pandas.read_csv(path,
        # index_col=0) read it as it is; the formula and units are in the help and the .json form
        lines = [",".join(["axis", *facts["inputs"], "offset"])]
        for label, row, b in zip(facts["outputs"], facts["matrix"], facts["offset"]):
            lines.append(",".join([label, *(repr(float(v)) for v in row), repr(float(b))]))
        plan.write_text(output.name, "\n".join(lines) + "\n")
    console.info(f"exported the {len(facts['outputs'])}x{len(facts['inputs'])} calibration matrix and offset of "
                 f"{type(model).__name__} to {output}")
    return 0
