"""``benchmarks/tune_networks.py``: bad arguments, no overwriting, and a tiny end-to-end run."""

from __future__ import annotations

import importlib.util
import json
from pathlib import Path

import pytest

from ftcal.compose._search import DEFAULT_SEARCH_SPACES

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def tune():
    spec = importlib.util.spec_from_file_location("bench_tune_networks", ROOT / "benchmarks" / "tune_networks.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


@pytest.mark.parametrize("argv, message", [
    (["--n-iter", "0"], "--n-iter must be >= 1; got 0"),
    (["--cv", "1"], "--cv must be >= 2; got 1"),
    (["--validate", "0"], "--validate must be >= 1; got 0"),
])
def test_bad_counts_are_refused_before_any_work(tune, tmp_path, capsys, argv, message):
    assert tune.main([*argv, "--out", str(tmp_path)]) == 2
    assert message in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize("text", ["{lr: 1}", "[1, 2]", "{}"])
def test_setting_must_be_a_json_object(tune, capsys, text):
    with pytest.raises(SystemExit):
        tune.main(["--setting", text])
    assert "--setting" in capsys.readouterr().err


def test_existing_outputs_are_not_overwritten(tune, tmp_path, capsys):
    mine = tmp_path / "tune_networks.md"
    mine.write_text("my notes\n")
    with pytest.raises(SystemExit) as stop:
        tune.main(["--out", str(tmp_path)])
    assert stop.value.code == 2
    assert capsys.readouterr().err.strip().splitlines()[-1].endswith(
        f"{mine} exists and was not written by this benchmark (or was edited since). Fix: choose another output "
        "folder or pass --force to overwrite it.")
    assert mine.read_text() == "my notes\n"


def test_search_then_validation_end_to_end(tune, tmp_path):
    argv = ["--models", "directional", "--presets", "stress", "--n-iter", "1", "--cv", "2", "--validate", "1",
            "--n-per-sphere", "30", "--jobs", "1", "--out", str(tmp_path)]
    assert tune.main(argv) == 0
    result = json.loads((tmp_path / "tune_networks.json").read_text())
    (row,) = result["rows"]
    space = DEFAULT_SEARCH_SPACES["directional"]
    for key, value in row["search"]["best_params"].items():
        value = tuple(value) if isinstance(value, list) else value
        assert value in space[key]
    assert len(row["default_rmse"]) == len(row["tuned_rmse"]) == 1
    assert row["tuned_over_default"] == pytest.approx(row["tuned_rmse"][0] / row["default_rmse"][0])
    assert row["tuned_wins"] is False  # one pair cannot reach p < 0.05
    assert "--n-iter 1" in (tmp_path / "tune_networks.md").read_text()
