"""The public API: what the top level keeps, and the deprecated aliases of every public name that moved.

Each alias (an old top-level name, a name of the former packages ``ftcal.models``, ``ftcal.neural_network``,
``ftcal.evaluation``, ``ftcal.core.calibration_folds``, a renamed class) must warn with a ``FutureWarning``
naming its new home and return the very object of that home. Everywhere else in the suite these warnings are
errors (``pyproject.toml``'s ``filterwarnings``), so the library, its tests and benchmarks use the new homes.
"""

from __future__ import annotations

import ast
import importlib
import re
import subprocess
import sys
import warnings
from pathlib import Path

import pytest
from sklearn.base import BaseEstimator

import ftcal

PACKAGE = Path(ftcal.__file__).parent
SHIMS = ("models", "neural_network", "evaluation")

#: The top level's functions and non-estimator classes (the rule of docs/architecture.md, "The public API").
FIRST_CALLS = {"CalibrationDataset", "ColumnMap", "load_model", "save_model", "make_calibrator", "register_calibrator",
               "make_artificial_dataset", "neg_scaled_rmse", "export_onnx", "calibration_certificate", "FtcalError"}


def _resolve(path: str):
    module, _, name = path.rpartition(".")
    return getattr(importlib.import_module(module), name)


def _aliases() -> list[tuple[str, str, str]]:
    """(module, old name, new dotted path) of every alias ftcal declares."""
    found = [("ftcal", old, new) for old, new in ftcal._MOVED.items()]
    found += [("ftcal.core", old, new) for old, new in importlib.import_module("ftcal.core")._MOVED.items()]
    for shim in SHIMS:
        module = importlib.import_module(f"ftcal.{shim}")
        found += [(module.__name__, old, new) for old, new in module._MOVED.items()]
    return found


ALIASES = _aliases()


@pytest.mark.parametrize("module, old, new", ALIASES, ids=[f"{m}.{o}" for m, o, _ in ALIASES])
def test_a_moved_name_warns_naming_its_new_home_and_is_the_same_object(module, old, new):
    with pytest.warns(FutureWarning, match=rf"^{re.escape(module)}\.{old} moved to {re.escape(new)};"):
        value = getattr(importlib.import_module(module), old)
    assert value is _resolve(new)
    assert not new.split(".")[-1].startswith("_")  # the new home is public
    with pytest.warns(FutureWarning):  # not cached: every use warns, not only the first
        getattr(importlib.import_module(module), old)


def test_the_aliases_cover_every_name_the_top_level_and_the_old_packages_had():
    """The names of ftcal 0.1's top level (before the API rule) and of the three former packages all still resolve."""
    old_top_level = {"icosphere", "write_bag", "RunLog", "ThermalDrift", "CALIBRATOR_NAMES", "fit_stacked",
                     "identify_tool_load", "plan_calibration_poses", "run_artificial_benchmark", "CalibrationReport"}
    assert old_top_level <= set(ftcal._MOVED)
    assert len(ftcal._MOVED) + len(ftcal.__all__) >= 118  # nothing that was public disappeared
    assert set(importlib.import_module("ftcal.models")._MOVED) == {
        "search_summary", "DEFAULT_SEARCH_SPACES", "stock_baselines", "STOCK_BASELINE_NAMES", "SubsampledRegressor",
        "default_candidates", "check_calibration"}


def test_from_import_of_a_moved_name_warns():
    with pytest.warns(FutureWarning, match="ftcal.models.stock_baselines moved to ftcal.calibrators.stock_baselines"):
        from ftcal.models import stock_baselines
    from ftcal.calibrators import stock_baselines as new

    assert stock_baselines is new
    with pytest.warns(FutureWarning, match="ftcal.icosphere moved to ftcal.robot.icosphere"):
        from ftcal import icosphere  # noqa: F401


def test_a_renamed_class_answers_under_its_old_name():
    with pytest.warns(FutureWarning, match="CalibrationReport moved to ftcal.core.CalibrationMetrics"):
        old = ftcal.CalibrationReport
    assert old is ftcal.core.CalibrationMetrics
    with pytest.warns(FutureWarning, match="calibration_report moved to ftcal.core.calibration_metrics"):
        metrics = ftcal.calibration_report([[10.0, 0, 0, 0, 0, 1]], [[11.0, 0, 0, 0, 0, 1]], alpha=10.0)
    assert isinstance(metrics, ftcal.core.CalibrationMetrics) and metrics.rmse == pytest.approx(1 / 6**0.5)


def test_an_unknown_name_is_still_an_attribute_error():
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        ftcal.no_such_name  # noqa: B018
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        importlib.import_module("ftcal.models").no_such_name  # noqa: B018


def test_the_old_packages_are_shims_that_say_so():
    for shim in SHIMS:
        path = PACKAGE / shim
        assert sorted(p.name for p in path.glob("*.py")) == ["__init__.py"], f"ftcal/{shim} holds modules"
        doc = ast.get_docstring(ast.parse((path / "__init__.py").read_text()))
        assert doc.lower().startswith("deprecated alias of"), doc
        module = importlib.import_module(f"ftcal.{shim}")
        assert module.__all__ == [] and not set(module._MOVED) & set(dir(module))


def test_the_top_level_keeps_only_calibrators_datasets_model_files_and_first_calls():
    for name in ftcal.__all__:
        value = getattr(ftcal, name)
        is_estimator = isinstance(value, type) and issubclass(value, BaseEstimator) and hasattr(value, "predict")
        assert is_estimator or name in FIRST_CALLS, f"ftcal.{name} is neither a calibrator nor a first call"
    assert FIRST_CALLS <= set(ftcal.__all__)
    assert len(ftcal.__all__) <= 25
    assert not set(ftcal._MOVED) & set(dir(ftcal))  # a deprecated alias is not advertised


def test_every_top_level_name_is_also_in_its_public_subpackage():
    """The top level re-exports: each name there is the object its subpackage lists."""
    for name in ftcal.__all__:
        homes = [sub for sub in ftcal.SUBPACKAGES if name in importlib.import_module(f"ftcal.{sub}").__all__]
        assert homes, f"ftcal.{name} is in no public subpackage"
        assert getattr(importlib.import_module(f"ftcal.{homes[0]}"), name) is getattr(ftcal, name)


def test_a_subpackage_is_reachable_after_import_ftcal_alone():
    code = ("import warnings, sys; warnings.simplefilter('error'); import ftcal; "
            "assert 'ftcal.robot' not in sys.modules; print(ftcal.robot.STANDARD_GRAVITY)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert float(out.stdout) == pytest.approx(9.80665)


def test_the_suite_turns_a_moved_name_into_an_error():
    """pyproject's filterwarnings makes any use of an alias outside ``pytest.warns`` fail the test that made it."""
    with pytest.raises(FutureWarning, match="moved to"):
        ftcal.icosphere  # noqa: B018
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        assert ftcal.icosphere is ftcal.robot.icosphere


def test_a_models_inputs_have_one_definition_for_the_report_and_the_command_line():
    """``ftcal evaluate`` / ``ftcal report`` (the CLI) and the calibration report take a model's ``X`` from one
    function: the raw channels, plus the temperature column for a model whose tags say it reads one."""
    import numpy as np

    from ftcal import CalibrationDataset, LinearCalibrator, TemperatureCompensatedCalibrator
    from ftcal.cli._models import model_inputs as cli_inputs
    from ftcal.core import CalibrationInputError
    from ftcal.reporting import model_inputs

    rng = np.random.default_rng(0)
    raw = rng.normal(size=(40, 6))
    wrench = raw @ rng.normal(size=(6, 6))
    warm = CalibrationDataset(raw=raw, wrench=wrench, temperature=rng.uniform(15.0, 35.0, 40))
    cold = CalibrationDataset(raw=raw, wrench=wrench)
    linear = LinearCalibrator().fit(raw, wrench)
    compensated = TemperatureCompensatedCalibrator().fit(warm.features(temperature=True), wrench)
    for inputs in (model_inputs, cli_inputs):
        assert inputs(linear, warm) is warm.raw  # a model without a temperature input ignores the column
        np.testing.assert_array_equal(inputs(compensated, warm), warm.features(temperature=True))
        with pytest.raises(CalibrationInputError, match="takes 6 raw channels and a temperature column but the dataset "
                                                        "has 6 raw channels and no temperature column"):
            inputs(compensated, cold)
        with pytest.raises(CalibrationInputError, match="takes 6 raw channels but the dataset has 5 raw channels"):
            inputs(linear, CalibrationDataset(raw=raw[:, :5], wrench=wrench))
