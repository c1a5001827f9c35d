"""The certificate as a typed, JSON-able result; its uncertainty budget (GUM form, Welch-Satterthwaite k) checked
against a simulated second session; the user's names (sensor, channels, groups) kept on the page."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from scipy import stats

from ftcal import CalibrationDataset, LinearCalibrator, calibration_certificate
from ftcal.cli import main

AXES = ("Fx", "Fy", "Fz")
#: The fields the budget of each axis has, and each of its components (no more, no fewer).
BUDGET_FIELDS = {"axis", "components", "combined_standard_uncertainty", "effective_dof", "coverage_factor",
                 "expanded_uncertainty"}
COMPONENT_FIELDS = {"name", "standard_uncertainty", "dof", "source"}


class LoadCell:
    """A 3-axis load cell read by a 16-bit ADC: counts = G w + offset + noise, rounded to whole counts."""

    def __init__(self, seed: int = 0, noise_counts: float = 3.0):
        rng = np.random.default_rng(seed)
        self.gain = np.eye(3) * 40.0 + rng.normal(scale=4.0, size=(3, 3))  # counts per N
        self.offset = np.array([32000.0, 31000.0, 33000.0])
        self.noise = noise_counts

    def session(self, n_groups: int, cases: int, repeats: int, seed: int) -> CalibrationDataset:
        """``n_groups`` load configurations of ``cases`` loads each, every load read ``repeats`` times."""
        rng = np.random.default_rng(seed)
        loads = rng.uniform(-100, 100, size=(n_groups * cases, 3))
        w = np.repeat(loads, repeats, axis=0)
        counts = np.round(w @ self.gain.T + self.offset + rng.normal(scale=self.noise, size=w.shape))
        return CalibrationDataset(raw=counts, wrench=w, axes=AXES,
                                  group=np.repeat(np.arange(n_groups), cases * repeats))


def test_u95_of_session_one_covers_about_95_percent_of_a_second_sessions_errors():
    cell = LoadCell()
    first = cell.session(60, 5, 2, seed=1)
    model = LinearCalibrator().fit(first.raw, first.wrench)
    cert = calibration_certificate(model, first, baselines=False, figures=False)
    second = cell.session(60, 5, 2, seed=2)
    errors = model.predict(second.raw) - second.wrench
    m = len(errors)
    # 99.9 % two-sided binomial acceptance band of the count within U at the nominal 95.45 %, per axis
    low, high = stats.binom.interval(0.999, m, 0.9545)
    for j, b in enumerate(cert.budget):
        covered = int(np.sum(np.abs(errors[:, j]) <= b.expanded_uncertainty))
        assert low <= covered <= high, (b.axis, covered, m, low, high)
        # and not by a U far too large: 2 x U would cover all; the nominal half would cover ~68 %
        assert np.sum(np.abs(errors[:, j]) <= b.expanded_uncertainty / 2) < low
    # the repeatability is seen (each load read twice) and the resolution (one count) is listed
    names = [c.name for c in cert.budget[0].components]
    assert names[:3] == ["reproducibility (held-out)", "repeatability", "resolution"]
    rep = cert.budget[0].components[1]
    assert rep.dof == m / 2 and rep.standard_uncertainty > 0
    # the repeatability is the reading noise (plus a count's rounding) through the inverse gain: s_r of 300 dof
    # lies within 15 % of it (its relative SE is 1/sqrt(600), 4 %)
    count_sd = math.sqrt(cell.noise**2 + 1 / 12)
    assert rep.standard_uncertainty == pytest.approx(count_sd * np.linalg.norm(np.linalg.inv(cell.gain)[0]), rel=0.15)


def test_fifteen_rows_get_a_coverage_factor_above_two_and_the_reference_is_listed():
    cell = LoadCell(seed=3)
    data = cell.session(15, 1, 1, seed=4)
    data.group = None
    model = LinearCalibrator().fit(data.raw, data.wrench)
    cert = calibration_certificate(model, data, baselines=False, figures=False, reference_relative=0.0005)
    for b, a in zip(cert.budget, cert.accuracy):
        assert b.components[0].dof == 14  # the held-out error of 15 independent rows
        # Welch-Satterthwaite adds a little for the Type B terms (infinite dof); still about 15: k about 2.2
        assert 14 <= b.effective_dof < 20 and b.coverage_factor > 2.1
        assert b.coverage_factor == pytest.approx(stats.t.ppf(0.5 + 0.9545 / 2, b.effective_dof))
        assert a["u95"] == b.expanded_uncertainty == pytest.approx(b.coverage_factor * b.combined_standard_uncertainty)
        ref = [c for c in b.components if c.name == "reference standard"]
        assert len(ref) == 1 and math.isinf(ref[0].dof)
        j = AXES.index(b.axis)
        assert ref[0].standard_uncertainty == pytest.approx(0.0005 * np.abs(data.wrench[:, j]).max() / 2)
        assert b.combined_standard_uncertainty == pytest.approx(
            math.sqrt(sum(c.standard_uncertainty**2 for c in b.components)))


def test_pass_fail_follows_the_expanded_uncertainty_not_twice_the_rms():
    cell = LoadCell(seed=5)
    data = cell.session(6, 3, 1, seed=6)
    model = LinearCalibrator().fit(data.raw, data.wrench)
    probe = calibration_certificate(model, data, baselines=False, figures=False, rated=[100.0] * 3)
    a = probe.accuracy[0]
    assert a["coverage_factor"] > 2.2  # 6 groups: 5 dof
    between = (200 * a["rms"] / 100 + a["u95_pct_fs"]) / 2  # above 2 x RMS, below U95 (in % FS)
    cert = calibration_certificate(model, data, baselines=False, figures=False, rated=[100.0] * 3,
                                   spec=[between, 100.0, 100.0])
    assert cert.accuracy[0]["verdict"] == "FAIL" and cert.verdict == "FAIL"


def test_the_certificate_is_json_able_and_its_budget_has_exactly_the_named_fields(tmp_path):
    cell = LoadCell(seed=7)
    data = cell.session(8, 4, 2, seed=8)
    model = LinearCalibrator().fit(data.raw, data.wrench)
    cert = calibration_certificate(model, data, baselines=False, figures=False, reference_uncertainty=[0.1, 0.1, 0.2],
                                   temperature_coefficient=[0.01, 0.01, 0.02], temperature_deviation=5.0)
    facts = json.loads(json.dumps(cert.to_dict()))
    assert facts == json.loads(cert.to_json())
    budget = facts["uncertainty_budget"]
    assert [b["axis"] for b in budget] == list(AXES)
    for b in budget:
        assert set(b) == BUDGET_FIELDS and all(set(c) == COMPONENT_FIELDS for c in b["components"])
        named = {c["name"]: c for c in b["components"]}
        assert named["temperature"]["standard_uncertainty"] == pytest.approx(
            {"Fx": 0.01, "Fy": 0.01, "Fz": 0.02}[b["axis"]] * 5 / math.sqrt(3))
        assert named["reference standard"]["standard_uncertainty"] == pytest.approx(
            {"Fx": 0.05, "Fy": 0.05, "Fz": 0.1}[b["axis"]])
    csv_lines = cert.to_csv().splitlines()
    assert len(csv_lines) == 1 + facts["cases"]["count"] == 1 + 8 * 4  # the repeated readings averaged per case
    assert cert.held_out_predictions.shape == data.wrench.shape


def test_names_of_the_sensor_channels_and_groups_are_kept_and_force_only_prints_no_torque_scale():
    cell = LoadCell(seed=9)
    data = cell.session(5, 4, 1, seed=10)
    files = [f"pose_{i:02d}.csv" for i in range(5)]
    data.meta = {"sensor": "LC-3 serial 0042", "channel_names": ["bridge_a", "bridge_b", "bridge_c"],
                 "group_names": files}
    model = LinearCalibrator().fit(data.raw, data.wrench)
    cert = calibration_certificate(model, data, baselines=False, figures=False)
    page = cert.to_html()
    assert cert.sensor == "LC-3 serial 0042" and "not named" not in page
    assert cert.identity["model"]["matrix"]["columns"] == ["bridge_a", "bridge_b", "bridge_c"]
    assert "<th>bridge_a</th>" in page and "<th>s0</th>" not in page
    assert set(cert.cases.group) == set(files) and all(g in page for g in files[:3])
    assert set(cert.to_dict()["cases"]["group"]) == set(files)
    assert "1/m" not in page and "alpha" not in page and cert.identity["model"]["alpha"] is None
    # without groups: no word of groups in the folds or the warnings
    data.group, data.meta = None, {}
    plain = calibration_certificate(model, data, baselines=False, figures=False)
    text = plain.to_html()
    assert "group" not in plain.validation["split"] and "by group" not in text and "whole groups" not in text
    assert "not named" in plain.sensor


def test_readings_dropped_or_flagged_and_data_beyond_the_calibrated_range_are_listed():
    cell = LoadCell(seed=11)
    data = cell.session(6, 5, 1, seed=12)
    small = np.abs(data.wrench).max(axis=1) < 70
    model = LinearCalibrator().fit(data.raw[small], data.wrench[small])  # a narrower range than the data
    data.meta = {"readings_dropped": [{"kind": "out_of_range", "file": "pose_03.csv", "line": 17, "channel": "s1",
                                       "value": 4598.0, "reason": "beyond the 10-bit range 0..1023"}],
                 "readings_flagged": [{"kind": "spike", "file": "pose_04.csv", "line": 9, "channel": "s0",
                                       "value": 900.0, "reason": "robust z 14"}]}
    cert = calibration_certificate(model, data, baselines=False, figures=False)
    page = cert.to_html()
    assert "pose_03.csv" in page and "4598" in page and "pose_04.csv" in page and "robust z 14" in page
    assert cert.data["readings_dropped"][0]["line"] == 17
    beyond = {e["channel"]: e for e in cert.extrapolation}
    lo, hi = model.calibrated_range_
    for c, name in enumerate(("s0", "s1", "s2")):
        outside = int(np.sum((data.raw[:, c] < lo[c]) | (data.raw[:, c] > hi[c])))
        if outside:
            assert beyond[name]["rows_beyond"] == outside
            half = (hi[c] - lo[c]) / 2
            assert beyond[name]["largest_x_range"] == pytest.approx(
                np.max(np.abs(data.raw[:, c] - (lo[c] + hi[c]) / 2)) / half)
    assert beyond and "beyond the model's calibrated range" in page


def test_the_report_command_takes_the_reference_uncertainty_and_the_channel_names_of_the_file(tmp_path):
    cell = LoadCell(seed=13)
    data = cell.session(6, 5, 1, seed=14)
    lines = ["pose,g_a,g_b,g_c,Fx,Fy,Fz"] + [f"p{int(g)},{r[0]:.0f},{r[1]:.0f},{r[2]:.0f},{w[0]},{w[1]},{w[2]}"
                                            for g, r, w in zip(data.group, data.raw, data.wrench)]
    (tmp_path / "cell.csv").write_text("\n".join(lines) + "\n")
    assert main(["fit", str(tmp_path / "cell.csv"), "--channels", "g_a,g_b,g_c", "--wrench", "Fx,Fy,Fz", "--groups",
                 "pose", "--model", "linear", "--out", str(tmp_path / "m"), "-q"]) == 0
    model = next((tmp_path / "m").glob("*.model.npz"))
    assert main(["report", str(model), str(tmp_path / "cell.csv"), "--channels", "g_a,g_b,g_c", "--wrench",
                 "Fx,Fy,Fz", "--groups", "pose", "--no-baselines", "--reference-uncertainty", "0.05%",
                 "--out", str(tmp_path / "r"), "-q"]) == 0
    facts = json.loads(next((tmp_path / "r").glob("*.report.json")).read_text())
    assert facts["model"]["matrix"]["columns"] == ["g_a", "g_b", "g_c"]
    assert all("reference standard" in [c["name"] for c in b["components"]] for b in facts["uncertainty_budget"])
    assert set(facts["cases"]["group"]) == {f"p{i}" for i in range(6)}
