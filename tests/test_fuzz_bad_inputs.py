"""The bad inputs and faults of issue 11, kept as a regression suite.

Each case is a real call (library or CLI) with a bad input; each must end in a clear domain error (a
``ValueError`` subclass naming what is wrong, or ``ftcal: error: ...`` and exit 2 on the command line) or in
the right answer, and must never lose or overwrite a file the user had.
"""

from __future__ import annotations

import hashlib
import json
import os
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np
import pytest

import ftcal
from ftcal import (
    CalFileError,
    CalibrationDataset,
    CalibrationInputError,
    ComparativeCalibrator,
    DatasetFileError,
    DirectionalCalibrator,
    LinearCalibrator,
    LogFormatError,
    ModelFileError,
    PolynomialCalibrator,
)
from ftcal.core._files import atomic_output
from ftcal.cli import main

TINY = dict(hidden_layer_sizes=(8,), max_epochs=3, plateau_epochs=1, max_recover_epochs=1, random_state=0)
TINY_CLI = ["--schedule", "short", "--param", "max_epochs=3", "--param", "plateau_epochs=1",
            "--param", "max_recover_epochs=1", "--param", "hidden_layer_sizes=[8]"]


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
        extra = [] if model == "linear" else TINY_CLI
        assert run(["fit", str(root / "data" / "train.csv"), "--model", model, *extra, "--out",
                     str(root / "models"), "-q"]) == 0
    return root


def data_lines(workdir) -> tuple[list[str], list[str]]:
    lines = (workdir / "data" / "train.csv").read_text().splitlines()
    comments = [ln for ln in lines if ln.startswith("#")]
    return comments, [ln for ln in lines if not ln.startswith("#")]


# ------------------------------------------------------------------ 1. interrupts propagate, nothing is saved
def _default_sigint() -> None:
    # A test run started in the background (CI, `cmd &`) ignores SIGINT and its children inherit that; give the
    # child the default disposition, as a terminal gives a program the user may Ctrl-C.
    signal.signal(signal.SIGINT, signal.SIG_DFL)


def _start_cli(args, cwd) -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "ftcal", *map(str, args)], cwd=cwd, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, preexec_fn=_default_sigint)


def _interrupt_after_training_starts(proc: subprocess.Popen, marker: str) -> tuple[int, str]:
    lines = []
    for line in proc.stderr:  # the run says what it fits before the epochs start
        lines.append(line)
        if marker in line:
            break
    time.sleep(2.0)  # well inside a 20 000-epoch run
    proc.send_signal(signal.SIGINT)
    rest = proc.communicate(timeout=120)[1]
    return proc.returncode, "".join(lines) + rest


@pytest.mark.parametrize("command", ["fit", "tune"])
def test_ctrl_c_stops_training_and_saves_nothing(workdir, tmp_path, command):
    out = tmp_path / "models"
    out.mkdir()
    long_run = ["--param", "max_epochs=20000", "--param", "hidden_layer_sizes=[8]"]
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
    code, err = _interrupt_after_training_starts(_start_cli(args, tmp_path), "fitting" if command == "fit" else "searching")
    # 130 is main()'s status for an interrupt; under load CPython sometimes ends the process by SIGINT itself
    # (status -2), which a shell reports the same way. Either way the run must say so and save nothing.
    assert code in (130, -signal.SIGINT), err
    assert "interrupted" in err and "Traceback" not in err
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
    with pytest.raises(DatasetFileError, match=r"line 4: '1_000' is not a number"):
        CalibrationDataset.load(bad)
    readings = tmp_path / "r.csv"
    readings.write_text("1_000,0.2,0.3,0.4,0.5,0.6\n")  # a first line of numbers is data, not a header
    assert "'1_000' is not a number" in cli_error(["predict", workdir / "models" / "linear.model.npz", readings], capsys)


# ------------------------------------------------------------------ 6. no NaN or inf printed
def test_float32_overflow_through_the_comparative_model_is_an_error(workdir, capsys, monkeypatch):
    import io

    monkeypatch.setattr(sys, "stdin", io.StringIO("0.1,0.2,0.3,0.4,0.5,1e39\n"))
    msg = cli_error(["predict", workdir / "models" / "comparative.model.npz"], capsys)
    assert "non-finite wrench" in msg and "row 0" in msg


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
        ComparativeCalibrator(**{**TINY, "max_epochs": 20, "hidden_layer_sizes": hidden}, lr=1e6).fit(raw, w)


# ------------------------------------------------------------------ 8. labels and dtypes
def test_fractional_group_labels_are_refused():
    with pytest.raises(DatasetFileError, match="row 1 holds 1.7"):
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
        ftcal.read_ati_calibration(cal)
    out = tmp_path / "sim"
    assert "exceed" in cli_error(["simulate", "dataset", "--sensor", cal, "--out", out, "-q"], capsys)
    assert not out.exists() or not any(out.iterdir())


def test_ati_file_without_calibration_names_the_problem(tmp_path):
    cal = tmp_path / "FT1.cal"
    cal.write_text('<FTSensor Serial="FT1"></FTSensor>')
    with pytest.raises(CalFileError, match="no <Calibration> element inside <FTSensor>"):
        ftcal.read_ati_calibration(cal)


@pytest.mark.parametrize("argv, message", [
    (["simulate", "dataset", "--n-per-sphere", "100000000000"], "at most 1000000"),
    (["plan", "--subdivisions", "12"], "at most 6"),
    (["simulate", "dataset", "--n-test", "0"], "integer >= 1"),
])
def test_sizes_that_would_exhaust_memory_are_refused(argv, message, capsys):
    assert message in cli_error(argv, capsys)


# ------------------------------------------------------------------ 11. ensembles through the CLI
def test_fit_ensemble_with_tare_through_the_cli(workdir, tmp_path):
    tare = ",".join(["0"] * 6)
    assert run(["fit", workdir / "data" / "train.csv", "--model", "directional_ensemble", *TINY_CLI,
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
    msg = cli_error(["fit", workdir / "data" / "train.csv", "--model", "directional", *TINY_CLI,
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
        ftcal.prepare_dataset(str(tmp_path / "x.csv"))


# ------------------------------------------------------------------ the new entry points (issues 12, 13, 15)
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
