"""The ``ftcal`` command line through ``main(argv)``: framework, errors, --force, fit/evaluate/predict."""

from __future__ import annotations

import io
import json
from pathlib import Path

import numpy as np
import pytest

import ftcal
from ftcal import CalibrationDataset
from ftcal.cli import main

SUBCOMMANDS = ["simulate", "plan", "prepare", "fit", "tune", "evaluate", "predict", "benchmark", "demo"]

# A known affine sensor: raw = A @ wrench + b, so the exact calibration is wrench = A^-1 (raw - b).
_RNG = np.random.default_rng(42)
A = np.eye(6) * 1e-3 + _RNG.normal(scale=1e-4, size=(6, 6))
B = np.array([0.1, -0.2, 0.05, 0.0, 0.3, -0.1])


def raw_of(wrench: np.ndarray) -> np.ndarray:
    return wrench @ A.T + B


def wrenches(n: int, seed: int) -> np.ndarray:
    rng = np.random.default_rng(seed)
    return rng.uniform(-1, 1, size=(n, 6)) * [500, 500, 500, 10, 10, 10]


@pytest.fixture(scope="module")
def affine_dir(tmp_path_factory) -> Path:
    """train.csv / test.csv from the exact affine sensor, and a linear model fitted by the CLI."""
    d = tmp_path_factory.mktemp("affine")
    for name, seed, n in (("train", 0, 60), ("test", 1, 25)):
        w = wrenches(n, seed)
        CalibrationDataset(raw=raw_of(w), wrench=w, meta={"alpha": 50.0}).save(d / f"{name}.csv")
    assert main(["fit", str(d / "train.csv"), "--model", "linear", "--out", str(d / "models"), "-q"]) == 0
    return d


def one_error_line(capsys) -> str:
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    assert lines[0].startswith("ftcal: error: "), err
    assert "Traceback" not in err
    return lines[0]


def read_csv(text: str) -> tuple[list[str], np.ndarray]:
    lines = text.strip().splitlines()
    return lines[0].split(","), np.array([[float(v) for v in line.split(",")] for line in lines[1:]])


# ------------------------------------------------------------------ framework
@pytest.mark.parametrize("command", SUBCOMMANDS)
def test_every_subcommand_has_help_with_an_example(command, capsys):
    assert main([command, "--help"]) == 0
    out = capsys.readouterr().out
    assert f"ftcal {command}" in out
    assert "example" in out.lower()


def test_version_and_top_level_help(capsys):
    assert main(["--version"]) == 0
    assert capsys.readouterr().out.strip() == f"ftcal {ftcal.__version__}"
    assert main(["--help"]) == 0
    out = capsys.readouterr().out
    assert all(c in out for c in SUBCOMMANDS)


@pytest.mark.parametrize(
    "argv, fragment",
    [
        ([], "required"),
        (["calibrate"], "invalid choice"),
        (["fit", "x.csv", "--model", "quadratic"], "invalid choice"),
        (["simulate", "dataset", "--seed", "-3"], "--seed"),
        (["simulate", "dataset", "--n-test", "zero"], "integer >= 1"),
        (["simulate", "dataset", "--n-per-sphere", "100000000000"], "at most 1000000"),
        (["fit"], "dataset"),
        (["predict", "no_such_model.npz"], "no_such_model.npz does not exist"),
    ],
)
def test_bad_arguments_give_one_line_and_exit_2(argv, fragment, capsys):
    assert main(argv) == 2
    assert fragment in one_error_line(capsys)


def test_missing_dataset_file_names_it(tmp_path, capsys):
    assert main(["fit", str(tmp_path / "nope.csv"), "--out", str(tmp_path / "m")]) == 2
    assert "nope.csv" in one_error_line(capsys)
    assert not (tmp_path / "m").exists()


def test_malformed_dataset_names_file_and_problem(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("s0,s1,s2,a,b,c\n1,2,3,4,5,6\n")  # no wrench column (any of Fx..Tz makes an n-axis dataset)
    assert main(["fit", str(bad), "--out", str(tmp_path / "m"), "-q"]) == 2
    line = one_error_line(capsys)
    assert "bad.csv" in line and "no wrench columns" in line and "--wrench" in line


def test_garbage_model_file_gives_one_line(tmp_path, affine_dir, capsys):
    garbage = tmp_path / "model.npz"
    garbage.write_bytes(b"this is not a model")
    assert main(["predict", str(garbage), str(affine_dir / "test.csv")]) == 2
    assert "model.npz" in one_error_line(capsys)


def test_out_that_is_a_file_is_refused(tmp_path, affine_dir, capsys):
    (tmp_path / "taken").write_text("mine")
    assert main(["fit", str(affine_dir / "train.csv"), "--model", "linear", "--out", str(tmp_path / "taken")]) == 2
    assert "not a directory" in one_error_line(capsys)
    assert (tmp_path / "taken").read_text() == "mine"


# ------------------------------------------------------------------ --force
def test_existing_outputs_are_kept_without_force_and_checked_before_work(tmp_path, affine_dir, capsys, monkeypatch):
    out = tmp_path / "models"
    out.mkdir()
    (out / "linear.model.npz").write_text("the user's own file")

    def must_not_be_called(*args, **kwargs):
        raise AssertionError("the model was built although the output file exists")

    monkeypatch.setattr(ftcal, "make_calibrator", must_not_be_called)
    assert main(["fit", str(affine_dir / "train.csv"), "--model", "linear", "--out", str(out)]) == 2
    line = one_error_line(capsys)
    assert "--force" in line and "linear.model.npz" in line
    assert (out / "linear.model.npz").read_text() == "the user's own file"
    assert not (out / "linear.fit.json").exists()


def test_force_overwrites(tmp_path, affine_dir):
    out = tmp_path / "models"
    out.mkdir()
    (out / "linear.model.npz").write_text("old")
    argv = ["fit", str(affine_dir / "train.csv"), "--model", "linear", "--out", str(out), "-q", "--force"]
    assert main(argv) == 0
    model = ftcal.load_model(out / "linear.model.npz")
    assert model.n_features_in_ == 6


# ------------------------------------------------------------------ fit / predict / evaluate
def test_fit_linear_recovers_the_known_sensor(affine_dir):
    model = ftcal.load_model(affine_dir / "models" / "linear.model.npz")
    w = wrenches(5, 99)
    np.testing.assert_allclose(model.predict(raw_of(w)), w, atol=1e-6)
    summary = json.loads((affine_dir / "models" / "linear.fit.json").read_text())
    assert summary["n_samples"] == 60 and summary["model"] == "linear"
    assert summary["alpha"] == 50.0  # taken from the dataset's meta
    assert summary["training_rmse"] < 1e-6


def test_fit_passes_params_and_tare(tmp_path, affine_dir):
    tare = ",".join(str(v) for v in B)
    argv = ["fit", str(affine_dir / "train.csv"), "--model", "linear", "--tare", tare,
            "--param", "ridge=0.0", "--name", "tared", "--out", str(tmp_path), "-q"]
    assert main(argv) == 0
    model = ftcal.load_model(tmp_path / "tared.model.npz")
    np.testing.assert_allclose(model.zero_reading_, B)


def test_fit_unknown_param_names_the_known_ones(tmp_path, affine_dir, capsys):
    argv = ["fit", str(affine_dir / "train.csv"), "--model", "linear", "--param", "phase1_epochs=3", "--out", str(tmp_path)]
    assert main(argv) == 2
    line = one_error_line(capsys)
    assert "phase1_epochs" in line and "ridge" in line


def test_fit_group_offsets_need_a_group_column(tmp_path, affine_dir, capsys):
    argv = ["fit", str(affine_dir / "train.csv"), "--model", "polynomial", "--param", "group_offsets=true",
            "--out", str(tmp_path / "out")]
    assert main(argv) == 2
    assert "group_offsets=true needs one group" in one_error_line(capsys)
    assert not (tmp_path / "out").exists()  # nothing written


def test_an_existing_output_file_names_the_option_of_its_command(tmp_path, affine_dir, capsys):
    target = tmp_path / "m.onnx"
    target.write_text("mine")
    model = affine_dir / "models" / "linear.model.npz"
    assert main(["export", str(model), "--output", str(target)]) == 2
    assert "choose another --output" in one_error_line(capsys)
    assert target.read_text() == "mine"


def test_fit_tare_of_wrong_length_is_refused(tmp_path, affine_dir, capsys):
    argv = ["fit", str(affine_dir / "train.csv"), "--model", "linear", "--tare", "1,2,3", "--out", str(tmp_path)]
    assert main(argv) == 2
    assert "--tare has 3 values" in one_error_line(capsys)


def test_predict_stdin_to_stdout_is_a_clean_csv(affine_dir, capsys, monkeypatch):
    w = wrenches(4, 7)
    text = "# a comment\n" + "\n".join(" ".join(f"{v:.12g}" for v in row) for row in raw_of(w)) + "\n\n"
    monkeypatch.setattr("sys.stdin", io.StringIO(text))
    assert main(["predict", str(affine_dir / "models" / "linear.model.npz")]) == 0
    captured = capsys.readouterr()
    # at most the one warning that some readings lie beyond the training readings (random loads here)
    assert all(line.startswith("ftcal: warning:") and "beyond the calibrated range" in line
               for line in captured.err.splitlines())
    header, values = read_csv(captured.out)
    assert header == ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"]
    np.testing.assert_allclose(values, w, atol=1e-5)


def test_predict_line_buffered_and_headed_input(affine_dir, capsys, monkeypatch):
    w = wrenches(3, 8)
    raw = raw_of(w)
    # columns in another order with extra ones: only s0..s5 are used, in channel order
    lines = ["t,s5,s4,s3,s2,s1,s0"] + [",".join([str(i)] + [f"{v:.12g}" for v in r[::-1]]) for i, r in enumerate(raw)]
    monkeypatch.setattr("sys.stdin", io.StringIO("\n".join(lines)))
    model = str(affine_dir / "models" / "linear.model.npz")
    assert main(["predict", model, "-", "--line-buffered", "--no-header"]) == 0
    out = capsys.readouterr().out
    np.testing.assert_allclose(np.loadtxt(io.StringIO(out), delimiter=",", ndmin=2), w, atol=1e-5)


@pytest.mark.parametrize("sep, decimal", [("\t", "."), ("\t", ","), (";", ".")])
def test_predict_refuses_tab_or_semicolon_readings_in_the_words_fit_refuses_them(tmp_path, affine_dir, capsys,
                                                                                 monkeypatch, sep, decimal):
    import subprocess

    text = (affine_dir / "test.csv").read_text()
    other = "".join(line.replace(",", "\0").replace(".", decimal).replace("\0", sep) + "\n"
                    for line in text.splitlines() if not line.startswith("#"))
    (tmp_path / "IN.csv").write_text(other)
    assert main(["fit", str(tmp_path / "IN.csv"), "--model", "linear", "--out", str(tmp_path / "m")]) == 2
    refused = one_error_line(capsys)
    model = str(affine_dir / "models" / "linear.model.npz")
    assert main(["predict", model, str(tmp_path / "IN.csv")]) == 2
    assert one_error_line(capsys) == refused  # the same words
    monkeypatch.setattr("sys.stdin", io.StringIO(other))
    assert main(["predict", model]) == 2
    assert one_error_line(capsys) == refused.replace(str(tmp_path / "IN.csv"), "stdin")
    command = refused.split(", e.g. ", 1)[1].rstrip(".")  # the advice followed, as written
    subprocess.run(command, shell=True, cwd=tmp_path, check=True)
    assert main(["predict", model, str(tmp_path / "OUT.csv"), "--output", str(tmp_path / "w.csv"), "-q"]) == 0
    assert len((tmp_path / "w.csv").read_text().splitlines()) == 1 + 25


def test_predict_names_the_line_byte_and_conversion_of_a_file_that_is_not_utf8(tmp_path, affine_dir, capsys):
    src = tmp_path / "raw.csv"
    lines = [b"# reading at 20 \xb0C", b"1,2,3,4,5,6"]  # a Latin-1 degree sign in a comment
    src.write_bytes(b"\n".join(lines) + b"\n")
    model = str(affine_dir / "models" / "linear.model.npz")
    assert main(["predict", model, str(src)]) == 2
    line = one_error_line(capsys)
    assert f"{src}: line 1 (byte 16): not UTF-8 text (invalid start byte)" in line
    assert "Fix: save it as UTF-8, e.g. iconv -f LATIN1 -t UTF-8 raw.csv > raw-utf8.csv" in line
    src.write_bytes(b"1,2,3,4,5,6\r\n" * 3 + b"1,2,3,4,5,6 \xe9\n")  # byte 3 * 13 + 12: CR LF counted
    assert main(["predict", model, str(src)]) == 2
    assert f"{src}: line 4 (byte 51): not UTF-8 text" in one_error_line(capsys)
    src.write_bytes("s0,s1,s2,s3,s4,s5\n1,2,3,4,5,6\n".encode("utf-16"))
    assert main(["predict", model, str(src)]) == 2
    assert "UTF-16 text (it starts with a UTF-16 byte-order mark), not UTF-8" in one_error_line(capsys)


def test_predict_names_the_byte_of_standard_input_that_is_not_utf8(affine_dir):
    import subprocess
    import sys

    proc = subprocess.run([sys.executable, "-m", "ftcal", "predict", str(affine_dir / "models" / "linear.model.npz")],
                          input=b"1,2,3,4,5,6\n1,2,3,\xff,5,6\n", capture_output=True)
    assert proc.returncode == 2
    assert "stdin: line 2 (byte 18): not UTF-8 text (invalid start byte)" in proc.stderr.decode()
    assert "iconv -f LATIN1 -t UTF-8" in proc.stderr.decode()


def test_predict_bad_line_names_source_and_line(tmp_path, affine_dir, capsys):
    src = tmp_path / "raw.txt"
    src.write_text("1,2,3,4,5,6\n1,2,3,4,5,6\n1,2,x,4,5,6\n")
    assert main(["predict", str(affine_dir / "models" / "linear.model.npz"), str(src)]) == 2
    line = one_error_line(capsys)
    assert "raw.txt: line 3" in line and "'x'" in line


def test_predict_to_file_respects_force(tmp_path, affine_dir, capsys):
    model = str(affine_dir / "models" / "linear.model.npz")
    target = tmp_path / "wrench.csv"
    target.write_text("keep me")
    assert main(["predict", model, str(affine_dir / "test.csv"), "--output", str(target)]) == 2
    one_error_line(capsys)
    assert target.read_text() == "keep me"
    assert main(["predict", model, str(affine_dir / "test.csv"), "--output", str(target), "--force", "-q"]) == 0
    header, values = read_csv(target.read_text())
    np.testing.assert_allclose(values, CalibrationDataset.load(affine_dir / "test.csv").wrench, atol=1e-5)


def test_evaluate_reports_hand_computable_errors(tmp_path, affine_dir, capsys):
    # The exact model on a test set whose reference Fx is off by +2 N and Tz by -0.1 N·m:
    # axis RMSE (2, 0, 0, 0, 0, 0.1); eq. 18 with alpha 50: sqrt((2² + (50·0.1)²) / 6).
    test = CalibrationDataset.load(affine_dir / "test.csv")
    shifted = test.wrench + [2.0, 0, 0, 0, 0, -0.1]
    CalibrationDataset(raw=test.raw, wrench=shifted, meta={"alpha": 50.0}).save(tmp_path / "shifted.csv")
    argv = ["evaluate", str(tmp_path / "shifted.csv"), str(affine_dir / "models" / "linear.model.npz"),
            "--out", str(tmp_path / "eval"), "-q"]
    assert main(argv) == 0
    out = capsys.readouterr().out
    assert out.startswith("| model | RMSE [N]")
    metrics = json.loads((tmp_path / "eval" / "metrics.json").read_text())
    rep = metrics["models"]["linear"]
    assert rep["rmse"] == pytest.approx(np.sqrt((4 + 25) / 6), rel=1e-5)
    assert rep["axis_rmse"]["Fx"] == pytest.approx(2.0, rel=1e-5)
    assert rep["axis_rmse"]["Tz"] == pytest.approx(0.1, rel=1e-4)
    assert rep["axis_rmse"]["Fy"] == pytest.approx(0.0, abs=1e-5)
    for name in ("rmse_distribution.png", "axis_rmse.png", "errors_linear.png", "metrics.md"):
        assert (tmp_path / "eval" / name).stat().st_size > 0


def test_evaluate_channel_mismatch_is_one_line(tmp_path, affine_dir, capsys):
    w = wrenches(10, 3)
    CalibrationDataset(raw=np.hstack([raw_of(w), raw_of(w)[:, :2]]), wrench=w).save(tmp_path / "eight.csv")
    argv = ["evaluate", str(tmp_path / "eight.csv"), str(affine_dir / "models" / "linear.model.npz"),
            "--out", str(tmp_path / "e")]
    assert main(argv) == 2
    assert "8" in one_error_line(capsys)


def test_the_command_line_starts_without_torch_or_pinocchio():
    # `ftcal --help` must be instant: the heavy libraries load only inside the subcommand that needs them
    import subprocess
    import sys

    code = ("import sys, ftcal.cli; ftcal.cli.build_parser(); "
            "print(sorted(m for m in ('torch', 'pinocchio', 'skorch', 'sklearn') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


@pytest.mark.parametrize("argv, got", [(["fit", "--model=--", "d.csv"], "'--'"), (["fit", "d.csv", "--out=--"], "'--'"),
                                       (["predict", "--output=--", "m.npz"], "'--'"),
                                       (["fit", "d.csv", "--torque-unit="], "an empty value"),
                                       (["fit", "d.csv", "--name="], "an empty value")])
def test_an_option_given_two_dashes_or_nothing_is_a_usage_error(argv, got, capsys):
    # argparse hands `--name=--` to the option as an empty list (that crashed), and `--torque-unit=` (an unset
    # shell variable) meant the default unit, silently confirming N·mm torques as N·m
    assert main(argv) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("ftcal: error: argument ") and f"expected a value, got {got}" in err[0]


@pytest.mark.parametrize("option, value", [("--excluded-cap-deg", "nan"), ("--space-filling", "inf"),
                                           ("--load-mass", "nan")])
def test_plan_refuses_non_finite_numbers_at_the_command_line(option, value, capsys, tmp_path):
    assert main(["plan", option, value, "--out", str(tmp_path / "p")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err[-1].startswith(f"ftcal: error: argument {option}: '{value}' is not a") and not (tmp_path / "p").exists()


def test_plan_warns_when_too_few_poses_remain_for_the_linear_model(tmp_path, capsys):
    assert main(["plan", "--excluded-cap-deg", "179.9", "--out", str(tmp_path / "p"), "-q"]) == 0
    err = capsys.readouterr().err
    assert "ftcal: warning: 1 poses cannot calibrate even the linear model (it needs 7" in err


@pytest.mark.parametrize("make, words", [
    (lambda p: p.write_text("s0,s1\n1,2\n"), "not an .npz (zip) archive"),
    (lambda p: np.savez(p, raw=np.array([[1, "a"]], dtype=object)), "holds Python objects"),
    (lambda p: p.write_bytes(_valid_npz_bytes()[:200]), "not an .npz (zip) archive"),
])
def test_a_broken_readings_npz_gets_advice_for_readings_not_for_a_dataset(affine_dir, tmp_path, capsys, make, words):
    # predict reads its .npz through the library's ArrayFile: the advice must name readings (the array raw), not a
    # dataset's raw and wrench
    path = tmp_path / "readings.npz"
    make(path)
    assert main(["predict", str(affine_dir / "models" / "linear.model.npz"), str(path)]) == 2
    line = one_error_line(capsys)
    assert words in line and str(path) in line and "raw" in line
    assert "wrench" not in line and "dataset" not in line


def _valid_npz_bytes() -> bytes:
    import io

    buffer = io.BytesIO()
    np.savez(buffer, raw=np.ones((50, 6)))
    return buffer.getvalue()
