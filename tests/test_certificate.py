"""The calibration report as a certificate: rated capacity and specification (PASS/FAIL on the first page), the
calibration matrix, the held-out applied-vs-indicated table (worst first, all cases in the JSON and CSV), the
warnings, the conditions, the printed PDF; and ``fit --report`` as one unit (checks before any work, nothing
written when the report fails, hashes of the bytes written, concurrent runs never mixed).

Pages are checked as Chromium renders them (its DOM after load, and its PDF read back with poppler's
``pdftotext`` / ``pdftoppm``); figures are recomputed independently (scikit-learn's OLS on the same folds)."""

from __future__ import annotations

import csv
import hashlib
import json
import os
import re
import shlex
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from sklearn.linear_model import LinearRegression
from scipy import stats

import browser
from ftcal import CalibrationDataset
from ftcal.cli import main
from ftcal.model_selection import FoldPlan

AXES = ("Fx", "Fy", "Fz", "Tx", "Ty", "Tz")
RATED = (500.0, 500.0, 900.0, 20.0, 20.0, 20.0)


def bent_sensor(n_groups: int = 10, per_group: int = 12, seed: int = 0, bend: float = 0.0) -> CalibrationDataset:
    """An affine 6-channel sensor (loads of O(100 N), O(3 N·m)) with an optional quadratic bend of channel 0
    (that a linear calibration cannot follow and a degree-2 polynomial can)."""
    rng = np.random.default_rng(seed)
    wrench = rng.uniform(-1, 1, size=(n_groups * per_group, 6)) * [200, 200, 400, 3, 3, 3]
    gains = rng.normal(size=(6, 6)) / [200, 200, 400, 3, 3, 3]
    raw = wrench @ gains.T + 0.3 + 0.002 * rng.normal(size=(len(wrench), 6))
    raw[:, 0] += bend * (wrench[:, 0] / 200) ** 2
    return CalibrationDataset(raw=raw, wrench=wrench, group=np.repeat(np.arange(n_groups), per_group),
                              meta={"sensor": "FT-TEST-7"})


def _held_out_ols(data: CalibrationDataset, folds: int) -> np.ndarray:
    """scikit-learn's OLS on the folds of ftcal's one fold rule (whole groups held out)."""
    pred = np.empty_like(data.wrench)
    for train, test in FoldPlan.for_data(data.raw, data.wrench, data.group, cv=folds).folds:
        pred[test] = LinearRegression().fit(data.raw[train], data.wrench[train]).predict(data.raw[test])
    return pred


@pytest.fixture(scope="module")
def certified(tmp_path_factory):
    """``ftcal fit --report`` with rated capacities, a per-axis specification that Fx meets and Fy does not, and
    conditions from a YAML file beside the data; the page rendered by Chromium."""
    work = tmp_path_factory.mktemp("certificate")
    data = bent_sensor()
    data.save(work / "data.csv")
    # U95 = k u_c: continuous readings (no resolution step), no repeated load, no reference uncertainty given: u_c is
    # the held-out RMS, its dof the 10 groups less one, k the t-factor at 95.45 %
    k = stats.t.ppf(0.5 + 0.9545 / 2, 10 - 1)
    u95_pct = 100 * k * np.sqrt(np.mean((_held_out_ols(data, 4) - data.wrench) ** 2, axis=0)) / RATED
    spec = {a: (2.0 * u if a != "Fy" else 0.5 * u) for a, u in zip(AXES, u95_pct)}  # all pass but Fy
    (work / "data.conditions.yaml").write_text(
        "reference_standard: dead weights, class M1, certificate 2024-117\nprocedure: ftcal docs, 6 axes x 10 loads\n"
        "recalibration_interval: 12 months\n", encoding="utf-8")
    argv = ["fit", str(work / "data.csv"), "--model", "linear", "--report", "--cv", "4", "--out", str(work / "m"),
            "--rated", ",".join(f"{a}={r:g}" for a, r in zip(AXES, RATED)),
            "--spec", ",".join(f"{a}={s:.6g}%FS" for a, s in spec.items()), "--operator", "A. Tester", "-q"]
    assert main(argv) == 0
    shown = browser.render(work / "m" / "linear.report.html", work / "chromium")
    facts = json.loads((work / "m" / "linear.report.json").read_text())
    return work, data, facts, shown, u95_pct, spec


def _summary(dom: str) -> str:
    return dom[dom.index('id="summary"'):dom.index('id="calibration"')]


def test_summary_states_u95_in_percent_of_rated_capacity_and_pass_fail_per_axis(certified):
    work, data, facts, shown, u95_pct, spec = certified
    assert shown.console == [] and shown.page_requests == []
    acc = {a["axis"]: a for a in facts["accuracy"]}
    for k, axis in enumerate(AXES):
        assert acc[axis]["full_scale"] == RATED[k]
        assert acc[axis]["u95_pct_fs"] == pytest.approx(u95_pct[k], rel=1e-6)
        assert acc[axis]["verdict"] == ("FAIL" if axis == "Fy" else "PASS")
    assert facts["verdict"] == "FAIL"
    summary = _summary(shown.dom)
    assert "FT-TEST-7" in summary and "LinearCalibrator" in summary and facts["date_utc"] in summary
    assert re.search(r'class="verdict FAIL">FAIL: Fy beyond the specification', summary)
    rows = re.findall(r"<tr><td>(F[xyz]|T[xyz])</td>(.*?)</tr>", summary)
    verdicts = {axis: re.search(r'class="(PASS|FAIL)"', cells).group(1) for axis, cells in rows}
    assert verdicts == {a: ("FAIL" if a == "Fy" else "PASS") for a in AXES}
    assert f"{u95_pct[0]:.3g}" in dict(rows)["Fx"]  # U95 [% FS] printed as computed independently
    assert "Against the stock models:" in summary


def test_the_matrix_on_the_page_reproduces_the_models_predictions(certified):
    work, data, facts, shown, *_ = certified
    mx = facts["model"]["matrix"]
    matrix, offset = np.array(mx["matrix"]), np.array(mx["offset"])
    import ftcal

    model = ftcal.load_model(work / "m" / "linear.model.npz")
    np.testing.assert_allclose(data.raw @ matrix.T + offset, model.predict(data.raw), rtol=1e-8, atol=1e-8)
    section = shown.dom[shown.dom.index('id="calibration"'):shown.dom.index('id="accuracy"')]
    assert "Calibration matrix" in section and "Fx [N per raw unit]" in section and "Tz [N·m per raw unit]" in section
    assert f"{matrix[0, 0]:.5g}" in section
    digest = hashlib.sha256((work / "m" / "linear.model.npz").read_bytes()).hexdigest()
    assert facts["model"]["sha256"] == digest and digest in section
    assert "ftcal.load_model(&#x27;linear.model.npz&#x27;)" in section or "ftcal.load_model('linear.model.npz')" in section


def test_applied_vs_indicated_table_lists_held_out_cases_worst_first_everywhere(certified):
    work, data, facts, shown, *_ = certified
    pred = _held_out_ols(data, 4)
    worst = np.max(np.abs(100 * (pred - data.wrench) / RATED), axis=1)
    cases = facts["cases"]
    assert cases["count"] == len(data.wrench) and cases["by"] == "row"  # every row its own load here
    assert cases["first_row"][0] == int(np.argmax(worst))
    got = np.max(np.abs(np.array(cases["error_pct_fs"], dtype=float)), axis=1)
    assert np.all(np.diff(got) <= 1e-9) and got[0] == pytest.approx(worst.max(), rel=1e-3)
    np.testing.assert_allclose(np.array(cases["indicated"], dtype=float)[0], pred[np.argmax(worst)], rtol=1e-5)
    with open(work / "m" / "linear.report.csv", newline="", encoding="utf-8") as fh:
        table = list(csv.reader(fh))
    assert len(table) == 1 + len(data.wrench) and table[0][4] == "Fx_applied [N]"
    assert int(table[1][2]) == int(np.argmax(worst))
    section = shown.dom[shown.dom.index('id="cases"'):shown.dom.index('id="choice"')]
    first_row = re.search(r"<tbody>\s*<tr><td>1</td><td>(\d+)</td>", section)
    assert first_row is not None and int(first_row.group(1)) == data.group[int(np.argmax(worst))]
    assert f"30 of {len(data.wrench)} cases shown" in section


def test_conditions_are_printed_when_given_and_not_stated_otherwise(certified):
    work, data, facts, shown, *_ = certified
    cond = facts["conditions"]
    assert cond["reference_standard"].startswith("dead weights") and cond["operator"] == "A. Tester"
    assert cond["recalibration_due"].endswith("(issue date + 12 months)")
    assert cond["procedure"].startswith("ftcal docs")
    assert "dead weights, class M1" in shown.dom and "A. Tester" in shown.dom
    # the data have no temperature: not stated, and how to add it
    row = re.search(r"<tr><td>ambient temperature</td><td>(.*?)</td></tr>", shown.dom).group(1)
    assert "not stated" in row and "temperature" in row and "ambient_temperature: 23 °C" in row


def test_warnings_name_a_better_stock_model_errors_beyond_full_scale_and_few_rows(tmp_path):
    """A bent sensor calibrated with the LTM: the stock degree-2 polynomial beats it beyond noise; a rated
    capacity below the data's loads; too few rows for the channels."""
    data = bent_sensor(n_groups=8, per_group=8, bend=0.6, seed=2)
    data.save(tmp_path / "bent.csv")
    assert main(["fit", str(tmp_path / "bent.csv"), "--model", "linear", "--report", "--cv", "3", "--out",
                 str(tmp_path / "m"), "--rated", "Fx=100,Fy=500,Fz=900,Tx=20,Ty=20,Tz=20", "--spec", "1%FS",
                 "-q"]) == 0
    facts = json.loads((tmp_path / "m" / "linear.report.json").read_text())
    kinds = {w["kind"]: w["text"] for w in facts["warnings"]}
    assert "stock better" in kinds and facts["comparison"]["best_stock"] in kinds["stock better"]
    choice = {c["model"]: c for c in facts["model_choice"] if c["status"] == "scored"}
    assert min(c["rmse"] for n, c in choice.items() if n.startswith("sk_")) < facts["comparison"]["rmse"]
    assert "Fx" in kinds["beyond rated capacity"] and "100 N" in kinds["beyond rated capacity"]
    assert "few rows" in kinds and "64 rows" in kinds["few rows"]
    shown = browser.render(tmp_path / "m" / "linear.report.html", tmp_path / "chromium")
    summary = _summary(shown.dom)
    for kind in ("stock better", "beyond rated capacity", "few rows"):
        assert f'<span class="warn-kind">{kind}:</span>' in summary


def test_no_rated_capacity_and_no_spec_say_so(tmp_path):
    bent_sensor(seed=3).save(tmp_path / "d.csv")
    assert main(["fit", str(tmp_path / "d.csv"), "--model", "linear", "--report", "--no-baselines", "--cv", "3",
                 "--out", str(tmp_path / "m"), "-q"]) == 0
    facts = json.loads((tmp_path / "m" / "linear.report.json").read_text())
    assert facts["verdict"] is None and "no rated capacity" in {w["kind"] for w in facts["warnings"]}
    page = (tmp_path / "m" / "linear.report.html").read_text()
    assert "No specification given" in page and "not stated" in page


def test_the_readme_pdf_command_prints_a_numbered_multi_page_pdf_with_the_summary_first(certified, tmp_path):
    work, *_ = certified
    readme = (Path(__file__).parents[1] / "README.md").read_text(encoding="utf-8")
    command = next(line for line in readme.splitlines() if line.startswith("chromium --headless"))
    argv = shlex.split(command)
    pdf = tmp_path / "linear.report.pdf"
    argv = [browser.chromium()] + [a for a in argv[1:] if not a.startswith("--print-to-pdf") and
                                   not a.endswith(".html")]
    argv += ["--disable-gpu", f"--user-data-dir={tmp_path / 'profile'}", f"--print-to-pdf={pdf}",
             str(work / "m" / "linear.report.html")]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=300, stdin=subprocess.DEVNULL)
    assert done.returncode == 0, done.stderr[-2000:]
    info = subprocess.run(["pdfinfo", str(pdf)], capture_output=True, text=True, check=True).stdout
    pages = int(re.search(r"Pages:\s+(\d+)", info).group(1))
    assert pages >= 4  # summary, calibration, accuracy, cases, choice, range/conditions: each starts a page
    first = subprocess.run(["pdftotext", "-f", "1", "-l", "1", "-layout", str(pdf), "-"], capture_output=True,
                           text=True, check=True).stdout
    assert "Calibration report: FT-TEST-7" in first and "FAIL: Fy beyond the specification" in first
    assert f"page 1 of {pages}" in first and "Calibration matrix" not in first
    last = subprocess.run(["pdftotext", "-f", str(pages), "-l", str(pages), str(pdf), "-"], capture_output=True,
                          text=True, check=True).stdout
    assert f"page {pages} of {pages}" in last
    # the wide applied-vs-indicated table gets a landscape page and is not cut: its last column is printed
    texts = [subprocess.run(["pdftotext", "-f", str(p), "-l", str(p), "-layout", str(pdf), "-"], capture_output=True,
                            text=True, check=True).stdout for p in range(1, pages + 1)]
    (cases_page,) = [p for p, t in enumerate(texts, 1) if "Applied against indicated load" in t]
    assert re.search(r"Tz\s+error", texts[cases_page - 1])
    sizes = subprocess.run(["pdfinfo", "-f", "1", "-l", str(pages), str(pdf)], capture_output=True, text=True,
                           check=True).stdout
    width, height = map(float, re.search(rf"Page\s+{cases_page} size:\s+([\d.]+) x ([\d.]+)", sizes).groups())
    assert width > height
    subprocess.run(["pdftoppm", "-f", "1", "-l", "1", "-r", "40", "-gray", "-png", str(pdf), str(tmp_path / "p")],
                   check=True)
    (png,) = tmp_path.glob("p*.png")
    import matplotlib.image

    pixels = matplotlib.image.imread(png)
    assert pixels.shape[0] > pixels.shape[1]  # portrait A4
    ink = float(np.mean(pixels.mean(axis=-1) < 0.9)) if pixels.ndim == 3 else float(np.mean(pixels < 0.9))
    assert 0.01 < ink < 0.5  # text on the page, not blank, not black


def _outputs(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir()) if folder.exists() else []


def test_fit_report_that_fails_writes_nothing(tmp_path, capsys):
    """Seven rows: the LTM fits on all of them, but 5-fold cross-validation trains it on five: the report fails,
    after the fit, and the run leaves no file (not the model, not fit.json)."""
    data = bent_sensor(n_groups=7, per_group=1, seed=4)
    CalibrationDataset(raw=data.raw, wrench=data.wrench).save(tmp_path / "seven.csv")
    code = main(["fit", str(tmp_path / "seven.csv"), "--model", "linear", "--report", "--no-baselines", "--out",
                 str(tmp_path / "m")])
    err = capsys.readouterr().err
    assert code == 2 and "ftcal: error:" in err and "cross-validation" in err
    assert _outputs(tmp_path / "m") == []


def test_fit_report_with_a_bad_tool_file_checks_it_before_any_work(tmp_path, capsys):
    bent_sensor(seed=5).save(tmp_path / "d.csv")
    (tmp_path / "bad.tool.json").write_text('{"format": "something else"}', encoding="utf-8")
    code = main(["fit", str(tmp_path / "d.csv"), "--model", "linear", "--report", "--tool",
                 str(tmp_path / "bad.tool.json"), "--out", str(tmp_path / "m")])
    err = capsys.readouterr().err
    assert code == 2 and "bad.tool.json" in err and "tool file" in err
    assert "fitting" not in err  # refused before the fit started
    assert _outputs(tmp_path / "m") == []


@pytest.mark.parametrize("option, value, expected", [
    ("--rated", "Fx=500,Fy=500,Fz=900", "no value for Tx, Ty, Tz"),
    ("--rated", "Fx=500,Fy=-5,Fz=900,Tx=1,Ty=1,Tz=1", "Fy: '-5' is not a positive number"),
    ("--rated", "Fq=1", "axis 'Fq' is not an output of this dataset"),
    ("--spec", "one percent", "'one percent' is not a positive number"),
    ("--spec", "1%FS,2%FS", "'2%FS' names no axis"),
    ("--spec", "1%FS,Fz=0%FS", "Fz: '0%FS' is not a positive number"),
    ("--recalibration-interval", "soon", "'soon': give a number and a unit"),
])
def test_bad_report_options_are_refused_before_the_fit(tmp_path, capsys, option, value, expected):
    bent_sensor(seed=6).save(tmp_path / "d.csv")
    code = main(["fit", str(tmp_path / "d.csv"), "--model", "linear", "--report", option, value, "--out",
                 str(tmp_path / "m")])
    err = capsys.readouterr().err
    assert code == 2 and expected in err and len(err.strip().splitlines()) == 1, err
    assert "fitting" not in err and _outputs(tmp_path / "m") == []


def test_concurrent_forced_runs_leave_one_whole_set_whose_hashes_are_its_own(tmp_path):
    """Two ``fit --report --force`` runs into one folder at once, on different data (different models): the set
    left behind is one run's whole set; the report and fit.json carry the SHA-256 of the model beside them."""
    for k in range(2):
        bent_sensor(seed=10 + k).save(tmp_path / f"d{k}.csv")
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).parents[1])}
    for _ in range(1):  # each round: the two runs overlap (their fits and reports take seconds, the commits microseconds)
        runs = [subprocess.Popen([sys.executable, "-m", "ftcal", "fit", str(tmp_path / f"d{k}.csv"), "--model",
                                  "linear", "--report", "--no-baselines", "--cv", "3", "--force", "-q", "--out",
                                  str(tmp_path / "cc")], env=env, stderr=subprocess.PIPE, text=True)
                for k in range(2)]
        for run in runs:
            assert run.wait(timeout=300) == 0, run.stderr.read()
        assert _outputs(tmp_path / "cc") == ["linear.fit.json", "linear.model.npz", "linear.report.csv",
                                             "linear.report.html", "linear.report.json"]
        digest = hashlib.sha256((tmp_path / "cc" / "linear.model.npz").read_bytes()).hexdigest()
        facts = json.loads((tmp_path / "cc" / "linear.report.json").read_text())
        fit = json.loads((tmp_path / "cc" / "linear.fit.json").read_text())
        assert facts["model"]["sha256"] == digest == fit["model_sha256"]
        assert facts["data"]["sha256"] == fit["dataset_sha256"]


def test_report_of_auto_reuses_its_comparison_only_on_its_own_fold_plan_and_rows():
    """auto scored the stock models on its fold plan when it chose: the report on the same plan (same folds, same
    rows) takes those rows and its choice's held-out predictions; other folds or other rows: nothing is reused."""
    from ftcal import AutoCalibrator, LinearCalibrator, PolynomialCalibrator, calibration_certificate

    data = bent_sensor(bend=0.6, seed=7)
    auto = AutoCalibrator(candidates=[("linear", LinearCalibrator()), ("polynomial", PolynomialCalibrator())],
                          cv=4, stack=False).fit(data.raw, data.wrench, groups=data.group)
    cert = calibration_certificate(auto, data, cv=4, figures=False)
    res = auto.comparison_
    assert cert.validation["reused_auto_comparison"] is True
    stock = {r.name: r for r in res.rows if r.kind in ("stock", "baseline")}
    assert len(stock) == 5  # the five stock models, on auto's folds (one of them may be its choice)
    rows = {c["model"]: c for c in cert.comparison["rows"]}
    assert set(rows) - set(stock) == {cert.comparison["rows"][0]["model"]}
    for name, row in stock.items():
        if name != auto.best_name_:
            assert rows[name]["rmse"] == row.rmse
    this = cert.comparison["rows"][0]
    assert auto.best_name_ in this["model"] and this["rmse"] == pytest.approx(res.row(auto.best_name_).rmse,
                                                                              rel=1e-9)
    # other folds than auto's: nothing is reused
    other = calibration_certificate(auto, data, cv=3, figures=False, baselines=False)
    assert other.validation["reused_auto_predictions"] is False
    # the same extremes on every channel, rows dropped: other data, nothing is reused
    extremes = np.unique(np.concatenate([data.raw.argmin(axis=0), data.raw.argmax(axis=0)]))
    keep = np.ones(len(data.raw), dtype=bool)
    keep[np.setdiff1d(np.arange(len(keep)), extremes)[::7]] = False
    fewer = CalibrationDataset(raw=data.raw[keep], wrench=data.wrench[keep], group=data.group[keep])
    dropped = calibration_certificate(auto, fewer, cv=4, figures=False, baselines=False)
    assert dropped.validation["reused_auto_predictions"] is False


def test_a_three_axis_load_cell_gets_a_report_without_torque_rows(tmp_path, capsys):
    rng = np.random.default_rng(8)
    wrench = rng.uniform(-1, 1, size=(90, 3)) * [100, 100, 300]
    raw = wrench @ rng.normal(size=(3, 4)) / 100 + 0.2 + 1e-3 * rng.normal(size=(90, 4))
    CalibrationDataset(raw=raw, wrench=wrench, axes=("Fx", "Fy", "Fz"), group=np.repeat(np.arange(6), 15),
                       meta={"sensor": "3-axis cell"}).save(tmp_path / "cell.csv")
    assert main(["fit", str(tmp_path / "cell.csv"), "--model", "linear", "--report", "--cv", "3", "--out",
                 str(tmp_path / "m"), "--rated", "Fx=200,Fy=200,Fz=500", "--spec", "1%FS", "-q"]) == 0
    facts = json.loads((tmp_path / "m" / "linear.report.json").read_text())
    assert [a["axis"] for a in facts["accuracy"]] == ["Fx", "Fy", "Fz"]
    assert [a["full_scale"] for a in facts["accuracy"]] == [200, 200, 500]
    assert facts["cases"]["axes"] == ["Fx", "Fy", "Fz"] and len(facts["cases"]["applied"][0]) == 3
    shown = browser.render(tmp_path / "m" / "linear.report.html", tmp_path / "chromium")
    text = re.sub(r'src="data:[^"]+"', "", shown.dom)
    assert not re.search(r"\bT[xyz]\b|N·m per raw unit|largest \|T\|", text)
    header = (tmp_path / "m" / "linear.report.csv").read_text().splitlines()[0]
    assert "Fz_error [%FS]" in header and "Tx" not in header
    # a rated capacity for an axis the cell does not measure is refused, naming its axes
    code = main(["fit", str(tmp_path / "cell.csv"), "--model", "linear", "--report", "--out", str(tmp_path / "n"),
                 "--rated", "Fx=200,Fy=200,Fz=500,Tx=5"])
    err = capsys.readouterr().err
    assert code == 2 and "axis 'Tx' is not an output of this dataset; its axes are Fx, Fy, Fz" in err


def _ftcal(*args: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(Path(__file__).parents[1])}
    return subprocess.run([sys.executable, "-m", "ftcal", *args], cwd=cwd, env=env, capture_output=True, text=True,
                          timeout=300)


@pytest.mark.parametrize("model, report", [("linear", False), ("polynomial", False), ("linear", True)])
def test_fit_refuses_a_calibration_no_better_than_the_mean_and_writes_nothing(tmp_path, model, report):
    """Wrenches drawn independently of the readings: any model's held-out error is no better than predicting the
    mean wrench. ``ftcal fit`` refuses in one line (exit 2) and leaves the folder as it was, ``--force`` or not."""
    rng = np.random.default_rng(3)
    wrench = rng.normal(size=(120, 6)) * [10, 10, 10, 1, 1, 1]
    CalibrationDataset(raw=rng.normal(size=(120, 6)), wrench=wrench,
                       group=np.repeat(np.arange(10), 12)).save(tmp_path / "noise.csv")
    (tmp_path / "m").mkdir()
    (tmp_path / "m" / f"{model}.model.npz").write_bytes(b"the user's earlier model")
    done = _ftcal("fit", "noise.csv", "--model", model, "--force", "--out", "m",
                  *(["--report", "--no-baselines"] if report else []), cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    errors = [line for line in done.stderr.splitlines() if line.startswith("ftcal: error:")]
    assert len(errors) == 1 and "noise.csv" in errors[0] and "no better than predicting the mean" in errors[0]
    assert _outputs(tmp_path / "m") == [f"{model}.model.npz"]
    assert (tmp_path / "m" / f"{model}.model.npz").read_bytes() == b"the user's earlier model"


def test_fit_keeps_a_calibration_that_beats_the_mean(tmp_path):
    bent_sensor(seed=21).save(tmp_path / "d.csv")
    done = _ftcal("fit", "d.csv", "--model", "linear", "--out", "m", cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    assert _outputs(tmp_path / "m") == ["linear.fit.json", "linear.model.npz"]


@pytest.mark.parametrize("start, interval, due", [
    ("2025-01-15", "12 months", "2026-01-15"),
    ("2025-01-15", "1 year", "2026-01-15"),
    ("2025-01-31", "1 month", "2025-02-28"),  # no Feb 31: the last day of the month
    ("2024-01-31", "1 month", "2024-02-29"),  # a leap year
    ("2024-02-29", "12 months", "2025-02-28"),
    ("2024-02-29", "48 months", "2028-02-29"),
    ("2025-11-30", "3 months", "2026-02-28"),  # across a year end
    ("2025-01-15", "90 days", "2025-04-15"),
    ("2025-12-25", "2 weeks", "2026-01-08"),
    ("2025-01-15", "6", "2025-07-15"),  # a bare number counts months
])
def test_recalibration_due_date_is_counted_in_calendar_months_from_the_calibration_date(start, interval, due):
    import datetime as dt

    from ftcal.reporting._calibration_report import add_interval

    assert add_interval(dt.date.fromisoformat(start), interval) == dt.date.fromisoformat(due)


def test_report_counts_the_due_date_from_the_calibration_date_and_flags_it_overdue(tmp_path):
    """Calibrated 2025-01-15 with a 12-month interval: due 2026-01-15 (whatever the date of issue), and overdue on
    any later date of issue; a bare ambient temperature is printed in °C."""
    import datetime as dt

    bent_sensor(seed=22).save(tmp_path / "d.csv")
    assert _ftcal("fit", "d.csv", "--model", "linear", "--out", "m", cwd=tmp_path).returncode == 0
    done = _ftcal("report", "m/linear.model.npz", "d.csv", "--no-baselines", "--calibration-date", "2025-01-15",
                  "--recalibration-interval", "12 months", "--ambient-temperature", "22.5", "--out", "r",
                  cwd=tmp_path)
    assert done.returncode == 0, done.stderr
    facts = json.loads((tmp_path / "r" / "linear.report.json").read_text())
    due = facts["conditions"]["recalibration_due"]
    assert due.startswith("2026-01-15 (calibration date 2025-01-15 + 12 months)")
    overdue = dt.date.fromisoformat(facts["date_utc"][:10]) > dt.date(2026, 1, 15)
    assert facts["recalibration_overdue"] is overdue and due.endswith("OVERDUE on the date of issue") is overdue
    assert any(w["kind"] == "recalibration overdue" for w in facts["warnings"]) is overdue
    html = (tmp_path / "r" / "linear.report.html").read_text(encoding="utf-8")
    assert "2026-01-15 (calibration date 2025-01-15 + 12 months)" in html
    assert facts["conditions"]["ambient_temperature"] == "22.5 °C" and "22.5 °C" in html
    bad = _ftcal("report", "m/linear.model.npz", "d.csv", "--no-baselines", "--calibration-date", "last spring",
                 "--recalibration-interval", "12 months", "--out", "r2", cwd=tmp_path)
    assert bad.returncode == 2 and "calibration_date 'last spring'" in bad.stderr and not (tmp_path / "r2").exists()


def test_fit_report_and_evaluate_a_folder_of_per_pose_files_identified_by_its_data_files(tmp_path):
    """A folder of one CSV per pose is one dataset: ``fit --report``, ``report`` and ``evaluate`` read it, and its
    identity (SHA-256) is that of the data files the loader reads: a note beside them changes nothing, an edited
    data file changes it."""
    data = bent_sensor(seed=23)
    (tmp_path / "poses").mkdir()
    for g in np.unique(data.group):
        keep = data.group == g
        CalibrationDataset(raw=data.raw[keep], wrench=data.wrench[keep]).save(tmp_path / "poses" / f"pose {g}.csv")
    fit = _ftcal("fit", "poses", "--model", "linear", "--report", "--no-baselines", "--out", "m", cwd=tmp_path)
    assert fit.returncode == 0, fit.stderr
    facts = json.loads((tmp_path / "m" / "linear.report.json").read_text())
    summary = json.loads((tmp_path / "m" / "linear.fit.json").read_text())
    assert facts["data"]["groups"] == 10 and facts["data"]["sha256"] == summary["dataset_sha256"]
    (tmp_path / "poses" / "notes.txt").write_text("operator's notes", encoding="utf-8")
    report = _ftcal("report", "m/linear.model.npz", "poses", "--no-baselines", "--out", "r", cwd=tmp_path)
    assert report.returncode == 0, report.stderr
    assert json.loads((tmp_path / "r" / "linear.report.json").read_text())["data"]["sha256"] == summary["dataset_sha256"]
    evaluate = _ftcal("evaluate", "poses", "m/linear.model.npz", "--out", "e", cwd=tmp_path)
    assert evaluate.returncode == 0, evaluate.stderr
    first = tmp_path / "poses" / "pose 0.csv"
    first.write_text(first.read_text() + first.read_text().splitlines()[-1] + "\n")  # one row recorded twice
    again = _ftcal("report", "m/linear.model.npz", "poses", "--no-baselines", "--out", "r2", cwd=tmp_path)
    assert again.returncode == 0, again.stderr
    assert json.loads((tmp_path / "r2" / "linear.report.json").read_text())["data"]["sha256"] != summary["dataset_sha256"]


def test_report_of_a_one_axis_model_on_six_axis_data_is_refused_naming_both_or_certifies_the_selected_axis(tmp_path):
    """A 1-axis (Fz) model reported on data of six axes: refused, naming both, nothing written; with the model's
    axis selected from the same data by name (``--wrench Fz``) the certificate has that one axis."""
    data = bent_sensor(seed=24)
    data.save(tmp_path / "d.csv")
    CalibrationDataset(raw=data.raw, wrench=data.wrench[:, 2:3], group=data.group,
                       axes=["Fz"]).save(tmp_path / "fz.csv")
    assert _ftcal("fit", "fz.csv", "--model", "linear", "--out", "m", cwd=tmp_path).returncode == 0
    bad = _ftcal("report", "m/linear.model.npz", "d.csv", "--no-baselines", "--out", "r", cwd=tmp_path)
    assert bad.returncode == 2 and len(bad.stderr.strip().splitlines()) == 1
    assert "(Fx, Fy, Fz, Tx, Ty, Tz)" in bad.stderr and "(Fz)" in bad.stderr
    assert not (tmp_path / "r").exists() or _outputs(tmp_path / "r") == []
    good = _ftcal("report", "m/linear.model.npz", "d.csv", "--wrench", "Fz", "--no-baselines", "--out", "r",
                  cwd=tmp_path)
    assert good.returncode == 0, good.stderr
    facts = json.loads((tmp_path / "r" / "linear.report.json").read_text())
    assert [a["axis"] for a in facts["accuracy"]] == ["Fz"]


def test_certificate_of_a_model_of_other_axes_than_the_data_is_refused_by_the_library():
    from ftcal import LinearCalibrator
    from ftcal.core._exceptions import CalibrationInputError
    from ftcal.reporting import calibration_certificate

    data = bent_sensor(seed=25)
    one_axis = LinearCalibrator().fit(data.raw, data.wrench[:, 2:3])
    with pytest.raises(CalibrationInputError, match=r"gives 1 output axis\(es\) but the dataset has 6 \(Fx, Fy"):
        calibration_certificate(one_axis, data, baselines=False, figures=False)


def test_a_stock_model_row_names_its_baseline():
    from ftcal.calibrators import StockCalibrator
    from ftcal.reporting import calibration_certificate

    rng = np.random.default_rng(0)
    wrench = rng.normal(size=(60, 6))
    raw = wrench @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(60, 6))
    data = CalibrationDataset(raw=raw, wrench=wrench)
    cert = calibration_certificate(StockCalibrator(baseline="sk_poly2").fit(raw, wrench), data, baselines=False,
                                   figures=False)
    rows = json.loads(cert.to_json())["model_choice"]
    assert rows[0]["model"] == "StockCalibrator: sk_poly2 (this calibration)", rows
