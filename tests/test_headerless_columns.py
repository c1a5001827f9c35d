"""Files without a header, named by the user: ``--columns`` names their columns and joins several side by side
(a gravity-compensation tool's pose file and wrench file), on every command that reads data."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

import ftcal
from ftcal.cli import build_parser, main
from ftcal.core import DatasetFileError
from ftcal.io import has_header, join_headerless

POSE_AND_WRENCH = "x,y,z,qx,qy,qz,qw,Fx,Fy,Fz,Tx,Ty,Tz"


def one_line_error(capsys, code: int) -> str:
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1 and err.startswith("ftcal: error:"), err
    return err


@pytest.fixture
def tool_files(tmp_path):
    """A 0.8 kg tool at 40 static poses: pose.txt (x y z qx qy qz qw, spaces) and wrench.txt (Fx..Tz, commas), both
    without a header, as a public gravity-compensation tool writes them."""
    rng = np.random.default_rng(0)
    q = Rotation.random(40, random_state=1).as_quat()
    force = np.einsum("nji,j->ni", Rotation.from_quat(q).as_matrix(), [0.0, 0.0, -9.81 * 0.8])
    wrench = np.hstack([force, np.cross([0.0, 0.01, 0.04], force)]) + 0.005 * rng.normal(size=(40, 6))
    np.savetxt(tmp_path / "pose.txt", np.hstack([rng.normal(size=(40, 3)), q]), fmt="%.9f")
    np.savetxt(tmp_path / "wrench.txt", wrench, fmt="%.9f", delimiter=",")
    return tmp_path


def test_the_pose_and_wrench_pair_identifies_the_tool(tool_files, capsys):
    code = main(["identify-load", str(tool_files / "pose.txt"), str(tool_files / "wrench.txt"), "--columns",
                 POSE_AND_WRENCH, "--out", str(tool_files / "tool")])
    assert code == 0, capsys.readouterr().err
    tool = ftcal.experiment.ToolLoad.load(tool_files / "tool" / "tool.tool.json")
    assert tool.mass == pytest.approx(0.8, abs=0.002)
    assert main(["compensate", str(tool_files / "pose.txt"), str(tool_files / "wrench.txt"), "--columns",
                 POSE_AND_WRENCH, "--tool", str(tool_files / "tool" / "tool.tool.json"), "--output",
                 str(tool_files / "external.csv")]) == 0
    external = np.loadtxt(tool_files / "external.csv", delimiter=",", skiprows=1)[:, 1:]
    assert external.shape == (40, 6) and np.abs(external[:, :3]).max() < 0.05  # the tool's weight taken out


def test_a_headerless_file_without_columns_is_one_line_naming_the_option(tool_files, capsys):
    code = main(["identify-load", str(tool_files / "pose.txt"), str(tool_files / "wrench.txt"), "--out",
                 str(tool_files / "tool")])
    err = one_line_error(capsys, code)
    assert "pose.txt: the file has no header line" in err and "--columns" in err and "--model" not in err


def test_files_of_different_row_counts_are_named_with_their_counts(tool_files, capsys):
    lines = (tool_files / "wrench.txt").read_text().splitlines()
    (tool_files / "short.txt").write_text("\n".join(lines[:37]) + "\n")
    code = main(["identify-load", str(tool_files / "pose.txt"), str(tool_files / "short.txt"), "--columns",
                 POSE_AND_WRENCH, "--out", str(tool_files / "tool")])
    err = one_line_error(capsys, code)
    assert "pose.txt holds 40 rows but" in err and "short.txt holds 37" in err
    code = main(["identify-load", str(tool_files / "pose.txt"), str(tool_files / "wrench.txt"), "--columns",
                 POSE_AND_WRENCH.rsplit(",", 1)[0], "--out", str(tool_files / "tool")])
    err = one_line_error(capsys, code)
    assert "--columns names 12 columns but the files hold 13" in err and "pose.txt (7)" in err


def test_join_headerless_keeps_the_rows_in_order_and_refuses_a_header(tmp_path):
    (tmp_path / "a.txt").write_text("# recorded 2026\n1 2\n\n3 4\n")
    (tmp_path / "b.txt").write_text("5\n6\n")
    table = join_headerless([tmp_path / "a.txt", tmp_path / "b.txt"], ["s0", "s1", "Fz"])
    assert table.rows == [["1", "2", "5"], ["3", "4", "6"]] and table.lines == (2, 4)
    assert table.to_csv().splitlines()[:2] == ["# recorded 2026", "s0,s1,Fz"]
    (tmp_path / "c.csv").write_text("s0,s1\n1,2\n")
    assert has_header(tmp_path / "c.csv") and not has_header(tmp_path / "a.txt")
    with pytest.raises(DatasetFileError, match="has a header"):
        join_headerless([tmp_path / "c.csv"], ["s0", "s1"])


def test_fit_evaluate_and_predict_read_a_headerless_dataset(tmp_path, capsys):
    rng = np.random.default_rng(2)
    raw = rng.normal(size=(120, 6))
    wrench = raw @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(120, 6))
    np.savetxt(tmp_path / "data.txt", np.hstack([raw, wrench]), fmt="%.9f")
    np.savetxt(tmp_path / "raw.txt", raw, fmt="%.9f", delimiter=",")
    names = "s0..s5,Fx,Fy,Fz,Tx,Ty,Tz"
    assert main(["fit", str(tmp_path / "data.txt"), "--model", "linear", "--out", str(tmp_path / "m")]) == 2
    assert "--columns" in capsys.readouterr().err
    assert main(["fit", str(tmp_path / "data.txt"), "--columns", names, "--model", "linear", "--out",
                 str(tmp_path / "m")]) == 0
    assert main(["evaluate", str(tmp_path / "data.txt"), str(tmp_path / "m" / "linear.model.npz"), "--columns",
                 names, "--no-plots", "--out", str(tmp_path / "eval")]) == 0
    capsys.readouterr()
    assert main(["predict", str(tmp_path / "m" / "linear.model.npz"), str(tmp_path / "raw.txt"), "--columns",
                 "s0..s5", "--output", str(tmp_path / "w.csv")]) == 0
    predicted = np.loadtxt(tmp_path / "w.csv", delimiter=",", skiprows=1)
    assert np.abs(predicted - wrench).max() < 0.1
    capsys.readouterr()
    bad = (tmp_path / "data.txt").read_text().splitlines()
    bad[6] = bad[6].replace(bad[6].split()[2], "oops", 1)
    (tmp_path / "bad.txt").write_text("\n".join(bad) + "\n")
    code = main(["fit", str(tmp_path / "bad.txt"), "--columns", names, "--model", "linear", "--out",
                 str(tmp_path / "m2")])
    err = one_line_error(capsys, code)
    assert "bad.txt: line 7: 'oops' is not a finite number" in err  # the user's own file and line


@pytest.mark.parametrize("command", ["fit", "evaluate", "report", "predict", "retare", "compensate",
                                     "identify-load", "prepare"])
def test_every_command_that_reads_data_takes_columns(command):
    parser = build_parser()
    sub = next(a for a in parser._actions if hasattr(a, "choices") and a.choices and "fit" in a.choices)
    assert "--columns" in sub.choices[command]._option_string_actions
