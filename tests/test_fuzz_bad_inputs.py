"""The bad inputs and faults found by fuzzing, kept as a regression suite.

Each case is a real call (library or CLI) with a bad input; each must end in a clear domain error (a
``ValueError`` subclass naming what is wrong, or ``ftcal: error: ...`` and exit 2 on the command line) or in
the right answer, and must never lose or overwrite a file the user had.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

import ftcal
from ftcal.core import CalFileError, CalibrationInputError, DatasetFileError, LogFormatError, ModelFileError
from ftcal import (CalibrationDataset, ComparativeCalibrator, DirectionalCalibrator, LinearCalibrator,
                   PolynomialCalibrator)
from ftcal.core._files import atomic_output
from ftcal.cli import main

from conftest import SMALL_NET_CLI

TINY = dict(hidden_layer_sizes=(8,), phase1_epochs=3, plateau_epochs=1, max_recover_epochs=1, random_state=0)


def sha(path: Path) -> str:
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


def run(argv) -> int:
    return main([str(a) for a in argv])


def cli_error(argv, capsys) -> str:
    """Run the CLI, require exit 2 and exactly one 'ftcal: error:' line; return it."""
    code = main([str(a) for a in argv])
    err = capsys.readouterr().err.strip().splitlines()
    assert code == 2, err
    assert len(err) == 1 and err[0].startswith("ftcal: error: "), err
    return err[0]


@pytest.fixture(scope="module")
def workdir(tmp_path_factory):
    """A small simulated dataset and fitted linear / comparative / directional model files."""
    root = tmp_path_factory.mktemp("fuzz")
    assert main(["simulate", "dataset", "--n-per-sphere", "25", "--n-test", "50", "--out", str(root / "data"),
                 "-q"]) == 0
    for model in ("linear", "comparative", "directional"):
        extra = [] if model == "linear" else SMALL_NET_CLI
        assert run(["fit", str(root / "data" / "train.csv"), "--model", model, *extra, "--out",
                     str(root / "models"), "-q"]) == 0
    return root


def data_lines(workdir) -> tuple[list[str], list[str]]:
    lines = (workdir / "data" / "train.csv").read_text().splitlines()
    comments = [ln for ln in lines if ln.startswith("#")]
    return comments, [ln for ln in lines if not ln.startswith("#")]


# ------------------------------------------------------------------ 1. interrupts propagate, nothing is saved
def _default_sigint() -> None:
    # A test run started in the background (CI, `cmd &`) ignores SIGINT, one started by nohup SIGHUP, and the
    # children inherit that (ftcal keeps an ignored signal ignored, as it should); give the child the default
    # dispositions, as a terminal gives a program the user may Ctrl-C or close.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    if hasattr(signal, "SIGHUP"):
        signal.signal(signal.SIGHUP, signal.SIG_DFL)


def _start_cli(args, cwd) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "ftcal", *map(str, args)], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint)


def _interrupt_after_training_starts(proc: subprocess.Popen, marker: str, sig=signal.SIGINT) -> tuple[int, str]:
    lines = []
    for line in proc.stderr:  # the run says what it fits before the epochs start
        lines.append(line)
        if marker in line:
            break
    time.sleep(2.0)  # well inside a 20 000-epoch run
    proc.send_signal(sig)
    rest = proc.communicate(timeout=120)[1]
    return proc.returncode, "".join(lines) + rest


@pytest.mark.parametrize("command, sig", [("fit", signal.SIGINT), ("fit", signal.SIGTERM), ("tune", signal.SIGINT)])
def test_ctrl_c_stops_training_and_saves_nothing(workdir, tmp_path, command, sig):
    out = tmp_path / "models"
    out.mkdir()
    long_run = ["--param", "phase1_epochs=20000", "--param", "hidden_layer_sizes=[8]"]
    if command == "fit":
        args = ["fit", workdir / "data" / "train.csv", "--model", "directional", "--schedule", "short", *long_run,
                "--out", out, "--force"]
        good = out / "directional.model.npz"
    else:
        args = ["tune", workdir / "data" / "train.csv", "--model", "directional", "--n-iter", "1", "--cv", "2",
                "--grid", "lr=[0.001]", *long_run, "--out", out, "--force"]
        good = out / "directional.model.npz"
    good.write_bytes((workdir / "models" / "directional.model.npz").read_bytes())  # the user's good model
    before = sha(good)
    code, err = _interrupt_after_training_starts(_start_cli(args, tmp_path), "fitting" if command == "fit" else "searching",
                                                 sig)
    # 128 + the signal number, as a shell reports it; -2 (CPython killing itself after an unhandled
    # KeyboardInterrupt) only ever came from a Ctrl-C before main() ran (see ftcal/__main__.py)
    assert code == 128 + sig, err
    assert f"interrupted by {signal.Signals(sig).name}" in err and "Traceback" not in err
    assert sha(good) == before  # --force did not replace the good model with a half-trained one
    assert not list(out.glob(".*partial*"))


# ------------------------------------------------------------------ 2-4. outputs never collide or destroy inputs
def test_atomic_outputs_use_unique_temporary_files_and_never_replace_a_newer_file(tmp_path):
    target = tmp_path / "o.csv"
    first = atomic_output(target, overwrite=False, error=FileExistsError)
    second = atomic_output(target, overwrite=False, error=FileExistsError)
    a, b = first.__enter__(), second.__enter__()
    assert a != b  # two concurrent writers never share a temporary file
    a.write_text("first\n")
    b.write_text("second\n")
    first.__exit__(None, None, None)
    with pytest.raises(FileExistsError, match="appeared while this run was working"):
        second.__exit__(None, None, None)
    assert target.read_text() == "first\n"  # the first finished run's file is not replaced
    kept = list(tmp_path.glob("o.*.csv"))
    assert [k.read_text() for k in kept] == ["second\n"]  # the second run's output is kept, not lost
    assert not list(tmp_path.glob(".*partial*"))


def test_concurrent_predict_runs_leave_one_complete_output(workdir, tmp_path):
    out = tmp_path / "o.csv"
    inputs = []
    for k, rows in enumerate((400, 600)):
        raw = np.random.default_rng(k).normal(size=(rows, 6))
        path = tmp_path / f"in{k}.csv"
        np.savetxt(path, raw, delimiter=",")
        inputs.append(path)
    model = workdir / "models" / "linear.model.npz"
    procs = [_start_cli(["predict", model, p, "--output", out], tmp_path) for p in inputs]
    results = [p.communicate(timeout=120) for p in procs]
    codes = sorted(p.returncode for p in procs)
    assert codes == [0, 2], results
    lines = out.read_text().splitlines()
    assert lines[0] == "Fx,Fy,Fz,Tx,Ty,Tz" and len(lines) - 1 in (400, 600)  # one run's rows, whole


@pytest.mark.parametrize("victim", ["input", "model"])
def test_predict_output_onto_input_or_model_is_refused(workdir, tmp_path, capsys, victim):
    model = tmp_path / "m.model.npz"
    model.write_bytes((workdir / "models" / "linear.model.npz").read_bytes())
    readings = tmp_path / "r.csv"
    readings.write_text("0.1,0.2,0.3,0.4,0.5,0.6\n")
    target = readings if victim == "input" else model
    before = sha(target)
    msg = cli_error(["predict", model, readings, "--output", target, "--force"], capsys)
    assert f"is the {victim} file" in msg
    assert sha(target) == before


def test_dataset_save_does_not_overwrite(tmp_path):
    ds = CalibrationDataset(raw=np.eye(8, 6), wrench=np.eye(8, 6))
    path = ds.save(tmp_path / "d.csv")
    before = sha(path)
    with pytest.raises(DatasetFileError, match="already exists; pass overwrite=True"):
        CalibrationDataset(raw=np.ones((8, 6)), wrench=np.eye(8, 6)).save(path)
    assert sha(path) == before
    ds.save(path, overwrite=True)


# ------------------------------------------------------------------ 5. one header reader
def test_bom_header_keeps_every_channel(workdir, tmp_path, capsys):
    comments, body = data_lines(workdir)
    bom = tmp_path / "bom.csv"
    bom.write_bytes(b"\xef\xbb\xbf" + "\n".join(body).encode() + b"\n")
    ds = CalibrationDataset.load(bom)
    assert ds.n_channels == 6
    assert run(["fit", bom, "--model", "linear", "--out", tmp_path / "fit", "-q"]) == 0
    summary = json.loads((tmp_path / "fit" / "linear.fit.json").read_text())
    assert summary["n_channels"] == 6
    # the same numbers as the file without the BOM
    plain = CalibrationDataset.load(workdir / "data" / "train.csv")
    np.testing.assert_array_equal(ds.raw, plain.raw)
    # predict reads a BOM-prefixed stream too
    stream = tmp_path / "bom_readings.csv"
    stream.write_bytes(b"\xef\xbb\xbf0.1,0.2,0.3,0.4,0.5,0.6\n")
    assert run(["predict", workdir / "models" / "linear.model.npz", stream]) == 0


@pytest.mark.parametrize(
    "edit, message",
    [
        (lambda h: h.replace("s1,", "s0,", 1), "column 's0' appears 2 times"),
        (lambda h: h.replace("s2,", "s\u0662,", 1), r"column 3 is named 's\\\\u0662'"),
        (lambda h: h.replace("s3,", "x3,", 1), "raw channel column s3 is missing|unknown column 'x3'"),
        (lambda h: h.replace("s1,", "s01,", 1), "without leading zeros"),
    ],
    ids=["duplicate", "non-ascii", "gap", "leading-zero"],
)
def test_bad_dataset_headers_are_refused(workdir, tmp_path, edit, message):
    comments, body = data_lines(workdir)
    bad = tmp_path / "bad.csv"
    bad.write_text("\n".join(comments + [edit(body[0])] + body[1:]) + "\n", encoding="utf-8")
    with pytest.raises(DatasetFileError, match=message):
        CalibrationDataset.load(bad)


def test_a_gap_in_the_channels_is_refused_by_every_reader(workdir, tmp_path, capsys):
    comments, body = data_lines(workdir)
    header = body[0].split(",")
    keep = [i for i, name in enumerate(header) if name != "s3"]
    gap = tmp_path / "gap.csv"
    gap.write_text("\n".join(",".join(ln.split(",")[i] for i in keep) for ln in body) + "\n")
    with pytest.raises(DatasetFileError, match="s3 is missing"):
        CalibrationDataset.load(gap)
    assert "s3 is missing" in cli_error(["predict", workdir / "models" / "linear.model.npz", gap], capsys)


def test_predict_header_with_a_channel_twice_is_refused(workdir, tmp_path, capsys):
    readings = tmp_path / "r.csv"
    readings.write_text("s0,s1,s2,s3,s4,s0\n1,2,3,4,5,6\n")
    assert "'s0' appears 2 times" in cli_error(["predict", workdir / "models" / "linear.model.npz", readings], capsys)


def test_underscore_numbers_are_refused(workdir, tmp_path, capsys):
    comments, body = data_lines(workdir)
    fields = body[3].split(",")
    fields[0] = "1_000"
    bad = tmp_path / "underscore.csv"
    bad.write_text("\n".join(body[:3] + [",".join(fields)] + body[4:]) + "\n")
    with pytest.raises(DatasetFileError, match=r"line 4, column s0: '1_000' is not a number"):
        CalibrationDataset.load(bad)
    readings = tmp_path / "r.csv"
    readings.write_text("1_000,0.2,0.3,0.4,0.5,0.6\n")  # a first line of numbers is data, not a header
    assert "'1_000' is not a number" in cli_error(["predict", workdir / "models" / "linear.model.npz", readings], capsys)


# ------------------------------------------------------------------ 6. no NaN or inf printed
def test_float32_overflow_through_the_comparative_model_is_an_error(workdir, capsys, monkeypatch):
    import io

    monkeypatch.setattr(sys, "stdin", io.StringIO("0.1,0.2,0.3,0.4,0.5,1e39\n"))
    msg = cli_error(["predict", workdir / "models" / "comparative.model.npz"], capsys)
    assert "non-finite wrench" in msg and "stdin: line 1: the reading" in msg


@pytest.mark.parametrize("model", [DirectionalCalibrator(**TINY), PolynomialCalibrator(degree=3)],
                         ids=["directional", "polynomial"])
def test_huge_readings_give_an_error_not_inf(model):
    rng = np.random.default_rng(0)
    w = rng.normal(size=(60, 6))
    raw = w @ rng.normal(size=(6, 6))
    model.fit(raw, w)
    with pytest.raises(CalibrationInputError, match="X row 1 .* non-finite wrench"):
        model.predict(np.vstack([raw[:1], np.full((1, 6), 1e155)]))


def _rewrite_model(src: Path, dst: Path, change) -> Path:
    with np.load(src, allow_pickle=False) as z:
        arrays = {k: z[k] for k in z.files}
    meta = json.loads(str(arrays["__metadata__"]))
    change(meta, arrays)
    arrays["__metadata__"] = np.array(json.dumps(meta) if isinstance(meta, dict) else meta)
    with open(dst, "wb") as fh:
        np.savez(fh, **arrays)
    return dst


def test_nan_weights_are_refused_at_load(workdir, tmp_path):
    def poison(meta, arrays):
        arrays["module/layers.0.weight"][0, 0] = np.nan

    path = _rewrite_model(workdir / "models" / "directional.model.npz", tmp_path / "nan.model.npz", poison)
    with pytest.raises(ModelFileError, match="holds NaN, inf"):
        ftcal.load_model(path)


# ------------------------------------------------------------------ 7. nothing to identify
@pytest.mark.parametrize("case", ["duplicate-rows", "constant", "all-zero", "dead-channel"])
@pytest.mark.parametrize("cls", [LinearCalibrator, PolynomialCalibrator, DirectionalCalibrator])
def test_unidentifiable_fits_are_refused(cls, case):
    rng = np.random.default_rng(1)
    w = rng.normal(size=(50, 6))
    raw = w @ rng.normal(size=(6, 6))
    if case == "duplicate-rows":
        raw, w = np.repeat(raw[:1], 50, axis=0), np.repeat(w[:1], 50, axis=0)
    elif case == "constant":
        raw = np.full_like(raw, 3.0)
    elif case == "all-zero":
        raw = np.zeros_like(raw)
    else:
        raw[:, 4] = raw[:, 3]  # a channel wired twice: rank 5 for a 6-D load
    params = TINY if cls is DirectionalCalibrator else {}
    with pytest.raises(CalibrationInputError, match="nothing to calibrate from|no load change|different loads give"):
        cls(**params).fit(raw, w)


@pytest.mark.parametrize("hidden", [(8,), (64, 64, 64)], ids=["finite-nonsense", "nan"])
def test_diverging_training_is_an_error(hidden):
    rng = np.random.default_rng(0)
    w = rng.normal(size=(80, 6)) * 100
    raw = w @ rng.normal(size=(6, 6))
    with pytest.raises(CalibrationInputError, match="training diverged.*lower lr"):
        ComparativeCalibrator(**{**TINY, "phase1_epochs": 20, "hidden_layer_sizes": hidden}, lr=1e6).fit(raw, w)


# ------------------------------------------------------------------ 8. labels and dtypes
def test_fractional_group_labels_are_refused():
    with pytest.raises(DatasetFileError, match=r"row 1 \(rows counted from 0\) holds 1.7"):
        CalibrationDataset(raw=np.ones((3, 6)), wrench=np.zeros((3, 6)), group=[0, 1.7, 2])
    ds = CalibrationDataset(raw=np.ones((3, 6)), wrench=np.zeros((3, 6)), group=np.array([0.0, 1.0, 2.0]))
    assert ds.group.dtype == np.int64


@pytest.mark.parametrize("where", ["fit-X", "fit-y", "predict"])
def test_complex_input_is_refused_with_a_short_message(where):
    rng = np.random.default_rng(0)
    w = rng.normal(size=(30, 6))
    raw = w @ rng.normal(size=(6, 6))
    model = LinearCalibrator()
    with pytest.raises(CalibrationInputError, match="Complex data not supported") as info:
        if where == "fit-X":
            model.fit(raw + 1j, w)
        elif where == "fit-y":
            model.fit(raw, w + 1j)
        else:
            model.fit(raw, w).predict(raw + 1j)
    assert len(str(info.value)) < 300  # names dtype and shape, never prints the array


def test_one_dimensional_input_message_is_short():
    model = LinearCalibrator().fit(np.random.default_rng(0).normal(size=(30, 6)), np.random.default_rng(1).normal(size=(30, 6)))
    with pytest.raises(CalibrationInputError, match=r"1-D array of shape \(1000,\).*reshape\(1, -1\)") as info:
        model.predict(np.arange(1000.0))
    assert "999" not in str(info.value)


# ------------------------------------------------------------------ 9-10. damaged or foreign model files
def test_cuda_model_file_runs_on_the_cpu_with_a_warning(workdir, tmp_path):
    def to_cuda(meta, arrays):
        meta["params"]["device"] = "cuda"

    path = _rewrite_model(workdir / "models" / "directional.model.npz", tmp_path / "cuda.model.npz", to_cuda)
    with pytest.warns(UserWarning, match="device='cuda'.*runs on the CPU"):
        model = ftcal.load_model(path)
    reference = ftcal.load_model(workdir / "models" / "directional.model.npz")
    x = np.random.default_rng(0).normal(size=(4, 6))
    np.testing.assert_array_equal(model.predict(x), reference.predict(x))


def test_fitting_on_a_missing_device_is_a_clear_error():
    rng = np.random.default_rng(0)
    w = rng.normal(size=(30, 6))
    with pytest.raises(CalibrationInputError, match="device='cuda' is not available"):
        DirectionalCalibrator(**TINY, device="cuda").fit(w @ rng.normal(size=(6, 6)), w)


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda meta, arrays: meta["fitted"].update(alpha_=None), "stored alpha_ is None"),
        (lambda meta, arrays: meta["params"].update(hidden_layer_sizes={"tuple": [20000, 20000]}),
         "do not match the declared layers"),
        (lambda meta, arrays: arrays.update({"fitted/zero_reading_": np.zeros(5)}), "do not fit together"),
    ],
    ids=["null-scalar", "declared-20000x20000", "wrong-shape"],
)
def test_inconsistent_model_files_are_refused(workdir, tmp_path, change, message):
    path = _rewrite_model(workdir / "models" / "directional.model.npz", tmp_path / "bad.model.npz", change)
    with pytest.raises(ModelFileError, match=message):
        ftcal.load_model(path)


def test_weight_shape_mismatch_in_a_linear_model_is_named(workdir, tmp_path):
    def shrink(meta, arrays):
        arrays["fitted/calibration_matrix_"] = arrays["fitted/calibration_matrix_"][:, :4]

    path = _rewrite_model(workdir / "models" / "linear.model.npz", tmp_path / "bad.model.npz", shrink)
    with pytest.raises(ModelFileError, match="stored arrays do not fit together"):
        ftcal.load_model(path)


def test_deeply_nested_metadata_is_refused(workdir, tmp_path):
    path = tmp_path / "deep.model.npz"
    deep = '{"format": "ftcal-model", "x": ' + "[" * 100_000 + "]" * 100_000 + "}"
    with open(path, "wb") as fh:
        np.savez(fh, __metadata__=np.array(deep))
    with pytest.raises(ModelFileError, match="not valid JSON"):
        ftcal.load_model(path)


def test_dataset_meta_must_be_an_object(tmp_path):
    path = tmp_path / "d.csv"
    path.write_text("# meta: [1, 2]\ns0,s1,s2,Fx,Fy,Fz,Tx,Ty,Tz\n" + "1,2,3,4,5,6,7,8,9\n" * 3)
    with pytest.raises(DatasetFileError, match="holds a JSON list; it must be a JSON object"):
        CalibrationDataset.load(path)


ATI = """<FTSensor Serial="FT1" NumGages="6"><Calibration ForceUnits="N" TorqueUnits="N-m" DistUnits="m">
{rows}</Calibration></FTSensor>"""


def _ati_rows(max_force: str) -> str:
    return "\n".join(
        f'<UserAxis Name="{a}" values="{" ".join("1" if j == i else "0" for j in range(6))}" '
        f'max="{max_force if i < 3 else 10}"/>'
        for i, a in enumerate(["Fx", "Fy", "Fz", "Tx", "Ty", "Tz"])
    )


def test_ati_file_with_an_absurd_range_is_refused_before_anything_is_written(tmp_path, capsys):
    cal = tmp_path / "FT1.cal"
    cal.write_text(ATI.format(rows=_ati_rows("1e308")))
    with pytest.raises(CalFileError, match=r"rated ranges \['Fx=1e\+308'"):
        ftcal.simulation.read_ati_calibration(cal)
    out = tmp_path / "sim"
    assert "exceed" in cli_error(["simulate", "dataset", "--sensor", cal, "--out", out, "-q"], capsys)
    assert not out.exists() or not any(out.iterdir())


def test_ati_file_without_calibration_names_the_problem(tmp_path):
    cal = tmp_path / "FT1.cal"
    cal.write_text('<FTSensor Serial="FT1"></FTSensor>')
    with pytest.raises(CalFileError, match="no <Calibration> element inside <FTSensor>"):
        ftcal.simulation.read_ati_calibration(cal)


@pytest.mark.parametrize("argv, message", [
    (["simulate", "dataset", "--n-per-sphere", "100000000000"], "at most 1000000"),
    (["plan", "--subdivisions", "12"], "at most 6"),
    (["simulate", "dataset", "--n-test", "0"], "integer >= 1"),
    (["plan", "--strategy", "d-optimal", "--poses", "20", "--space-filling", "1e308"], "weight from 0 to 1e6"),
])
def test_sizes_that_would_exhaust_memory_are_refused(argv, message, capsys):
    assert message in cli_error(argv, capsys)


# ------------------------------------------------------------------ 11. ensembles through the CLI
def test_fit_ensemble_with_tare_through_the_cli(workdir, tmp_path):
    tare = ",".join(["0"] * 6)
    assert run(["fit", workdir / "data" / "train.csv", "--model", "directional_ensemble", *SMALL_NET_CLI,
                 "--param", "n_members=2", "--tare", tare, "--out", tmp_path, "-q"]) == 0
    model = ftcal.load_model(tmp_path / "directional_ensemble.model.npz")
    assert len(model.estimators_) == 2
    np.testing.assert_array_equal(model.zero_reading_, np.zeros(6))


def test_unknown_parameter_is_named_for_an_ensemble(workdir, capsys, tmp_path):
    msg = cli_error(["fit", workdir / "data" / "train.csv", "--model", "directional_ensemble", "--param",
                     "ridge=1", "--out", tmp_path], capsys)
    assert "--param ridge: directional_ensemble has no such parameter" in msg and "n_members" in msg


# ------------------------------------------------------------------ misleading messages
def test_unwritable_out_is_found_before_training(workdir, capsys):
    msg = cli_error(["fit", workdir / "data" / "train.csv", "--model", "directional", *SMALL_NET_CLI,
                     "--out", "/proc/ftcal-cannot-write-here"], capsys)
    assert "cannot create files" in msg


def test_write_errors_name_the_users_file_not_the_temporary_one(tmp_path):
    target = tmp_path / "result.json"
    with pytest.raises(OSError) as info:
        with atomic_output(target, overwrite=False, error=FileExistsError) as tmp:
            raise OSError(28, "No space left on device", str(tmp))
    assert info.value.filename == str(target)
    assert not list(tmp_path.iterdir())


def test_prepare_dataset_takes_one_path(tmp_path):
    with pytest.raises(LogFormatError, match=r"x\.csv: no such log file"):
        ftcal.experiment.prepare_dataset(str(tmp_path / "x.csv"))


# ------------------------------------------------------------------ grouped CV, ONNX, Dask, tool load and temperature
@pytest.mark.parametrize("argv, message", [
    (["benchmark", "dataset", "{nogroup}", "--folds", "group", "--out", "{tmp}/b"], "has no group column"),
    (["benchmark", "dataset", "{train}", "--model", "auto", "--out", "{tmp}/b"], "'auto' is itself this comparison"),
    (["fit", "{train}", "--model", "linear", "--temperature", "--out", "{tmp}/m"], "has no temperature column"),
    (["simulate", "dataset", "--temperature-range", "35,15", "--out", "{tmp}/s"], "need -60 <= LOW < HIGH"),
    (["simulate", "dataset", "--temperature-range", "warm", "--out", "{tmp}/s"], "give LOW,HIGH in deg C"),
    (["identify-load", "{train}", "--model", "{model}", "--gravity", "0,-9.81", "--out", "{tmp}/t"],
     "give three comma-separated numbers"),
    (["identify-load", "{train}", "--model", "{model}", "--out", "{tmp}/t"], "missing comment '# time_unit: <unit>'"),
    (["retare", "{model}", "{tmp}/missing.csv"], "missing.csv does not exist (the zero-load readings)"),
    (["tune", "{train}", "--model", "linear", "--grid", "ridge=[0,1]", "--scheduler", "tcp//x", "--out", "{tmp}/u"],
     "is not 'local' nor a scheduler address"),
])
def test_new_entry_points_reject_bad_input(workdir, tmp_path, capsys, argv, message):
    train = CalibrationDataset.load(workdir / "data" / "train.csv")
    nogroup = CalibrationDataset(raw=train.raw, wrench=train.wrench).save(tmp_path / "nogroup.csv")
    fill = {"train": workdir / "data" / "train.csv", "model": workdir / "models" / "linear.model.npz", "tmp": tmp_path,
            "nogroup": nogroup}
    assert message in cli_error([a.format(**fill) for a in argv], capsys)


# ================================================================== bad input and faults: files, columns, units, models
def _inputs_and_outputs(workdir, tmp_path):
    """Real input files of every kind a command reads: a model, a dataset, readings, a log, a tool file."""
    files = {
        "model": tmp_path / "lin.model.npz",
        "readings": tmp_path / "zeros.csv",
        "log": tmp_path / "run.csv",
        "tool": tmp_path / "t.tool.json",
        "dataset": tmp_path / "ds.model.npz",  # an .npz dataset named like the model fit writes
    }
    files["model"].write_bytes((workdir / "models" / "linear.model.npz").read_bytes())
    files["readings"].write_text("0.1,0.2,0.3,0.4,0.5,0.6\n")
    files["log"].write_bytes((workdir / "data" / "train.csv").read_bytes())
    ftcal.experiment.ToolLoad(mass=1.0, center_of_mass=np.zeros(3), bias=np.zeros(6)).save(files["tool"])
    train = CalibrationDataset.load(workdir / "data" / "train.csv")
    with open(files["dataset"], "wb") as fh:
        np.savez(fh, raw=train.raw, wrench=train.wrench)
    return files


# every subcommand that reads files, each with an output that is one of its inputs (--force given)
OUTPUT_OVER_INPUT = [
    ("compensate", ["compensate", "{log}", "--model", "{model}", "--tool", "{tool}", "--output", "{model}"], "model"),
    ("compensate", ["compensate", "{log}", "--model", "{model}", "--tool", "{tool}", "--output", "{log}"], "log"),
    ("compensate", ["compensate", "{log}", "--model", "{model}", "--tool", "{tool}", "--output", "{tool}"], "tool"),
    ("retare", ["retare", "{model}", "{readings}", "--output", "{readings}"], "readings"),
    ("retare", ["retare", "{model}", "{readings}", "--output", "{model}"], "model"),
    ("fit", ["fit", "{dataset}", "--model", "linear", "--name", "ds", "--out", "{tmp}"], "dataset"),
    ("identify-load", ["identify-load", "{tmp}/x.tool.json", "--model", "{model}", "--name", "x", "--out", "{tmp}"],
     "x.tool.json"),
    ("prepare", ["prepare", "{tmp}/dataset.csv", "--out", "{tmp}"], "dataset.csv"),
    ("predict", ["predict", "{model}", "{readings}", "--output", "{readings}"], "readings"),
    ("export", ["export", "{model}", "--output", "{model}"], "model"),
    ("evaluate", ["evaluate", "{tmp}/metrics.md", "{model}", "--out", "{tmp}"], "metrics.md"),
    ("benchmark", ["benchmark", "dataset", "{tmp}/dataset_results.md", "--model", "linear", "--out", "{tmp}"],
     "dataset_results.md"),
    ("tune", ["tune", "{tmp}/linear.tune.json", "--model", "linear", "--out", "{tmp}"], "linear.tune.json"),
    ("simulate", ["simulate", "dataset", "--sensor", "{tmp}/info.json", "--out", "{tmp}"], "info.json"),
    ("plan", ["plan", "--robot", "{tmp}/plan.json", "--out", "{tmp}"], "plan.json"),
]


@pytest.mark.parametrize("command, argv, victim", OUTPUT_OVER_INPUT, ids=[f"{c[0]}-{c[2]}" for c in OUTPUT_OVER_INPUT])
@pytest.mark.parametrize("link", ["same", "symlink", "hardlink"])
def test_no_output_ever_replaces_an_input(workdir, tmp_path, capsys, command, argv, victim, link):
    files = _inputs_and_outputs(workdir, tmp_path)
    fill = {**{k: str(v) for k, v in files.items()}, "tmp": str(tmp_path)}
    argv = [a.format(**fill) for a in argv] + ["--force"]
    target = files.get(victim, tmp_path / victim)
    if not target.exists():  # an input the user named like the command's output file
        target.write_bytes((workdir / "data" / "train.csv").read_bytes())
    if link != "same":  # the input reached by another name: a symbolic or a hard link to it
        other = tmp_path / "linked" / target.name
        other.parent.mkdir()
        (other.symlink_to if link == "symlink" else other.hardlink_to)(target)
        argv = [str(other) if a == str(target) and i > 0 and argv[i - 1] not in ("--output", "--out") else a
                for i, a in enumerate(argv)]
    before = {p: sha(p) for p in tmp_path.rglob("*") if p.is_file() and not p.is_symlink()}
    msg = cli_error(argv, capsys)
    assert "an input of this command" in msg and "--force or not" in msg, msg
    assert {p: sha(p) for p in before} == before  # nothing the user had changed
    assert not list(tmp_path.rglob(".*partial*"))


def test_outputs_that_are_not_regular_files_are_refused(workdir, tmp_path, capsys):
    model = workdir / "models" / "linear.model.npz"
    readings = tmp_path / "r.csv"
    readings.write_text("0.1,0.2,0.3,0.4,0.5,0.6\n")
    os.mkfifo(tmp_path / "pipe")
    for target, what in (("/dev/null", "not a regular file"), (tmp_path / "pipe", "not a regular file"),
                         (tmp_path, "is a directory")):
        msg = cli_error(["predict", model, readings, "--output", target, "--force"], capsys)
        assert what in msg
    assert Path("/dev/null").is_char_device()


# ------------------------------------------------------------------ signals: the CLI's, never the library's
def _wait_for(predicate, what: str, proc: subprocess.Popen) -> None:
    """Poll until ``predicate()`` (a state of the child, not a duration, decides; the bound only stops a hang)."""
    for _ in range(6000):
        if predicate():
            return
        if proc.poll() is not None:
            raise AssertionError(f"the command ended ({proc.returncode}) before {what}: {proc.stderr.read()}")
        time.sleep(0.05)
    raise AssertionError(f"never saw {what}")


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_during_predict_removes_the_partial_output(workdir, tmp_path, sig):
    out = tmp_path / "wrench.csv"
    out.write_text("the user's previous results\n")
    proc = subprocess.Popen([sys.executable, "-m", "ftcal", "predict", str(workdir / "models" / "linear.model.npz"),
                             "-", "--output", str(out), "--force"], cwd=tmp_path, stdin=subprocess.PIPE,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint)
    proc.stdin.write("0.1,0.2,0.3,0.4,0.5,0.6\n" * 10)
    proc.stdin.flush()  # stdin stays open: predict is mid-stream, its partial file exists
    _wait_for(lambda: list(tmp_path.glob(".wrench.*.partial.csv")), "the partial output", proc)
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + sig, err
    assert err.strip() == f"ftcal: interrupted by {signal.Signals(sig).name} (no half-written file is left)"
    assert not list(tmp_path.glob(".*partial*"))
    assert out.read_text() == "the user's previous results\n"


def test_library_fit_installs_no_signal_handler_and_still_reports_a_ctrl_c():
    from skorch.callbacks import Callback

    seen = []

    class Probe(Callback):
        def on_epoch_begin(self, net, **kwargs):
            seen.append((signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM)))
            if len(seen) == 2:
                os.kill(os.getpid(), signal.SIGINT)  # a real Ctrl-C in the middle of training

    rng = np.random.default_rng(0)
    raw = rng.normal(size=(200, 6))
    before = (signal.getsignal(signal.SIGINT), signal.getsignal(signal.SIGTERM))
    signal.signal(signal.SIGINT, signal.default_int_handler)  # what a terminal gives a Python program
    try:
        model = DirectionalCalibrator(**{**TINY, "phase1_epochs": 50}, callbacks=[("probe", Probe())])
        with pytest.raises(KeyboardInterrupt, match="interrupted at epoch"):
            model.fit(raw, raw @ rng.normal(size=(6, 6)))
        assert not hasattr(model, "net_")  # no half-trained model left as if it had finished
        assert all(h == (signal.default_int_handler, before[1]) for h in seen)
        # the schedule's own early stop (a KeyboardInterrupt from a callback) is not mistaken for a Ctrl-C
        model = DirectionalCalibrator(**{**TINY, "phase1_epochs": 30, "plateau_epochs": 1}).fit(raw, raw)
        assert model.n_epochs_ >= 1
    finally:
        signal.signal(signal.SIGINT, before[0])


# ------------------------------------------------------------------ scale-out: a wrong server fails in seconds
class _Silent(__import__("http.server").server.BaseHTTPRequestHandler):
    def log_message(self, *args):
        pass


@pytest.fixture
def web_server():
    """A real HTTP server on 127.0.0.1 (waits for a request, as web servers do); stopped after the test."""
    import http.server
    import threading

    server = http.server.ThreadingHTTPServer(("127.0.0.1", 0), _Silent)
    thread = threading.Thread(target=server.serve_forever, kwargs={"poll_interval": 0.05}, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{server.server_address[1]}"
    server.shutdown()
    server.server_close()


@pytest.fixture
def talking_server():
    """A server that speaks first, as HTTP would answer (its bytes read as a Dask frame length: exabytes)."""
    import socket
    import threading

    listener = socket.socket()
    listener.bind(("127.0.0.1", 0))
    listener.listen()
    done = threading.Event()

    def serve():
        listener.settimeout(0.1)
        while not done.is_set():
            try:
                conn, _ = listener.accept()
            except OSError:
                continue
            with conn:
                conn.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n")
                done.wait(1.0)

    thread = threading.Thread(target=serve, daemon=True)
    thread.start()
    yield f"tcp://127.0.0.1:{listener.getsockname()[1]}"
    done.set()
    thread.join()
    listener.close()


@pytest.mark.parametrize("server, message", [("web_server", "sent no Dask handshake"),
                                             ("talking_server", "not as a Dask scheduler does")])
def test_a_scheduler_address_of_another_service_is_one_clear_line(workdir, tmp_path, capsys, request, server, message):
    address = request.getfixturevalue(server)
    msg = cli_error(["tune", workdir / "data" / "train.csv", "--model", "linear", "--grid", "ridge=[0,1]", "--cv", "2",
                     "--scheduler", address, "--out", tmp_path / "u"], capsys)
    assert message in msg and address in msg and "Unable to allocate" not in msg
    assert not (tmp_path / "u" / "linear.model.npz").exists()


def test_a_real_dask_scheduler_still_passes_the_handshake_check():
    import joblib
    from distributed import LocalCluster

    from ftcal.cli._scale_out import dask_backend, probe_scheduler

    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, protocol="tcp://",
                      dashboard_address=None) as cluster:
        assert cluster.scheduler_address.startswith("tcp://")
        probe_scheduler(cluster.scheduler_address)
        with dask_backend(cluster.scheduler_address) as client:
            assert client is not None
            assert joblib.Parallel(n_jobs=2)(joblib.delayed(abs)(-i) for i in range(4)) == [0, 1, 2, 3]


# ------------------------------------------------------------------ physics checked
def _rotations(n=20):
    from scipy.spatial.transform import Rotation

    return Rotation.random(n, random_state=0).as_matrix()


TRUE_TOOL = dict(mass=1.2, center_of_mass=np.array([0.01, -0.02, 0.08]), bias=np.arange(6.0) / 10)


def test_mirrored_frames_are_refused_and_rounded_rotations_accepted():
    R = _rotations()
    wrench = ftcal.experiment.ToolLoad(**TRUE_TOOL).gravity_wrench(R)
    mirrored = R.copy()
    mirrored[5, :, 0] *= -1  # one pose logged with a flipped axis: det = -1
    with pytest.raises(CalibrationInputError, match=r"sensor_rotations\[5\] is a reflection"):
        ftcal.experiment.identify_tool_load(mirrored, wrench)
    for decimals in (6, 4):  # rotations as a log prints them; the rounding (1e-4) bounds the error
        tool = ftcal.experiment.identify_tool_load(np.round(R, decimals), wrench)
        assert abs(tool.mass - 1.2) < 1.2 * 10 * 10.0**-decimals
        assert np.abs(tool.center_of_mass - TRUE_TOOL["center_of_mass"]).max() < 10 * 10.0**-decimals
    with pytest.raises(CalibrationInputError, match="not a rotation matrix"):
        ftcal.experiment.identify_tool_load(R * 1.1, wrench)


@pytest.mark.parametrize("field, value, message", [
    ("mass", -1.0, "mass must be a finite number >= 0"),
    ("mass", float("nan"), "mass must be a finite number >= 0"),
    ("center_of_mass", [np.nan, 0.0, 0.0], "center_of_mass must be 3 finite numbers"),
    ("center_of_mass", [0.0, 0.0], "center_of_mass must be 3 finite numbers"),
    ("bias", [0.0] * 5, "bias must be 6 finite numbers"),
    ("gravity", [0.0, 0.0, 0.0], "gravity must be a non-zero vector"),
    ("mass_std_error", -0.1, "mass_std_error must be a finite number >= 0"),
    ("center_of_mass", "abc", "center_of_mass must be numbers"),
])
def test_tool_load_checks_its_fields(field, value, message):
    with pytest.raises(CalibrationInputError, match=message):
        ftcal.experiment.ToolLoad(**{**TRUE_TOOL, field: value})


def _noise_free_model(tmp_path) -> Path:
    rng = np.random.default_rng(0)
    wrench = rng.uniform(-1, 1, size=(300, 6)) * [50, 50, 50, 1, 1, 1]
    raw = wrench @ rng.normal(size=(6, 6)) * 0.01 + 0.5  # averaged, noise-free readings: reading_noise_ ~ 1e-14
    model = LinearCalibrator().fit(raw, wrench)
    assert model.reading_noise_.max() < 1e-10
    return ftcal.save_model(model, tmp_path / "quiet.model.npz"), raw


def test_retare_takes_real_readings_after_noise_free_training_and_refuses_far_readings(tmp_path, capsys):
    path, raw = _noise_free_model(tmp_path)
    span = raw.max(axis=0) - raw.min(axis=0)
    zeros = tmp_path / "zeros.csv"
    rng = np.random.default_rng(1)
    # a real sensor at rest: noise of 1e-5 of the span (a 16-bit converter's step is 1.5e-5)
    np.savetxt(zeros, 0.51 + 1e-5 * span * rng.normal(size=(50, 6)), delimiter=",")
    assert main(["retare", str(path), str(zeros), "-q"]) == 0
    np.testing.assert_allclose(ftcal.load_model(tmp_path / "quiet-retared.model.npz").tare_reading_, 0.51,
                               atol=1e-4 * span.max())
    far = tmp_path / "far.csv"
    np.savetxt(far, np.full((1, 6), 1e6), delimiter=",")
    msg = cli_error(["retare", path, far, "--output", tmp_path / "far.model.npz"], capsys)
    assert "lies far outside the readings channel s0 gave in training" in msg
    touched = tmp_path / "touched.csv"  # something leaning on the sensor: 1 % of the span
    np.savetxt(touched, 0.51 + 1e-2 * span * rng.normal(size=(50, 6)), delimiter=",")
    assert "is not quiet" in cli_error(["retare", path, touched, "--output", tmp_path / "t.model.npz"], capsys)


# ------------------------------------------------------------------ data never silently changed
def _two_logs(tmp_path, with_temperature):
    """A load and a no-load log of one pose set; the temperature column only in the logs asked."""
    paths = []
    for kind, has_t in zip(("load", "no-load"), with_temperature):
        n = 4
        paths.append(ftcal.io.write_run_log(
            tmp_path / f"{kind}.csv", timestamp=np.arange(n, dtype=float), run_kind=[kind] * n, config=[0] * n,
            pose=np.arange(n), q=np.zeros((n, 7)) + np.arange(n)[:, None] * 0.1, raw=np.ones((n, 6)),
            load_mass=1.0, temperature=np.full(n, 25.0) if has_t else None))
    return paths


def test_prepare_never_drops_the_temperature_of_some_logs(tmp_path):
    load, no_load = _two_logs(tmp_path, (True, True))
    paired = ftcal.experiment.pair_runs([ftcal.io.read_run_log(load), ftcal.io.read_run_log(no_load)])
    assert paired.temperature_load is not None
    more = ftcal.io.write_run_log(
        tmp_path / "load2.csv", timestamp=np.arange(4.0), run_kind=["load"] * 4, config=[1] * 4, pose=np.arange(4),
        q=np.zeros((4, 7)) + np.arange(4)[:, None] * 0.1, raw=np.ones((4, 6)), load_mass=1.0)
    shared = ftcal.io.write_run_log(
        tmp_path / "nl2.csv", timestamp=np.arange(4.0), run_kind=["no-load"] * 4, config=[1] * 4, pose=np.arange(4),
        q=np.zeros((4, 7)) + np.arange(4)[:, None] * 0.1, raw=np.ones((4, 6)), load_mass=1.0)
    logs = [ftcal.io.read_run_log(p) for p in (load, no_load, more, shared)]
    with pytest.raises(LogFormatError, match=r"load2\.csv:line \d+: this load row has no temperature"):
        ftcal.experiment.pair_runs(logs)


@pytest.mark.parametrize("labels, message", [
    ([100000000000000001, 100000000000000000, 7], None),  # distinct above 2^53: kept distinct
    ([9223372036854775807, 0, 1], None),
    (["18446744073709551615", "0", "1"], "beyond the 64-bit integer labels"),
])
def test_group_labels_are_read_exactly(tmp_path, labels, message):
    rng = np.random.default_rng(0)
    header = ",".join([f"s{i}" for i in range(6)] + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz", "group"])
    rows = [",".join(f"{v:.6g}" for v in rng.normal(size=12)) + f",{g}" for g in labels]
    path = tmp_path / "d.csv"
    path.write_text(header + "\n" + "\n".join(rows) + "\n")
    if message:
        with pytest.raises(DatasetFileError, match=message):
            CalibrationDataset.load(path)
        return
    ds = CalibrationDataset.load(path)
    assert ds.group.tolist() == [int(g) for g in labels]
    again = CalibrationDataset.load(ds.save(tmp_path / "again.csv"))  # and written back exactly
    assert again.group.tolist() == [int(g) for g in labels]


def test_log_ids_are_read_exactly(tmp_path):
    load, _ = _two_logs(tmp_path, (False, False))
    text = load.read_text().replace("\nload,0,", "\nload,100000000000000001,", 1)
    lines = load.read_text().splitlines()
    head = [ln for ln in lines if not ln.startswith("#")][0].split(",")
    ci = head.index("config")
    body = []
    for k, ln in enumerate(lines):
        fields = ln.split(",")
        if not ln.startswith("#") and fields != head:
            fields[ci] = "100000000000000001" if k % 2 else "100000000000000000"
        body.append(",".join(fields))
    load.write_text("\n".join(body) + "\n")
    log = ftcal.io.read_run_log(load)
    assert sorted(set(log.config.tolist())) == [100000000000000000, 100000000000000001]
    body = [ln.replace("100000000000000001", "99999999999999999999") for ln in body]
    load.write_text("\n".join(body) + "\n")
    with pytest.raises(LogFormatError, match="beyond the 64-bit integers"):
        ftcal.io.read_run_log(load)
    assert text


@pytest.mark.parametrize("kind", ["npz", "text"])
def test_complex_readings_are_refused(workdir, tmp_path, capsys, kind):
    if kind == "npz":
        path = tmp_path / "r.npz"
        np.savez(path, raw=np.ones((3, 6)) + 1j)
        expected = "holds complex numbers"
    else:
        path = tmp_path / "r.csv"
        path.write_text("1+2j,0,0,0,0,0\n")
        expected = "line 1: '1+2j' is not a number"
    msg = cli_error(["predict", workdir / "models" / "linear.model.npz", path], capsys)
    assert expected in msg


# ------------------------------------------------------------------ messages that say what is wrong, where
def _special_paths(tmp_path):
    os.mkfifo(tmp_path / "fifo")
    (tmp_path / "dir").mkdir()
    (tmp_path / "dangling").symlink_to(tmp_path / "gone.csv")
    return {"directory": (tmp_path / "dir", "is a directory, not a file"),
            "device": ("/dev/null", "is a device, not a regular file"),
            "fifo": (tmp_path / "fifo", "is a named pipe, not a regular file"),
            "dangling link": (tmp_path / "dangling", "is a broken symbolic link"),
            "missing": (tmp_path / "missing.csv", "does not exist")}


@pytest.mark.parametrize("kind", ["directory", "device", "fifo", "dangling link", "missing"])
@pytest.mark.parametrize("role", ["dataset", "model", "log"])
def test_inputs_that_are_not_files_are_named_for_what_they_are(workdir, tmp_path, capsys, kind, role):
    path, expected = _special_paths(tmp_path)[kind]
    model = workdir / "models" / "linear.model.npz"
    argv = {"dataset": ["fit", path, "--model", "linear", "--out", tmp_path / "o"],
            "model": ["evaluate", workdir / "data" / "test.csv", path, "--out", tmp_path / "o"],
            "log": ["prepare", path, "--out", tmp_path / "o"]}[role]
    if role == "log" and kind == "directory":
        expected = "holds no *.csv run logs"
    if role == "dataset" and kind == "directory":  # a folder is a dataset of one file per pose: an empty one is named
        expected = "the folder holds no dataset files"
    msg = cli_error(argv, capsys)
    assert expected in msg and "no such file" not in msg.replace("does not exist", "")
    assert model.exists()


def test_predict_reads_pipes_and_process_substitution(workdir, tmp_path):
    model = workdir / "models" / "linear.model.npz"
    reader, writer = os.pipe()
    os.write(writer, b"0.1,0.2,0.3,0.4,0.5,0.6\n0,0,0,0,0,0\n")
    os.close(writer)
    proc = subprocess.run([sys.executable, "-m", "ftcal", "predict", str(model), f"/dev/fd/{reader}", "--no-header"],
                          pass_fds=(reader,), capture_output=True, text=True, cwd=tmp_path)
    os.close(reader)
    assert proc.returncode == 0, proc.stderr
    assert len(proc.stdout.splitlines()) == 2


def test_chunked_predict_errors_name_the_file_line(workdir, tmp_path, capsys):
    rows = np.random.default_rng(0).normal(size=(6000, 6))
    rows[4998] = [1.7e308, -1.7e308] * 3  # overflows the calibration: found in the second 4096-row chunk
    path = tmp_path / "r.csv"
    with open(path, "w") as fh:
        fh.write("# a comment\ns0,s1,s2,s3,s4,s5\n")
        np.savetxt(fh, rows, delimiter=",")
    msg = cli_error(["predict", workdir / "models" / "linear.model.npz", path], capsys)
    assert f"{path}: line 5001: the reading" in msg and "row 902" not in msg


@pytest.mark.parametrize("content, expected", [
    (b"\x00\x01\x02\xff\xfe" * 50, "not UTF-8 text"),
    (b"1," * 700_000, "is longer than"),
    (b"0,0,0,0,0,0\n\x00\x00\n", "holds a NUL byte"),
])
def test_binary_or_unbroken_reading_files_are_refused_by_line(workdir, tmp_path, capsys, content, expected):
    path = tmp_path / "r.csv"
    path.write_bytes(content)
    assert expected in cli_error(["predict", workdir / "models" / "linear.model.npz", path], capsys)


def test_temperature_models_count_raw_channels_and_temperature(tmp_path, capsys):
    rng = np.random.default_rng(0)
    w = rng.normal(size=(300, 6))
    X = np.hstack([w @ rng.normal(size=(6, 6)), rng.uniform(15, 35, size=(300, 1))])
    path = ftcal.save_model(ftcal.TemperatureCompensatedCalibrator(LinearCalibrator()).fit(X, w),
                            tmp_path / "t.model.npz")
    readings = tmp_path / "r.csv"
    readings.write_text("0.1,0.2,0.3,0.4,0.5,0.6\n")
    msg = cli_error(["predict", path, readings], capsys)
    assert "6 values but the model takes 6 raw channels and the temperature per line" in msg


def test_cli_errors_give_cli_advice_not_api_advice(workdir, tmp_path, capsys):
    train = CalibrationDataset.load(workdir / "data" / "train.csv")
    one_group = CalibrationDataset(raw=train.raw, wrench=train.wrench, group=np.zeros(train.n_samples, int))
    path = one_group.save(tmp_path / "one_group.csv")
    msg = cli_error(["benchmark", "dataset", path, "--model", "linear", "--folds", "group", "--out", tmp_path / "b",
                     "-q"], capsys)
    assert "groups=None" not in msg and "remove that column" in msg


@pytest.mark.parametrize("argv", [
    ["fit", "{train}", "--model", "linear", "--tare", "-0.001,0.002,-0.003,0,0,-1e-3", "--out", "{tmp}/m", "-q"],
    ["fit", "{train}", "--model", "linear", "--tare", "-.5,0,0,0,0,0", "--out", "{tmp}/m", "-q"],
])
def test_negative_values_of_list_options_are_values(workdir, tmp_path, argv):
    fill = {"train": workdir / "data" / "train.csv", "tmp": tmp_path}
    assert run([a.format(**fill) for a in argv]) == 0
    assert (tmp_path / "m" / "linear.model.npz").exists()


def test_gravity_may_start_with_a_minus(workdir, tmp_path, capsys):
    # reaches the logs (a dataset CSV is not a run log): the gravity itself was accepted
    msg = cli_error(["identify-load", workdir / "data" / "train.csv", "--model", workdir / "models" / "linear.model.npz",
                     "--gravity", "-9.81,0,0", "--out", tmp_path / "t"], capsys)
    assert "expected one argument" not in msg and "--gravity" not in msg


def test_benchmark_dataset_help_lists_its_own_default_models(capsys):
    from ftcal.cli._benchmark import DATASET_DEFAULT_MODELS

    assert main(["benchmark", "dataset", "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    assert f"default: {', '.join(DATASET_DEFAULT_MODELS)};" in text


def test_dataset_rows_of_the_wrong_width_are_named_by_line(workdir, tmp_path, capsys):
    comments, body = data_lines(workdir)
    body[5] = body[5].rsplit(",", 1)[0]
    path = tmp_path / "short.csv"
    path.write_text("\n".join(comments + body) + "\n")
    msg = cli_error(["fit", path, "--model", "linear", "--out", tmp_path / "o"], capsys)
    assert f"line {len(comments) + 6}: 12 values but the header names 13 columns" in msg
    assert "usecols" not in msg and " row " not in msg


# ------------------------------------------------------------------ memory estimated before allocating
def test_polynomial_features_are_estimated_before_allocating():
    from ftcal.core._memory import MemoryLimitError

    rng = np.random.default_rng(0)
    X = rng.normal(size=(1200, 1000))
    with pytest.raises(MemoryLimitError, match=r"501500 monomials.*lower degree"):
        PolynomialCalibrator(degree=2).fit(X, rng.normal(size=(1200, 6)))


def test_polynomial_memory_refusal_is_one_cli_line(workdir, tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("FTCAL_MEMORY_LIMIT_GB", "0.0001")  # 100 kB: the 100-row dataset's degree-3 system is more
    msg = cli_error(["fit", workdir / "data" / "train.csv", "--model", "polynomial", "--out", tmp_path / "o", "-q"],
                    capsys)
    assert "PolynomialCalibrator(degree=3)" in msg and "FTCAL_MEMORY_LIMIT_GB" in msg


@pytest.mark.parametrize("shape, expected", [
    ((10**10, 6), "declares shape (10000000000, 6) (447.03 GiB) but holds"),
    ((1000, 6), "declares shape (1000, 6)")])
def test_npz_readings_declaring_huge_arrays_are_refused_before_reading(workdir, tmp_path, capsys, shape, expected):
    import io

    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False, "shape": shape})
    path = tmp_path / "r.npz"
    with zipfile.ZipFile(path, "w") as z:
        z.writestr("raw.npy", header.getvalue() + b"\0" * 96)
    assert expected in cli_error(["predict", workdir / "models" / "linear.model.npz", path], capsys)


@pytest.mark.parametrize("command", ["fit", "evaluate"])
def test_values_no_fit_can_square_are_named_by_file_line(workdir, tmp_path, capsys, command):
    comments, body = data_lines(workdir)
    fields = body[7].split(",")
    fields[2] = "1e308"
    body[7] = ",".join(fields)
    path = tmp_path / "huge.csv"
    path.write_text("\n".join(comments + body) + "\n")
    argv = (["fit", path, "--model", "linear"] if command == "fit"
            else ["evaluate", path, workdir / "models" / "linear.model.npz"]) + ["--out", tmp_path / "o"]
    msg = cli_error(argv, capsys)
    assert f"{path}: line {len(comments) + 8}: a raw reading of 1e+308 (column s2)" in msg


# --- review of the merged round: a huge network, labels with no order, a range file of another sensor ---------

def test_a_network_too_large_for_memory_is_refused_before_any_allocation():
    from ftcal.core._memory import MemoryLimitError

    rng = np.random.default_rng(0)
    w = rng.normal(size=(40, 6)) * [100, 100, 100, 2, 2, 2]
    raw = w @ rng.normal(size=(6, 6))
    with pytest.raises(MemoryLimitError, match=r"hidden_layer_sizes=\(100000000,\).*narrower or fewer hidden layers"):
        ftcal.DirectionalCalibrator(hidden_layer_sizes=(100_000_000,), phase1_epochs=1).fit(raw, w)


@pytest.mark.parametrize("groups", [[None] * 40, [0, "a"] * 20, [0.5, 1.5] * 20], ids=["none", "mixed", "fractional"])
def test_group_labels_without_an_order_are_a_clear_error(groups):
    from ftcal.model_selection._selection import check_groups

    with pytest.raises(ftcal.core.CalibrationInputError, match="integer or string labels"):
        check_groups(np.array(groups, dtype=object if groups[0] is None or "a" in groups else float), 40)


def test_predict_range_file_of_another_channel_count_is_refused(tmp_path, capsys):
    rng = np.random.default_rng(0)
    w = rng.normal(size=(60, 6)) * [100, 100, 100, 2, 2, 2]
    raw = w @ rng.normal(size=(6, 6))
    ftcal.save_model(ftcal.LinearCalibrator().fit(raw, w), tmp_path / "m.model.npz")
    five = CalibrationDataset(raw=raw[:, :5], wrench=w)
    five.save(tmp_path / "five.csv")
    np.savetxt(tmp_path / "readings.csv", raw[:3], delimiter=",")
    code = main(["predict", str(tmp_path / "m.model.npz"), str(tmp_path / "readings.csv"), "--range",
                 str(tmp_path / "five.csv")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("ftcal: error: --range") and "5 raw channels" in err


# ------------------------------------------------------------------ flags, generator arguments, overflow, exact CSV
@pytest.fixture(scope="module")
def small_gp():
    rng = np.random.default_rng(5)
    w = rng.normal(size=(40, 6)) * [100, 100, 100, 2, 2, 2]
    raw = w @ rng.normal(size=(6, 6))
    gp = ftcal.GaussianProcessCalibrator(max_samples=40, mean="linear", kernel="rbf", per_output=False,
                                         random_state=0).fit(raw, w)
    return gp, raw


@pytest.mark.parametrize("flag", ["no", "True", 1, 0, 1.0, None, [True]])
def test_return_std_that_is_not_a_bool_is_refused(small_gp, flag):
    gp, raw = small_gp
    with pytest.raises(CalibrationInputError, match=rf"return_std must be True or False; got {re.escape(repr(flag))}"):
        gp.predict(raw[:2], return_std=flag)


@pytest.mark.parametrize("flag", ["no", 1, None])
def test_return_std_of_auto_that_is_not_a_bool_is_refused(small_gp, flag):
    gp, raw = small_gp
    rows = np.vstack([raw, raw * 1.01])  # 80 rows: 64-row training folds, enough to judge a GP on 6 channels
    auto = ftcal.AutoCalibrator(candidates=[("gaussian_process", gp)], baselines=False, stack=False,
                                random_state=0).fit(rows, gp.predict(rows))
    with pytest.raises(CalibrationInputError, match=rf"return_std must be True or False; got {re.escape(repr(flag))}"):
        auto.predict(raw[:2], return_std=flag)


def test_network_overflow_is_named_float32():
    from ftcal.networks._base import NetworkCalibrator

    assert "float32" in NetworkCalibrator._overflow_note


def test_return_std_takes_python_and_numpy_bools(small_gp):
    gp, raw = small_gp
    for yes in (True, np.True_):
        mean, std = gp.predict(raw[:3], return_std=yes)
        assert mean.shape == std.shape == (3, 6) and np.all(std > 0)
    for no in (False, np.False_):
        assert gp.predict(raw[:3], return_std=no).shape == (3, 6)


def test_return_std_of_a_one_dimensional_target_is_one_dimensional(small_gp):
    _, raw = small_gp
    y = raw @ np.arange(1.0, 7.0)
    gp = ftcal.GaussianProcessCalibrator(max_samples=40, mean="linear", kernel="rbf", per_output=False,
                                         random_state=0).fit(raw, y)
    mean, std = gp.predict(raw[:4], return_std=True)
    assert mean.shape == std.shape == (4,)
    np.testing.assert_array_equal(mean, gp.predict(raw[:4]))


@pytest.mark.parametrize(("make", "kwargs", "message"), [
    ("make_soft_sensor_dataset", {"n_samples": -5}, r"'n_samples' parameter .* int in the range \[1, inf\)\. Got -5"),
    ("make_soft_sensor_dataset", {"n_samples": 0}, r"'n_samples' .* Got 0 instead"),
    ("make_soft_sensor_dataset", {"n_samples": 100.0}, r"'n_samples' parameter .* must be an int .* Got 100\.0"),
    ("make_soft_sensor_dataset", {"n_samples": True}, r"'n_samples' .* not a bool\. Got True"),
    ("make_soft_sensor_dataset", {"n_samples": 100, "n_zero": 200}, r"n_zero=200 .* n_samples=100 .* at most 95"),
    ("make_soft_sensor_dataset", {"n_zero": -1}, r"'n_zero' .* Got -1"),
    ("make_soft_sensor_dataset", {"n_presses": 0}, r"'n_presses' .* Got 0"),
    ("make_soft_sensor_dataset", {"n_samples": 20, "n_zero": 0, "n_presses": 21}, r"n_presses=21 .* n_samples is 20"),
    ("make_soft_sensor_dataset", {"hysteresis": float("nan")}, r"'hysteresis' .* \[0\.0, 10\.0\]\. Got nan"),
    ("make_soft_sensor_dataset", {"hysteresis": 1e300}, r"'hysteresis' .* Got 1e\+300"),
    ("make_soft_sensor_dataset", {"random_state": -1}, r"'random_state' .* Got -1"),
    ("make_robot_held_dataset", {"n_samples": 10, "n_poses": 47}, r"n_poses=47 .* n_samples is 10"),
    ("make_robot_held_dataset", {"n_samples": 1, "n_poses": 1}, r"'n_samples' .* \[2, inf\)\. Got 1"),
    ("make_robot_held_dataset", {"n_poses": 0}, r"'n_poses' .* Got 0"),
    ("make_robot_held_dataset", {"tool_mass_kg": -1.0}, r"'tool_mass_kg' .* \[0\.0, 1000\.0\]\. Got -1\.0"),
    ("make_robot_held_dataset", {"tool_mass_kg": float("inf")}, r"'tool_mass_kg' .* Got inf"),
    ("make_robot_held_dataset", {"pose_offset": float("nan")}, r"'pose_offset' .* Got nan"),
    ("make_dead_weight_dataset", {"n_samples": 0}, r"'n_samples' .* Got 0"),
    ("make_dead_weight_dataset", {"n_validation": -1}, r"'n_validation' .* Got -1"),
    ("make_dead_weight_dataset", {"range_factor": 0.5}, r"'range_factor' .* \[1\.0, 1000\.0\]\. Got 0\.5"),
    ("make_dead_weight_dataset", {"range_factor": float("inf")}, r"'range_factor' .* Got inf"),
    ("make_dead_weight_dataset", {"n_channels": 0}, r"'n_channels' .* \[3, inf\)\. Got 0"),
    ("make_dead_weight_dataset", {"n_channels": 2}, r"'n_channels' .* Got 2"),
    ("make_dead_weight_dataset", {"nonlinearity": float("nan")}, r"'nonlinearity' .* Got nan"),
])
def test_dataset_generators_name_a_bad_argument_and_its_value(make, kwargs, message):
    with pytest.raises(CalibrationInputError, match=message):
        getattr(ftcal.simulation, make)(**kwargs)


@pytest.mark.parametrize("make", ["make_soft_sensor_dataset", "make_robot_held_dataset", "make_dead_weight_dataset"])
def test_dataset_generators_refuse_huge_row_counts_before_allocating(make):
    from ftcal.core._memory import MemoryLimitError

    with pytest.raises(MemoryLimitError, match=r"n_samples=1000000000000 rows would need .*; lower n_samples"):
        getattr(ftcal.simulation, make)(n_samples=10**12)


def test_dataset_generators_at_the_edges_of_their_ranges_give_finite_data():
    datasets = [ftcal.simulation.make_soft_sensor_dataset(1, n_zero=0, n_presses=1),
                ftcal.simulation.make_soft_sensor_dataset(10, n_zero=5, n_presses=10, hysteresis=10.0),
                ftcal.simulation.make_robot_held_dataset(np.int64(2), n_poses=2, tool_mass_kg=0.0, pose_offset=1.0),
                *ftcal.simulation.make_dead_weight_dataset(1, n_validation=1, n_channels=3, range_factor=1000, nonlinearity=-1)]
    assert [d.n_samples for d in datasets] == [1, 10, 2, 1, 1]
    for d in datasets:
        assert np.isfinite(d.raw).all() and np.isfinite(d.wrench).all() and np.isfinite(d.meta["noise_floor_rmse"])


@pytest.mark.parametrize(("kwargs", "message"), [
    ({"n_channels": 0}, r"'n_channels' parameter of stock_baselines .* \[1, inf\)\. Got 0"),
    ({"n_channels": 6.0}, r"'n_channels' .* Got 6\.0"),
    ({"n_channels": "6"}, r"'n_channels' .* Got '6'"),
    ({"n_channels": True}, r"'n_channels' .* not a bool"),
    ({"n_channels": 6, "max_kernel_samples": 0}, r"'max_kernel_samples' .* \[1, inf\) or None\. Got 0"),
    ({"n_channels": 6, "max_kernel_samples": 2.5}, r"'max_kernel_samples' .* Got 2\.5"),
    ({"n_channels": 6, "random_state": -2}, r"'random_state' .* Got -2"),
])
def test_stock_baselines_name_a_bad_argument(kwargs, message):
    from ftcal.calibrators import stock_baselines

    with pytest.raises(CalibrationInputError, match=message):
        stock_baselines(**kwargs)
    assert list(stock_baselines(np.int64(6), max_kernel_samples=None)) == list(ftcal.calibrators.STOCK_BASELINE_NAMES)


@pytest.mark.parametrize("value", ["1e300", "-1e300", "1e7", "inf", "nan"])
def test_simulate_refuses_an_absurd_zero_offset_in_one_line(tmp_path, capsys, value):
    out = tmp_path / "data"
    msg = cli_error(["simulate", "dataset", "--n-per-sphere", "5", "--n-test", "5", f"--zero-offset={value}",
                     "--out", out, "-q"], capsys)
    # the default sensor reads at most ~9.7 V at its rated loads (pinv(C) over the rated box): 10^6 x that
    expected = "is not a finite number" if value in ("inf", "nan") else \
        r"accepted range is -9\.67e\+06 to 9\.67e\+06 V \(1e\+06 x the sensor's raw full scale, 9\.67 V\)"
    assert re.search(expected, msg), msg
    assert not (out / "train.csv").exists()


def test_zero_offset_within_range_is_in_the_readings_and_in_the_file_exactly(tmp_path):
    assert run(["simulate", "dataset", "--n-per-sphere", "5", "--n-test", "5", "--zero-offset", "9e6", "--seed", "3",
                "--out", tmp_path / "a", "-q"]) == 0
    assert run(["simulate", "dataset", "--n-per-sphere", "5", "--n-test", "5", "--seed", "3", "--out", tmp_path / "b",
                "-q"]) == 0
    offset = CalibrationDataset.load(tmp_path / "a" / "train.csv")
    tared = CalibrationDataset.load(tmp_path / "b" / "train.csv")
    # the signal (|raw| < 10 V) survives an offset of 9e6 to float64's resolution there (~2e-9 V), file included
    np.testing.assert_allclose(offset.raw - 9e6, tared.raw, rtol=0, atol=4e-9)
    np.testing.assert_array_equal(offset.wrench, tared.wrench)
    with pytest.raises(CalibrationInputError, match=r"zero_offset holds 1e\+12 \(channel 0\); the accepted range"):
        ftcal.simulation.VirtualSensor(zero_offset=np.full(6, 1e12))


def test_dataset_csv_round_trip_is_exact(tmp_path):
    rng = np.random.default_rng(8)
    n = 200
    raw = 2**20 + rng.normal(size=(n, 7)) * 10.0 ** rng.integers(-12, 4, size=(n, 7))  # counts far above the signal
    raw[0, :4] = [5e-324, -0.0, 1.7976931348623157e308, 0.1]
    wrench = rng.normal(size=(n, 6)) * 10.0 ** rng.integers(-20, 20, size=(n, 6))
    data = CalibrationDataset(raw=raw, wrench=wrench, group=rng.integers(-2**62, 2**62, size=n),
                              temperature=rng.uniform(15, 35, n), meta={"note": "exact"})
    back = CalibrationDataset.load(data.save(tmp_path / "d.csv"))
    for name in ("raw", "wrench", "group", "temperature"):
        np.testing.assert_array_equal(getattr(back, name), getattr(data, name), err_msg=name)
    assert np.signbit(back.raw[0, 1]) and back.meta == {"note": "exact"}
    assert back.raw.tobytes() == raw.tobytes() and back.wrench.tobytes() == wrench.tobytes()


def test_run_log_round_trip_is_exact(tmp_path):
    from ftcal.io._logs import read_run_log, write_run_log

    rng = np.random.default_rng(9)
    n = 30
    q = rng.uniform(-np.pi, np.pi, size=(n, 7))
    raw = 8_388_608 + rng.normal(size=(n, 6)) * 1e-3  # a 24-bit ADC's mid-scale with sub-count detail
    write_run_log(tmp_path / "run.csv", timestamp=np.arange(n) * 0.01, run_kind=["load"] * n, config=[1] * n,
                  pose=np.arange(n), q=q, raw=raw)
    log = read_run_log(tmp_path / "run.csv")
    assert log.q.tobytes() == q.tobytes() and log.raw.tobytes() == raw.tobytes()


def _overflow_models():
    rng = np.random.default_rng(6)
    w = rng.normal(size=(40, 6)) * [100, 100, 100, 2, 2, 2]
    raw = w @ rng.normal(size=(6, 6))
    gp = dict(max_samples=40, per_output=False, random_state=0)
    return raw, {
        "linear": (LinearCalibrator().fit(raw, w), 1e308, "its float64 computation exceeds float64's largest"),
        "polynomial": (PolynomialCalibrator(degree=3).fit(raw, w), 1e120, "float64"),
        "gp_matern": (ftcal.GaussianProcessCalibrator(mean="linear", kernel="matern52", **gp).fit(raw, w), 1e200,
                      "its kernel squares the distance from the reading to the training readings"),
        "gp_matern_linear": (ftcal.GaussianProcessCalibrator(mean="none", kernel="matern52+linear", **gp).fit(raw, w),
                             1e200, "its kernel squares the distance"),
    }


@pytest.mark.parametrize("kind", ["linear", "polynomial", "gp_matern", "gp_matern_linear"])
def test_overflowing_readings_are_named_for_what_overflowed_without_runtime_warnings(kind):
    import warnings

    raw, models = _overflow_models()
    model, value, note = models[kind]
    bad = np.vstack([raw[:1], np.full((1, 6), value)])
    calls = [lambda: model.predict(bad)]
    if kind.startswith("gp"):
        calls.append(lambda: model.predict(bad, return_std=True))
    for call in calls:
        with warnings.catch_warnings():
            warnings.simplefilter("error")  # no RuntimeWarning (overflow, invalid value) may leak
            with pytest.raises(CalibrationInputError, match="X row 1 ") as info:
                call()
        msg = str(info.value)
        assert "non-finite" in msg and note in msg and "float32" not in msg and "network" not in msg, msg


def test_gp_far_outside_its_data_gives_the_linear_mean_or_an_error_never_a_warning():
    """An RBF kernel between a reading at 1e200 and the training readings is exp(-inf) = 0 (the limit): the GP gives
    its linear mean there, with the prior's standard deviation; with a linear kernel term the variance is
    inf - inf, an error naming the standard deviation."""
    import warnings

    rng = np.random.default_rng(7)
    w = rng.normal(size=(40, 6)) * [100, 100, 100, 2, 2, 2]
    raw = w @ rng.normal(size=(6, 6))
    far = np.vstack([raw[:1], raw[1:2] * 1e198])
    rbf = ftcal.GaussianProcessCalibrator(mean="linear", kernel="rbf", max_samples=40, per_output=False,
                                          random_state=0).fit(raw, w)
    with_linear = ftcal.GaussianProcessCalibrator(mean="none", kernel="rbf+linear", max_samples=40,
                                                  per_output=False, random_state=0).fit(raw, w)
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        mean, std = rbf.predict(far, return_std=True)
        ltm = (far - rbf.zero_reading_) @ rbf.linear_matrix_.T  # the linear mean, in torque-scaled units
        np.testing.assert_allclose(ftcal.core.scale_torques(mean[1:], rbf.alpha_), ltm[1:], rtol=1e-9)
        assert np.all(np.isfinite(std)) and np.all(std[1] >= std[0])
        with pytest.raises(CalibrationInputError, match="X row 1 .*non-finite standard deviation"):
            with_linear.predict(far, return_std=True)


# ------------------------------------------------------------------ fuzz session 9: standard streams and signals
def _closing(fd: int):
    def close() -> None:
        _default_sigint()
        os.close(fd)
    return close


@pytest.mark.parametrize("command, fd, message", [
    ("predict", 1, "standard output is closed"),
    ("predict-stdin", 0, "standard input is closed"),
    ("evaluate", 1, "standard output is closed"),
])
def test_closed_standard_streams_are_one_clear_error(workdir, tmp_path, command, fd, message):
    model = workdir / "models" / "linear.model.npz"
    if command == "predict":
        args = ["predict", model, workdir / "data" / "test.csv"]
    elif command == "predict-stdin":
        args = ["predict", model, "-"]
    else:
        args = ["evaluate", workdir / "data" / "test.csv", model, "--no-plots", "--out", tmp_path / "ev", "-q"]
    proc = subprocess.run([sys.executable, "-m", "ftcal", *map(str, args)], cwd=tmp_path,
                          stdout=subprocess.DEVNULL if fd == 0 else None,
                          stderr=subprocess.PIPE, text=True, preexec_fn=_closing(fd), timeout=300)
    err = [ln for ln in proc.stderr.strip().splitlines() if not ln.startswith("ftcal: warning: ")]  # data's facts
    assert proc.returncode == 2, err
    assert len(err) == 1 and err[0].startswith("ftcal: error: ") and message in err[0], err


def test_a_command_that_does_not_use_the_closed_stream_still_runs(workdir, tmp_path):
    proc = subprocess.run([sys.executable, "-m", "ftcal", "fit", str(workdir / "data" / "train.csv"), "--model",
                           "linear", "--out", str(tmp_path / "m"), "-q"], cwd=tmp_path, stderr=subprocess.PIPE,
                          text=True, preexec_fn=_closing(1), timeout=300)  # imports pandas, which reads stdout's encoding
    assert proc.returncode == 0 and proc.stderr == "", proc.stderr
    assert (tmp_path / "m" / "linear.model.npz").is_file()


def test_a_full_standard_output_is_named(workdir, tmp_path):
    with open("/dev/full", "w") as full:
        proc = subprocess.run([sys.executable, "-m", "ftcal", "predict", str(workdir / "models" / "linear.model.npz"),
                               str(workdir / "data" / "test.csv")], cwd=tmp_path, stdout=full, stderr=subprocess.PIPE,
                              text=True, timeout=300)
    err = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, err
    assert len(err) == 1 and "could not write to standard output (No space left on device)" in err[0], err


def test_a_reader_that_leaves_early_is_no_error(workdir, tmp_path):
    big = tmp_path / "big.csv"
    line = ",".join(["0.1"] * 6) + "\n"
    big.write_text("s0,s1,s2,s3,s4,s5\n" + line * 200_000)
    proc = subprocess.Popen([sys.executable, "-m", "ftcal", "predict", str(workdir / "models" / "linear.model.npz"),
                             str(big)], cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.readline()
    proc.stdout.close()  # `| head -1`
    err = proc.communicate(timeout=300)[1].decode()
    assert proc.returncode == 0 and err == "", err


@pytest.mark.skipif(not hasattr(signal, "SIGHUP"), reason="this OS has no SIGHUP")
@pytest.mark.parametrize("command", ["predict", "fit"])
def test_sighup_removes_the_partial_output(workdir, tmp_path, command):
    if command == "predict":
        out = tmp_path / "wrench.csv"
        args = ["predict", workdir / "models" / "linear.model.npz", "-", "--output", out]
        proc = subprocess.Popen([sys.executable, "-m", "ftcal", *map(str, args)], cwd=tmp_path, stdin=subprocess.PIPE,
                                stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint)
        proc.stdin.write("0.1,0.2,0.3,0.4,0.5,0.6\n" * 10)
        proc.stdin.flush()  # mid-stream: the partial file exists
        _wait_for(lambda: list(tmp_path.glob(".wrench.*.partial.csv")), "the partial output", proc)
        proc.send_signal(signal.SIGHUP)
        err = proc.communicate(timeout=120)[1]
        code = proc.returncode
    else:
        out = tmp_path / "models"
        out.mkdir()
        args = ["fit", workdir / "data" / "train.csv", "--model", "directional", "--schedule", "short", "--param",
                "phase1_epochs=20000", "--param", "hidden_layer_sizes=[8]", "--out", out, "--force"]
        code, err = _interrupt_after_training_starts(_start_cli(args, tmp_path), "fitting", signal.SIGHUP)
    assert code == 128 + signal.SIGHUP, err
    assert "interrupted by SIGHUP (no half-written file is left)" in err and "Traceback" not in err
    assert not list(tmp_path.rglob(".*partial*"))
    assert not out.exists() if command == "predict" else not list(out.iterdir())


# ------------------------------------------------------------------ fuzz session 9: dataset CSV lines and comments
def _edit_cell(workdir, tmp_path, data_row: int, column: str, value: str) -> Path:
    """train.csv with one cell of data row ``data_row`` (0-based) replaced; line numbers are those of the file."""
    lines = (workdir / "data" / "train.csv").read_text().splitlines()
    header_at = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    names = lines[header_at].split(",")
    fields = lines[header_at + 1 + data_row].split(",")
    fields[names.index(column)] = value
    lines[header_at + 1 + data_row] = ",".join(fields)
    path = tmp_path / f"edited_{column}.csv"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.mark.parametrize("column, value, expected", [
    ("Fz", "", "column Fz: empty value"),
    ("Fz", "1.0.0", "column Fz: '1.0.0' is not a number"),
    ("s2", "\u0661\u0662", "column s2: '\u0661\u0662' is not a number"),
    ("s2", "nan", "column s2: 'nan' is NaN or inf"),
    ("group", "1.5", "column group: 1.5 is not an integer label"),
])
def test_dataset_value_errors_name_the_file_line_and_column(workdir, tmp_path, capsys, column, value, expected):
    path = _edit_cell(workdir, tmp_path, 3, column, value)  # data row 3 is line 6 (meta, header, rows 0-2)
    msg = cli_error(["fit", path, "--model", "linear", "--out", tmp_path / "m"], capsys)
    assert f"{path}: line 6, {expected}" in msg, msg
    assert "row 3" not in msg


@pytest.mark.parametrize("value, expected", [("nan", "temperature is NaN or inf"), ("300", "is it in kelvin")])
def test_dataset_temperature_errors_name_the_file_line(tmp_path, value, expected):
    ds = CalibrationDataset(raw=np.eye(8, 6), wrench=np.eye(8, 6), temperature=np.linspace(20, 30, 8))
    lines = ds.save(tmp_path / "d.csv").read_text().splitlines()
    lines[7] = lines[7].rsplit(",", 1)[0] + "," + value  # data row 5, file line 8
    (tmp_path / "d.csv").write_text("\n".join(lines) + "\n")
    with pytest.raises(DatasetFileError, match=rf"d\.csv: line 8, column temperature: .*{expected}"):
        CalibrationDataset.load(tmp_path / "d.csv")


def test_dataset_npz_errors_say_how_rows_are_counted(tmp_path):
    raw = np.ones((4, 6))
    raw[1, 2] = np.nan
    np.savez(tmp_path / "d.npz", raw=raw, wrench=np.zeros((4, 6)))
    with pytest.raises(DatasetFileError, match=r"d\.npz: array 'raw', row 1 \(rows counted from 0\): NaN or inf"):
        CalibrationDataset.load(tmp_path / "d.npz")


@pytest.mark.parametrize("where", ["top", "after_meta", "after_header", "between_rows", "end"])
def test_blank_and_comment_lines_are_skipped_anywhere_in_a_dataset(workdir, tmp_path, where):
    lines = (workdir / "data" / "train.csv").read_text().splitlines()
    at = {"top": 0, "after_meta": 1, "after_header": 2, "between_rows": 10, "end": len(lines)}[where]
    edited = lines[:at] + ["", "# a comment", "   "] + lines[at:]
    path = tmp_path / "d.csv"
    path.write_text("\n".join(edited) + "\n")
    original = CalibrationDataset.load(workdir / "data" / "train.csv")
    back = CalibrationDataset.load(path)
    np.testing.assert_array_equal(back.raw, original.raw)
    np.testing.assert_array_equal(back.group, original.group)
    assert back.meta == original.meta
    last = len(edited) - 1 - (3 if where == "end" else 0)  # the last data line: its number is the file's
    edited[last] = "1_000" + edited[last][edited[last].index(","):]
    path.write_text("\n".join(edited) + "\n")
    with pytest.raises(DatasetFileError, match=rf"line {last + 1}, column s0: '1_000'"):
        CalibrationDataset.load(path)


def test_a_second_meta_comment_is_refused_naming_both_lines(workdir, tmp_path, capsys):
    lines = (workdir / "data" / "train.csv").read_text().splitlines()
    path = tmp_path / "d.csv"
    path.write_text("\n".join(lines[:1] + ['# meta: {"alpha": 5.0}'] + lines[1:]) + "\n")
    msg = cli_error(["fit", path, "--model", "linear", "--out", tmp_path / "m"], capsys)
    assert f"{path}: line 2: a second '# meta:' comment (the first is line 1)" in msg


# ------------------------------------------------------------------ fuzz session 9: array types and foreign files
@pytest.mark.parametrize("suffix, make, expected", [
    (".npz", lambda raw: raw.astype(complex), "array 'raw' has dtype complex128 (complex numbers)"),
    (".npz", lambda raw: raw > 0, "array 'raw' has dtype bool (booleans)"),
    (".npz", lambda raw: raw.astype("datetime64[s]"), "array 'raw' has dtype datetime64[s] (dates)"),
    (".npz", lambda raw: raw.astype(str), "array 'raw' has dtype <U"),
    (".npz", lambda raw: raw.astype(object), "array 'raw' holds Python objects (a pickle), which ftcal never loads"),
    (".mat", lambda raw: raw.astype(complex), "variable 'raw' has dtype complex128 (complex numbers)"),
    (".mat", lambda raw: np.array([raw], dtype=object), "variable 'raw' has dtype object (objects (a MATLAB cell"),
    (".mat", lambda raw: {"a": raw}, "variable 'raw' is a MATLAB struct (fields, not an array of numbers)"),
    (".mat", lambda raw: __import__("scipy.sparse").sparse.csr_matrix(raw), "variable 'raw' is a sparse matrix"),
    (".mat", lambda raw: "text", "variable 'raw' has dtype <U4 (text)"),
])
def test_arrays_that_are_not_real_numbers_are_refused_by_name_and_type(workdir, tmp_path, capsys, suffix, make,
                                                                       expected):
    import scipy.io

    ds = CalibrationDataset.load(workdir / "data" / "train.csv")
    path = tmp_path / f"d{suffix}"
    if suffix == ".npz":
        np.savez(path, raw=make(ds.raw), wrench=ds.wrench)
    else:
        scipy.io.savemat(path, {"raw": make(ds.raw), "wrench": ds.wrench})
    msg = cli_error(["fit", path, "--model", "linear", "--out", tmp_path / "m"], capsys)
    assert f"{path}: {expected}" in msg, msg
    assert not (tmp_path / "m").exists()


def test_a_csv_named_npz_is_not_read_as_a_pickle(workdir, tmp_path, capsys):
    path = tmp_path / "train.npz"
    path.write_bytes((workdir / "data" / "train.csv").read_bytes())
    msg = cli_error(["fit", path, "--model", "linear", "--out", tmp_path / "m"], capsys)
    assert f"{path}: not an .npz (zip) archive: it is a text file" in msg, msg
    assert "pickle" not in msg


# ------------------------------------------------------------------ fuzz session 9: predict --range
def _range_report(tmp_path, raw_min, raw_max) -> Path:
    path = tmp_path / "r.report.json"
    path.write_text(json.dumps({"calibrated_range": {"raw_min": raw_min, "raw_max": raw_max}}))
    return path


@pytest.mark.parametrize("raw_min, raw_max, expected", [
    ([float("nan")] * 6, [1.0] * 6, "calibrated_range.raw_min[0] is nan, not a finite number"),
    ([1.0] * 6, [-1.0] * 6, "calibrated_range.raw_min[0] = 1 is above raw_max[0] = -1"),
    ([0.0] * 5, [1.0] * 6, "calibrated_range.raw_min has 5 entries but raw_max has 6"),
    ("low", [1.0] * 6, "calibrated_range.raw_min is not a list of numbers"),
    ([0.0, "a", 0, 0, 0, 0], [1.0] * 6, "calibrated_range.raw_min is not a list of numbers"),
])
def test_predict_range_report_is_validated(workdir, tmp_path, capsys, raw_min, raw_max, expected):
    report = _range_report(tmp_path, raw_min, raw_max)
    msg = cli_error(["predict", workdir / "models" / "linear.model.npz", workdir / "data" / "test.csv", "--range",
                     report], capsys)
    assert msg.startswith(f"ftcal: error: --range {report}: ") and expected in msg, msg


def test_predict_range_given_a_model_file_says_so_with_predicts_own_options(workdir, tmp_path, capsys):
    model = workdir / "models" / "linear.model.npz"
    msg = cli_error(["predict", model, workdir / "data" / "test.csv", "--range", model], capsys)
    assert f"--range {model} is a model file" in msg and "--wrench" not in msg and "--channels" not in msg, msg
    np.savez(tmp_path / "other.npz", readings=np.ones((3, 6)))
    msg = cli_error(["predict", model, workdir / "data" / "test.csv", "--range", tmp_path / "other.npz"], capsys)
    assert "no array 'wrench'" in msg and "--wrench" not in msg and "--channels" not in msg, msg


# ------------------------------------------------------------------ fuzz session 9: errors name the file
def test_library_errors_about_the_data_name_the_dataset_file(workdir, tmp_path, capsys):
    lines = (workdir / "data" / "train.csv").read_text().splitlines()
    header_at = next(i for i, ln in enumerate(lines) if not ln.startswith("#"))
    for i in range(header_at + 1, len(lines)):  # channel s5 a copy of s4: the readings span 5 directions
        fields = lines[i].split(",")
        fields[5] = fields[4]
        lines[i] = ",".join(fields)
    path = tmp_path / "dup_channel.csv"
    path.write_text("\n".join(lines) + "\n")
    msg = cli_error(["fit", path, "--model", "linear", "--out", tmp_path / "m", "-q"], capsys)
    assert msg.startswith(f"ftcal: error: {path}: X (raw readings") and "spans only 5" in msg, msg


def test_report_on_too_few_rows_names_the_fold_and_the_rows_needed(workdir, tmp_path, capsys):
    ds = CalibrationDataset.load(workdir / "data" / "train.csv")
    small = ds.subset(np.arange(7))
    small.group = None
    small.save(tmp_path / "seven.csv")
    code = main(["report", str(workdir / "models" / "linear.model.npz"), str(tmp_path / "seven.csv"), "--out",
                 str(tmp_path / "rep"), "-q"])
    err = [ln for ln in capsys.readouterr().err.splitlines() if not ln.startswith("ftcal: warning:")]
    assert code == 2 and len(err) == 1, err
    assert (f"{tmp_path / 'seven.csv'}: the report's 5-fold cross-validation of its 7 rows trains LinearCalibrator "
            "on only 5 rows (one fold held out), but LinearCalibrator needs at least 7; 5 folds need a dataset of at "
            "least 9 rows") in err[0], err
    assert not (tmp_path / "rep").exists() or not list((tmp_path / "rep").iterdir())
    assert err[0].endswith("Fix: record more rows"), err  # 7 rows: no number of folds trains on 7


def test_report_on_few_rows_suggests_the_folds_that_work_and_they_do(workdir, tmp_path, capsys):
    # 8 rows: 5 folds train on 6, 8 folds (leave one out) on 7 = LinearCalibrator's minimum
    ds = CalibrationDataset.load(workdir / "data" / "train.csv")
    small = ds.subset(np.arange(8))
    small.group = None
    small.save(tmp_path / "eight.csv")
    argv = ["report", str(workdir / "models" / "linear.model.npz"), str(tmp_path / "eight.csv"), "--no-baselines",
            "--out", str(tmp_path / "rep"), "-q"]
    assert main(argv) == 2
    err = [ln for ln in capsys.readouterr().err.splitlines() if not ln.startswith("ftcal: warning:")]
    assert "Fix: pass --cv 8 (more folds hold out fewer rows each), or record more rows" in err[0], err
    assert main([*argv, "--cv", "8"]) == 0


def test_an_output_folder_named_like_a_choice_is_no_input(workdir, tmp_path, monkeypatch):
    # `--model linear --out linear`: the model name is no path, even with a folder `linear` (holding the previous
    # fit) in the working directory; refitting into it with --force works
    monkeypatch.chdir(tmp_path)
    (tmp_path / "linear").mkdir()
    argv = ["fit", str(workdir / "data" / "train.csv"), "--model", "linear", "--out", "linear", "-q"]
    assert main(argv) == 0
    assert main([*argv, "--force"]) == 0
    assert (tmp_path / "linear" / "linear.model.npz").is_file()


def test_prepare_into_its_own_logs_folder_is_refused_as_such(tmp_path, capsys):
    logs = tmp_path / "logs"
    ftcal.experiment.simulate_experiment(logs, robot=ftcal.robot.load_robot("kuka_iiwa14"), subdivisions=0, random_state=0)
    before = sorted(p.name for p in logs.iterdir())
    msg = cli_error(["prepare", logs, "--out", logs, "-q"], capsys)
    assert f"--out {logs} is the logs folder {logs}, an input of this command" in msg, msg
    assert sorted(p.name for p in logs.iterdir()) == before


# ------------------------------------------------------------------ fuzz session 9: broken URDF files
_NO_LIMITS_URDF = """<?xml version="1.0"?>
<robot name="r">
  <link name="a"/><link name="b"/>
  <joint name="j" type="revolute"><parent link="a"/><child link="b"/><axis xyz="0 0 1"/></joint>
</robot>
"""


@pytest.mark.parametrize("content, expected", [
    ("garbage\n", "line 1, column 1: not valid XML (syntax error)"),
    ('<?xml version="1.0"?>\n<robot name="r">\n  <link name="a">\n</robot>\n', "line 4, column 3: not valid XML"),
    ("", "the URDF file is empty"),
    (_NO_LIMITS_URDF, "urdfdom: Joint [j] is of type REVOLUTE but it does not specify limits"),
])
def test_a_broken_urdf_is_one_line_saying_what_is_wrong(tmp_path, content, expected):
    urdf = tmp_path / "g.urdf"
    urdf.write_text(content)
    proc = subprocess.run([sys.executable, "-m", "ftcal", "plan", "--robot", str(urdf), "--sensor-frame", "b",
                           "--out", str(tmp_path / "plan"), "-q"], cwd=tmp_path, capture_output=True, text=True,
                          timeout=300)
    err = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, err
    assert len(err) == 1 and err[0].startswith("ftcal: error: ") and expected in err[0], err
    assert str(urdf) in err[0]


# ------------------------------------------------------------------ fuzz session 9: tune distributions
@pytest.mark.parametrize("grid, n_iter, expected", [
    ("ridge=loguniform(1,0)", True, "loguniform(a, b) needs 0 < a < b; got a = 1, b = 0"),
    ("ridge=loguniform(0, 1)", True, "loguniform(a, b) needs 0 < a < b; got a = 0, b = 1"),
    ("ridge=uniform(2, 2)", True, "uniform(a, b) needs a < b"),
    ("ridge=randint(1.5, 3)", True, "randint(a, b) needs integers a <= b"),
    ("ridge=loguniform(nan, 1)", True, "loguniform(a, b) needs finite bounds"),
    ("ridge=loguniform(1e-4, 1e-2)", False, "a distribution is sampled by a randomized search; pass --n-iter N"),
])
def test_tune_distribution_bounds_are_checked_before_any_work(workdir, tmp_path, capsys, grid, n_iter, expected):
    argv = ["tune", workdir / "data" / "train.csv", "--grid", grid, "--out", tmp_path / "t", "-q",
            *(["--n-iter", "2"] if n_iter else [])]
    msg = cli_error(argv, capsys)
    assert f"--grid '{grid}': {expected}" in msg and "Domain error" not in msg, msg
    assert not (tmp_path / "t").exists()


@pytest.mark.parametrize("reader", ["predict", "log"])
def test_digits_of_other_scripts_are_refused_by_every_text_reader(workdir, tmp_path, capsys, reader):
    arabic = "\u0661\u0662"  # float() reads it as 12
    if reader == "predict":
        path = tmp_path / "r.csv"
        path.write_text(f"s0,s1,s2,s3,s4,s5\n0.1,0.2,{arabic},0.4,0.5,0.6\n")
        msg = cli_error(["predict", workdir / "models" / "linear.model.npz", path], capsys)
        assert f"{path}: line 2: '{arabic}' is not a number" in msg, msg
    else:
        path = ftcal.io.write_run_log(tmp_path / "run.csv", timestamp=[0.0, 1.0], run_kind=["load", "load"],
                                   config=[0, 0], pose=[0, 1], q=np.zeros((2, 7)), raw=np.ones((2, 6)), load_mass=2.0)
        lines = path.read_text().splitlines()
        lines[-1] = lines[-1].rsplit(",", 1)[0] + "," + arabic
        path.write_text("\n".join(lines) + "\n")
        with pytest.raises(LogFormatError, match=rf"line {len(lines)}: column s5: '{arabic}' is not a number"):
            ftcal.io.read_run_log(path)


def test_parameter_errors_are_not_blamed_on_the_dataset(workdir, tmp_path, capsys):
    msg = cli_error(["fit", workdir / "data" / "train.csv", "--model", "linear", "--param", "ridge=-1", "--out",
                     tmp_path / "m", "-q"], capsys)
    assert "'ridge' parameter" in msg and str(workdir / "data" / "train.csv") not in msg, msg


def test_a_model_member_declaring_an_empty_array_of_absurd_length_is_refused(tmp_path):
    # shape (1e10, 0) declares no bytes, so no size check sees it; its length is checked against what it holds
    from ftcal import LinearCalibrator, load_model, save_model
    from ftcal.core import ModelFileError
    from test_model_io import replace_member

    rng = np.random.default_rng(0)
    w = rng.normal(size=(60, 6))
    path = save_model(LinearCalibrator().fit(w @ rng.normal(size=(6, 6)), w), tmp_path / "m.model.npz")
    def empty_but_long(zf):
        with zf.open("fitted/offset_.npy", "w") as f:
            np.lib.format.write_array_header_1_0(f, {"descr": "<f8", "fortran_order": False, "shape": (10**10, 0)})

    replace_member(path, "fitted/offset_", empty_but_long)
    with pytest.raises(ModelFileError, match=r"declares shape \(10000000000, 0\), a dimension longer than the 0 "
                                             r"values it holds"):
        load_model(path)
