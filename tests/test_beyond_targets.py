"""The target checks of ``benchmarks/beyond.py`` (the "beyond the thesis" study) on hand-built benchmark records."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import numpy as np
import pytest

from ftcal.benchmark._artificial import summarize_results

ROOT = Path(__file__).resolve().parents[1]
MODELS = ["linear", "axis_nonlinear", "comparative", "directional", "directional_ensemble"]


def _beyond():
    spec = importlib.util.spec_from_file_location("bench_beyond", ROOT / "benchmarks" / "beyond.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _records(rmse: dict[str, np.ndarray], floor: np.ndarray, members: list[list[float]]) -> list[dict]:
    out = []
    for model, values in rmse.items():
        for i, r in enumerate(values):
            out.append(dict(preset="p", dataset=i, model=model, rmse=float(r), rel_force_mean=0.0,
                            rel_torque_mean=0.0, noise_floor=float(floor[i]),
                            member_rmse=members[i] if model == "directional_ensemble" else None))
    return out


FLOOR = np.array([4.0, 4.5, 5.0, 5.5, 6.0, 6.5])
JITTER = np.array([0.3, -0.3, 0.1, -0.1, 0.2, -0.2])
MEMBERS = [[6.0, 6.2, 6.4, 6.6, 6.8]] * 6  # five seeds per dataset, sample std sqrt(0.1)


def _targets(rmse):
    beyond = _beyond()
    results = _records(rmse, FLOOR, MEMBERS)
    summary = summarize_results(results, MODELS, ["p"])
    return beyond.targets(summary, results, MODELS)["p"]


def test_ensemble_ratios_and_seed_spread_against_hand_computed_values():
    directional = FLOOR + 1.0 + JITTER  # excess over the floor: 1 + jitter
    ensemble = FLOOR + 0.5 + 0.25 * JITTER  # excess: 0.5 + jitter / 4
    row = _targets({"linear": FLOOR + 0.1, "axis_nonlinear": FLOOR, "comparative": FLOOR + 2.0,
                    "directional": directional, "directional_ensemble": ensemble})
    e = row["ensemble"]
    assert e["n"] == 6
    # raw RMSE: both follow the floor, so the std ratio is far from the excess' exact 1/4
    expected = np.std(ensemble, ddof=1) / np.std(directional, ddof=1)
    assert e["std_ratio"] == pytest.approx(expected) and e["std_ratio"] > 0.7
    assert e["excess_std_ratio"] == pytest.approx(0.25)
    assert e["excess_directional"]["mean"] == pytest.approx(1.0)
    assert e["noise_floor"]["std"] == pytest.approx(np.std(FLOOR, ddof=1))
    # 6.0 .. 6.8 in steps of 0.2: deviations -0.4, -0.2, 0, 0.2, 0.4 -> variance 0.4 / 4 = 0.1
    assert e["member_seed_std"]["mean"] == pytest.approx(np.sqrt(0.1)) and e["member_seed_std"]["n"] == 6
    assert row["hybrid_no_worse_than_thesis_models"] is True
    assert row["hybrid_over_ltm"] == pytest.approx(np.mean(FLOOR) / np.mean(FLOOR + 0.1))
    assert row["hybrid_over_floor"]["mean"] == pytest.approx(1.0)
    # hybrid below the other model on all 6 datasets: the smallest exact two-sided p, 2 / 2**6
    assert row["vs"]["comparative"]["wilcoxon_p"] == pytest.approx(2 / 64)


def test_a_better_thesis_model_fails_the_hybrid_target():
    row = _targets({"linear": FLOOR - 0.01, "axis_nonlinear": FLOOR, "comparative": FLOOR + 2.0,
                    "directional": FLOOR + 1.0, "directional_ensemble": FLOOR + 0.5})
    assert row["hybrid_no_worse_than_thesis_models"] is False
    assert row["hybrid_over_ltm"] > 1.0
