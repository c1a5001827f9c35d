"""One recording given twice (two names, or twice in a folder) is refused by its content: it would count its poses
twice and put its twins in different folds, so a drift or a model would be judged on its own rows."""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from ftcal.cli import main
from ftcal.experiment import ToolLoad
from ftcal.io import CalibrationDataset, write_run_log
from ftcal.io._bags import write_bag


def _pose_file(path, seed):
    tool = ToolLoad(mass=1.3, center_of_mass=np.array([0.012, -0.008, 0.065]), bias=np.array([1.5, -2, 0.7, 0, 0, 0]))
    R = Rotation.random(12, random_state=seed).as_matrix()
    W = tool.gravity_wrench(R) + np.random.default_rng(seed).normal(size=(12, 6)) * 0.01
    rows = np.column_stack([Rotation.from_matrix(R).as_quat(), W])
    path.write_text("qx,qy,qz,qw,Fx,Fy,Fz,Tx,Ty,Tz\n" + "".join(",".join(repr(float(v)) for v in r) + "\n"
                                                            for r in rows))
    return path


def test_a_pose_file_given_twice_is_refused_and_two_recordings_are_read(tmp_path, capsys):
    a = _pose_file(tmp_path / "a.csv", 1)
    twin = tmp_path / "renamed.csv"
    shutil.copy(a, twin)
    out = tmp_path / "t"
    assert main(["identify-load", str(a), str(twin), "--out", str(out), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and f"{twin} holds the same pose file as {a} (the same values read from both)" in err[0], err
    assert not out.exists()
    b = _pose_file(tmp_path / "b.csv", 2)
    assert main(["identify-load", str(a), str(b), "--out", str(out), "-q"]) == 0


def test_a_folder_holding_the_same_bag_twice_is_refused(tmp_path, capsys):
    folder = tmp_path / "bags"
    folder.mkdir()
    t = np.arange(0.0, 1.0, 0.01)
    bag = write_bag(folder / "run1", "sqlite3", sensor_time=t, reading=np.ones((100, 6)), pose_time=t,
                    joints=np.c_[t, -t], joint_names=["j1", "j2"])
    shutil.copytree(bag, folder / "run1_copy")
    assert main(["identify-load", str(folder), "--out", str(tmp_path / "t"), "-q"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "run1_copy holds the same ROS bag as" in err[0], err


def _refused(argv, capsys, twin, first, what):
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("ftcal: error: "), err
    assert f"{twin} holds the same {what} as {first} (the same values read from both)" in err[0], err


def test_a_pose_file_written_again_with_other_number_formatting_is_refused(tmp_path, capsys):
    a = _pose_file(tmp_path / "a.csv", 3)
    lines = a.read_text().splitlines()
    rewritten = [lines[0]] + [",".join(f"{float(v):.17e}" for v in line.split(",")) for line in lines[1:]]
    twin = tmp_path / "reformatted.csv"
    twin.write_text("# the same recording, exported again\n" + "\r\n".join(rewritten) + "\r\n")
    assert twin.read_bytes() != a.read_bytes()
    _refused(["identify-load", str(a), str(twin), "--out", str(tmp_path / "t"), "-q"], capsys, twin, a, "pose file")


def test_a_run_log_saved_again_in_other_units_is_refused(tmp_path, capsys):
    rng = np.random.default_rng(4)
    n = 8
    kw = dict(run_kind=["load"] * n, config=[0] * n, pose=list(range(n)), raw=rng.normal(size=(n, 6)), load_mass=1.0)
    q = rng.uniform(-1, 1, size=(n, 6))
    a = write_run_log(tmp_path / "logs" / "a.csv", timestamp=np.arange(n) * 0.5, q=q, **kw)
    text = a.read_text().replace("# time_unit: s", "# time_unit: ms")
    head, *rows = [line for line in text.splitlines() if not line.startswith("#")]
    ms = [",".join([f"{float(r.split(',')[0]) * 1000:g}"] + r.split(",")[1:]) for r in rows]
    twin = tmp_path / "logs" / "b_in_ms.csv"
    twin.write_text("\n".join([line for line in text.splitlines() if line.startswith("#")] + [head] + ms) + "\n")
    other = write_run_log(tmp_path / "other.csv", timestamp=np.arange(n) * 0.5, q=q + 0.1, **kw)
    _refused(["prepare", str(tmp_path / "logs"), "--out", str(tmp_path / "d"), "-q"], capsys, twin, a, "run log")
    assert not (tmp_path / "d").exists()
    main(["prepare", str(a), str(other), "--out", str(tmp_path / "d2"), "-q"])  # two recordings: no twins
    assert "holds the same" not in capsys.readouterr().err


def test_one_recording_stored_as_sqlite3_mcap_and_ros1_bags_is_refused(tmp_path, capsys):
    t = np.arange(0.0, 1.0, 0.01)
    kw = dict(sensor_time=t, reading=np.random.default_rng(5).normal(size=(100, 6)), pose_time=t,
              joints=np.c_[t, -t], joint_names=["j1", "j2"])
    sqlite = write_bag(tmp_path / "run_sqlite", "sqlite3", **kw)
    mcap = write_bag(tmp_path / "run_mcap", "mcap", **kw)
    ros1 = write_bag(tmp_path / "run.bag", "ros1", **kw)
    for first, twin in ((sqlite, mcap), (sqlite, ros1), (mcap, ros1)):
        _refused(["identify-load", str(first), str(twin), "--out", str(tmp_path / "t"), "-q"], capsys, twin, first,
                 "ROS bag")
    # another recording of the same length and topics (noise at a sensor's resolution, 1e-3): not a twin
    kw["reading"] = kw["reading"] + 1e-3 * np.random.default_rng(6).normal(size=(100, 6))
    other = write_bag(tmp_path / "other", "mcap", **kw)
    main(["identify-load", str(sqlite), str(other), "--out", str(tmp_path / "t"), "-q"])
    assert "holds the same" not in capsys.readouterr().err


def test_a_dataset_folder_holding_one_recording_written_twice_otherwise_is_refused(tmp_path):
    rng = np.random.default_rng(6)
    ds = CalibrationDataset(raw=rng.normal(size=(20, 6)).astype(np.float32), wrench=rng.normal(size=(20, 6)))
    folder = tmp_path / "data"
    folder.mkdir()
    a = ds.save(folder / "a.csv")
    header = a.read_text().splitlines()[1]
    rows = [",".join(f"{v:.17e}" for v in row) for row in np.column_stack([ds.raw, ds.wrench])]
    (folder / "b.csv").write_text("\n".join([header.replace(",", ", ")] + rows) + "\n")
    with pytest.raises(ValueError, match=r"b\.csv holds the same readings and wrenches as .*a\.csv \(20 rows\)"):
        CalibrationDataset.load(folder)


# ------------------------------------------------------------------ the same data written in another form
def _rows(path):
    lines = path.read_text().splitlines()
    return lines[0], [np.array([float(v) for v in line.split(",")]) for line in lines[1:]]


def test_a_pose_file_with_its_rows_reordered_or_its_orientation_as_a_matrix_is_refused(tmp_path, capsys):
    a = _pose_file(tmp_path / "a.csv", 7)
    header, rows = _rows(a)
    reordered = tmp_path / "reordered.csv"
    reordered.write_text("\n".join([header] + [",".join(repr(float(v)) for v in r) for r in rows[::-1]]) + "\n")
    _refused(["identify-load", str(a), str(reordered), "--out", str(tmp_path / "t"), "-q"], capsys, reordered, a,
             "pose file")
    # the orientation written as its rotation matrix: the values read differ by round-off (~1e-16)
    matrix = tmp_path / "matrix.csv"
    names = ",".join(f"R{i}{j}" for i in range(3) for j in range(3)) + ",Fx,Fy,Fz,Tx,Ty,Tz"
    lines = [",".join(repr(float(v)) for v in np.r_[Rotation.from_quat(r[:4]).as_matrix().ravel(), r[4:]])
             for r in rows]
    matrix.write_text("\n".join([names] + lines) + "\n")
    _refused(["identify-load", str(a), str(matrix), "--out", str(tmp_path / "t"), "-q"], capsys, matrix, a,
             "pose file")


def test_two_recordings_sharing_most_rows_are_read_and_a_truncated_copy_is_not_a_twin(tmp_path, capsys):
    """A low-resolution ADC reading the same loads twice: most rows equal, one row 0.01 N apart (a count of the
    ADC). Not one recording given twice: both are read. A copy missing its last row holds fewer rows: accepted."""
    a = _pose_file(tmp_path / "a.csv", 8)
    header, rows = _rows(a)
    rows[5][6] += 0.01
    again = tmp_path / "again.csv"
    again.write_text("\n".join([header] + [",".join(repr(float(v)) for v in r) for r in rows]) + "\n")
    assert main(["identify-load", str(a), str(again), "--out", str(tmp_path / "t"), "-q"]) == 0
    assert "holds the same" not in capsys.readouterr().err
    truncated = tmp_path / "truncated.csv"
    truncated.write_text("\n".join(a.read_text().splitlines()[:-1]) + "\n")
    assert main(["identify-load", str(a), str(truncated), "--out", str(tmp_path / "t2"), "-q"]) == 0
    assert "holds the same" not in capsys.readouterr().err


@pytest.mark.parametrize("form", ["reversed rows", "%.8g"])
def test_a_dataset_file_with_its_rows_reversed_or_saved_with_fewer_digits_is_refused(tmp_path, form):
    rng = np.random.default_rng(9)
    ds = CalibrationDataset(raw=rng.normal(size=(20, 6)), wrench=rng.normal(size=(20, 6)))
    folder = tmp_path / "data"
    folder.mkdir()
    a = ds.save(folder / "a.csv")
    header = a.read_text().splitlines()[1]
    table = np.column_stack([ds.raw, ds.wrench])
    rows = ([",".join(repr(float(v)) for v in row) for row in table[::-1]] if form == "reversed rows"
            else [",".join(f"{v:.8g}" for v in row) for row in table])
    (folder / "b.csv").write_text("\n".join([header] + rows) + "\n")
    with pytest.raises(ValueError, match=r"b\.csv holds the same readings and wrenches as .*a\.csv \(20 rows\)"):
        CalibrationDataset.load(folder)
    table[3, 2] += 1e-3  # another recording: one reading a count apart
    (folder / "b.csv").write_text("\n".join([header] + [",".join(repr(float(v)) for v in r) for r in table]) + "\n")
    assert CalibrationDataset.load(folder).n_samples == 40


def _copy_bag(source, target, *, shift_ns=0, extra_topic=False):
    """``source`` copied message by message (rosbags), receive times shifted by ``shift_ns``, optionally with an
    unrelated topic of log text added."""
    from rosbags.rosbag2 import Reader, Writer
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS2_HUMBLE)
    with Reader(source) as r, Writer(target, version=8) as w:
        conns = {c.id: w.add_connection(c.topic, c.msgtype, typestore=store) for c in r.connections}
        last = 0
        for conn, t, data in r.messages():
            w.write(conns[conn.id], t + shift_ns, data)
            last = t + shift_ns
        if extra_topic:
            log = w.add_connection("/rosout_text", "std_msgs/msg/String", typestore=store)
            String = store.types["std_msgs/msg/String"]
            w.write(log, last + 1, store.serialize_cdr(String(data="hello"), "std_msgs/msg/String"))
    return target


@pytest.mark.parametrize("change", ["receive times shifted", "an unrelated topic added"])
def test_a_bag_copied_with_other_receive_times_or_an_extra_topic_is_refused(tmp_path, capsys, change):
    t = np.arange(0.0, 1.0, 0.01)
    bag = write_bag(tmp_path / "run", "sqlite3", sensor_time=t, reading=np.random.default_rng(10).normal(size=(100, 6)),
                    pose_time=t, joints=np.c_[t, -t], joint_names=["j1", "j2"])
    twin = _copy_bag(bag, tmp_path / "copy", shift_ns=10**9 if change == "receive times shifted" else 0,
                     extra_topic=change == "an unrelated topic added")
    _refused(["identify-load", str(bag), str(twin), "--out", str(tmp_path / "t"), "-q"], capsys, twin, bag, "ROS bag")


def _folder_of(tmp_path, tables):
    folder = tmp_path / "data"
    folder.mkdir()
    for k, (raw, wrench) in enumerate(tables):
        CalibrationDataset(raw=raw, wrench=wrench).save(folder / f"run{k}.csv")
    return folder


def test_a_repeatability_run_a_microvolt_apart_on_a_biased_bridge_is_not_a_twin(tmp_path):
    """The same dead-weight loads recorded twice by bridges biased at 2.5 V (a 10 mV signal, 0.1 µV resolution):
    every reading of the second run is 1-2 µV from the first, 4e-7 of the reading, far above re-formatting and
    round-off. Two recordings, both read: a tolerance on the column's largest value (the 2.5 V offset) called them
    twins in most such draws."""
    rng = np.random.default_rng(0)
    wrench = rng.integers(-5, 6, size=(30, 6)) * np.array([10.0, 10, 20, 0.5, 0.5, 0.5])
    signal = wrench @ rng.normal(size=(6, 6))
    first = np.round((2.5 + signal / np.abs(signal).max() * 0.010) * 1e7) / 1e7
    second = first + rng.choice([-2e-6, -1e-6, 1e-6, 2e-6], size=first.shape)
    assert CalibrationDataset.load(_folder_of(tmp_path, [(first, wrench), (second, wrench)])).n_samples == 60


def test_samples_of_static_poses_written_in_reverse_order_are_a_twin(tmp_path):
    """Several samples a pose (the reference wrench the same within a pose, the readings apart by their noise), the
    file written again with its rows reversed: the samples of one pose tie on the wrench, and are ordered by their
    readings, so the copy is found."""
    rng = np.random.default_rng(1)
    wrench = np.repeat(rng.normal(size=(20, 6)) * 10, 10, axis=0)
    raw = wrench @ rng.normal(size=(6, 6)) / 10 + 1e-4 * rng.normal(size=wrench.shape)
    with pytest.raises(ValueError, match=r"run1\.csv holds the same readings and wrenches as .*run0\.csv"):
        CalibrationDataset.load(_folder_of(tmp_path, [(raw, wrench), (raw[::-1], wrench[::-1])]))


def test_infinities_must_stand_in_the_same_places_with_the_same_values_around_them(tmp_path):
    from ftcal.core import content_twins

    values = {"a": [np.array([1.0, 2.0, np.inf])], "b": [np.array([5.0, 7.0, np.inf])],
              "c": [np.array([2.0, np.inf, 1.0])]}
    assert content_twins(list(values), lambda p: values[str(p)]) == [(Path("a"), Path("c"))]


def test_refuse_twin_recordings_names_an_unknown_kind(tmp_path):
    from ftcal.core import CalibrationInputError
    from ftcal.io import refuse_twin_recordings

    with pytest.raises(CalibrationInputError, match=r"what must be one of .*'pose file'.*got 'poses'"):
        refuse_twin_recordings([tmp_path / "a.csv"], "poses")
