"""Getting a user's data in: column mapping, Mx/My/Mz aliases, .mat and .npz, declared units, the
lever-arm check, a missing header; and data out: the 6xN matrix, predict's header and out-of-range flag."""

from __future__ import annotations

import json
import select
import subprocess
import sys

import numpy as np
import pytest
import scipy.io

from ftcal import CalibrationDataset, LinearCalibrator, load_model
from ftcal.core import DatasetFileError
from ftcal.cli import main
from ftcal.io import has_header
from ftcal.io._readers import ColumnMap, lever_arm_problem

from test_calibration_report import sensor_dataset


def one_line_error(capsys, code: int) -> str:
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and err.startswith("ftcal: error:"), err
    return err


def test_csv_with_mx_my_mz_headers_reads_as_tx_ty_tz(tmp_path):
    data = sensor_dataset()
    text = "s0,s1,s2,s3,s4,s5,Fx,Fy,Fz,Mx,My,Mz\n" + "\n".join(
        ",".join(repr(float(v)) for v in row) for row in np.hstack([data.raw, data.wrench]))
    (tmp_path / "bota.csv").write_text(text)
    read = CalibrationDataset.load(tmp_path / "bota.csv")
    np.testing.assert_array_equal(read.wrench, data.wrench)


def test_csv_column_mapping_picks_named_columns_and_ignores_others(tmp_path, capsys):
    data = sensor_dataset()
    cols = ["time"] + [f"gauge{i + 1}" for i in range(6)] + ["force_x", "force_y", "force_z", "tx", "ty", "tz"]
    rows = np.hstack([np.arange(len(data.raw))[:, None], data.raw, data.wrench])
    (tmp_path / "log.csv").write_text(",".join(cols) + "\n" + "\n".join(",".join(repr(float(v)) for v in r) for r in rows))
    mapped = CalibrationDataset.load(tmp_path / "log.csv", columns=ColumnMap(
        channels=[f"gauge{i + 1}" for i in range(6)], wrench=["force_x", "force_y", "force_z", "tx", "ty", "tz"]))
    np.testing.assert_array_equal(mapped.raw, data.raw)
    np.testing.assert_array_equal(mapped.wrench, data.wrench)
    code = main(["fit", str(tmp_path / "log.csv"), "--channels", "gauge1,gauge2,gauge3,gauge4,gauge5,gauge7",
                 "--wrench", "force_x,force_y,force_z,tx,ty,tz", "--model", "linear", "--out", str(tmp_path / "m")])
    err = one_line_error(capsys, code)
    assert "'gauge7'" in err and "gauge6" in err  # names the missing column and lists what the header has


def test_missing_header_is_said_plainly(tmp_path):
    (tmp_path / "bare.csv").write_text("1,2,3,4,5,6,7,8,9,10,11,12\n1,2,3,4,5,6,7,8,9,10,11,12\n")
    with pytest.raises(DatasetFileError, match="line 1: the file has no header"):
        CalibrationDataset.load(tmp_path / "bare.csv")


def _mat_in_newton_millimetres(path, data, layout="matrix"):
    wrench_nmm = data.wrench * [1, 1, 1, 1000, 1000, 1000]
    if layout == "matrix":  # MATLAB users often store one row per component
        scipy.io.savemat(path, {"raw": data.raw.T, "wrench": wrench_nmm.T, "group": data.group[None, :]})
    else:
        names = dict(zip(("Fx", "Fy", "Fz", "Mx", "My", "Mz"), wrench_nmm.T))
        scipy.io.savemat(path, {**{f"s{i}": c for i, c in enumerate(data.raw.T)}, **names})


@pytest.mark.parametrize("layout", ["matrix", "vectors"])
def test_mat_file_with_torques_in_newton_millimetres(tmp_path, layout):
    data = sensor_dataset()
    _mat_in_newton_millimetres(tmp_path / "rec.mat", data, layout)
    read = CalibrationDataset.load(tmp_path / "rec.mat", columns=ColumnMap(torque_unit="N.mm"))
    np.testing.assert_allclose(read.wrench, data.wrench, rtol=1e-12)
    np.testing.assert_array_equal(read.raw, data.raw)
    assert read.meta["source_torque_unit"] == "N.mm"
    if layout == "matrix":
        np.testing.assert_array_equal(read.group, data.group)


def test_torques_in_newton_millimetres_are_detected_by_the_lever_arm(tmp_path, capsys):
    """The issue's case: N·mm torques read as N·m give a lever arm of metres; fit refuses and names the fix."""
    data = sensor_dataset()
    _mat_in_newton_millimetres(tmp_path / "rec.mat", data)
    code = main(["fit", str(tmp_path / "rec.mat"), "--model", "linear", "--out", str(tmp_path / "m")])
    err = one_line_error(capsys, code)
    assert "lever arm" in err and "--torque-unit N.mm" in err
    assert main(["fit", str(tmp_path / "rec.mat"), "--torque-unit", "N.mm", "--model", "linear", "--out",
                 str(tmp_path / "m"), "-q"]) == 0
    model = load_model(tmp_path / "m" / "linear.model.npz")
    # the same calibration as least squares on the data in N·m (the unit conversion is exact)
    from sklearn.linear_model import LinearRegression

    reference = LinearRegression().fit(data.raw, data.wrench).predict(data.raw)
    np.testing.assert_allclose(model.predict(data.raw), reference, rtol=1e-6, atol=1e-9)
    assert lever_arm_problem(data.wrench) is None  # the same data in N·m are plausible


def test_unknown_unit_is_one_line(tmp_path, capsys):
    sensor_dataset().save(tmp_path / "d.csv")
    err = one_line_error(capsys, main(["fit", str(tmp_path / "d.csv"), "--torque-unit", "N.furlong", "--out",
                                       str(tmp_path / "m")]))
    assert "unknown torque unit 'N.furlong'" in err and "N.mm" in err


def test_npz_with_named_arrays(tmp_path):
    data = sensor_dataset()
    np.savez(tmp_path / "d.npz", gauges=data.raw, ft=data.wrench * [1000, 1000, 1000, 1, 1, 1])
    read = CalibrationDataset.load(tmp_path / "d.npz", columns=ColumnMap(channels=["gauges"], wrench=["ft"],
                                                                          force_unit="mN", torque_unit="N.m"))
    np.testing.assert_allclose(read.wrench, data.wrench, rtol=1e-12)


# ------------------------------------------------------------------ out
@pytest.fixture()
def linear_model(tmp_path):
    data = sensor_dataset()
    data.save(tmp_path / "d.csv")
    assert main(["fit", str(tmp_path / "d.csv"), "--model", "linear", "--out", str(tmp_path / "m"), "-q"]) == 0
    return tmp_path, data


def test_export_matrix_reproduces_predict(linear_model):
    work, data = linear_model
    model_file = work / "m" / "linear.model.npz"
    assert main(["export", str(model_file), "--format", "matrix", "--output", str(work / "C.csv"), "-q"]) == 0
    assert main(["export", str(model_file), "--format", "matrix", "--output", str(work / "C.json"), "-q"]) == 0
    lines = [line.split(",") for line in (work / "C.csv").read_text().splitlines() if not line.startswith("#")]
    assert lines[0] == ["axis", "s0", "s1", "s2", "s3", "s4", "s5", "offset"]
    assert [row[0] for row in lines[1:]] == ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"]
    numbers = np.array([row[1:] for row in lines[1:]], dtype=float)
    matrix, offset = numbers[:, :6], numbers[:, 6]
    expected = load_model(model_file).predict(data.raw)
    np.testing.assert_allclose(data.raw @ matrix.T + offset, expected, rtol=1e-9, atol=1e-9)
    facts = json.loads((work / "C.json").read_text())
    np.testing.assert_allclose(np.asarray(facts["matrix"]), matrix, rtol=1e-12)
    # a re-tared model: the matrix export includes the new zero
    model = LinearCalibrator().fit(data.raw, data.wrench).retare(np.full((3, 6), 0.6))
    from ftcal.persistence._matrix import linear_calibration_matrix

    C, b = linear_calibration_matrix(model)
    np.testing.assert_allclose(data.raw @ C.T + b, model.predict(data.raw), rtol=1e-9, atol=1e-9)


def test_export_matrix_of_a_nonlinear_model_is_one_line(linear_model, capsys):
    work, _ = linear_model
    assert main(["fit", str(work / "d.csv"), "--model", "polynomial", "--out", str(work / "m"), "-q"]) == 0
    capsys.readouterr()
    err = one_line_error(capsys, main(["export", str(work / "m" / "polynomial.model.npz"), "--format", "matrix",
                                       "--output", str(work / "P.csv")]))
    assert "not a linear calibration" in err and "--format onnx" in err
    assert not (work / "P.csv").exists()


def test_predict_line_buffered_writes_its_header_before_any_reading(linear_model):
    """A driver waiting for the header before sending readings must not deadlock."""
    work, data = linear_model
    proc = subprocess.Popen([sys.executable, "-m", "ftcal", "predict", str(work / "m" / "linear.model.npz"),
                             "--line-buffered"], stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True)
    try:
        ready, _, _ = select.select([proc.stdout], [], [], 120)  # a guard against a hang, not a timing
        assert ready, "no header before the first reading"
        assert proc.stdout.readline() == "Fx,Fy,Fz,Tx,Ty,Tz\n"
        proc.stdin.write(",".join(repr(float(v)) for v in data.raw[0]) + "\n")
        proc.stdin.flush()
        values = np.array(proc.stdout.readline().split(","), dtype=float)
        np.testing.assert_allclose(values, load_model(work / "m" / "linear.model.npz").predict(data.raw[:1])[0],
                                   rtol=1e-8)
    finally:
        proc.stdin.close()
        proc.wait()


def test_predict_flags_readings_beyond_the_calibrated_range(linear_model, capsys):
    work, data = linear_model
    readings = np.vstack([data.raw[:3], data.raw.max(axis=0) + 1.0])
    np.savetxt(work / "r.csv", readings, delimiter=",")
    assert main(["predict", str(work / "m" / "linear.model.npz"), str(work / "r.csv"), "--range",
                 str(work / "d.csv")]) == 0
    out, err = capsys.readouterr()
    lines = out.strip().splitlines()
    assert lines[0] == "Fx,Fy,Fz,Tx,Ty,Tz,out_of_range"
    assert [line.rsplit(",", 1)[1] for line in lines[1:]] == ["0", "0", "0", "1"]
    assert "1 of 4 readings lie beyond the calibrated range" in err


def test_tool_export_as_ros_gravity_compensation_yaml(tmp_path, capsys):
    """The YAML's ROS 2 filter parameters reproduce the tool's gravity wrench at any pose (the filter's formula:
    f_sensor = R^T CoG.force, t_sensor = CoG.pos x f_sensor), and the ROS 1 keys carry mass, centre and bias."""
    import yaml
    from scipy.spatial.transform import Rotation

    from ftcal.experiment import ToolLoad

    tool = ToolLoad(mass=1.7, center_of_mass=np.array([0.01, -0.02, 0.08]), bias=np.arange(6) * 0.1)
    tool.save(tmp_path / "grip.tool.json")
    assert main(["export", str(tmp_path / "grip.tool.json"), "--format", "ros", "--sensor-frame", "my_ft", "-q"]) == 0
    doc = yaml.safe_load((tmp_path / "grip.ros.yaml").read_text())
    assert doc["gripper_mass"] == 1.7 and doc["gripper_com_frame_id"] == "my_ft"
    assert doc["bias"] == pytest.approx(list(np.arange(6) * 0.1))
    assert doc["gripper_com_pose"] == pytest.approx([0.01, -0.02, 0.08, 0, 0, 0])
    params = doc["gravity_compensation"]["ros__parameters"]
    assert params["sensor_frame"] == "my_ft"
    R = Rotation.random(5, random_state=0).as_matrix()  # sensor orientations in the world frame
    f = np.einsum("nji,j->ni", R, params["CoG"]["force"])
    t = np.cross(params["CoG"]["pos"], f)
    np.testing.assert_allclose(np.hstack([f, t]), tool.gravity_wrench(R) - tool.bias, atol=1e-12)
    err = one_line_error(capsys, main(["export", str(tmp_path / "grip.tool.json"), "--format", "ros", "--output",
                                       str(tmp_path / "x.json")]))
    assert ".yaml" in err


def test_evaluate_warns_when_given_the_training_file(linear_model, capsys):
    """The README's old evaluation step printed training errors without a word."""
    work, _ = linear_model
    capsys.readouterr()
    assert main(["evaluate", str(work / "d.csv"), str(work / "m" / "linear.model.npz"), "--no-plots", "--out",
                 str(work / "e1")]) == 0
    err = capsys.readouterr().err
    assert "is the training data of linear" in err and "ftcal report" in err
    assert json.loads((work / "e1" / "metrics.json").read_text())["models"]["linear"]["training_data"] is True
    # the check is by content (the hash fit keeps): a file of other content is not taken for the training file
    sensor_dataset(seed=0).subset(slice(0, 80)).save(work / "held_out.csv")
    assert main(["evaluate", str(work / "held_out.csv"), str(work / "m" / "linear.model.npz"), "--no-plots", "--out",
                 str(work / "e2")]) == 0
    assert "training data" not in capsys.readouterr().err


def test_an_implausibly_short_lever_arm_is_only_pointed_out(tmp_path, capsys):
    """A 3-axis cell's torque columns may hold noise only: a warning, not a refusal."""
    data = sensor_dataset()
    data.wrench[:, 3:] *= 1e-5  # arm ~ 2e-7 m
    data.save(tmp_path / "cell.csv")
    assert main(["fit", str(tmp_path / "cell.csv"), "--model", "linear", "--out", str(tmp_path / "m"), "-q"]) == 0
    err = capsys.readouterr().err
    assert "ftcal: warning:" in err and "lever arm" in err


@pytest.mark.parametrize("suffix", [".csv", ".npz"])
def test_a_dataset_that_would_not_read_back_is_not_saved(tmp_path, suffix):
    # the readers refuse NaN/inf and non-JSON metadata: save refuses to write such a file, and writes nothing
    rng = np.random.default_rng(0)
    raw, wrench = rng.normal(size=(10, 6)), rng.normal(size=(10, 6))
    bad_raw = raw.copy()
    bad_raw[4, 2] = np.inf
    cases = {r"raw holds inf at row 4 \(rows counted from 0\), column 2": dict(raw=bad_raw, wrench=wrench),
             r"meta must hold plain JSON values.*Out of range float": dict(raw=raw, wrench=wrench,
                                                                         meta={"alpha": float("nan")}),
             r"meta must hold plain JSON values.*not JSON serializable": dict(raw=raw, wrench=wrench,
                                                                             meta={"x": object()})}
    for message, fields in cases.items():
        with pytest.raises(DatasetFileError, match=f"cannot save .*ds{suffix}: {message}"):
            CalibrationDataset(**fields).save(tmp_path / f"ds{suffix}")
    assert list(tmp_path.iterdir()) == []


def test_wrench_columns_given_as_channels_are_refused_not_read_as_a_smaller_wrench(tmp_path):
    # Fx,Fy,Fz as the channels: the wrench found by its names would have been Tx,Ty,Tz alone, the inputs the reference
    rng = np.random.default_rng(0)
    w = rng.normal(size=(30, 6))
    CalibrationDataset(raw=w @ rng.normal(size=(6, 6)), wrench=w).save(tmp_path / "d.csv")
    with pytest.raises(DatasetFileError, match=r"channels takes column 'Fx', which is named as a wrench axis") as err:
        CalibrationDataset.load(tmp_path / "d.csv", columns=ColumnMap(channels=["Fx", "Fy", "Fz"]))
    assert err.value.parameter == "channels" and err.value.value == "Fx"
    # a raw channel that happens to be named like an axis is read when the wrench is named
    d = CalibrationDataset.load(tmp_path / "d.csv", columns=ColumnMap(channels=["s0", "s1", "Fx"], wrench=["Fy", "Fz"]))
    np.testing.assert_array_equal(d.raw[:, 2], w[:, 0])


def _npz_of_version_3(path, members, descr="<f8"):
    """An .npz whose members are .npy files of format 3.0, written by numpy itself."""
    import io
    import zipfile

    with zipfile.ZipFile(path, "w") as archive:
        for name, value in members.items():
            buffer = io.BytesIO()
            np.lib.format.write_array(buffer, np.asarray(value), version=(3, 0), allow_pickle=True)
            archive.writestr(f"{name}.npy", buffer.getvalue())
    return path


def test_npz_members_of_npy_format_3_are_read_and_pickles_in_them_still_refused(tmp_path):
    raw = np.arange(60.0).reshape(10, 6)
    wrench = 2.0 * raw + 1.0
    path = _npz_of_version_3(tmp_path / "v3.npz", {"raw": raw, "wrench": wrench})
    with np.load(path) as check:  # numpy itself reads this file
        np.testing.assert_array_equal(check["raw"], raw)
    ds = CalibrationDataset.load(path)
    np.testing.assert_array_equal(ds.raw, raw)
    np.testing.assert_array_equal(ds.wrench, wrench)
    pickled = _npz_of_version_3(tmp_path / "obj.npz", {"raw": np.array([raw, "x"], dtype=object), "wrench": wrench})
    with pytest.raises(DatasetFileError, match=r"array 'raw' holds Python objects \(a pickle\)"):
        CalibrationDataset.load(pickled)


def test_a_csv_in_another_encoding_names_where_and_the_conversion(tmp_path, capsys):
    text = "# temp\u00e9rature en \u00b0C\ns0,s1,Fx\n1,2,3\n4,5,6\n"
    utf16 = tmp_path / "u16.csv"
    utf16.write_bytes(text.encode("utf-16"))  # with its byte-order mark, as Windows tools write it
    err = one_line_error(capsys, main(["fit", str(utf16), "--out", str(tmp_path / "m"), "-q"]))
    assert "u16.csv: UTF-16 text (it starts with a UTF-16 byte-order mark), not UTF-8" in err
    assert "iconv -f UTF-16 -t UTF-8 u16.csv > u16-utf8.csv" in err
    latin1 = tmp_path / "latin1.csv"
    logged = "s0,s1,Fx\n1,2,3\n# temp\u00e9rature\n4,5,6\n"  # the first non-ASCII byte: 9 + 6 + 6 = byte 21, line 3
    latin1.write_bytes(logged.encode("latin-1"))
    for load in (lambda: CalibrationDataset.load(latin1), lambda: has_header(latin1)):
        with pytest.raises(DatasetFileError, match=r"latin1.csv: line 3 \(byte 21\): not UTF-8 text .* Fix: save it as "
                           r"UTF-8, e.g. iconv -f LATIN1 -t UTF-8 latin1.csv > latin1-utf8.csv"):
            load()
    converted = tmp_path / "converted.csv"  # the advised conversion reads
    converted.write_text(logged, encoding="utf-8")
    np.testing.assert_array_equal(CalibrationDataset.load(converted).raw, [[1, 2], [4, 5]])


def test_empty_files_are_said_to_be_empty(tmp_path, capsys):
    empty = tmp_path / "a.csv"
    empty.write_bytes(b"")
    err = one_line_error(capsys, main(["fit", str(empty), "--out", str(tmp_path / "m"), "-q"]))
    assert err == f"ftcal: error: {empty}: the file is empty (0 bytes). Fix: give the file that holds the recording " \
                  "(the copy or export may have failed)."
    with pytest.raises(DatasetFileError, match=r"a.csv: the file is empty \(no text\)"):
        CalibrationDataset.load(empty)
    comments = tmp_path / "b.csv"
    comments.write_text("# exported\n\n")
    err = one_line_error(capsys, main(["fit", str(comments), "--out", str(tmp_path / "m"), "-q"]))
    assert "b.csv: the file holds no header and no data (12 bytes of # comments)" in err
