"""Data as it comes: one-matrix .mat files, 1- and 3-axis load cells in grams, per-pose folders with saturated
files, empty and unused column names, N·mm torques on every command, predict --channels, the mapping kept in the
model file, exact units, and bounded .mat/.npz readers; each through fit, report, predict and export."""

from __future__ import annotations

import json
import resource
import subprocess
import sys
import zipfile

import numpy as np
import pytest
import scipy.io

from ftcal import CalibrationDataset, load_model
from ftcal.core import DatasetFileError
from ftcal.cli import main
from ftcal.io._readers import ColumnMap, lever_arm_problem, unit_scale

G0 = 9.80665


def one_line_error(capsys, code: int) -> str:
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and err.startswith("ftcal: error:"), err
    return err


def _sensor(n_axes: int = 6, n_channels: int = 8, n: int = 240, seed: int = 0):
    """Raw bridge readings and the wrench (N, N·m) of a linear sensor with noise, loads up to 50 N / 2.5 N·m."""
    rng = np.random.default_rng(seed)
    wrench = rng.uniform(-1, 1, size=(n, 6)) * [50, 50, 50, 2.5, 2.5, 2.5]
    wrench[:, n_axes:] = 0.0  # a sensor of fewer axes sees no other load
    gain = rng.normal(size=(n_channels, 6)) * [1, 1, 1, 20, 20, 20]
    raw = wrench @ gain.T + rng.normal(scale=1e-3, size=(n, n_channels)) + 100.0
    return raw, wrench[:, :n_axes]


def _csv(path, names, *columns):
    rows = np.column_stack(columns)
    path.write_text(",".join(names) + "\n" + "".join(",".join(repr(float(v)) for v in r) + "\n" for r in rows))
    return path


def _through_every_command(tmp_path, dataset, options, axes, capsys, readings=None, predict_options=()):
    """fit, report, predict and export (matrix and ONNX) of a linear model on ``dataset``; returns the model."""
    out = tmp_path / "m"
    assert main(["fit", str(dataset), *options, "--model", "linear", "--out", str(out), "-q"]) == 0, \
        capsys.readouterr().err
    model = out / "linear.model.npz"
    assert main(["report", str(model), str(dataset), "--out", str(tmp_path / "r"), "-q"]) == 0, capsys.readouterr().err
    facts = json.loads((tmp_path / "r" / "linear.report.json").read_text())
    assert json.dumps(facts)  # the report of the axes that exist
    capsys.readouterr()
    assert main(["predict", str(model), str(readings or dataset), *predict_options]) == 0, capsys.readouterr().err
    header = capsys.readouterr().out.splitlines()[0]
    assert header.split(",") == list(axes)
    assert main(["export", str(model), "--format", "matrix", "--output", str(tmp_path / "cal.matrix")]) == 0
    import pandas

    table = pandas.read_csv(tmp_path / "cal.matrix", index_col=0)  # reads as it is: no comment line
    assert list(table.index) == list(axes)
    loaded = np.loadtxt(tmp_path / "cal.matrix", delimiter=",", skiprows=1, usecols=range(1, table.shape[1] + 1), ndmin=2)
    assert loaded.shape == (len(axes), table.shape[1])
    assert main(["export", str(model), "--output", str(tmp_path / "cal.onnx"), "-q"]) == 0
    return load_model(model)


def test_one_matrix_mat_file_with_column_slices(tmp_path, capsys):
    raw, wrench = _sensor()
    scipy.io.savemat(tmp_path / "rec.mat", {"data": np.hstack([raw, wrench])})  # 8 bridges then Fx..Mz
    model = _through_every_command(tmp_path, tmp_path / "rec.mat",
                                   ["--channels", "data[:,0:8]", "--wrench", "data[:,8:14]"], tuple("Fx Fy Fz Tx Ty Tz".split()),
                                   capsys)
    np.testing.assert_allclose(model.predict(raw), wrench, atol=0.1)


def test_one_matrix_in_matlab_v73_is_refused_with_the_fix(tmp_path, capsys):
    header = b"MATLAB 7.3 MAT-file, Platform: GLNXA64, Created on: Mon Jan 1 00:00:00 2024 HDF5 schema 1.00 .".ljust(116)
    (tmp_path / "rec.mat").write_bytes(header + b"\0" * 8 + b"\x00\x02" + b"IM" + b"\x89HDF\r\n\x1a\n" + b"\0" * 64)
    err = one_line_error(capsys, main(["fit", str(tmp_path / "rec.mat"), "--out", str(tmp_path / "m")]))
    assert "v7.3 (HDF5)" in err and "'-v7'" in err


def test_three_axis_load_cell_in_grams_with_unused_columns(tmp_path, capsys):
    raw, wrench = _sensor(n_axes=3, n_channels=4)
    names = ["", "g1", "g2", "g3", "g4", "force_x", "force_y", "force_z", "time [s]"]  # an index, a time, no name
    path = _csv(tmp_path / "cell.csv", names, np.arange(len(raw)), raw, wrench / (G0 * 1e-3), np.arange(len(raw)))
    model = _through_every_command(tmp_path, path, ["--channels", "g1..g4", "--force-unit", "g"], ("Fx", "Fy", "Fz"),
                                   capsys)
    np.testing.assert_allclose(model.predict(raw), wrench, atol=0.1)  # grams read as their weight in N
    assert model.predict(raw).shape == (len(raw), 3)


def test_one_axis_cell(tmp_path, capsys):
    raw, wrench = _sensor(n_axes=3, n_channels=2)
    path = _csv(tmp_path / "cell.csv", ["bridge_a", "bridge_b", "load"], raw, wrench[:, 2])
    model = _through_every_command(tmp_path, path, ["--channels", "bridge_a,bridge_b", "--wrench", "load", "--axes",
                                                    "Fz"], ("Fz",), capsys)
    assert model.predict(raw).shape == (len(raw), 1)


def test_per_pose_folder_with_two_saturated_files(tmp_path, capsys):
    raw, wrench = _sensor(n=300)
    folder = tmp_path / "poses"
    folder.mkdir()
    for k in range(10):
        r = raw[30 * k:30 * (k + 1)].copy()
        if k in (3, 7):  # the ADC pinned at its limit for part of these poses
            r[:12, 2] = 4095.0
        _csv(folder / f"pose{k:02d}.csv", [f"s{i}" for i in range(8)] + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"], r,
             wrench[30 * k:30 * (k + 1)])
    data = CalibrationDataset.load(folder, columns=ColumnMap(groups="file"))
    assert sorted(set(data.group.tolist())) == list(range(10)) and data.meta["group_labels"][3] == "pose03.csv"
    code = main(["fit", str(folder), "--groups", "file", "--model", "linear", "--out", str(tmp_path / "w")])
    assert code == 0 and "24 of 300 rows have a channel pinned" in capsys.readouterr().err
    model = _through_every_command(tmp_path, folder, ["--groups", "file", "--exclude-saturated", "auto"],
                                   tuple("Fx Fy Fz Tx Ty Tz".split()), capsys, readings=folder / "pose00.csv")
    np.testing.assert_allclose(model.predict(raw[:30]), wrench[:30], atol=0.1)


def test_repeated_load_cases_are_not_taken_for_a_saturated_channel(tmp_path, capsys):
    raw, wrench = _sensor(n=40)
    path = _csv(tmp_path / "repeats.csv", [f"s{i}" for i in range(8)] + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"],
                np.repeat(raw, 8, axis=0), np.repeat(wrench, 8, axis=0))  # every load case recorded 8 times
    assert main(["fit", str(path), "--model", "linear", "--out", str(tmp_path / "m")]) == 0
    assert "pinned" not in capsys.readouterr().err
    pinned = raw.copy()
    pinned[:12, 2] = pinned[:, 2].max() + 1.0  # and one channel pinned under 12 different loads is still said
    path = _csv(tmp_path / "pinned.csv", [f"s{i}" for i in range(8)] + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"],
                np.repeat(pinned, 8, axis=0), np.repeat(wrench, 8, axis=0))
    assert main(["fit", str(path), "--model", "linear", "--out", str(tmp_path / "p")]) == 0
    assert "96 of 320 rows have a channel pinned" in capsys.readouterr().err


def test_predict_channels_and_the_mapping_kept_in_the_model(tmp_path, capsys):
    raw, wrench = _sensor(n_channels=6)
    names = [f"g{i + 1}" for i in range(6)] + ["Fx", "Fy", "Fz", "Mx", "My", "Mz"]
    path = _csv(tmp_path / "log.csv", names, raw, wrench)
    out = tmp_path / "m"
    assert main(["fit", str(path), "--channels", "g6,g5,g4,g3,g2,g1", "--model", "linear", "--out", str(out),
                 "-q"]) == 0
    capsys.readouterr()
    # predict reads the model's own channel order from the file: the numbers are right, whatever the header order
    assert main(["predict", str(out / "linear.model.npz"), str(path)]) == 0
    lines = capsys.readouterr().out.splitlines()
    predicted = np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]])
    np.testing.assert_allclose(predicted, wrench, atol=0.1)
    # evaluate and retare read alike; another input's names go through predict --channels
    assert main(["evaluate", str(path), str(out / "linear.model.npz"), "--no-plots", "--out", str(tmp_path / "e"),
                 "-q"]) == 0
    capsys.readouterr()
    metrics = json.loads((tmp_path / "e" / "metrics.json").read_text())
    assert metrics["models"]["linear"]["rmse"] < 0.05
    other = _csv(tmp_path / "other.csv", [f"ch{i}" for i in range(6)], raw[:, ::-1])
    assert main(["predict", str(out / "linear.model.npz"), str(other), "--channels", "ch0..ch5"]) == 0
    lines = capsys.readouterr().out.splitlines()
    np.testing.assert_allclose(np.array([[float(v) for v in ln.split(",")] for ln in lines[1:]]), wrench, atol=0.1)
    # a file without the model's columns is refused, naming the column
    err = one_line_error(capsys, main(["predict", str(out / "linear.model.npz"), str(other)]))
    assert "'g6'" in err and "--channels" in err


def test_newton_millimetres_given_to_benchmark_dataset_are_refused_with_the_fix(tmp_path, capsys):
    raw, wrench = _sensor()
    path = _csv(tmp_path / "soft.csv", [f"s{i}" for i in range(8)] + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"], raw,
                wrench * [1, 1, 1, 1000, 1000, 1000])
    for argv in (["benchmark", "dataset", str(path)], ["fit", str(path), "--force-unit", "N"]):
        err = one_line_error(capsys, main([*argv, "--model", "linear", "--out", str(tmp_path / "b")]))
        assert "--torque-unit N.mm" in err
    assert main(["benchmark", "dataset", str(path), "--torque-unit", "N.mm", "--model", "linear", "--out",
                 str(tmp_path / "b"), "-q"]) == 0


def test_forces_in_kilonewtons_are_named_as_such():
    wrench = np.array([[0.004, 0.002, 0.0, 0.0, 0.05, 0.01]])  # kN forces, N·m torques: arm 12 m read as N
    problem = lever_arm_problem(wrench)
    assert "forces look like kN" in str(problem) and problem.settings["force_unit"] == "kN"
    from ftcal.cli._messages import cli_message

    assert "--force-unit kN" in cli_message(problem)


@pytest.mark.parametrize("unit, kind, factor", [("MN", "force", 1e6), ("mN", "force", 1e-3), ("kgf", "force", G0),
                                                 ("g", "force", G0 * 1e-3), ("N·mm", "torque", 1e-3),
                                                 ("MN.m", "torque", 1e6), ("mN.m", "torque", 1e-3),
                                                 ("kN.m", "torque", 1e3), ("lbf.in", "torque", 0.1129848290276167)])
def test_units_are_read_exactly(unit, kind, factor):
    assert unit_scale(unit, kind) == pytest.approx(factor, rel=1e-12)


@pytest.mark.parametrize("argv, fragment", [
    (["--channels", "data[:,0:8]", "--wrench", "data[:,8:20]"], "selects no columns of 'data', which has 14"),
    (["--channels", "data[:,0:9]", "--wrench", "data[:,8:14]"], "overlap"),
    (["--force-unit", "furlong"], "unknown force unit 'furlong'"),
    (["--force-unit", "n"], "did you mean 'N'"),
])
def test_bad_mappings_are_one_line_naming_the_fix(tmp_path, capsys, argv, fragment):
    raw, wrench = _sensor()
    scipy.io.savemat(tmp_path / "rec.mat", {"data": np.hstack([raw, wrench])})
    base = [] if "--channels" in argv else ["--channels", "data[:,0:8]", "--wrench", "data[:,8:14]"]
    err = one_line_error(capsys, main(["fit", str(tmp_path / "rec.mat"), *base, *argv, "--out", str(tmp_path / "m")]))
    assert fragment in err and "Fix" in err or "known" in err


def test_group_column_with_one_value_and_folder_of_other_columns(tmp_path, capsys):
    raw, wrench = _sensor()
    names = [f"s{i}" for i in range(8)] + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz", "session"]
    path = _csv(tmp_path / "d.csv", names, raw, wrench, np.ones(len(raw)))
    err = one_line_error(capsys, main(["fit", str(path), "--groups", "session", "--out", str(tmp_path / "m")]))
    assert "one group" in err and "Fix" in err
    folder = tmp_path / "poses"
    folder.mkdir()
    _csv(folder / "a.csv", names[:-1], raw[:100], wrench[:100])
    _csv(folder / "b.csv", names, raw[100:], wrench[100:], np.ones(140))
    err = one_line_error(capsys, main(["fit", str(folder), "--out", str(tmp_path / "m")]))
    assert "b.csv" in err and "same columns" in err


def test_a_header_with_tx_and_mx_names_the_clash(tmp_path):
    raw, wrench = _sensor(n_channels=6)
    names = [f"s{i}" for i in range(6)] + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz", "Mx"]
    path = _csv(tmp_path / "d.csv", names, raw, wrench, wrench[:, 3])
    with pytest.raises(DatasetFileError, match="columns 'Tx' and 'Mx' both read as the wrench axis Tx"):
        CalibrationDataset.load(path)


def test_matlab_logical_array_is_refused(tmp_path):
    raw, wrench = _sensor()
    scipy.io.savemat(tmp_path / "rec.mat", {"raw": raw > 100, "wrench": wrench})
    with pytest.raises(DatasetFileError, match="'raw' is a MATLAB logical array"):
        CalibrationDataset.load(tmp_path / "rec.mat")


def test_upper_case_npz_reads_in_predict_and_retare(tmp_path, capsys):
    raw, wrench = _sensor(n_channels=6)
    with open(tmp_path / "D.NPZ", "wb") as fh:  # numpy.savez would add .npz to a name of another suffix
        np.savez(fh, raw=raw, wrench=wrench)
    assert main(["fit", str(tmp_path / "D.NPZ"), "--model", "linear", "--out", str(tmp_path / "m"), "-q"]) == 0
    with open(tmp_path / "ZERO.NPZ", "wb") as fh:
        np.savez(fh, raw=np.full((20, 6), 100.0) + np.random.default_rng(1).normal(scale=1e-3, size=(20, 6)))
    assert main(["predict", str(tmp_path / "m" / "linear.model.npz"), str(tmp_path / "D.NPZ"), "-q"]) == 0
    assert main(["retare", str(tmp_path / "m" / "linear.model.npz"), str(tmp_path / "ZERO.NPZ"), "-q"]) == 0


_BOMB = """
import resource, sys
import numpy as np
from ftcal import CalibrationDataset
from ftcal.io._readers import ColumnMap
CalibrationDataset.load(sys.argv[1])
print(resource.getrusage(resource.RUSAGE_SELF).ru_maxrss)
"""


@pytest.mark.parametrize("suffix", [".mat", ".npz"])
def test_an_unused_huge_compressed_variable_is_never_decompressed(tmp_path, suffix):
    """A small file whose unused member inflates to 2 GiB: the reader lists it without reading it."""
    raw, wrench = _sensor()
    path = tmp_path / f"bomb{suffix}"
    if suffix == ".npz":
        with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as z:
            for name, value in (("raw", raw), ("wrench", wrench)):
                with z.open(f"{name}.npy", "w") as fh:
                    np.lib.format.write_array(fh, value)
            with z.open("junk.npy", "w", force_zip64=True) as fh:  # 2 GiB of zeros, written in blocks
                np.lib.format.write_array_header_1_0(fh, {"descr": "<f8", "fortran_order": False,
                                                          "shape": (2**28,)})
                block = bytes(2**24)
                for _ in range(2**31 // 2**24):
                    fh.write(block)
    else:
        scipy.io.savemat(path, {"junk": np.zeros(2**25), "raw": raw, "wrench": wrench},  # 256 MiB of zeros first
                         do_compression=True)
    assert path.stat().st_size < 4 * 2**20
    small = tmp_path / f"small{suffix}"
    if suffix == ".npz":
        np.savez(small, raw=raw, wrench=wrench)
    else:
        scipy.io.savemat(small, {"raw": raw, "wrench": wrench})
    peaks = []
    for file in (small, path):
        done = subprocess.run([sys.executable, "-c", _BOMB, str(file)], capture_output=True, text=True, timeout=300)
        assert done.returncode == 0, done.stderr
        peaks.append(int(done.stdout.split()[-1]))  # peak resident set [KiB]
    assert peaks[1] < peaks[0] + 100_000  # the junk (2 GiB / 256 MiB inflated) never entered memory


@pytest.mark.parametrize("n_axes", [1, 3])
def test_evaluate_with_plots_of_a_one_and_three_axis_cell(tmp_path, capsys, n_axes):
    raw, wrench = _sensor(n_axes=3, n_channels=4)
    axes = ["Fx", "Fy", "Fz"][3 - n_axes:]
    path = _csv(tmp_path / "cell.csv", ["g1", "g2", "g3", "g4", *axes], raw, wrench[:, 3 - n_axes:])
    assert main(["fit", str(path), "--channels", "g1..g4", "--wrench", ",".join(axes), "--axes", ",".join(axes),
                 "--model", "linear", "--out", str(tmp_path / "m"), "-q"]) == 0, capsys.readouterr().err
    out = tmp_path / "e"
    run = subprocess.run([sys.executable, "-m", "ftcal", "evaluate", str(path), str(tmp_path / "m" / "linear.model.npz"),
                          "--out", str(out), "-q"], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    written = sorted(p.name for p in out.iterdir())
    assert written == ["axis_rmse.png", "errors_linear.png", "metrics.json", "metrics.md", "rmse_distribution.png"]
    assert list(json.loads((out / "metrics.json").read_text())["models"]["linear"]["axis_rmse"]) == axes
    for name in written:
        assert (out / name).stat().st_size > 0


def test_fit_of_a_force_only_cell_says_no_torque_scaling(tmp_path):
    raw, wrench = _sensor(n_axes=3, n_channels=4)
    path = _csv(tmp_path / "cell.csv", ["g1", "g2", "g3", "g4", "Fx", "Fy", "Fz"], raw, wrench)
    run = subprocess.run([sys.executable, "-m", "ftcal", "fit", str(path), "--channels", "g1..g4", "--model", "linear",
                          "--out", str(tmp_path / "m")], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    done = next(line for line in run.stderr.splitlines() if "training RMSE" in line)
    assert "N (forces only: no torque scaling)" in done and "torque-scaled" not in done and "alpha" not in done


@pytest.mark.parametrize("axes, says, not_says", [
    (("Fx", "Fy", "Fz"), "forces in N.", "torques in N·m"),
    (("Fz", "Tx", "Ty"), "forces in N, torques in N·m", "the axes above, in their unit"),
])
def test_the_report_states_the_units_of_the_axes_that_exist(tmp_path, capsys, axes, says, not_says):
    raw, wrench = _sensor(n_axes=6, n_channels=6)
    columns = [["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"].index(a) for a in axes]
    path = _csv(tmp_path / "cell.csv", ["s0", "s1", "s2", "s3", "s4", "s5", *axes], raw, wrench[:, columns])
    assert main(["fit", str(path), "--model", "linear", "--report", "--no-baselines", "--cv", "3",
                 "--out", str(tmp_path / "m"), "-q"]) == 0, capsys.readouterr().err
    html = (tmp_path / "m" / "linear.report.html").read_text()
    section = html[html.index("Frames and units"):][:600]
    assert says in section and not_says not in section, section


def test_folder_files_with_the_same_columns_in_another_order_are_read_by_name(tmp_path):
    raw, wrench = _sensor(n_channels=6, n=80)
    halves = [slice(0, 40), slice(40, 80)]
    for suffix in ("npz", "mat", "csv"):
        folder = tmp_path / suffix
        folder.mkdir()
        for k, rows in enumerate(halves):
            first, last = ("raw", "wrench") if k == 0 else ("wrench", "raw")
            arrays = {first: raw[rows] if first == "raw" else wrench[rows],
                      last: raw[rows] if last == "raw" else wrench[rows]}
            if suffix == "npz":
                np.savez(folder / f"p{k}.npz", **arrays)
            elif suffix == "mat":
                scipy.io.savemat(folder / f"p{k}.mat", arrays)
            else:
                names = [f"s{i}" for i in range(6)] + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"]
                order = list(range(12)) if k == 0 else list(range(6, 12)) + list(range(6))[::-1]
                table = np.column_stack([raw[rows], wrench[rows]])[:, order]
                _csv(folder / f"p{k}.csv", [names[i] for i in order], table)
        ds = CalibrationDataset.load(folder)
        np.testing.assert_array_equal(ds.raw, raw)
        np.testing.assert_array_equal(ds.wrench, wrench)
        np.testing.assert_array_equal(ds.group, np.repeat([0, 1], 40))
    extra = tmp_path / "extra"
    extra.mkdir()
    np.savez(extra / "p0.npz", raw=raw[:40], wrench=wrench[:40])
    np.savez(extra / "p1.npz", wrench=wrench[40:], raw=raw[40:], temperature=np.full(40, 25.0))
    with pytest.raises(DatasetFileError, match=r"p1.npz: its columns .* differ from those of .*temperature differs"):
        CalibrationDataset.load(extra)


@pytest.mark.parametrize("torques", [["Mx", "My", "Mz"], ["tx", "ty", "tz"]])
def test_folder_files_naming_the_wrench_by_an_alias_are_read_as_the_same_columns(tmp_path, torques):
    """One file of a folder names its torques Mx..Mz (or in lower case) where the others write Tx..Tz: the reader
    takes both as the same axes, so the folder is one dataset (it was refused as 'columns differ')."""
    raw, wrench = _sensor(n_channels=6, n=80)
    folder = tmp_path / "data"
    folder.mkdir()
    channels = [f"s{i}" for i in range(6)]
    _csv(folder / "p0.csv", channels + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"], np.column_stack([raw, wrench])[:40])
    _csv(folder / "p1.csv", channels + ["Fx", "Fy", "Fz", *torques], np.column_stack([raw, wrench])[40:])
    ds = CalibrationDataset.load(folder)
    np.testing.assert_array_equal(ds.raw, raw)
    np.testing.assert_array_equal(ds.wrench, wrench)


def test_a_truncated_mat_file_is_said_to_be_truncated_not_to_lack_the_wrench(tmp_path, capsys):
    raw, wrench = _sensor(n_channels=6, n=60)
    variables = {f"s{i}": raw[:, i] for i in range(6)} | {a: wrench[:, i] for i, a in enumerate(["Fx", "Fy", "Fz",
                                                                                                  "Tx", "Ty", "Tz"])}
    whole = tmp_path / "whole.mat"
    scipy.io.savemat(whole, variables)
    data = whole.read_bytes()
    cut = tmp_path / "cut.mat"
    cut.write_bytes(data[:len(data) // 2])  # s0..s5 whole, the wrench variables lost
    assert [name for name, *_ in scipy.io.whosmat(cut)] == [f"s{i}" for i in range(6)]
    for options, sought in (([], "variable 'wrench'"), (["--wrench", "Fx,Fy,Fz,Tx,Ty,Tz"], "variable 'Fx'")):
        err = one_line_error(capsys, main(["fit", str(cut), *options, "--out", str(tmp_path / "m"), "-q"]))
        assert f"cut.mat: the file is truncated or damaged: it ends at byte {len(data) // 2}, inside a variable" in err
        assert sought in err and "lacks" not in err and "copy or save the whole file again" in err
    assert CalibrationDataset.load(whole).n_samples == 60


def test_nan_in_a_column_slice_names_the_variable_the_user_named(tmp_path, capsys):
    raw, wrench = _sensor(n_channels=6, n=40)
    data = np.column_stack([raw, wrench])
    data[5, 2] = np.nan  # a raw channel: column 2 of 'data'
    data[3, 8] = np.inf  # the wrench: column 8 of 'data', in an earlier row
    path = tmp_path / "one.mat"
    scipy.io.savemat(path, {"data": data})
    err = one_line_error(capsys, main(["fit", str(path), "--channels", "data[:,0:6]", "--wrench", "data[:,6:12]",
                                       "--out", str(tmp_path / "m"), "-q"]))
    assert "one.mat: array 'data[:,2]', row 5 (rows counted from 0): NaN or inf" in err and "'raw'" not in err
    data[5, 2] = 1.0
    scipy.io.savemat(path, {"data": data})
    err = one_line_error(capsys, main(["fit", str(path), "--channels", "data[:,0:6]", "--wrench", "data[:,6:12]",
                                       "--out", str(tmp_path / "m"), "-q"]))
    assert "one.mat: array 'data[:,8]', row 3 (rows counted from 0): NaN or inf" in err
    vectors = tmp_path / "vectors.npz"
    raw[7, 4] = np.nan
    np.savez(vectors, **{f"s{i}": raw[:, i] for i in range(6)}, wrench=wrench)
    with pytest.raises(DatasetFileError, match=r"vectors.npz: array 's4', row 7 \(rows counted from 0\): NaN or inf"):
        CalibrationDataset.load(vectors)


def _npy_with_header(shape: str) -> bytes:
    """A .npy member whose header declares ``shape`` as written (a damaged or hand-made header)."""
    header = "{'descr': '<f8', 'fortran_order': False, 'shape': %s, }" % shape
    header += " " * (63 - len(header) % 64) + "\n"
    return b"\x93NUMPY\x01\x00" + len(header).to_bytes(2, "little") + header.encode() + b"\0" * 96


@pytest.mark.parametrize("shape", ["(-2, -6)", "(2, -6)", "(True, 6)", "(2, 6"])
def test_a_damaged_npy_header_in_a_dataset_or_a_model_file_is_one_clear_error(tmp_path, capsys, shape):
    """Negative or bool dimensions and an unclosed header (a tokenizer error inside numpy's parser) are refused as a
    damaged member of that file, for a dataset and a model file alike: exit 2 and one line, never 'a bug in
    ftcal'."""
    dataset = tmp_path / "ds.npz"
    with zipfile.ZipFile(dataset, "w") as z:
        z.writestr("raw.npy", _npy_with_header(shape))
        z.writestr("wrench.npy", _npy_with_header("(2, 6)"))
    assert main(["fit", str(dataset), "--model", "linear", "--out", str(tmp_path / "m"), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "ds.npz" in err[0] and "'raw'" in err[0] and "damaged" in err[0], err
    assert "bug" not in err[0]
    model = tmp_path / "bad.model.npz"
    with zipfile.ZipFile(model, "w") as z:
        z.writestr("__metadata__.npy", _npy_with_header(shape))
    with pytest.raises(ValueError, match=r"bad\.model\.npz: member '__metadata__'.*damaged"):
        load_model(model)


@pytest.mark.parametrize("raw, wrench, said", [
    (np.float64(3.0), np.ones((60, 6)), "array 'raw' has shape ()"),
    (np.ones((60, 6)), np.float64(1.0), "array 'wrench' has shape ()"),
    (np.zeros((0, 6)), np.zeros((0, 6)), "has no values"),
])
def test_a_scalar_or_an_empty_array_in_an_npz_is_one_clear_error(tmp_path, capsys, raw, wrench, said):
    path = tmp_path / "d.npz"
    np.savez(path, raw=raw, wrench=wrench)
    assert main(["fit", str(path), "--model", "linear", "--out", str(tmp_path / "m"), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{path}: " in err[0] and said in err[0] and "bug" not in err[0], err
