"""Hyperparameter search: from Python (grid, randomized, grouped folds, networks) and through ``ftcal tune``."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest
from sklearn.model_selection import GridSearchCV, RandomizedSearchCV

from ftcal import CalibrationDataset, PolynomialCalibrator, load_model
from ftcal.core import CalibrationInputError
from ftcal.compose import search_calibrator
from ftcal.compose._search import DEFAULT_SEARCH_SPACES, parse_search_space, search_summary
from ftcal.cli import main

from conftest import TINY_SCHEDULE


def _cubic_sensor(n: int = 150, seed: int = 0):
    """Forces and torques as an odd cubic of the readings: degree 3 fits, degree 1 cannot."""
    rng = np.random.default_rng(seed)
    raw = rng.uniform(-1, 1, size=(n, 6))
    wrench = (raw + 0.3 * raw**3) @ rng.normal(size=(6, 6)).T * 100 + 0.01 * rng.normal(size=(n, 6))
    return raw, wrench


def test_grid_search_picks_the_degree_the_data_need():
    raw, wrench = _cubic_sensor()
    search = search_calibrator("polynomial", raw, wrench, space={"degree": [1, 3], "ridge": [1e-8]}, cv=3)
    assert isinstance(search, GridSearchCV)
    assert search.best_params_["degree"] == 3
    assert isinstance(search.best_estimator_, PolynomialCalibrator)
    summary = search_summary(search)
    assert summary["n_candidates"] == 2 and summary["candidates"][0]["params"]["degree"] == 3
    assert summary["best_rmse"] < summary["candidates"][1]["rmse_mean"]


def test_randomized_search_with_distributions_and_groups():
    raw, wrench = _cubic_sensor(seed=1)
    groups = np.repeat(np.arange(5), 30)
    space = parse_search_space(["ridge=loguniform(1e-8, 1e-2)", "powers=[[1.0], [2.0]]"])
    search = search_calibrator("axis_nonlinear", raw, wrench, space=space, n_iter=3, cv=5, groups=groups)
    assert isinstance(search, RandomizedSearchCV) and len(search.cv_results_["params"]) == 3
    assert search.n_splits_ == 5 and 1e-8 <= search.best_params_["ridge"] <= 1e-2


def test_network_search_end_to_end():
    raw, wrench = _cubic_sensor(n=60, seed=2)
    search = search_calibrator(
        "directional", raw, wrench, space={"hidden_layer_sizes": [(4,), (8, 8)], "lr": [1e-3]}, cv=2,
        **{k: v for k, v in TINY_SCHEDULE.items() if k != "hidden_layer_sizes"},
    )
    assert search.best_estimator_.predict(raw).shape == (60, 6)


def test_default_spaces_name_real_parameters():
    from ftcal import make_calibrator

    for name, space in DEFAULT_SEARCH_SPACES.items():
        assert set(space) <= set(make_calibrator(name).get_params(deep=True)), name



def test_cli_tune_of_the_stock_model_searches_every_stock_baseline(tmp_path):
    from ftcal.calibrators import STOCK_BASELINE_NAMES

    assert DEFAULT_SEARCH_SPACES["stock"] == {"baseline": list(STOCK_BASELINE_NAMES)}
    raw, wrench = _cubic_sensor(n=90)
    data = CalibrationDataset(raw=raw, wrench=wrench).save(tmp_path / "train.csv")
    assert main(["tune", str(data), "--model", "stock", "--out", str(tmp_path / "o"), "-q"]) == 0
    summary = json.loads((tmp_path / "o" / "stock.tune.json").read_text())
    assert sorted(str(c["params"]["baseline"]) for c in summary["candidates"]) == sorted(STOCK_BASELINE_NAMES)
    assert summary["best_params"]["baseline"] in ("sk_poly3", "sk_kernel_ridge", "sk_gp")  # a cubic sensor

@pytest.mark.parametrize(
    "kwargs, match",
    [(dict(space={"bogus": [1]}), "no parameter"), (dict(space={}), "empty"), (dict(cv=1), "cv"),
     (dict(space={"degree": [1, 2]}, groups=np.zeros(150)), "distinct"),
     (dict(space=parse_search_space(["ridge=uniform(0, 1)"])), "n_iter")],
)
def test_bad_search_requests(kwargs, match):
    with pytest.raises(CalibrationInputError, match=match):
        search_calibrator("polynomial", *_cubic_sensor(), **kwargs)


@pytest.mark.parametrize("entry", ["degree", "degree=3", "degree=[]", "lr=gauss(1, 2)", "=[1]"])
def test_bad_search_entries(entry):
    with pytest.raises(CalibrationInputError, match="search entry"):
        parse_search_space([entry])


def test_cli_tune_writes_the_best_model_and_the_ranking(tmp_path, capsys):
    raw, wrench = _cubic_sensor()
    data = CalibrationDataset(raw=raw, wrench=wrench).save(tmp_path / "train.csv")
    out = tmp_path / "tuned"
    argv = ["tune", str(data), "--model", "polynomial", "--grid", "degree=[1, 3]", "--cv", "2", "--out", str(out), "-q"]
    assert main(argv) == 0
    summary = json.loads((out / "polynomial.tune.json").read_text())
    assert summary["best_params"] == {"degree": 3} and len(summary["candidates"]) == 2
    model = load_model(out / "polynomial.model.npz")
    assert model.degree == 3 and model.predict(raw).shape == (150, 6)
    assert main(argv) == 2  # outputs exist: refused without --force
    assert "already exist" in capsys.readouterr().err


def test_cli_tune_reports_bad_parameters(tmp_path, capsys):
    raw, wrench = _cubic_sensor()
    data = CalibrationDataset(raw=raw, wrench=wrench).save(tmp_path / "train.csv")
    assert main(["tune", str(data), "--grid", "bogus=[1]", "--out", str(tmp_path / "o"), "-q"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ftcal: error:") and "bogus" in err and "Traceback" not in err


@pytest.mark.parametrize("entry, expected", [
    ("ridge=loguniform(1, 0)", "loguniform(a, b) needs 0 < a < b; got a = 1, b = 0"),
    ("ridge=loguniform(0, 1)", "loguniform(a, b) needs 0 < a < b"),
    ("ridge=uniform(2, 2)", "uniform(a, b) needs a < b"),
    ("degree=randint(1.5, 3)", "randint(a, b) needs integers a <= b"),
    ("ridge=uniform(0, inf)", "uniform(a, b) needs finite bounds; got a = 0, b = inf"),
    ("ridge=uniform(x, 1)", "uniform(a, b) takes two numbers"),
])
def test_search_space_bounds_are_checked_when_parsed_not_when_sampled(entry, expected):
    # scipy would accept these and fail only when the search samples, with "Domain error in arguments"
    from ftcal.compose._search import parse_search_space

    with pytest.raises(CalibrationInputError, match=re.escape(f"search entry {entry!r}: {expected}")):
        parse_search_space([entry])


# ------------------------------------------------------------------ groups: grouped folds, routed only where requested
def _grouped_sensor(n_groups: int = 6, per_group: int = 20, seed: int = 3):
    raw, wrench = _cubic_sensor(n=n_groups * per_group, seed=seed)
    return raw, wrench, np.repeat(np.arange(n_groups), per_group)


def _whole_groups(folds, groups) -> bool:
    return all(not set(groups[train]) & set(groups[test]) for train, test in folds)


@pytest.mark.parametrize("model, space, extra", [
    ("linear", {"ridge": [0.0, 1e-3]}, {}),  # requests no groups
    ("polynomial", {"degree": [1, 2]}, {}),  # requests them (group offsets)
    ("axis_nonlinear", {"powers": [(), (1.0,)]}, {}),
    ("directional", {"lr": [1e-3]}, {k: v for k, v in TINY_SCHEDULE.items()}),  # a network: requests none
])
def test_search_with_groups_holds_out_whole_groups_for_every_calibrator(model, space, extra):
    raw, wrench, groups = _grouped_sensor()
    search = search_calibrator(model, raw, wrench, space=space, cv=3, groups=groups, **extra)
    assert search.n_splits_ == 3 and _whole_groups(search.cv, groups)
    assert search.best_estimator_.predict(raw).shape == wrench.shape


def test_search_routes_groups_only_to_a_calibrator_that_requests_them():
    from sklearn import config_context
    from ftcal.compose._registry import _FACTORIES, register_calibrator

    seen: list = []

    class Recording(PolynomialCalibrator):
        def fit(self, X, y, groups=None):
            seen.append(None if groups is None else np.unique(groups).tolist())
            return super().fit(X, y, groups)

    def declining(**params):
        with config_context(enable_metadata_routing=True):
            return Recording(**params).set_fit_request(groups=False)

    raw, wrench, groups = _grouped_sensor()
    register_calibrator("recording_polynomial", Recording)
    register_calibrator("declining_polynomial", declining)
    try:
        search = search_calibrator("recording_polynomial", raw, wrench, space={"degree": [1, 2]}, cv=3, groups=groups)
        assert _whole_groups(search.cv, groups)
        # each fold's fit got its training groups (4 of the 6), the refit all 6
        assert sorted(map(len, seen)) == [4] * 6 + [6]
        seen.clear()
        search = search_calibrator("declining_polynomial", raw, wrench, space={"degree": [1, 2]}, cv=3, groups=groups)
        assert seen == [None] * 7 and _whole_groups(search.cv, groups)  # folds still grouped, groups never passed
    finally:
        _FACTORIES.pop("recording_polynomial"), _FACTORIES.pop("declining_polynomial")


def test_cli_tune_on_a_csv_with_a_group_column(tmp_path):
    import subprocess
    import sys

    raw, wrench, groups = _grouped_sensor()
    header = ",".join([f"s{i}" for i in range(6)] + ["Fx", "Fy", "Fz", "Tx", "Ty", "Tz", "group"])
    np.savetxt(tmp_path / "g.csv", np.c_[raw, wrench, groups], delimiter=",", header=header, comments="")
    done = subprocess.run([sys.executable, "-m", "ftcal", "tune", str(tmp_path / "g.csv"), "--model", "linear",
                           "--out", str(tmp_path / "tu"), "-f", "-q"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    summary = json.loads((tmp_path / "tu" / "linear.tune.json").read_text())
    assert summary["n_folds"] == 3 and len(summary["candidates"]) == 4
