"""ROS bags in (rosbag2 sqlite3 and MCAP, ROS 1): bags written here with ``rosbags`` from the virtual experiment
(a known tool, noise, settling transients, moves between poses, the sensor and the joints at different rates);
``identify-load`` recovers the tool, ``prepare`` + ``fit`` reach the calibration of the run logs, and bad bags
are one line each with nothing written."""

from __future__ import annotations

import json
import tracemalloc

import numpy as np
import pytest

import ftcal
from ftcal.core import LogFormatError
from ftcal.experiment import ToolLoad
from ftcal.cli import main
from ftcal.experiment._virtual_recording import continuous_recording
from ftcal.io._bags import bag_topics, read_bag, write_bag

TOOL = ToolLoad(mass=1.1, center_of_mass=np.array([0.01, 0.02, 0.07]),
                bias=np.array([2.0, -1.0, 0.5, 0.04, 0.02, -0.03]))
NOISE = np.array([0.2, 0.2, 0.2, 0.008, 0.008, 0.008])
T0 = 1.7e9  # a ROS clock


@pytest.fixture(scope="module")
def robot_poses():
    robot = ftcal.robot.load_robot("kuka_iiwa14")
    plan = ftcal.robot.plan_calibration_poses(robot, subdivisions=0, excluded_cap_deg=0)
    return robot, plan.q


def _tool_recording(robot, q, seed, **kwargs):
    R = ftcal.robot.sensor_pose_in_base(robot, q)[:, :3, :3]
    options = dict(still_s=4.0, move_s=2.0, sensor_rate_hz=100.0, pose_rate_hz=40.0, settle_amplitude=1.0,
                   settle_tau_s=0.5, noise=NOISE, start_time_s=T0, random_state=seed)
    options.update(kwargs)
    return continuous_recording(TOOL.gravity_wrench(R), joints=q, **options)


def _tool_bag(path, storage, robot, q, seed, **write):
    rec = _tool_recording(robot, q, seed)
    return write_bag(path, storage, sensor_time=rec.sensor_time, reading=rec.reading, pose_time=rec.pose_time,
                     joints=rec.joints, joint_names=robot.joint_names, **write)


@pytest.mark.parametrize("storage", ["sqlite3", "mcap", "ros1"])
def test_identify_load_from_a_bag_recovers_the_tool_within_its_standard_errors(tmp_path, capsys, robot_poses,
                                                                               storage):
    robot, q = robot_poses
    bag = _tool_bag(tmp_path / ("rec.bag" if storage == "ros1" else "rec"), storage, robot, q, seed=1)
    assert main(["identify-load", str(bag), "--robot", "kuka_iiwa14", "--out", str(tmp_path / "t")]) == 0
    err = capsys.readouterr().err
    assert f"found {len(q)} still poses, kept {len(q)}, rejected 0" in err
    tool = ToolLoad.load(tmp_path / "t" / "tool.tool.json")
    assert abs(tool.mass - TOOL.mass) <= 4 * tool.mass_std_error
    assert np.all(np.abs(tool.center_of_mass - TOOL.center_of_mass) <= 4 * tool.center_of_mass_std_error)
    assert np.all(np.abs(tool.bias - TOOL.bias) <= 4 * tool.bias_std_error)
    d = json.loads((tmp_path / "t" / "tool.tool.json").read_text())
    assert len(d["pose_time_s"]) == len(q) and min(d["pose_time_s"]) > T0  # each still pose's bag stamp


def test_identify_load_takes_the_orientation_from_tf_and_raw_gauges_through_a_model(tmp_path, capsys, robot_poses):
    robot, q = robot_poses
    rec = _tool_recording(robot, q, seed=2)
    R_at_pose_times = ftcal.robot.sensor_pose_in_base(robot, rec.joints)[:, :3, :3]
    gain = np.diag([50.0, 50.0, 50.0, 2000.0, 2000.0, 2000.0])  # raw units per N and per N·m
    raw = rec.reading @ gain.T
    bag = write_bag(tmp_path / "raw.bag", "ros1", sensor_time=rec.sensor_time, reading=raw, raw=True,
                    pose_time=rec.pose_time, rotations=R_at_pose_times, tf_frames=("base_link", "ft_sensor"))
    data = ftcal.CalibrationDataset(raw=np.random.default_rng(0).normal(size=(60, 6)) @ gain.T, wrench=np.zeros((60, 6)))
    data.wrench = data.raw @ np.linalg.inv(gain).T
    model = ftcal.LinearCalibrator().fit(data.raw, data.wrench)
    ftcal.save_model(model, tmp_path / "gain.model.npz")
    assert main(["identify-load", str(bag), "--tf", "base_link,ft_sensor", "--raw-topic", "/ft_sensor/raw",
                 "--model", str(tmp_path / "gain.model.npz"), "--out", str(tmp_path / "t"), "-q"]) == 0
    tool = ToolLoad.load(tmp_path / "t" / "tool.tool.json")
    assert abs(tool.mass - TOOL.mass) <= 4 * tool.mass_std_error
    assert np.all(np.abs(tool.center_of_mass - TOOL.center_of_mass) <= 4 * tool.center_of_mass_std_error)


def test_prepare_and_fit_from_bags_reach_the_calibration_of_the_run_logs(tmp_path, capsys):
    logs = tmp_path / "sim"
    assert main(["simulate", "experiment", "--subdivisions", "0", "--bag", "mcap", "--seed", "3", "--out", str(logs),
                 "-q"]) == 0
    assert main(["prepare", str(logs / "bags"), "--raw-topic", "/ft_sensor/raw", "--mass", "2.0",
                 "--out", str(tmp_path / "data_bag")]) == 0
    err = capsys.readouterr().err
    assert err.count("found 11 still poses, kept 11") == 14
    assert main(["prepare", str(logs), "--mass", "2.0", "--out", str(tmp_path / "data_log"), "-q"]) == 0
    for d in ("bag", "log"):
        assert main(["fit", str(tmp_path / f"data_{d}" / "dataset.csv"), "--model", "linear",
                     "--out", str(tmp_path / f"m_{d}"), "-q"]) == 0
    reference = ftcal.CalibrationDataset.load(tmp_path / "data_log" / "dataset.csv")
    from_bag = ftcal.load_model(tmp_path / "m_bag" / "linear.model.npz").predict(reference.raw)
    from_log = ftcal.load_model(tmp_path / "m_log" / "linear.model.npz").predict(reference.raw)
    # the two calibrations differ by far less than either's error against the reference wrenches
    fit_error = np.sqrt(np.mean((from_log - reference.wrench) ** 2, axis=0))
    assert np.all(np.sqrt(np.mean((from_bag - from_log) ** 2, axis=0)) <= 0.1 * fit_error)


def test_prepare_from_bags_with_the_orientation_from_tf_reaches_the_calibration_of_the_run_logs(tmp_path, capsys):
    """The same runs recorded with /tf (no joint states): --tf BASE,SENSOR, as identify-load takes it."""
    from ftcal.io._logs import read_run_log

    logs = tmp_path / "sim"
    assert main(["simulate", "experiment", "--subdivisions", "0", "--seed", "3", "--out", str(logs), "-q"]) == 0
    robot = ftcal.robot.load_robot("kuka_iiwa14")
    rng = np.random.default_rng(3)
    for path in sorted(logs.glob("config*.csv")):
        run = read_run_log(path)
        order = np.argsort(run.pose, kind="stable")
        R = ftcal.robot.sensor_pose_in_base(robot, run.q[order])[:, :3, :3]
        noise = 1e-4 * np.ptp(run.raw, axis=0) + 1e-12
        rec = continuous_recording(run.raw[order], rotations=R, noise=noise, settle_amplitude=10 * noise,
                                   start_time_s=T0, random_state=rng)
        write_bag(tmp_path / "tf_bags" / path.stem, "sqlite3", sensor_time=rec.sensor_time, reading=rec.reading,
                  raw=True, pose_time=rec.pose_time, rotations=rec.rotations, tf_frames=("world", "ft_link"))
    assert main(["prepare", str(tmp_path / "tf_bags"), "--raw-topic", "/ft_sensor/raw", "--tf", "world,ft_link",
                 "--mass", "2.0", "--out", str(tmp_path / "data_tf")]) == 0
    err = capsys.readouterr().err
    assert "the sensor's orientation from /tf (world, ft_link)" in err and err.count("kept 11") == 14, err
    assert main(["prepare", str(logs), "--mass", "2.0", "--out", str(tmp_path / "data_log"), "-q"]) == 0
    from_tf = ftcal.CalibrationDataset.load(tmp_path / "data_tf" / "dataset.csv")
    reference = ftcal.CalibrationDataset.load(tmp_path / "data_log" / "dataset.csv")
    assert from_tf.meta["orientation_source"] == "recorded (tf)"
    # the same pairs, the same reference wrenches (the orientation averaged over each still pose's slerped /tf
    # samples agrees with the joints' to ~1e-5 rad, which moves the load's weight by that fraction), the same fit
    np.testing.assert_allclose(from_tf.wrench, reference.wrench, atol=1e-5 * np.abs(reference.wrench).max())
    m_tf = ftcal.LinearCalibrator().fit(from_tf.raw, from_tf.wrench)
    m_log = ftcal.LinearCalibrator().fit(reference.raw, reference.wrench)
    fit_error = np.sqrt(np.mean((m_log.predict(reference.raw) - reference.wrench) ** 2, axis=0))
    assert np.all(np.sqrt(np.mean((m_tf.predict(reference.raw) - m_log.predict(reference.raw)) ** 2, axis=0))
                  <= 0.1 * fit_error)


def _one_line_error(argv, capsys, out):
    capsys.readouterr()
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("ftcal: error: "), err
    assert not out.exists()
    return err


def test_a_missing_topic_or_a_wrong_type_names_the_topics_present(tmp_path, capsys, robot_poses):
    robot, q = robot_poses
    bag = _tool_bag(tmp_path / "rec", "sqlite3", robot, q[:5], seed=4)
    out = tmp_path / "t"
    err = _one_line_error(["identify-load", str(bag), "--wrench-topic", "/wrench", "--out", str(out)], capsys, out)
    assert "no topic /wrench" in err and "/ft_sensor/wrench (geometry_msgs/msg/WrenchStamped" in err
    assert "/joint_states (sensor_msgs/msg/JointState" in err
    err = _one_line_error(["identify-load", str(bag), "--wrench-topic", "/joint_states", "--out", str(out)], capsys,
                          out)
    assert "topic /joint_states holds sensor_msgs/msg/JointState, not geometry_msgs/msg/WrenchStamped" in err
    err = _one_line_error(["identify-load", str(bag), "--tf", "base_link,ft_sensor", "--out", str(out)], capsys, out)
    assert "no topic /tf or /tf_static" in err


def test_a_folder_of_bags_is_read_and_a_raw_field_that_is_not_an_array_is_refused(tmp_path, capsys, robot_poses):
    robot, q = robot_poses
    rec = _tool_recording(robot, q, seed=7)
    (tmp_path / "bags").mkdir()
    bag = write_bag(tmp_path / "bags" / "rec", "mcap", sensor_time=rec.sensor_time, reading=rec.reading * 100,
                    raw=True, pose_time=rec.pose_time, joints=rec.joints, joint_names=robot.joint_names)
    out = tmp_path / "t"
    data = ftcal.CalibrationDataset(raw=np.eye(6) * 100, wrench=np.eye(6))
    ftcal.save_model(ftcal.LinearCalibrator().fit(np.vstack([data.raw, 2 * data.raw, -data.raw]),
                                                  np.vstack([data.wrench, 2 * data.wrench, -data.wrench])),
                     tmp_path / "x.model.npz")
    err = _one_line_error(["identify-load", str(tmp_path / "bags"), "--raw-topic", "/ft_sensor/raw", "--raw-field",
                           "layout", "--model", str(tmp_path / "x.model.npz"), "--out", str(out)], capsys, out)
    assert f"{bag}: field 'layout' of topic /ft_sensor/raw" in err and "is not an array of numbers" in err
    err = _one_line_error(["identify-load", str(tmp_path / "bags"), "--raw-topic", "/ft_sensor/raw", "--raw-field",
                           "values", "--model", str(tmp_path / "x.model.npz"), "--out", str(out)], capsys, out)
    assert "has no field 'values'; its fields are layout, data" in err and "Fix: name the array field with " \
        "--raw-field FIELD" in err
    assert main(["identify-load", str(tmp_path / "bags"), "--raw-topic", "/ft_sensor/raw", "--model",
                 str(tmp_path / "x.model.npz"), "--out", str(out), "-q"]) == 0
    tool = ToolLoad.load(out / "tool.tool.json")
    assert abs(tool.mass - TOOL.mass) <= 4 * tool.mass_std_error


def test_a_bag_without_a_still_segment_is_refused(tmp_path, capsys, robot_poses):
    robot, q = robot_poses
    t = np.arange(0.0, 10.0, 0.02)
    sweep = q[0] + np.outer(t / 10.0, q[1] - q[0])  # never still
    bag = write_bag(tmp_path / "moving", "mcap", sensor_time=T0 + t, reading=np.zeros((len(t), 6)),
                    pose_time=T0 + t, joints=sweep, joint_names=robot.joint_names)
    out = tmp_path / "t"
    err = _one_line_error(["identify-load", str(bag), "--out", str(out)], capsys, out)
    assert "no still pose in the" in err and str(bag) in err


def test_a_clock_offset_is_named_and_clocks_apart_are_refused_with_the_fix(tmp_path, capsys, robot_poses):
    robot, q = robot_poses
    shifted = _tool_bag(tmp_path / "shifted", "mcap", robot, q, seed=5, sensor_clock_offset_s=0.3)
    assert main(["identify-load", str(shifted), "--out", str(tmp_path / "s")]) == 0
    err = capsys.readouterr().err
    assert "clock offset between /ft_sensor/wrench and /joint_states" in err and "-0.3 s" in err
    apart = _tool_bag(tmp_path / "apart", "mcap", robot, q, seed=5, sensor_clock_offset_s=-T0 + 100.0)  # from boot
    out = tmp_path / "t"
    err = _one_line_error(["identify-load", str(apart), "--out", str(out)], capsys, out)
    assert "clocks apart" in err and "Fix: --stamps receive" in err
    assert main(["identify-load", str(apart), "--stamps", "receive", "--out", str(out), "-q"]) == 0
    tool = ToolLoad.load(out / "tool.tool.json")
    assert abs(tool.mass - TOOL.mass) <= 4 * tool.mass_std_error


@pytest.mark.parametrize("storage", ["sqlite3", "mcap", "ros1"])
def test_a_truncated_bag_is_one_line_and_nothing_is_written(tmp_path, capsys, robot_poses, storage):
    robot, q = robot_poses
    bag = _tool_bag(tmp_path / ("rec.bag" if storage == "ros1" else "rec"), storage, robot, q[:4], seed=6)
    data = bag if storage == "ros1" else next(p for p in bag.iterdir() if p.suffix in (".db3", ".mcap"))
    size = data.stat().st_size
    with open(data, "r+b") as f:
        f.truncate(size // 2)
    out = tmp_path / "t"
    err = _one_line_error(["identify-load", str(bag), "--out", str(out)], capsys, out)
    assert str(bag) in err and "cannot read the bag" in err and "truncated or damaged" in err


def _big_bag(path, n, storage):
    t = T0 + np.arange(n) * 1e-3  # a 1 kHz sensor
    return write_bag(path, storage, sensor_time=t, reading=np.zeros((n, 6)), pose_time=t[::10],
                     joints=np.zeros((len(t[::10]), 7)), joint_names=[f"j{k}" for k in range(7)],
                     ros1_chunk_bytes=64 * 1024)  # several chunks even in the small bag


def _peak_while_reading(bag):
    tracemalloc.start()
    try:
        rec = read_bag(bag, max_samples=300)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    return rec, peak


@pytest.mark.parametrize("storage, sizes", [("sqlite3", (2_000, 20_000)), ("ros1", (2_000, 20_000))])
def test_memory_stays_bounded_whatever_the_bag_size(tmp_path, storage, sizes):
    suffix = ".bag" if storage == "ros1" else ""
    small = _big_bag(tmp_path / f"small{suffix}", sizes[0], storage)
    large = _big_bag(tmp_path / f"large{suffix}", sizes[1], storage)
    _peak_while_reading(small)  # the first read registers the bag's message types
    rec_small, peak_small = _peak_while_reading(small)
    rec_large, peak_large = _peak_while_reading(large)
    assert bag_topics(large)["/ft_sensor/wrench"][1] == sizes[1]
    assert len(rec_large.time) <= 300 + 1 and len(rec_small.time) <= 300 + 1  # block means, not every message
    assert any(f"averaged in blocks of {-(-sizes[1] // 300)}" in str(n) for n in rec_large.notes)
    # ten times the messages, not ten times the memory (a whole-bag reader holds every message: ~10 MB here, and
    # rosbags' own ROS 1 reader an index entry per message)
    assert peak_large <= 1.2 * peak_small + 200_000


def test_memory_of_an_mcap_bag_is_its_chunk_buffer(tmp_path):
    # MCAP is read a chunk at a time: its peak is the chunk buffer's (~4 MB), not the bag's
    _, peak_mcap = _peak_while_reading(_big_bag(tmp_path / "mcap", 20_000, "mcap"))
    assert peak_mcap <= 6_000_000


def test_memory_stays_bounded_when_the_bag_metadata_under_counts_its_messages(tmp_path):
    import re

    n = 20_000
    bag = _big_bag(tmp_path / "undercounted", n, "sqlite3")
    meta = bag / "metadata.yaml"
    text = meta.read_text()
    # an interrupted or hand-merged recording: the metadata says 10 messages on every topic, the bag holds 20 000
    meta.write_text(re.sub(r"message_count: \d+", "message_count: 10", text))
    assert bag_topics(bag)["/ft_sensor/wrench"][1] == 10
    _peak_while_reading(bag)  # registers the message types
    rec, peak = _peak_while_reading(bag)
    honest = _big_bag(tmp_path / "honest", n, "sqlite3")
    _, peak_honest = _peak_while_reading(honest)
    assert 300 < len(rec.time) <= 2 * 300  # pairs merged in place as the buffer filled: at most 2 x max_samples
    assert rec.time[0] >= T0 and rec.time[-1] <= T0 + n * 1e-3  # block means of the whole recording, in order
    assert np.all(np.diff(rec.time) > 0)
    assert peak < 3 * peak_honest  # not every message kept (that would be ~70x the buffer)
    assert any(f"{n} messages averaged in blocks of" in str(note) for note in rec.notes)


def test_a_wrench_bag_with_tf_and_no_joint_states_is_told_to_use_tf_with_its_own_frames(tmp_path, capsys,
                                                                                         robot_poses):
    robot, q = robot_poses
    rec = _tool_recording(robot, q, seed=4)
    R = ftcal.robot.sensor_pose_in_base(robot, rec.joints)[:, :3, :3]
    bag = write_bag(tmp_path / "tf_only", "mcap", sensor_time=rec.sensor_time, reading=rec.reading,
                    pose_time=rec.pose_time, rotations=R, tf_frames=("world", "ft_link"), frame_id="ft_link")
    assert main(["identify-load", str(bag), "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and str(bag) in err[0] and "--tf world,ft_link" in err[0], err
    assert "--joint-topic" not in err[0] and not (tmp_path / "t").exists()
    assert main(["identify-load", str(bag), "--tf", "world,ft_link", "--out", str(tmp_path / "t"), "-q"]) == 0
    tool = ToolLoad.load(tmp_path / "t" / "tool.tool.json")
    assert abs(tool.mass - TOOL.mass) <= 4 * tool.mass_std_error
    # the same bag compensated with that tool file: every sensor sample at its stamp, nothing but noise left
    out = tmp_path / "external.csv"
    assert main(["compensate", str(bag), "--tf", "world,ft_link", "--tool", str(tmp_path / "t" / "tool.tool.json"),
                 "--output", str(out), "-q"]) == 0
    lines = out.read_text().splitlines()
    table = np.array([[float(v) for v in line.split(",")] for line in lines[1:]])
    kept = np.isin(rec.sensor_time, table[:, 0])  # each row's bag stamp, to the nanosecond
    assert lines[0] == "time,Fx,Fy,Fz,Tx,Ty,Tz" and kept.sum() == len(table) >= len(rec.sensor_time) - 2
    # the tool's weight is gone: what is left is the noise and the settling transients after each move (1 N, 1 N·m
    # decaying in 0.5 s), a small part of the weight the readings carried (|F| ~ 10.8 N, |T| ~ 0.8 N·m)
    left, read = table[:, 1:], rec.reading[kept] - TOOL.bias
    for axes in (slice(0, 3), slice(3, 6)):
        assert np.median(np.linalg.norm(left[:, axes], axis=1)) <= 0.1 * np.median(np.linalg.norm(read[:, axes], axis=1))
    assert np.all(np.median(np.abs(left[:, :3]), axis=0) <= 2 * NOISE[:3])


def test_a_wrench_bag_in_newton_millimetres_is_refused_naming_the_unit_until_declared(tmp_path, capsys, robot_poses):
    robot, q = robot_poses
    rec = _tool_recording(robot, q, seed=5)
    reading = rec.reading.copy()
    reading[:, 3:] *= 1000.0  # a driver publishing N·mm
    R = ftcal.robot.sensor_pose_in_base(robot, rec.joints)[:, :3, :3]
    bag = write_bag(tmp_path / "nmm", "sqlite3", sensor_time=rec.sensor_time, reading=reading,
                    pose_time=rec.pose_time, rotations=R)
    assert main(["identify-load", str(bag), "--tf", "base_link,ft_sensor", "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err.startswith(f"ftcal: error: {bag} (topic /ft_sensor/wrench)") and "--torque-unit N.mm" in err, err
    assert not (tmp_path / "t").exists()
    assert main(["identify-load", str(bag), "--tf", "base_link,ft_sensor", "--torque-unit", "N.mm",
                 "--out", str(tmp_path / "t"), "-q"]) == 0
    tool = ToolLoad.load(tmp_path / "t" / "tool.tool.json")
    assert np.all(np.abs(tool.center_of_mass - TOOL.center_of_mass) <= 4 * tool.center_of_mass_std_error)


def test_joint_states_named_unlike_the_robot_are_refused_even_when_the_counts_agree(tmp_path, capsys, robot_poses):
    # drivers rename joints and publishers reorder them: taking the bag's columns in order would give wrong FK
    robot, q = robot_poses
    rec = _tool_recording(robot, q, seed=3)
    renamed = [f"arm_{name}" for name in robot.joint_names][::-1]
    bag = write_bag(tmp_path / "renamed", "sqlite3", sensor_time=rec.sensor_time, reading=rec.reading,
                    pose_time=rec.pose_time, joints=rec.joints[:, ::-1], joint_names=renamed)
    out = tmp_path / "t"
    assert main(["identify-load", str(bag), "--robot", "kuka_iiwa14", "--out", str(out)]) == 2
    err = capsys.readouterr().err.splitlines()[-1]  # after the bag's notes (dropped samples), one error line
    assert err.startswith("ftcal: error: ") and "arm_" in err and robot.joint_names[0] in err
    assert "--tf BASE,SENSOR" in err and not out.exists()


def test_wrenches_stamped_in_another_frame_than_the_tf_sensor_frame_are_refused_naming_both(tmp_path, capsys,
                                                                                             robot_poses):
    # the bag's chain is base_link -> flange -> ft_sensor, the flange turned 90 deg from the sensor; the wrenches
    # are stamped in ft_sensor: naming the flange as the sensor frame would rotate them by 90 deg without a word
    robot, q = robot_poses
    rec = _tool_recording(robot, q, seed=6)
    R = ftcal.robot.sensor_pose_in_base(robot, rec.joints)[:, :3, :3]
    bag = write_bag(tmp_path / "frames", "sqlite3", sensor_time=rec.sensor_time, reading=rec.reading,
                    pose_time=rec.pose_time, rotations=R, frame_id="/ft_sensor")
    with pytest.raises(LogFormatError, match="expressed in frame 'ft_sensor'.*not in 'flange'") as info:
        read_bag(bag, tf=("base_link", "flange"))
    assert info.value.parameter == "tf" and info.value.settings["tf"] == ("base_link", "ft_sensor")
    assert read_bag(bag, tf=("base_link", "ft_sensor")).frame_id == "/ft_sensor"  # a leading slash is the same frame
    assert main(["identify-load", str(bag), "--tf", "base_link,flange", "--out", str(tmp_path / "t")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "'flange'" in err[0] and "--tf base_link,ft_sensor" in err[0], err
    assert not (tmp_path / "t").exists()


def test_a_tf_edge_keeps_evenly_spaced_samples_within_its_bound_whatever_other_edges_carry():
    from ftcal.io._bags import _Stream

    a, b = _Stream(0, max_samples=10, average=False), _Stream(0, max_samples=10, average=False)
    for k in range(10_000):  # two publishers alternating on /tf: each edge counts its own messages
        (a if k % 2 == 0 else b).add(float(k), float(k), np.array([0.0, 0.0, 0.0, 1.0]))
    for edge, first in ((a, 0.0), (b, 1.0)):
        times, _, quats = edge.arrays()
        assert 10 <= len(times) <= 20 and quats.shape == (len(times), 4)
        steps = np.diff(times)
        assert times[0] == first and np.all(steps == steps[0])  # evenly spaced over the whole recording
        assert times[-1] >= 10_000 - 2 - steps[0]
