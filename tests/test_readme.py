"""The README's commands: every ``ftcal`` command in its shell blocks parses with today's command
line, and the workflow blocks run, verbatim, in a fresh directory on data the test makes, as a new user would
(``my_sensor_reader`` / ``my_controller`` stand for the user's programs; the recordings a block says to make
are made first). The first block is the issue's "done when": a ``.mat`` of raw channels and wrenches with
torques in N·mm -> a report opened in a real browser, a matrix for a driver and an ONNX file."""

from __future__ import annotations

import json
import re
import shlex
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import onnxruntime
import scipy.io

import browser
from ftcal import load_model
from ftcal.cli import build_parser, main
from ftcal.cli._common import UsageError

README = Path(__file__).resolve().parents[1] / "README.md"


def shell_blocks() -> dict[str, list[str]]:
    """Heading -> the ```bash blocks under it, each as its text."""
    blocks: dict[str, list[str]] = {}
    heading = ""
    for match in re.finditer(r"^(#+ [^\n]*)$|^```bash\n(.*?)^```", README.read_text(encoding="utf-8"), re.M | re.S):
        if match.group(1):
            heading = match.group(1).lstrip("#").strip()
        else:
            blocks.setdefault(heading, []).append(match.group(2))
    return blocks


def ftcal_commands(block: str) -> list[list[str]]:
    """The ``ftcal`` commands of a block (continuations joined, comments and pipes split off)."""
    text = block.replace("\\\n", " ")
    out = []
    for line in text.splitlines():
        for part in re.split(r"\|\||&&|\||;", re.split(r"\s#", " " + line)[0]):
            words = shlex.split(part.split(">")[0])
            if words[:1] == ["ftcal"]:
                out.append(words[1:])
    return out


def test_every_readme_ftcal_command_parses(tmp_path, monkeypatch):
    monkeypatch.chdir(tmp_path)
    commands = [c for blocks in shell_blocks().values() for b in blocks for c in ftcal_commands(b)]
    assert len(commands) >= 20 and ["demo"] in commands
    parser = build_parser()
    for args in commands:
        for word in args:  # input files the command names exist (their content is the workflow tests' job)
            if not word.startswith("-") and ("/" in word or re.search(r"\.(csv|npz|mat|json)$", word)):
                path = tmp_path / word
                if path.suffix:
                    path.parent.mkdir(parents=True, exist_ok=True)
                    path.touch()
                else:
                    path.mkdir(parents=True, exist_ok=True)
        made: set[str] = set()
        while True:  # an input checked at parse time (a bare folder name, e.g. a recordings folder) is made too
            try:
                parser.parse_args(args)  # raises UsageError (a test failure) on an option the CLI no longer has
                break
            except UsageError as exc:
                missing = [w for w in args if not w.startswith("-") and w not in made
                           and f"{w} does not exist" in str(exc)]
                if not missing:
                    raise
                made.add(missing[0])
                (tmp_path / missing[0]).mkdir(parents=True, exist_ok=True)  # a folder of recordings, made earlier


def _shim(tmp: Path) -> dict:
    """PATH with an ``ftcal`` that runs this checkout's ftcal (the installed script may point elsewhere)."""
    bin_dir = tmp / "bin"
    bin_dir.mkdir()
    shim = bin_dir / "ftcal"
    shim.write_text(f'#!/bin/sh\nexec "{sys.executable}" -m ftcal "$@"\n')
    shim.chmod(0o755)
    chromium = bin_dir / "chromium"  # the README's 'chromium' with the flags a sandbox-less CI needs
    chromium.write_text(f'#!/bin/sh\nexec "{browser.chromium()}" {" ".join(browser.CHROMIUM_FLAGS)} '
                        f'--user-data-dir="{tmp}/chromium-profile" "$@"\n')
    chromium.chmod(0o755)
    import os

    return {**os.environ, "PATH": f"{bin_dir}:{os.environ['PATH']}",
            "PYTHONPATH": os.pathsep.join([str(README.parent), os.environ.get("PYTHONPATH", "")])}


def run_block(block: str, cwd: Path, env: dict, prelude: str = "") -> None:
    script = "set -euo pipefail\n" + prelude + "\n" + block
    done = subprocess.run(["bash", "-c", script], cwd=cwd, env=env, capture_output=True, text=True,
                          stdin=subprocess.DEVNULL)
    assert done.returncode == 0, f"README block failed:\n{block}\nstderr:\n{done.stderr[-3000:]}"
    return done


def test_from_a_mat_recording_to_report_matrix_and_onnx_with_readme_commands_only(tmp_path):
    from test_calibration_report import sensor_dataset

    data = sensor_dataset(n_channels=8)
    scipy.io.savemat(tmp_path / "recording.mat", {"raw": data.raw, "wrench": data.wrench * [1, 1, 1, 1e3, 1e3, 1e3],
                                                  "group": data.group})
    new = np.vstack([data.raw[:5], data.raw.max(axis=0) + 1.0])
    np.savetxt(tmp_path / "new_readings.csv", new, delimiter=",", header=",".join(f"s{i}" for i in range(8)),
               comments="")
    (block,) = shell_blocks()["From your recording to a report, a matrix and an ONNX file"]
    run_block(block, tmp_path, _shim(tmp_path))
    # the report, in the browser
    shown = browser.render(tmp_path / "models" / "linear.report.html", tmp_path / "chromium")
    assert shown.console == [] and shown.page_requests == [] and "Held-out accuracy per axis" in shown.dom
    assert (tmp_path / "models" / "linear.report.pdf").read_bytes().startswith(b"%PDF-")
    facts = json.loads((tmp_path / "models" / "linear.report.json").read_text())
    assert facts["data"]["units"] == {"source_force_unit": "N", "source_torque_unit": "N.mm"}
    assert max(a["rms_pct_fs"] for a in facts["accuracy"]) < 1.0  # torques converted: N·m errors, not N·mm
    # against the rated capacity and the specification of the README's command
    assert [a["full_scale"] for a in facts["accuracy"]] == [500, 500, 900, 20, 20, 20]
    assert facts["verdict"] == "PASS" and f'class="verdict PASS">PASS' in shown.dom
    # the matrix and the ONNX file compute what the model computes
    model = load_model(tmp_path / "models" / "linear.model.npz")
    rows = [line.split(",") for line in (tmp_path / "deploy" / "matrix.csv").read_text().splitlines()
            if not line.startswith("#")][1:]
    numbers = np.array([r[1:] for r in rows], dtype=float)
    np.testing.assert_allclose(data.raw @ numbers[:, :8].T + numbers[:, 8], model.predict(data.raw), rtol=1e-9,
                               atol=1e-9)
    session = onnxruntime.InferenceSession(str(tmp_path / "deploy" / "sensor.onnx"))
    (onnx_out,) = session.run(None, {"readings": data.raw})
    np.testing.assert_allclose(onnx_out, model.predict(data.raw), rtol=1e-5, atol=1e-9)
    wrench = (tmp_path / "wrench.csv").read_text().splitlines()
    assert wrench[0].endswith(",out_of_range") and [w[-1] for w in wrench[1:]] == ["0"] * 5 + ["1"]


def test_recorded_logs_blocks_run_as_written(tmp_path):
    # the second recording 'check/' that the README evaluates on, and the live step's recordings
    assert main(["simulate", "experiment", "--subdivisions", "1", "--seed", "1", "--out", str(tmp_path / "logs2"),
                 "-q"]) == 0
    assert main(["prepare", str(tmp_path / "logs2"), "--out", str(tmp_path / "check"), "-q"]) == 0
    blocks = shell_blocks()["Calibrating a real sensor from recorded logs"]
    blocks = [b for b in blocks if "--fixture" not in b]
    assert len(blocks) == 2
    env = _shim(tmp_path)
    done = run_block(blocks[0], tmp_path, env)
    # evaluated on a recording it was not fitted on: no warning but the extrapolation, said of the rows that go a
    # little beyond the calibrated loads (another recording's poses)
    warnings = [ln for ln in done.stderr.splitlines() if "warning" in ln]
    assert all("go beyond the" in ln for ln in warnings), warnings
    assert (tmp_path / "models" / "linear.report.html").is_file()
    # live: zero readings (a quiet no-load reading), tool logs (poses with a load on), a run to compensate
    no_load = [line for line in (tmp_path / "logs" / "config0_no-load.csv").read_text().splitlines()
               if line[:1].isdigit()]
    header = next(line for line in (tmp_path / "logs" / "config0_no-load.csv").read_text().splitlines()
                  if line.startswith("timestamp"))
    channels = [i for i, name in enumerate(header.split(",")) if re.fullmatch(r"s\d+", name)]
    (tmp_path / "zero_readings.csv").write_text(",".join(no_load[0].split(",")[i] for i in channels) + "\n")
    (tmp_path / "tool_logs").mkdir()
    shutil.copy(tmp_path / "logs" / "config0_load.csv", tmp_path / "tool_logs")
    shutil.copy(tmp_path / "logs" / "config3_load.csv", tmp_path / "run.csv")
    readings = "\n".join(",".join(line.split(",")[i] for i in channels) for line in no_load[:5])
    (tmp_path / "sensor.txt").write_text(readings + "\n")
    prelude = ("my_sensor_reader() { cat sensor.txt; }\n"
               "my_controller() { cat > controller.csv; }\n")
    run_block(blocks[1], tmp_path, env, prelude)
    lines = (tmp_path / "controller.csv").read_text().splitlines()
    assert lines[0] == "Fx,Fy,Fz,Tx,Ty,Tz" and len(lines) == 6
    external = np.loadtxt(tmp_path / "external.csv", delimiter=",", skiprows=1)
    # config 3 carries the same 2 kg as the tool logs' config 0, elsewhere: the external wrench is small against it
    assert np.sqrt(np.mean(external[:, -6:-3] ** 2)) < 2.0 * 9.81


def test_tool_and_temperature_block_runs_as_written(tmp_path):
    blocks = shell_blocks()["On the robot: tool gravity compensation, re-taring, temperature"]
    (block,) = blocks
    assert main(["simulate", "experiment", "--subdivisions", "1", "--temperature-range", "15,35", "--out",
                 str(tmp_path / "logs"), "-q"]) == 0
    assert main(["prepare", str(tmp_path / "logs"), "--out", str(tmp_path / "data"), "-q"]) == 0
    assert main(["fit", str(tmp_path / "data" / "dataset.csv"), "--model", "linear", "--out",
                 str(tmp_path / "models"), "-q"]) == 0
    log = (tmp_path / "logs" / "config0_no-load.csv").read_text().splitlines()
    header = next(line for line in log if line.startswith("timestamp")).split(",")
    channels = [i for i, name in enumerate(header) if re.fullmatch(r"s\d+", name)]
    first = next(line for line in log if line[:1].isdigit()).split(",")
    (tmp_path / "zero_readings.csv").write_text(",".join(first[i] for i in channels) + "\n")
    (tmp_path / "tool_logs").mkdir()
    shutil.copy(tmp_path / "logs" / "config0_load.csv", tmp_path / "tool_logs")
    shutil.copy(tmp_path / "logs" / "config3_load.csv", tmp_path / "run.csv")
    run_block(block, tmp_path, _shim(tmp_path))
    assert (tmp_path / "tool" / "tool.tool.json").is_file()
    assert (tmp_path / "models" / "linear-retared.model.npz").is_file()
    assert (tmp_path / "models" / "linear-thermal.model.npz").is_file()
    assert "gripper_mass:" in (tmp_path / "tool" / "gravity_compensation.yaml").read_text()


def test_fixture_and_mounting_block_runs_as_written(tmp_path):
    (block,) = [b for b in shell_blocks()["Calibrating a real sensor from recorded logs"] if "--fixture" in b]
    (tmp_path / "my_fixture.csv").write_text("id,name,mass_kg,com_x_m,com_y_m,com_z_m\n0,plate,1.5,0.1,0,0.05\n"
                                             "1,arm,3.0,0,0.15,0.05\n")
    done = run_block(block, tmp_path, _shim(tmp_path))
    assert "fixture: my_fixture.csv (2 load configurations" in done.stderr
    facts = json.loads((tmp_path / "my_data" / "prepare.json").read_text())
    assert facts["samples_per_configuration"].keys() == {"0", "1"} and facts["sensor_frame"] == "ftcal_mounted_sensor"


def test_ros_bag_blocks_run_as_written(tmp_path):
    from scipy.spatial.transform import Rotation
    from test_pose_files import TOOL, _continuous_file, _quat_base_file, _static_poses

    import ftcal
    from ftcal.experiment._virtual_recording import continuous_recording
    from ftcal.io._bags import write_bag

    raw_block, wrench_block = shell_blocks()["From a ROS bag"]
    env = _shim(tmp_path)
    done = run_block(raw_block, tmp_path, env)
    assert done.stderr.count("found 11 still poses, kept 11") == 14 + 1  # 14 runs prepared, 1 tool bag
    assert "gripper_mass:" in (tmp_path / "tool_bag" / "gravity_compensation.yaml").read_text()
    holder = json.loads((tmp_path / "sim" / "virtual_experiment.json").read_text())["mounting_device"]
    tool = ftcal.experiment.ToolLoad.load(tmp_path / "tool_bag" / "tool.tool.json")
    assert abs(tool.mass - holder["mass"]) <= 4 * tool.mass_std_error + 0.01 * holder["mass"]
    # the factory-calibrated sensor's recordings the second block reads: a pose file, a continuous CSV, a bag
    R, W = _static_poses(20, seed=12)
    _quat_base_file(tmp_path / "poses.csv", R, W)
    _continuous_file(tmp_path / "recording.csv", Rotation.random(12, random_state=13).as_matrix(), seed=13)
    robot = ftcal.robot.load_robot("kuka_iiwa14")
    q = ftcal.robot.plan_calibration_poses(robot, subdivisions=0, excluded_cap_deg=0).q
    rec = continuous_recording(TOOL.gravity_wrench(ftcal.robot.sensor_pose_in_base(robot, q)[:, :3, :3]), joints=q,
                               still_s=4.0, move_s=2.0, sensor_rate_hz=100.0, pose_rate_hz=40.0, noise=0.1,
                               settle_amplitude=0.5, start_time_s=1.7e9, random_state=14)
    write_bag(tmp_path / "wrench_bag", "sqlite3", sensor_time=rec.sensor_time, reading=rec.reading,
              pose_time=rec.pose_time, joints=rec.joints, joint_names=robot.joint_names,
              rotations=ftcal.robot.sensor_pose_in_base(robot, rec.joints)[:, :3, :3])
    run_block(wrench_block, tmp_path, env)
    for out in ("tool_poses", "tool_rec", "tool_joints", "tool_tf"):
        found = ftcal.experiment.ToolLoad.load(tmp_path / out / "tool.tool.json")
        assert abs(found.mass - TOOL.mass) <= 4 * found.mass_std_error, out
    # compensated with those tool files: one row per input row (pose file) and per sensor sample (bag; those outside
    # the span of the poses, at its ends, have no pose)
    assert len((tmp_path / "external.csv").read_text().splitlines()) == 1 + len(R)
    assert len(rec.sensor_time) - 2 <= len((tmp_path / "external_bag.csv").read_text().splitlines()) - 1 <= \
        len(rec.sensor_time)


def test_the_readme_shows_the_first_page_of_a_report():
    readme = README.read_text(encoding="utf-8")
    found = re.search(r"!\[The first page of a calibration report\]\((docs/[^)]+\.png)\)", readme)
    assert found is not None and "report_screenshot.py" in readme
    png = README.parent / found.group(1)
    assert png.read_bytes().startswith(b"\x89PNG") and png.stat().st_size < 200_000
    assert (README.parent / "docs" / "report_screenshot.py").is_file()
def test_getting_your_data_in_block_runs_as_written(tmp_path):
    from test_data_shapes import G0, _csv, _sensor

    raw, wrench = _sensor()
    scipy.io.savemat(tmp_path / "onematrix.mat", {"data": np.hstack([raw, wrench])})
    _csv(tmp_path / "other_names.csv", [f"ch{i}" for i in range(8)], raw[:10])
    raw3, wrench3 = _sensor(n_axes=3, n_channels=4)
    _csv(tmp_path / "cell3.csv", ["", "g1", "g2", "g3", "g4", "force_x", "force_y", "force_z", "time [s]"],
         np.arange(len(raw3)), raw3, wrench3 / (G0 * 1e-3), np.arange(len(raw3)) * 0.01)
    raw1, wrench1 = _sensor(n_axes=3, n_channels=2)
    _csv(tmp_path / "cell1.csv", ["bridge_a", "bridge_b", "load"], raw1, wrench1[:, 2])
    (tmp_path / "poses").mkdir()
    names = [f"s{i}" for i in range(8)] + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"]
    for k in range(8):
        r = raw[30 * k:30 * (k + 1)].copy()
        if k in (2, 5):
            r[:10, 0] = 4095.0
        _csv(tmp_path / "poses" / f"pose{k}.csv", names, r, wrench[30 * k:30 * (k + 1)])
    _csv(tmp_path / "soft.csv", names, raw, wrench * [1, 1, 1, 1e3, 1e3, 1e3])
    (block,) = shell_blocks()["Getting your data in"]
    run_block(block, tmp_path, _shim(tmp_path))
    predicted = np.loadtxt(tmp_path / "cell3_wrench.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(predicted, wrench3, atol=0.1)  # grams read as N, the model's own columns
    one = np.loadtxt(tmp_path / "one_wrench.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(one, wrench[:10], atol=0.1)
    assert load_model(tmp_path / "pose-model" / "linear.model.npz").n_features_in_ == 8


def test_the_readme_names_only_public_python_names():
    """Every ``ftcal.x.y`` the README names is reachable without a private module (``ftcal.compose._auto...``)."""
    import importlib

    names = set(re.findall(r"`(ftcal(?:\.\w+)+)", README.read_text(encoding="utf-8")))
    assert "ftcal.compose.check_calibration" in names  # the check of any fitted model, named in its public home
    private = sorted(n for n in names if any(part.startswith("_") for part in n.split(".")[1:]))
    assert not private, private
    for name in sorted(names):
        parts = name.split(".")
        obj = importlib.import_module(parts[0])
        for k, part in enumerate(parts[1:], start=1):
            try:
                obj = getattr(obj, part)
            except AttributeError:
                obj = importlib.import_module(".".join(parts[:k + 1]))
