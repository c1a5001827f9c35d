"""Bad input, round 6: advice checked before it is given, the reading checks' false alarms and misses, duplicate
files in a folder, headerless run logs with a text column, predict's bad input, a zero reference uncertainty."""

from __future__ import annotations

import numpy as np
import pytest

from ftcal.cli import main


def write_csv(path, raw, wrench, sep=",", names=None, extra=None):
    """A CSV of readings ``s0..`` and a wrench ``Fx..Tz`` (``extra``: name -> column of text appended)."""
    names = names or [f"s{i}" for i in range(raw.shape[1])] + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"][:wrench.shape[1]]
    extra = extra or {}
    lines = [sep.join(names + list(extra))]
    for i, row in enumerate(np.hstack([raw, wrench])):
        lines.append(sep.join([f"{v:.10g}" for v in row] + [str(c[i]) for c in extra.values()]))
    path.write_text("\n".join(lines) + "\n")
    return path


def sensor_data(n=200, seed=0, channels=6):
    """Loads up to 80 N and 2 N·m (a lever arm of a few cm) and affine readings of them with noise."""
    rng = np.random.default_rng(seed)
    wrench = rng.uniform(-1, 1, (n, 6)) * [50, 50, 80, 2, 2, 1]
    gains = rng.normal(size=(channels, 6))
    raw = wrench @ gains.T * 10 + 2000 + rng.normal(size=(n, channels))
    return raw, wrench


def one_error(capsys, code):
    err = capsys.readouterr().err.strip().splitlines()
    errors = [line for line in err if line.startswith("ftcal: error:")]
    assert code == 2 and len(errors) == 1, err
    return errors[0]


# ---------------------------------------------------------------- 1. unit advice is checked before it is given
@pytest.mark.parametrize("declared, right", [("uN", "N"), ("mN", "N"), ("kN", "N")])
def test_a_wrong_force_unit_is_answered_with_the_unit_that_makes_the_loads_plausible(tmp_path, capsys, declared,
                                                                                      right):
    from ftcal.io._readers import lever_arm_problem, unit_scale

    raw, wrench = sensor_data()  # forces in N, torques in N·m
    path = write_csv(tmp_path / "d.csv", raw, wrench)
    as_read = wrench * np.r_[[unit_scale(declared, "force")] * 3, 1, 1, 1]  # [N, N·m] as ftcal converts them
    problem = lever_arm_problem(as_read, "N.m", force_unit=declared)
    assert problem.settings["force_unit"] == right, str(problem)
    # the advice followed: the loads' check passes and the fit runs
    followed = as_read * np.r_[[unit_scale(right, "force") / unit_scale(declared, "force")] * 3, 1, 1, 1]
    assert lever_arm_problem(followed, "N.m", force_unit=right) is None
    code = main(["fit", str(path), "--model", "linear", "--force-unit", declared, "--out", str(tmp_path / "m")])
    if declared == "kN":  # too short an arm is only pointed out
        assert code == 0 and f"--force-unit {right} " in capsys.readouterr().err
    else:
        err = one_error(capsys, code)
        assert f"Fix: pass --force-unit {right} " in err and "MN" not in err and "uN.m" not in err, err
    assert main(["fit", str(path), "--model", "linear", "--force-unit", right, "--out", str(tmp_path / "n"),
                 "-q"]) == 0


def test_no_unit_is_proposed_when_none_makes_the_loads_plausible():
    from ftcal.io._readers import lever_arm_problem

    problem = lever_arm_problem([[1e-3, 0, 0, 0, 1e9, 0]])  # an arm of 1e12 m: no unit change of 1e3/1e6 helps
    assert "no common unit" in str(problem) and "force_unit" not in {k for k, v in problem.settings.items()
                                                                     if isinstance(v, str)}


# ---------------------------------------------------------------- 2. a row budget advised is one that works
def test_the_gp_memory_advice_names_a_row_count_that_fits_and_following_it_succeeds(tmp_path, capsys, monkeypatch):
    import re

    monkeypatch.setenv("FTCAL_MEMORY_LIMIT_GB", "0.001")  # 1 MiB: about 100 rows of a 6-channel GP
    raw, wrench = sensor_data(n=300)
    path = write_csv(tmp_path / "d.csv", raw, wrench)
    err = one_error(capsys, main(["fit", str(path), "--model", "gaussian_process", "--out", str(tmp_path / "a")]))
    rows = int(re.search(r"Fix: pass --param max_samples=(\d+) ", err).group(1))
    assert 10 <= rows < 300, err
    argv = ["fit", str(path), "--model", "gaussian_process", "-q", "--param"]
    assert main([*argv, f"max_samples={rows}", "--out", str(tmp_path / "b")]) == 0
    capsys.readouterr()
    again = one_error(capsys, main([*argv, f"max_samples={rows + 1}", "--out", str(tmp_path / "c")]))
    assert f"max_samples={rows} " in again  # one more row is over: the advice is the largest that works


# ---------------------------------------------------------------- 3. the training rows of a sliced .mat are in range
def test_the_training_rows_of_a_sliced_mat_are_within_the_range_read_from_that_mat(tmp_path, capsys):
    from scipy.io import savemat

    raw, wrench = sensor_data()
    path = tmp_path / "session.mat"
    # the calibration in one array sliced by the options; 'raw' and 'wrench' of another (a tenth of the readings)
    savemat(path, {"data": np.hstack([raw, wrench]), "raw": raw / 10, "wrench": wrench})
    slices = ["--channels", "data[:,0:6]", "--wrench", "data[:,6:12]"]
    assert main(["fit", str(path), *slices, "--model", "linear", "--out", str(tmp_path / "m"), "-q"]) == 0
    model = str(tmp_path / "m" / "linear.model.npz")
    capsys.readouterr()
    assert main(["predict", model, str(path), "--range", str(path)]) == 0
    out, err = capsys.readouterr()
    flags = [line.rsplit(",", 1)[1] for line in out.splitlines()[1:]]
    assert len(flags) == raw.shape[0] and set(flags) == {"0"}, err  # read as the model was: data[:,0:6]
    assert "beyond" not in err
    assert main(["evaluate", str(path), model, "--no-plots", "-o", str(tmp_path / "ev")]) == 0
    assert "beyond" not in capsys.readouterr().err


# ---------------------------------------------------------------- 4. one recording twice in a folder
@pytest.mark.parametrize("command", ["fit", "report"])
def test_a_recording_twice_in_a_folder_is_refused_by_every_command_that_reads_a_folder(tmp_path, capsys, command):
    from ftcal import CalibrationDataset

    folder = tmp_path / "poses"
    folder.mkdir()
    raw, wrench = sensor_data(n=120)
    for k in range(3):
        write_csv(folder / f"pose_{k}.csv", raw[40 * k:40 * k + 40], wrench[40 * k:40 * k + 40])
    copy = (folder / "pose_1.csv").read_bytes()
    (folder / "pose_1 (copy).csv").write_bytes(copy)  # the same recording twice, under another name
    argv = [command, str(folder), "--model", "linear", "--out", str(tmp_path / "m")] if command == "fit" else \
        [command, "--help"]
    if command == "report":  # report reads the folder with its model: fit one on the clean files first
        clean = tmp_path / "clean"
        clean.mkdir()
        for k in range(3):
            (clean / f"pose_{k}.csv").write_bytes((folder / f"pose_{k}.csv").read_bytes())
        assert main(["fit", str(clean), "--model", "linear", "--out", str(tmp_path / "m"), "-q"]) == 0
        argv = [command, str(tmp_path / "m" / "linear.model.npz"), str(folder), "-o", str(tmp_path / "r")]
    capsys.readouterr()
    err = one_error(capsys, main(argv))
    assert "holds the same readings and wrenches as" in err and "pose_1 (copy).csv" in err and "pose_1.csv" in err
    # the same rows written otherwise (a comment line, CRLF line ends) are the same recording too
    (folder / "pose_1 (copy).csv").unlink()
    (folder / "pose_9.csv").write_bytes(b"# exported again\r\n" + copy.replace(b"\n", b"\r\n"))
    with pytest.raises(ValueError, match="pose_9.csv holds the same readings and wrenches as .*pose_1.csv"):
        CalibrationDataset.load(folder)
    (folder / "pose_9.csv").unlink()
    assert CalibrationDataset.load(folder).n_samples == 120  # distinct recordings are read


# ---------------------------------------------------------------- 8. an ideal reference: 0 uncertainty
@pytest.mark.parametrize("given", ["0%", "Fx=0,Fy=0,Fz=0"])
def test_a_zero_reference_uncertainty_is_an_ideal_reference_not_an_error(tmp_path, capsys, given):
    import json

    from test_certificate_budget import LoadCell

    data = LoadCell(seed=13).session(6, 5, 1, seed=14)
    lines = ["pose,g_a,g_b,g_c,Fx,Fy,Fz"] + [f"p{int(g)},{r[0]:.0f},{r[1]:.0f},{r[2]:.0f},{w[0]},{w[1]},{w[2]}"
                                            for g, r, w in zip(data.group, data.raw, data.wrench)]
    (tmp_path / "cell.csv").write_text("\n".join(lines) + "\n")
    read = ["--channels", "g_a,g_b,g_c", "--wrench", "Fx,Fy,Fz", "--groups", "pose"]
    assert main(["fit", str(tmp_path / "cell.csv"), *read, "--model", "linear", "--out", str(tmp_path / "m"),
                 "-q"]) == 0
    model = str(tmp_path / "m" / "linear.model.npz")
    budgets = []
    for out, extra in (("zero", ["--reference-uncertainty", given]), ("none", [])):
        assert main(["report", model, str(tmp_path / "cell.csv"), *read, "--no-baselines", *extra, "--out",
                     str(tmp_path / out), "-q"]) == 0, capsys.readouterr().err
        budgets.append(json.loads((tmp_path / out / "linear.report.json").read_text())["uncertainty_budget"])
    for zero, none in zip(*budgets):
        named = {c["name"]: c["standard_uncertainty"] for c in zero["components"]}
        assert named["reference standard"] == 0.0
        assert zero["expanded_uncertainty"] == pytest.approx(none["expanded_uncertainty"])  # adds nothing
    capsys.readouterr()
    err = one_error(capsys, main(["report", model, str(tmp_path / "cell.csv"), *read, "--no-baselines",
                                  "--reference-uncertainty", "-1%", "--out", str(tmp_path / "neg")]))
    assert "--reference-uncertainty" in err


# ---------------------------------------------------------------- 9. semicolons and tabs: the conversion that works
@pytest.mark.parametrize("sep, decimal", [(";", "."), (";", ","), ("\t", ".")])
def test_a_csv_separated_otherwise_is_told_the_conversion_and_the_converted_file_fits(tmp_path, capsys, sep,
                                                                                       decimal):
    import shlex
    import subprocess

    raw, wrench = sensor_data()
    text = write_csv(tmp_path / "comma.csv", raw, wrench).read_text()
    other = text.replace(",", "\0").replace(".", decimal).replace("\0", sep)
    (tmp_path / "IN.csv").write_text(other)
    err = one_error(capsys, main(["fit", str(tmp_path / "IN.csv"), "--model", "linear", "--out", str(tmp_path / "a")]))
    assert "IN.csv: line 1: the fields are separated by" in err
    command = err.split(", e.g. ", 1)[1].rstrip(".")  # the advice followed, as written
    subprocess.run(command, shell=True, cwd=tmp_path, check=True)
    assert (tmp_path / "OUT.csv").read_text() == text, shlex.quote(command)
    assert main(["fit", str(tmp_path / "OUT.csv"), "--model", "linear", "--out", str(tmp_path / "b"), "-q"]) == 0


# ---------------------------------------------------------------- 7. predict's bad input
@pytest.fixture
def six_channel_model(tmp_path):
    raw, wrench = sensor_data()
    path = write_csv(tmp_path / "train.csv", raw, wrench)
    assert main(["fit", str(path), "--model", "linear", "--out", str(tmp_path / "m"), "-q"]) == 0
    return str(tmp_path / "m" / "linear.model.npz"), raw


def test_predict_of_a_file_with_too_few_columns_writes_nothing_and_says_what_to_do(tmp_path, capsys,
                                                                                    six_channel_model):
    from scipy.io import savemat

    model, raw = six_channel_model
    capsys.readouterr()
    write_csv(tmp_path / "five.csv", raw[:5, :5], np.zeros((5, 0)), names=[f"s{i}" for i in range(5)])
    err = one_error(capsys, main(["predict", model, str(tmp_path / "five.csv")]))
    assert "five.csv: line 2: 5 channel columns (s0,s1,...) but the model takes 6" in err
    err = one_error(capsys, main(["predict", model, str(tmp_path / "train.csv"), "--channels", "s0..s4"]))
    assert "train.csv: line 2: 5 channel columns (s0,s1,s2,s3,s4)" in err
    savemat(tmp_path / "five.mat", {"raw": raw[:, :5]})
    err = one_error(capsys, main(["predict", model, str(tmp_path / "five.mat")]))
    assert "no array of the file holds 6 columns" in err and "--channels" not in err  # it could not help
    savemat(tmp_path / "eight.mat", {"data": np.hstack([raw, raw[:, :2]])})
    err = one_error(capsys, main(["predict", model, str(tmp_path / "eight.mat"), "--channels", "data[:,0:5]"]))
    assert "--channels (e.g. a column slice such as data[:,0:6])" in err
    assert main(["predict", model, str(tmp_path / "eight.mat"), "--channels", "data[:,0:6]"]) == 0  # followed
    assert capsys.readouterr().out.count("\n") == 1 + raw.shape[0]
    # nothing on stdout before the error (a header with no rows reads as an empty result)
    for argv in (["predict", model, str(tmp_path / "five.csv")], ["predict", model, str(tmp_path / "five.mat")]):
        assert main(argv) == 2 and capsys.readouterr().out == ""


def test_predict_refuses_drop_bad_readings_and_says_why(tmp_path, capsys, six_channel_model):
    model, _ = six_channel_model
    capsys.readouterr()
    err = one_error(capsys, main(["predict", model, str(tmp_path / "train.csv"), "--drop-bad-readings", "auto"]))
    assert "one wrench per input line" in err and capsys.readouterr().out == ""


# ---------------------------------------------------------------- 5d. beyond the range: a tolerance, clear words
def test_range_excess_ignores_a_hair_past_the_edge_and_says_how_far_past_which_edge():
    from ftcal.io import range_excess

    rng = np.random.default_rng(0)
    readings = np.round(500 + 400 * np.sin(np.arange(2000) / 50) + rng.normal(0, 2, 2000))  # an LSB and 2 of noise
    low, high = readings.min(), readings.max()
    again = readings + np.round(rng.normal(0, 2, 2000))  # the same loads read again: a few LSB past an edge
    assert (again > high).any() and not range_excess(again[:, None], [low], [high]).any
    asymmetric = np.array([[-3.0], [2.0], [11.2]])  # a range of 0..10: 3 below, 1.2 above
    found = range_excess(asymmetric, [0.0], [10.0], names=["Fx"], tolerance=[0.0])
    words = found.words({"Fx": "N"})
    assert "up to 3 N past the low edge (30 % of the calibrated span)" in words, words
    assert "x the range" not in words and found.axes[0].to_dict()["edge"] == "low"


# ---------------------------------------------------------------- 5b. steady data without groups: no false alarm
def test_steady_poses_without_a_group_column_give_no_repeated_rows_nor_stuck_channels():
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from test_reading_checks import static_poses

    from ftcal.io import check_readings

    found = []
    for seed in range(3):
        for noise in (0.3, 0.5, 0.8):  # quiet 10-bit channels: consecutive rows repeat by quantisation alone
            raw, wrench, _ = static_poses(n_groups=6, rows=200, noise=noise, seed=seed)
            found += check_readings(raw, wrench=wrench).findings  # no groups: six poses in one file
        rng = np.random.default_rng(seed)  # one static recording, one load
        still = np.round(512 + 0.3 * rng.standard_normal((2000, 6)))
        found += check_readings(still, wrench=np.tile([0, 0, 10.0, 0, 0, 0], (2000, 1))).findings
        found += check_readings(still).findings
    assert [f.where() for f in found] == []
    # a row the logger wrote twice is still found where the loads move
    raw, wrench = 1000 * rng.normal(size=(200, 6)), rng.normal(size=(200, 6))
    raw[150], wrench[150] = raw[40], wrench[40]
    assert [f.line for f in check_readings(raw, wrench=wrench).of_kind("repeated")] == [151]


# ---------------------------------------------------------------- 5a. a channel dead over whole groups
def test_a_channel_frozen_over_whole_groups_of_differing_loads_is_stuck():
    import sys
    from pathlib import Path

    sys.path.insert(0, str(Path(__file__).parent))
    from test_reading_checks import static_poses

    from ftcal.io import FindingKind, check_readings

    raw, wrench, group = static_poses(n_groups=12, rows=60, noise=2.0)
    dead = raw.copy()
    dead[group >= 6, 2] = dead[np.flatnonzero(group == 6)[0], 2]  # s2 dead for the second half of the recording
    found = check_readings(dead, wrench=wrench, groups=group)
    assert [(f.kind, f.line, f.channel, f.rows.size) for f in found.findings] == \
        [(FindingKind.STUCK, 361, "s2", 360)]
    for seed in range(3):  # live channels, quiet ones too, are not
        for noise in (0.2, 2.0):
            raw, wrench, group = static_poses(n_groups=12, rows=60, noise=noise, seed=seed)
            assert check_readings(raw, wrench=wrench, groups=group).clean


# ---------------------------------------------------------------- 5c. a genuine peak is no impossible reading
def test_a_genuine_peak_past_the_bulk_range_is_not_out_of_range_but_a_lone_jump_is():
    from ftcal.io import check_readings

    rng = np.random.default_rng(1)
    t = np.arange(20000)
    slow = 500 + 300 * np.sin(t / 400) + 3 * rng.standard_normal(t.size)  # a 10-bit bulk (0..1023)
    peak = 2100 * np.exp(-((t - 9000) / 12.0) ** 2)  # a rare load to 2600 (a 12-bit ADC), rising over samples
    x = np.round(slow + peak)
    quiet = np.round(500 + 3 * rng.standard_normal(t.size))
    found = check_readings(np.column_stack([x, quiet]))
    assert not found.of_kind("out_of_range"), found.summary()
    x[15000] = 4598  # alone beyond twice the range: a glitch
    found = check_readings(np.column_stack([x, quiet]))
    assert [(f.line, f.channel, f.value) for f in found.of_kind("out_of_range")] == [(15001, "s0", 4598.0)]


# ---------------------------------------------------------------- 6. a headerless log with a text run column
def test_a_headerless_log_whose_run_column_is_text_is_read_with_columns(tmp_path, capsys):
    from ftcal.io import has_header

    raw, wrench = sensor_data(n=120)
    lines = [f"run_{i // 20:02d}," + ",".join(f"{v:.10g}" for v in row) for i, row in
             enumerate(np.hstack([raw, wrench]))]
    (tmp_path / "runs.txt").write_text("\n".join(lines) + "\n")
    assert not has_header(tmp_path / "runs.txt")  # text where the next line has text too: data, not names
    (tmp_path / "named.csv").write_text("run,s0\nrun_00,5\n")
    assert has_header(tmp_path / "named.csv")  # text above a number: a header
    columns = ["--columns", "run,s0..s5,Fx,Fy,Fz,Tx,Ty,Tz", "--groups", "run"]
    assert main(["fit", str(tmp_path / "runs.txt"), *columns, "--model", "linear", "--out", str(tmp_path / "m"),
                 "-q"]) == 0
    lines[30] = lines[30].replace(",", ",oops,", 1).replace(f",{raw[30, 0]:.10g}", "", 1)  # text in a number column
    (tmp_path / "runs.txt").write_text("\n".join(lines) + "\n")
    err = one_error(capsys, main(["fit", str(tmp_path / "runs.txt"), *columns, "--model", "linear", "--out",
                                  str(tmp_path / "n")]))
    assert "runs.txt: line 31: 'oops' is not a finite number" in err
