"""The public API: what the top level keeps, each name in its public subpackage, and no alias of an old name.

ftcal 0.1.0 is unreleased, so the names that moved while the package was split into subpackages keep no
deprecated alias (CHANGELOG.md): an old name is an ``AttributeError``, the old packages do not exist.
"""

from __future__ import annotations

import importlib
import subprocess
import sys
from pathlib import Path

import pytest
from sklearn.base import BaseEstimator

import ftcal

PACKAGE = Path(ftcal.__file__).parent

#: The top level's functions and non-estimator classes (the rule of docs/architecture.md, "The public API").
FIRST_CALLS = {"CalibrationDataset", "ColumnMap", "load_model", "save_model", "make_calibrator", "register_calibrator",
               "make_artificial_dataset", "neg_scaled_rmse", "export_onnx", "calibration_certificate", "FtcalError"}


#: Old top-level names (ftcal 0.1.0 before the subpackages) and their one home now.
OLD_TOP_LEVEL = {"icosphere": "robot", "write_bag": "io", "RunLog": "io", "ThermalDrift": "core",
                 "CALIBRATOR_NAMES": "compose", "fit_stacked": "networks", "identify_tool_load": "experiment",
                 "plan_calibration_poses": "robot", "run_artificial_benchmark": "benchmark",
                 "CalibrationMetrics": "core"}


@pytest.mark.parametrize("old, home", sorted(OLD_TOP_LEVEL.items()))
def test_an_old_top_level_name_is_gone_and_lives_in_its_subpackage(old, home):
    with pytest.raises(AttributeError, match=f"module 'ftcal' has no attribute '{old}'"):
        getattr(ftcal, old)
    assert old in importlib.import_module(f"ftcal.{home}").__all__
    assert old not in dir(ftcal)


def test_the_old_packages_and_names_are_gone():
    for package in ("models", "neural_network", "evaluation"):
        assert not (PACKAGE / package).exists() and package not in ftcal.SUBPACKAGES
    for gone in ("CalibrationReport", "calibration_report", "_MOVED"):
        assert not hasattr(ftcal, gone)
    with pytest.raises(AttributeError, match="has no attribute 'calibration_folds'"):
        importlib.import_module("ftcal.core").calibration_folds  # noqa: B018  (in ftcal.model_selection)
    with pytest.raises(ImportError, match="icosphere"):
        from ftcal import icosphere  # noqa: F401


def test_an_unknown_name_is_still_an_attribute_error():
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        ftcal.no_such_name  # noqa: B018
    with pytest.raises(AttributeError, match="has no attribute 'no_such_name'"):
        importlib.import_module("ftcal.compose").no_such_name  # noqa: B018


def test_the_top_level_keeps_only_calibrators_datasets_model_files_and_first_calls():
    for name in ftcal.__all__:
        value = getattr(ftcal, name)
        is_estimator = isinstance(value, type) and issubclass(value, BaseEstimator) and hasattr(value, "predict")
        assert is_estimator or name in FIRST_CALLS, f"ftcal.{name} is neither a calibrator nor a first call"
    assert FIRST_CALLS <= set(ftcal.__all__)
    assert len(ftcal.__all__) <= 25


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


def test_a_models_inputs_have_one_definition_for_the_report_and_the_command_line():
    """``ftcal evaluate`` / ``ftcal report`` (the CLI) and the calibration report take a model's ``X`` from one
    function: the raw channels, plus the temperature column for a model whose tags say it reads one."""
    import inspect
    import re

    import numpy as np

    import ftcal.cli._evaluate
    import ftcal.cli._models
    import ftcal.cli._report
    from ftcal import CalibrationDataset, LinearCalibrator, TemperatureCompensatedCalibrator
    from ftcal.core import CalibrationInputError
    from ftcal.reporting import model_inputs

    # the command line has no definition of its own: its commands import the library's
    assert not hasattr(ftcal.cli._models, "model_inputs")
    for module in (ftcal.cli._evaluate, ftcal.cli._report):
        assert re.search(r"from \.\.reporting import [^\n]*\bmodel_inputs\b", inspect.getsource(module)), module

    rng = np.random.default_rng(0)
    raw = rng.normal(size=(40, 6))
    wrench = raw @ rng.normal(size=(6, 6))
    warm = CalibrationDataset(raw=raw, wrench=wrench, temperature=rng.uniform(15.0, 35.0, 40))
    cold = CalibrationDataset(raw=raw, wrench=wrench)
    linear = LinearCalibrator().fit(raw, wrench)
    compensated = TemperatureCompensatedCalibrator().fit(warm.features(temperature=True), wrench)
    assert model_inputs(linear, warm) is warm.raw  # a model without a temperature input ignores the column
    np.testing.assert_array_equal(model_inputs(compensated, warm), warm.features(temperature=True))
    with pytest.raises(CalibrationInputError, match="takes 6 raw channels and a temperature column but the dataset "
                                                    "has 6 raw channels and no temperature column"):
        model_inputs(compensated, cold)
    with pytest.raises(CalibrationInputError, match="takes 6 raw channels but the dataset has 5 raw channels"):
        model_inputs(linear, CalibrationDataset(raw=raw[:, :5], wrench=wrench))
