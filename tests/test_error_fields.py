"""Errors carry fields (the argument, its value, the fix); the library names no command-line option, and the command
line spells the fields as its own options (one table, no regular expression over the library's prose)."""

from __future__ import annotations

import ast
import pickle
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import ftcal
from ftcal.core._exceptions import NO_SETTING, CalibrationInputError, ModelFileError, PlanningError

PACKAGE = Path(ftcal.__file__).parent
#: A command-line option in a message: two dashes and a letter, not inside a word ("x--y") or a longer dash run.
FLAG = re.compile(r"(?<![\w-])--[A-Za-z]")


def _message_strings(path: Path) -> list[tuple[int, str]]:
    """Every string of ``path`` that is not a docstring (an f-string's formatted parts read as ``X``)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docstrings = set()
    for node in ast.walk(tree):
        if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef)) and node.body:
            first = node.body[0]
            if isinstance(first, ast.Expr) and isinstance(first.value, ast.Constant):
                docstrings.add(id(first.value))
    found = []
    inside_fstrings = {id(v) for n in ast.walk(tree) if isinstance(n, ast.JoinedStr) for v in n.values}
    for node in ast.walk(tree):
        if isinstance(node, ast.JoinedStr):
            text = "".join(v.value if isinstance(v, ast.Constant) else "X" for v in node.values)
        elif isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings \
                and id(node) not in inside_fstrings:
            text = node.value
        else:
            continue
        found.append((node.lineno, text))
    return found


def _flags_in(relative: str) -> list[str]:
    return [f"{relative}:{line}: {text[:90]!r}" for line, text in _message_strings(PACKAGE / relative)
            if FLAG.search(text)]


LIBRARY_MODULES = sorted(str(p.relative_to(PACKAGE)) for p in PACKAGE.rglob("*.py") if p.parts[-2] != "cli")
CLI_MODULES = sorted(p.name for p in (PACKAGE / "cli").glob("*.py"))


def test_no_library_message_names_a_command_line_option():
    assert len(LIBRARY_MODULES) > 50  # the whole library is read, the dataset readers included
    assert "io/_readers.py" in LIBRARY_MODULES and "io/_dataset.py" in LIBRARY_MODULES
    found = [hit for module in LIBRARY_MODULES for hit in _flags_in(module)]
    assert found == []


_MATCHING = {"sub", "subn", "match", "search", "fullmatch", "findall", "finditer", "split"}


def _regexes_over_errors(source: str) -> list[int]:
    """Lines where a regular expression (``re.search``, a compiled pattern's ``.match``) reads an error: inside an
    ``except`` block, or over a name bound to an exception (an ``except ... as exc``, a parameter ``exc``)."""
    tree = ast.parse(source)
    patterns = {t.id for n in ast.walk(tree) if isinstance(n, ast.Assign) and isinstance(n.value, ast.Call)
                and isinstance(n.value.func, ast.Attribute) and n.value.func.attr == "compile"
                for t in n.targets if isinstance(t, ast.Name)}
    errors = {h.name for h in ast.walk(tree) if isinstance(h, ast.ExceptHandler) and h.name}
    errors |= {a.arg for f in ast.walk(tree) if isinstance(f, (ast.FunctionDef, ast.Lambda))
               for a in f.args.args + f.args.kwonlyargs if a.arg in ("exc", "error", "err", "failure")}
    assignments = [n for n in ast.walk(tree) if isinstance(n, ast.Assign)]
    while True:  # a name computed from an error (`text = str(exc)`) is the error's prose too
        more = {t.id for n in assignments for t in n.targets if isinstance(t, ast.Name)
                and {v.id for v in ast.walk(n.value) if isinstance(v, ast.Name)} & errors} - errors
        if not more:
            break
        errors |= more
    in_handlers = {id(n) for h in ast.walk(tree) if isinstance(h, ast.ExceptHandler) for s in h.body
                   for n in ast.walk(s)}
    found = []
    for node in ast.walk(tree):
        if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in _MATCHING
                and isinstance(node.func.value, ast.Name) and node.func.value.id in patterns | {"re"}):
            continue
        names = {n.id for a in node.args + [k.value for k in node.keywords] for n in ast.walk(a)
                 if isinstance(n, ast.Name)}
        if id(node) in in_handlers or names & errors:
            found.append(node.lineno)
    return found


def test_the_regex_check_finds_a_rewrite_of_an_error_message():
    rewrites = ['def f(exc):\n    text = " ".join(str(exc).split())\n    return re.search(r"row (\\d+)", text)\n',
                'try:\n    g()\nexcept ValueError as e:\n    text = re.sub("Fix:.*", "", str(e))\n',
                'P = re.compile("x")\ntry:\n    g()\nexcept ValueError as e:\n    m = P.match(f"{e}")\n']
    assert [bool(_regexes_over_errors(src)) for src in rewrites] == [True, True, True]
    assert _regexes_over_errors('P = re.compile("x")\ndef f(text):\n    return P.match(text)\n') == []


@pytest.mark.parametrize("module", CLI_MODULES)
def test_the_command_line_rewrites_no_library_prose_with_regular_expressions(module):
    assert len(CLI_MODULES) > 20  # every module of the command line is read
    assert _regexes_over_errors((PACKAGE / "cli" / module).read_text(encoding="utf-8")) == []


def test_an_error_keeps_its_fields_its_class_and_its_words_in_the_api_terms():
    err = PlanningError("{n_poses} must be at most 42; got 100.", parameter="n_poses", value=100,
                        fix="plan on a denser sphere ({candidate_subdivisions})",
                        settings={"candidate_subdivisions": NO_SETTING})
    assert isinstance(err, ValueError) and isinstance(err, ftcal.FtcalError)
    assert str(err) == "n_poses must be at most 42; got 100. Fix: plan on a denser sphere (candidate_subdivisions)."
    copy = pickle.loads(pickle.dumps(err))  # as a Dask worker sends it back
    assert (str(copy), copy.parameter, copy.value, copy.settings) == (str(err), "n_poses", 100, err.settings)
    # braces of a value (a file name) are no fields
    named = ModelFileError("a{n_poses}b{x}.npz exists.", parameter="path", fix="pass {overwrite}",
                           settings={"overwrite": True})
    assert str(named) == "a{n_poses}b{x}.npz exists. Fix: pass overwrite=True."
    assert str(CalibrationInputError("plain {text}")) == "plain {text}"


@pytest.mark.parametrize("field, setting, expected", [
    ("overwrite", True, "--force"),
    ("sensor_frame", ftcal.core._exceptions.Placeholder("<frame>"), "--sensor-frame NAME"),
    ("HistoryCalibrator", NO_SETTING, "--history"),
    ("model", "linear", "--model linear"),
    ("export_onnx", NO_SETTING, "--format onnx"),
    ("not_an_option", 3, "not_an_option=3"),
])
def test_the_command_line_spells_each_field_as_its_option(field, setting, expected):
    from ftcal.cli._messages import cli_message

    err = CalibrationInputError("problem.", parameter="x", fix=f"pass {{{field}}}", settings={field: setting})
    assert cli_message(err) == f"problem. Fix: pass {expected}."


# ------------------------------------------------------------------ the command line, on real files and processes
def _cli(*args, cwd=None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "ftcal", *map(str, args)], capture_output=True, text=True,
                          timeout=300, cwd=cwd)


def _error(proc: subprocess.CompletedProcess) -> str:
    lines = proc.stderr.strip().splitlines()
    assert proc.returncode == 2, proc.stderr
    assert len(lines) == 1 and lines[0].startswith("ftcal: error: "), lines
    return lines[0]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    """A dataset with a temperature column, and linear, temperature-compensated linear and polynomial models."""
    root = tmp_path_factory.mktemp("fields")
    assert _cli("simulate", "dataset", "--n-per-sphere", "25", "--n-test", "50", "--temperature-range", "15,35",
                "--out", root / "data", "-q").returncode == 0
    for model, extra in (("linear", []), ("polynomial", []), ("linear", ["--temperature"])):
        out = root / ("temperature" if extra else model)
        proc = _cli("fit", root / "data" / "train.csv", "--model", model, *extra, "--out", out, "-q")
        assert proc.returncode == 0, proc.stderr
    return root


def _model(files: Path, name: str) -> Path:
    return next((files / name).glob("*.model.npz"))


@pytest.mark.parametrize("case", ["temperature_linear", "polynomial"])
def test_a_matrix_export_refused_says_what_to_fit_in_the_commands_terms(files, tmp_path, case):
    model = _model(files, "temperature" if case == "temperature_linear" else "polynomial")
    line = _error(_cli("export", model, "--format", "matrix", "--output", tmp_path / "m.csv"))
    if case == "temperature_linear":  # the linear model is not the fix: it was fitted with --temperature
        assert "temperature-compensated" in line and "without --temperature" in line and "--format onnx" in line
        assert "--model linear" not in line
    else:
        assert "not a linear calibration" in line and "--model linear" in line and "--format onnx" in line
    fix = line.split("Fix:")[1]
    assert "TemperatureCompensatedCalibrator" not in fix and "export_onnx" not in fix
    assert not (tmp_path / "m.csv").exists()


@pytest.mark.parametrize("output, expected", [
    ("{tmp}/a_file/x.onnx", "--output {tmp}/a_file"),  # a folder that is a file
    ("{tmp}/existing.onnx", "pass --force to overwrite or choose another --output"),
])
def test_export_output_errors_name_output_not_out(files, tmp_path, output, expected):
    (tmp_path / "a_file").write_text("not a folder")
    (tmp_path / "existing.onnx").write_text("keep me")
    line = _error(_cli("export", _model(files, "linear"), "--output", output.format(tmp=tmp_path)))
    assert expected.format(tmp=tmp_path) in line and "--out " not in line
    assert (tmp_path / "existing.onnx").read_text() == "keep me"


def test_a_urdf_without_sensor_frame_is_told_the_option(files, tmp_path):
    urdf = tmp_path / "arm.urdf"
    urdf.write_text('<robot name="arm"><link name="base"/></robot>')
    line = _error(_cli("plan", "--robot", urdf, "--out", tmp_path / "p", "-q"))
    assert "Fix: pass --sensor-frame NAME" in line and "sensor_frame" not in line


def test_a_history_model_that_chose_no_term_exports_to_onnx_as_its_static_model(tmp_path):
    """Readings without any load history: the history model's cross-validation keeps no term, and then nothing
    stops its ONNX export (its wrench is its static calibrator's)."""
    import onnxruntime as ort

    from ftcal import CalibrationDataset

    rng = np.random.default_rng(3)
    raw = rng.normal(size=(240, 6)) * 100.0
    wrench = raw @ rng.normal(size=(6, 6)) * 0.01 + rng.normal(scale=1e-3, size=(240, 6))
    wrench[:, 3:] *= 0.02
    CalibrationDataset(raw=raw, wrench=wrench).save(tmp_path / "data.csv")
    proc = _cli("fit", tmp_path / "data.csv", "--model", "linear", "--history", "--out", tmp_path / "m", "-q")
    assert proc.returncode == 0, proc.stderr
    model_path = next((tmp_path / "m").glob("*.model.npz"))
    model = ftcal.load_model(model_path)
    assert model.tau_rows_ is None  # no history term was chosen
    proc = _cli("export", model_path, "--format", "onnx", "--output", tmp_path / "m.onnx", "-q")
    assert proc.returncode == 0, proc.stderr
    session = ort.InferenceSession(str(tmp_path / "m.onnx"))
    got = session.run(None, {session.get_inputs()[0].name: raw[:20]})[0]
    np.testing.assert_allclose(got, model.predict(raw[:20]), rtol=1e-9, atol=1e-9)


# ------------------------------------------------------------------ the dataset readers' errors carry their argument
@pytest.mark.parametrize("mapping, parameter, words", [
    ({"channels": "s3..s0"}, "channels", "channels 's3..s0': the range runs backwards"),
    ({"wrench": "Fx,,Fy"}, "wrench", "wrench mapping 'Fx,,Fy' holds an empty name"),
    ({"axes": "Fx,Qz"}, "axes", "axes 'Fx,Qz': name each output axis"),
    ({"channels": "s0..s5", "groups": "s2"}, "columns.groups", "columns.groups 's2' is also mapped"),
    ({"force_unit": "N.m"}, "force_unit", "give it as torque_unit, and the forces' unit (e.g. N) as force_unit"),
])
def test_a_column_mapping_error_names_its_argument_in_the_api_and_its_option_on_the_command_line(mapping, parameter,
                                                                                                 words):
    from ftcal.cli._messages import cli_message
    from ftcal.core._exceptions import DatasetFileError
    from ftcal.io._readers import ColumnMap

    with pytest.raises(DatasetFileError) as info:
        ColumnMap(**mapping)
    err = info.value
    assert err.parameter == parameter and words in str(err) and not FLAG.search(str(err))
    option = {"columns.groups": "--groups", "force_unit": "--torque-unit"}.get(parameter, f"--{parameter}")
    assert option in cli_message(err)


def test_the_lever_arm_problem_is_an_error_proposing_the_unit():
    from ftcal.io._readers import lever_arm_problem

    problem = lever_arm_problem([[10.0, 0, 0, 0, 500.0, 0]])  # torques in N·mm read as N·m: a 50 m lever arm
    assert (problem.parameter, problem.settings["torque_unit"]) == ("torque_unit", "N.mm")
    assert str(problem).endswith("Fix: pass torque_unit='N.mm' (the lever arm would be 50 mm) (or the forces are in "
                                 "kN: force_unit='kN').")


def test_a_reading_row_is_a_field_that_the_command_line_says_as_the_line(tmp_path):
    from ftcal.cli._readings import located_error
    from ftcal.core._validation import check_finite_output

    with pytest.raises(CalibrationInputError) as info:
        check_finite_output(np.ones((3, 6)), np.array([[0.0] * 6, [0.0] * 6, [np.inf] + [0.0] * 5]), "model")
    assert info.value.row == 2 and str(info.value).startswith("X row 2 (largest |value| 1) gives a non-finite")
    line = str(located_error(info.value, "r.csv", np.array([7, 9, 12])))
    assert line.startswith("r.csv: line 12: the reading (largest |value| 1) gives a non-finite") and "row 2" not in line


def test_too_few_rows_carry_the_rows_and_the_need_as_fields():
    from ftcal import LinearCalibrator
    from ftcal.core._exceptions import TooFewSamplesError

    rng = np.random.default_rng(0)
    with pytest.raises(TooFewSamplesError) as info:
        LinearCalibrator().fit(rng.normal(size=(5, 6)), rng.normal(size=(5, 6)))
    assert (info.value.value, info.value.needed, info.value.estimator) == (5, 7, "LinearCalibrator")
    copy = pickle.loads(pickle.dumps(info.value))  # from a joblib or Dask worker
    assert (copy.value, copy.needed, copy.estimator, str(copy)) == (5, 7, "LinearCalibrator", str(info.value))


def test_a_dataset_error_located_in_a_file_keeps_its_fields(tmp_path):
    from ftcal.core._exceptions import DatasetFileError

    err = DatasetFileError("{channels} 'x' is wrong.", parameter="channels", fix="pass {channels}",
                           settings={"channels": "s0..s5"})
    moved = err.located("data.csv: ")
    assert type(moved) is DatasetFileError and moved.parameter == "channels" and moved.settings == err.settings
    assert str(moved) == "data.csv: channels 'x' is wrong. Fix: pass channels='s0..s5'."


def test_the_command_line_spells_a_mapping_error_as_its_option(files, tmp_path):
    line = _error(_cli("fit", files / "data" / "train.csv", "--channels", "s3..s0", "--out", tmp_path / "m", "-q"))
    assert line == ("ftcal: error: --channels 's3..s0': the range runs backwards; write s0..s3 or list the columns "
                    "in the order you want.")


def test_a_library_warning_is_one_command_line_warning(files, tmp_path):
    """A GP on 7 rows with a linear mean of 7 coefficients warns that its std is uncalibrated: one line, in the
    command's words, not Python's warning format with a source file and line."""
    from ftcal import CalibrationDataset

    data = CalibrationDataset.load(files / "data" / "train.csv")
    CalibrationDataset(raw=data.raw[:7], wrench=data.wrench[:7]).save(tmp_path / "seven.csv")
    proc = _cli("fit", tmp_path / "seven.csv", "--model", "gaussian_process", "--param", 'mean="linear"', "--out",
                tmp_path / "m", "-q")
    lines = proc.stderr.strip().splitlines()
    warned = [line for line in lines if line.startswith("ftcal: warning: GaussianProcessCalibrator: 7 rows leave")]
    assert len(warned) == 1 and "predictive std could not be calibrated" in warned[0]
    assert all(line.startswith("ftcal: ") for line in lines), lines  # no "UserWarning", no source line


def test_a_drift_without_its_values_is_told_in_the_commands_terms():
    """``--drift temperature`` on poses without temperatures: the library names its argument and what it needs;
    the command line says the option and the column (not "pass temperatures", which it has no option for)."""
    from ftcal.cli._messages import cli_message
    from ftcal.experiment._drift import select_drift

    rng = np.random.default_rng(0)
    with pytest.raises(CalibrationInputError) as info:
        select_drift(rng.normal(size=(30, 3)), rng.normal(size=(30, 6)), np.arange(30.0), None, choice="temperature")
    err = info.value
    assert (err.parameter, err.value, err.settings["drift"]) == ("drift", "temperature", "auto")
    assert str(err).endswith("Fix: give temperatures, or drift='auto'.") and not FLAG.search(str(err))
    line = cli_message(err)
    assert line.startswith("--drift 'temperature' needs temperatures that vary over the poses")
    assert line.endswith("Fix: give a 'temperature' column (the sensor's temperature at each pose), or --drift auto.")


def test_the_load_mass_and_pose_count_are_said_as_the_options_of_the_command_that_ran(tmp_path):
    # prepare and simulate call the load mass --mass, plan --load-mass; plan's pose count is --poses
    line = _error(_cli("plan", "--strategy", "random", "--poses", "3", "--subdivisions", "0", "--out", tmp_path / "p",
                       "-q"))
    assert line.startswith("ftcal: error: --poses 3 is fewer than the 7 parameters") and "n_poses" not in line
    assert _cli("simulate", "experiment", "--subdivisions", "0", "--seed", "1", "--out", tmp_path / "e",
                "-q").returncode == 0
    line = _error(_cli("prepare", tmp_path / "e", "--mass", "5", "--out", tmp_path / "d", "-q"))
    assert "--mass 5 kg but the logs declare [2.0] kg; which one is right? Fix: correct --mass" in line
    assert "load_mass" not in line.replace("load_mass_kg", "")
    log = tmp_path / "e" / "config0_load.csv"
    (tmp_path / "e" / "extra_load.csv").write_text(log.read_text().replace("# load_mass_kg: 2.0", "# load_mass_kg: 2.5"))
    line = _error(_cli("prepare", tmp_path / "e", "--out", tmp_path / "d", "-q"))
    assert "--mass not given and the logs declare [2.0, 2.5]. Fix: pass --mass KG" in line
