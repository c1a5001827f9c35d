"""Readings checked before use: impossible values, spikes, stuck channels and repeated rows, each named by file,
line and channel; the CLI's warning lines and --drop-bad-readings; the rows' sources and the group names."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal import CalibrationDataset
from ftcal.cli import build_parser, main
from ftcal.cli._data_options import load_dataset_from_args
from ftcal.io import FindingKind, RowSources, check_readings
from ftcal.simulation._field_sensors import make_dead_weight_dataset, make_robot_held_dataset, make_soft_sensor_dataset


def static_poses(n_groups=6, rows=120, channels=6, noise=2.0, seed=0, levels=(150, 850)):
    """Integer readings of a 10-bit ADC at static poses (one mean per pose) with Gaussian noise, and wrenches."""
    rng = np.random.default_rng(seed)
    group = np.repeat(np.arange(n_groups), rows)
    loads = rng.uniform(-1, 1, size=(n_groups, 6))
    gains = np.linalg.qr(rng.normal(size=(channels, 6)))[0][:, :6] if channels >= 6 else rng.normal(size=(channels, 6))
    middle, half = (levels[0] + levels[1]) / 2, (levels[1] - levels[0]) / 2
    means = middle + half * np.clip(loads @ gains.T, -1, 1)  # the pose's readings follow its load
    raw = np.round(means[group] + noise * rng.standard_normal((n_groups * rows, channels)))
    return raw, loads[group] * [20, 20, 20, 1, 1, 1], group


def write_folder(folder, raw, wrench, group):
    """One CSV per group, with a comment line first (so that the file's lines are not the rows' numbers)."""
    folder.mkdir()
    for g in np.unique(group):
        m = group == g
        lines = ["# a pose", ",".join([f"s{k}" for k in range(raw.shape[1])] + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"])]
        lines += [",".join(f"{v:.10g}" for v in row) for row in np.hstack([raw[m], wrench[m]])]
        (folder / f"pose_{g:02d}.csv").write_text("\n".join(lines) + "\n")
    return folder


def test_an_impossible_reading_is_named_by_file_line_and_channel(tmp_path):
    raw, wrench, group = static_poses()
    raw[130, 4] = 4598  # pose 1, its 11th row: line 13 of pose_01.csv (a comment and the header before)
    data = CalibrationDataset.load(write_folder(tmp_path / "poses", raw, wrench, group))
    found = check_readings(data.raw, wrench=data.wrench, groups=data.group, sources=data.sources)
    assert [(f.kind, f.file, f.line, f.channel, f.value) for f in found.findings] == \
        [(FindingKind.OUT_OF_RANGE, "pose_01.csv", 13, "s4", 4598.0)]
    assert found.adc_ranges["s4"] == (0.0, 1023.0)


def test_a_lone_reading_at_the_adc_limit_is_flagged_but_a_channel_living_there_is_not():
    raw, wrench, group = static_poses(levels=(300, 700))
    raw[200, 0] = 0  # a dropped sample
    found = check_readings(raw, wrench=wrench, groups=group)
    assert [(f.kind, f.line, f.channel, f.value) for f in found.findings] == \
        [(FindingKind.OUT_OF_RANGE, 201, "s0", 0.0)]
    # a channel whose readings sit at 0..10: a 0 among them is no glitch
    near_zero = np.round(np.abs(np.random.default_rng(1).normal(0, 3, size=(raw.shape[0], 1))))
    assert check_readings(np.hstack([near_zero, raw[:, 1:]]), wrench=wrench, groups=group).clean


def test_a_spike_is_found_and_a_load_step_is_not():
    raw, wrench, group = static_poses(noise=3.0)
    raw[300, 2] += 60  # 20 noise SD above its neighbours on both sides
    found = check_readings(raw, wrench=wrench, groups=group)
    assert [(f.kind, f.line, f.channel) for f in found.findings] == [(FindingKind.SPIKE, 301, "s2")]
    assert 4 < found.spike_z < 7
    stepped = raw.copy()
    stepped[300, 2] -= 60
    stepped[400:480, 2] += 60  # a load step inside a group: each reading matches one side
    assert check_readings(stepped, wrench=wrench, groups=group).clean


def test_a_stuck_channel_is_found_while_the_others_move():
    raw, wrench, group = static_poses(noise=1.0)
    raw[250:320, 3] = raw[250, 3]
    found = check_readings(raw, wrench=wrench, groups=group)
    assert [(f.kind, f.line, f.channel, f.rows.size) for f in found.findings] == [(FindingKind.STUCK, 251, "s3", 70)]


def test_a_quiet_channel_below_one_step_of_noise_is_not_called_stuck():
    for seed in range(3):
        raw, wrench, group = static_poses(n_groups=12, rows=200, noise=0.2, seed=seed)
        assert check_readings(raw, wrench=wrench, groups=group).clean


def test_repeated_rows_are_flagged_beyond_what_quantisation_explains():
    rng = np.random.default_rng(3)
    raw, wrench = 1000 * rng.normal(size=(200, 6)), rng.normal(size=(200, 6))
    raw[150], wrench[150] = raw[40], wrench[40]  # the logger wrote row 40 again
    found = check_readings(raw, wrench=wrench)
    assert [(f.kind, f.line, f.channel) for f in found.findings] == [(FindingKind.REPEATED, 151, None)]
    assert "repeats dataset:row 41 exactly" in found.findings[0].reason
    coarse, _, group = static_poses(noise=0.4)  # a quiet 10-bit channel repeats rows by itself
    assert not check_readings(coarse, groups=group).of_kind("repeated")


def test_one_row_groups_neither_crash_nor_flag():
    raw, wrench, group = static_poses()
    group = group.copy()
    group[[0, 359, 719]] = [100, 101, 102]  # three groups of one row
    assert check_readings(raw, wrench=wrench, groups=group).clean
    assert check_readings(raw[:1], wrench=wrench[:1]).clean
    assert check_readings(raw[:0]).clean


def test_clean_simulated_recordings_give_no_false_alarm():
    found = []
    for seed in range(5):
        robot = make_robot_held_dataset(3000, random_state=seed)
        for raw in (robot.raw, np.round(robot.raw / 64)):  # and quantised as a 10-bit ADC would
            found += check_readings(raw, wrench=robot.wrench, groups=robot.group).findings
        soft = make_soft_sensor_dataset(random_state=seed)
        found += check_readings(soft.raw, wrench=soft.wrench, groups=soft.group).findings
        for cell in make_dead_weight_dataset(random_state=seed):
            found += check_readings(cell.raw, wrench=cell.wrench).findings
        raw, wrench, group = static_poses(seed=seed)
        found += check_readings(raw, wrench=wrench, groups=group).findings
    assert [f.where() for f in found] == []  # 30 datasets, each checked at a false-alarm budget of 0.01


def test_rows_keep_their_file_and_line_through_subsets(tmp_path):
    raw, wrench, group = static_poses(n_groups=2, rows=5)
    data = CalibrationDataset.load(write_folder(tmp_path / "poses", raw, wrench, group))
    assert [data.sources.describe(i) for i in (0, 4, 5)] == ["pose_00.csv:3", "pose_00.csv:7", "pose_01.csv:3"]
    assert data.meta["group_names"] == ["pose_00.csv", "pose_01.csv"]
    part = data.subset(np.array([False, True] * 5))
    assert [part.sources.describe(i) for i in range(part.n_samples)] == \
        ["pose_00.csv:4", "pose_00.csv:6", "pose_01.csv:3", "pose_01.csv:5", "pose_01.csv:7"]
    npz = tmp_path / "d.npz"
    CalibrationDataset(raw=raw, wrench=wrench).save(npz)
    assert CalibrationDataset.load(npz).sources.describe(2) == "d.npz:row 3"
    assert RowSources.of_file("x.csv", [5]).where(0) == ("x.csv", 5)


def test_text_group_labels_name_the_groups_across_a_folder(tmp_path):
    folder = tmp_path / "sessions"
    folder.mkdir()
    raw, wrench, _ = static_poses(n_groups=1, rows=8)
    for name, labels in (("a.csv", ["left"] * 4 + ["right"] * 4), ("b.csv", ["up"] * 4 + ["left"] * 4)):
        lines = ["s0,s1,s2,s3,s4,s5,Fx,Fy,Fz,Tx,Ty,Tz,group"]
        lines += [",".join(f"{v:.10g}" for v in row) + f",{g}" for row, g in zip(np.hstack([raw, wrench]), labels)]
        (folder / name).write_text("\n".join(lines) + "\n")
    data = CalibrationDataset.load(folder, columns=__import__("ftcal").io.ColumnMap(groups="group"))
    assert data.meta["group_names"] == ["left", "right", "up"]
    assert [data.meta["group_names"][g] for g in data.group[[0, 4, 8, 12]]] == ["left", "right", "up", "left"]


def test_fit_points_out_each_kind_and_drops_them_on_request(tmp_path, capsys):
    raw, wrench, group = static_poses(n_groups=30, rows=24, noise=3.0)
    raw[24 + 10, 4] = 4598  # line 13 of pose_01.csv (a comment and the header come first)
    raw[48 + 10, 2] += 80
    raw[96:120, 1] = raw[96, 1]  # every row of pose_04.csv
    folder = write_folder(tmp_path / "poses", raw, wrench, group)
    assert main(["fit", str(folder), "--model", "linear", "--out", str(tmp_path / "a.model.npz")]) == 0
    err = capsys.readouterr().err
    warned = [line for line in err.splitlines() if "ftcal: warning:" in line]
    assert len(warned) == 3, err
    assert "1 out_of_range reading (1 row): pose_01.csv:13:s4 = 4598" in warned[0]
    assert "1 spike reading (1 row): pose_02.csv:13:s2" in warned[1]
    assert "1 stuck channel run (24 rows): pose_04.csv:3:s1" in warned[2] and "--drop-bad-readings stuck" in warned[2]
    args = build_parser().parse_args(["fit", str(folder), "--drop-bad-readings", "auto", "-q"])
    data = load_dataset_from_args(args, folder)
    assert data.n_samples == raw.shape[0] - 2
    assert [(d["kind"], d["file"], d["line"], d["channel"]) for d in data.meta["readings_dropped"]] == \
        [("out_of_range", "pose_01.csv", 13, "s4"), ("spike", "pose_02.csv", 13, "s2")]
    assert [(d["kind"], d["file"], d["line"]) for d in data.meta["readings_flagged"]] == \
        [("stuck", "pose_04.csv", 3)]
    every = load_dataset_from_args(build_parser().parse_args(["fit", str(folder), "--drop-bad-readings", "all"]),
                                   folder)
    assert every.n_samples == raw.shape[0] - 26 and "readings_flagged" not in every.meta


@pytest.mark.parametrize("value", ["sometimes", "spike,typo", "none,spike"])
def test_drop_bad_readings_refuses_unknown_kinds(tmp_path, value, capsys):
    raw, wrench, group = static_poses(n_groups=2, rows=5)
    folder = write_folder(tmp_path / "poses", raw, wrench, group)
    assert main(["fit", str(folder), "--drop-bad-readings", value]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and err.startswith("ftcal: error:") and "--drop-bad-readings" in err
    assert "out_of_range,spike,stuck,repeated" in err
