"""``ftcal report`` / ``ftcal fit --report``: the calibration report, checked in a real browser.

The held-out figures are checked against an independent computation (scikit-learn's own
``LinearRegression`` on the same ``GroupKFold`` folds), the page in headless Chromium (no console message, no
request of its own, a PDF through the same browser)."""

from __future__ import annotations

import base64
import hashlib
import json
import re

import numpy as np
import pytest
from sklearn.linear_model import LinearRegression
from scipy import stats

import browser
from ftcal import CalibrationDataset
from ftcal.cli import main
from ftcal.model_selection import FoldPlan

N_GROUPS, PER_GROUP, NOISE = 8, 20, 0.01


def sensor_dataset(n_channels: int = 6, seed: int = 0, temperature: bool = False) -> CalibrationDataset:
    """A noisy affine sensor: loads of O(100 N) / O(2 N·m) in 8 groups (load configurations)."""
    rng = np.random.default_rng(seed)
    wrench = rng.normal(size=(N_GROUPS * PER_GROUP, 6)) * [100, 100, 100, 2, 2, 2]
    gains = rng.normal(size=(n_channels, 6)) / [100, 100, 100, 2, 2, 2]
    raw = wrench @ gains.T + 0.5 + NOISE * rng.normal(size=(len(wrench), n_channels))
    extra = {"temperature": rng.uniform(15, 35, len(wrench))} if temperature else {}
    return CalibrationDataset(raw=raw, wrench=wrench, group=np.repeat(np.arange(N_GROUPS), PER_GROUP),
                              meta={"sensor": "test sensor SN-1"}, **extra)


@pytest.fixture(scope="module")
def fitted(tmp_path_factory):
    """``ftcal fit --report`` once (with the stock baselines): its files."""
    work = tmp_path_factory.mktemp("report")
    data = sensor_dataset()
    data.save(work / "data.csv")
    assert main(["fit", str(work / "data.csv"), "--model", "linear", "--report", "--cv", "4", "--out",
                 str(work / "models"), "-q"]) == 0
    return work, data


def test_report_states_held_out_accuracy_per_axis_as_independently_computed(fitted):
    work, data = fitted
    facts = json.loads((work / "models" / "linear.report.json").read_text())
    # independent: scikit-learn's OLS on the folds of ftcal's one fold rule (4 folds of whole groups)
    plan = FoldPlan.for_data(data.raw, data.wrench, data.group, cv=4)
    pred = np.empty_like(data.wrench)
    for train, test in plan.folds:
        pred[test] = LinearRegression().fit(data.raw[train], data.wrench[train]).predict(data.raw[test])
    err = pred - data.wrench
    rms = np.sqrt(np.mean(err**2, axis=0))
    fs = np.abs(data.wrench).max(axis=0)
    # continuous readings, no load read twice, no reference given: u_c = RMS, 8 groups -> 7 dof, k the t-factor
    k = stats.t.ppf(0.5 + 0.9545 / 2, N_GROUPS - 1)
    acc = {a["axis"]: a for a in facts["accuracy"]}
    for j, axis in enumerate(("Fx", "Fy", "Fz", "Tx", "Ty", "Tz")):
        assert acc[axis]["rms"] == pytest.approx(rms[j], rel=1e-6)
        assert acc[axis]["max"] == pytest.approx(np.abs(err[:, j]).max(), rel=1e-6)
        assert acc[axis]["rms_pct_fs"] == pytest.approx(100 * rms[j] / fs[j], rel=1e-6)
        assert acc[axis]["coverage_factor"] == pytest.approx(k, rel=1e-6)
        assert acc[axis]["u95"] == pytest.approx(k * rms[j], rel=1e-6)
        # normal errors: about 95 % within U95 (160 rows: binomial spread ~2 %)
        assert 0.85 <= acc[axis]["coverage_u95"] <= 1.0
    assert facts["validation"]["folds"] == 4 and "whole groups held out" in facts["validation"]["split"]
    assert facts["validation"]["plan"]["fingerprint"] == plan.fingerprint()
    assert facts["data"]["rows"] == 160 and facts["data"]["groups"] == 8
    assert facts["sensor"] == "test sensor SN-1"
    model_file = work / "models" / "linear.model.npz"
    assert facts["model"]["sha256"] == hashlib.sha256(model_file.read_bytes()).hexdigest()


def test_report_compares_with_every_stock_baseline_on_the_same_folds(fitted):
    work, _ = fitted
    choice = json.loads((work / "models" / "linear.report.json").read_text())["model_choice"]
    names = [c["model"] for c in choice]
    assert names == ["LinearCalibrator (this calibration)", "sk_linear", "sk_poly2", "sk_poly3", "sk_kernel_ridge",
                     "sk_gp"]
    # the LTM and scikit-learn's OLS are the same least-squares problem: equal held-out RMSE on the same folds
    assert choice[0]["rmse"] == pytest.approx(choice[1]["rmse"], rel=1e-6)
    assert all(c["status"] == "scored" and c["rmse"] > 0 for c in choice)
    # each stock row against this calibration: its paired SE on the same folds, in symmetric words
    assert all(c["paired_se"] >= 0 and c["against"] for c in choice[1:])
    comparison = json.loads((work / "models" / "linear.report.json").read_text())["comparison"]
    assert comparison["paired_se"] >= 0 and comparison["combined_se"] > 0
    assert comparison["verdict"] == "equivalent" and "equivalent within noise" in comparison["sentence"]


def test_report_page_is_self_contained(fitted):
    work, _ = fitted
    page = (work / "models" / "linear.report.html").read_text()
    assert not re.search(r"(src|href)\s*=\s*[\"'](?!data:)", page)  # nothing to fetch
    assert "http://" not in page and "https://" not in page
    images = re.findall(r'src="data:image/png;base64,([^"]+)"', page)
    assert len(images) == 3  # error against applied load, against load magnitude, against load direction
    assert all(base64.b64decode(i).startswith(b"\x89PNG\r\n\x1a\n") for i in images)
    for heading in ("Held-out accuracy per axis", "Model choice", "Calibrated range", "Frames and units",
                    "Held-out error against applied load", "Held-out error against load magnitude",
                    "Held-out error against load direction", "Applied against indicated load"):
        assert heading in page


def test_report_loads_in_chromium_without_console_errors_or_requests(fitted, tmp_path):
    work, _ = fitted
    shown = browser.render(work / "models" / "linear.report.html", tmp_path / "chromium")
    assert shown.console == [] and shown.page_requests == []
    assert shown.dom.count("<tr") > 6 + 6 and "Held-out accuracy per axis" in shown.dom


def test_the_browser_check_catches_console_errors_and_requests(tmp_path):
    """The harness above can fail: a page that logs an error and fetches a picture is caught on both counts."""
    bad = tmp_path / "bad.html"
    bad.write_text('<!DOCTYPE html><html><body><img src="http://example.invalid/x.png">'
                   '<script>console.error("boom")</script></body></html>')
    shown = browser.render(bad, tmp_path / "chromium")
    assert any('"boom"' in line for line in shown.console)
    assert shown.page_requests == ["http://example.invalid/x.png"]


def test_report_prints_to_pdf_through_the_browser(fitted, tmp_path):
    work, _ = fitted
    pdf = browser.print_pdf(work / "models" / "linear.report.html", tmp_path / "report.pdf", tmp_path / "chromium")
    body = pdf.read_bytes()
    assert body.startswith(b"%PDF-") and len(body) > 20_000  # text and two pictures


def test_report_for_a_dataset_of_another_sensor_is_one_line(fitted, tmp_path, capsys):
    work, _ = fitted
    sensor_dataset(n_channels=8, seed=1).save(tmp_path / "other.csv")
    code = main(["report", str(work / "models" / "linear.model.npz"), str(tmp_path / "other.csv"),
                 "--out", str(tmp_path / "r"), "--no-baselines"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert err.startswith("ftcal: error:") and "6 raw channels" in err and "8 raw channels" in err
    assert not (tmp_path / "r").exists() or not any((tmp_path / "r").iterdir())


def test_temperature_fit_honours_alpha_and_reports_coefficients(tmp_path):
    sensor_dataset(temperature=True).save(tmp_path / "warm.csv")
    assert main(["fit", str(tmp_path / "warm.csv"), "--model", "linear", "--temperature", "--alpha", "50",
                 "--report", "--no-baselines", "--out", str(tmp_path / "m"), "-q"]) == 0
    assert json.loads((tmp_path / "m" / "linear.fit.json").read_text())["alpha"] == 50.0
    facts = json.loads((tmp_path / "m" / "linear.report.json").read_text())
    assert facts["model"]["alpha"] == 50.0
    assert len(facts["temperature_coefficients"]["gain_per_deg"]) == 6
    assert facts["data"]["temperature_range"][0] >= 15 and facts["data"]["temperature_range"][1] <= 35
    assert "Temperature coefficients" in (tmp_path / "m" / "linear.report.html").read_text()


@pytest.mark.parametrize("candidates, gives_std", [("linear,polynomial", False), ("gaussian_process", True)])
def test_report_of_auto_and_of_a_gp_states_the_std_coverage_only_where_a_std_exists(tmp_path, candidates, gives_std):
    """An ``auto`` model that chose a model without a std is reported (its std coverage empty); a GP's is given."""
    import ftcal

    data = sensor_dataset()
    data.save(tmp_path / "data.csv")
    names = candidates.split(",")
    kinds = {"linear": ftcal.LinearCalibrator(), "polynomial": ftcal.PolynomialCalibrator(degree=2),
             "gaussian_process": ftcal.GaussianProcessCalibrator(max_samples=100, kernel="rbf", mean="linear",
                                                                 per_output=False, random_state=0)}
    model = ftcal.AutoCalibrator(candidates=[(n, kinds[n]) for n in names], cv=3, baselines=False, stack=False)
    ftcal.save_model(model.fit(data.raw, data.wrench, groups=data.group), tmp_path / "auto.model.npz")
    assert main(["report", str(tmp_path / "auto.model.npz"), str(tmp_path / "data.csv"), "--out",
                 str(tmp_path / "rep"), "-q"]) == 0
    accuracy = json.loads((tmp_path / "rep" / "auto.report.json").read_text())["accuracy"]
    coverage = [axis["coverage_std"] for axis in accuracy]
    if gives_std:
        assert all(0.5 <= c <= 1.0 for c in coverage)
    else:
        assert coverage == [None] * 6


def test_report_on_data_the_model_was_not_fitted_on_says_so(tmp_path, capsys):
    import ftcal

    fitted_on, other = sensor_dataset(seed=0), sensor_dataset(seed=5)
    other.save(tmp_path / "other.csv")
    ftcal.save_model(ftcal.LinearCalibrator().fit(fitted_on.raw, fitted_on.wrench), tmp_path / "m.model.npz")
    assert main(["report", str(tmp_path / "m.model.npz"), str(tmp_path / "other.csv"), "--cv", "3", "--out",
                 str(tmp_path / "rep"), "-q"]) == 0
    err = capsys.readouterr().err
    assert "ftcal: warning:" in err and "is not the data" in err and "refitted on this dataset" in err
