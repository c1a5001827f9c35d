"""Capabilities declared once, as tags: every registered calibrator declares them; a new calibrator is one module
plus one registry line; the stock baselines as calibrators; a wrapper's after-fit adoption."""

from __future__ import annotations

import importlib
import sys

import numpy as np
import pytest

import ftcal
from ftcal import LinearCalibrator, TemperatureCompensatedCalibrator
from ftcal.core import ThermalDrift
from ftcal.calibrators._base import CalibrationTags, FtcalTags, calibration_tags
from ftcal.calibrators._baselines import STOCK_BASELINE_NAMES, StockCalibrator, stock_baselines
from ftcal.compose._registry import CALIBRATOR_NAMES, _CANDIDATES, _FACTORIES, _SEARCH_SPACES, make_calibrator, \
    model_classes


def _data(n=120, channels=6, seed=0):
    rng = np.random.default_rng(seed)
    w = rng.uniform(-1, 1, size=(n, 6))
    raw = w @ rng.normal(size=(6, channels)) + 0.01 * rng.normal(size=(n, channels))
    return raw, w


@pytest.mark.parametrize("cls", sorted(model_classes().values(), key=lambda c: c.__name__), ids=lambda c: c.__name__)
def test_every_registered_calibrator_declares_its_tags(cls):
    tags = cls().__sklearn_tags__() if cls.__name__ != "StackedCalibrator" else \
        cls(estimators=[LinearCalibrator()], weights=[1.0]).__sklearn_tags__()
    assert isinstance(tags, FtcalTags) and isinstance(tags.ftcal, CalibrationTags)
    assert tags.ftcal.cost in ("closed_form", "kernel", "network", "heavy")
    rows = tags.ftcal.min_training_rows(8)
    assert isinstance(rows, int) and rows >= 9  # at least one row more than the channels
    # ONNX support is what the class (or a parent) declares next to itself
    assert tags.ftcal.onnx == callable(getattr(cls, "_emit_onnx", None))


class _ShiftedLinear(LinearCalibrator):
    """A user's subclass that adds nothing: it keeps every tag of its parent."""


class _Clipped(LinearCalibrator):
    """A user's subclass whose predict is not its parent's graph: it says so by its tags."""

    def _predict_wrench(self, X):
        return np.clip(super()._predict_wrench(X), -0.5, 0.5)

    def __sklearn_tags__(self):
        from ftcal.calibrators import declare

        return declare(super().__sklearn_tags__(), onnx=False)


def test_a_subclass_keeps_its_parents_tags_and_exports_its_graph(tmp_path):
    pytest.importorskip("onnx")
    onnxruntime = pytest.importorskip("onnxruntime")
    from ftcal import export_onnx

    from dataclasses import asdict

    sub, parent = asdict(calibration_tags(_ShiftedLinear())), asdict(calibration_tags(LinearCalibrator()))
    assert sub.pop("min_training_rows")(6) == parent.pop("min_training_rows")(6) == 8
    assert sub == parent
    assert calibration_tags(_ShiftedLinear()).onnx and calibration_tags(_ShiftedLinear()).cost == "closed_form"
    raw, w = _data()
    model = _ShiftedLinear().fit(raw, w)
    path = export_onnx(model, tmp_path / "sub.onnx")
    session = onnxruntime.InferenceSession(str(path))
    np.testing.assert_allclose(session.run(None, {"readings": raw})[0], model.predict(raw), rtol=1e-9, atol=1e-9)


def test_a_subclass_that_computes_something_else_declares_it_and_is_not_exported(tmp_path):
    pytest.importorskip("onnx")
    from ftcal import export_onnx
    from ftcal.core import ExportError

    assert not calibration_tags(_Clipped()).onnx
    assert calibration_tags(_Clipped()).cost == "closed_form"  # the rest is inherited
    raw, w = _data()
    with pytest.raises(ExportError, match="_Clipped cannot be exported to ONNX"):
        export_onnx(_Clipped().fit(raw, w), tmp_path / "clipped.onnx")
    assert not (tmp_path / "clipped.onnx").exists()


def test_tags_say_what_the_code_used_to_guess():
    from ftcal import (AutoCalibrator, DirectionalCalibrator, GaussianProcessCalibrator, HistoryCalibrator,
                       PolynomialCalibrator)

    assert calibration_tags(TemperatureCompensatedCalibrator()).temperature_column
    assert not calibration_tags(LinearCalibrator()).temperature_column
    assert calibration_tags(HistoryCalibrator()).reads_history
    assert calibration_tags(AutoCalibrator()).chooses_model
    assert calibration_tags(GaussianProcessCalibrator()).provides_std
    assert calibration_tags(GaussianProcessCalibrator()).chooses_structure
    net = calibration_tags(DirectionalCalibrator())
    assert net.network and net.stackable and net.cost == "network"
    from skorch.callbacks import PrintLog
    assert not calibration_tags(DirectionalCalibrator(callbacks=[PrintLog()])).stackable
    assert calibration_tags(PolynomialCalibrator(degree=3)).min_training_rows(6) == 84  # C(9, 3)
    assert calibration_tags(LinearCalibrator()).min_training_rows(6) == 8
    # an estimator without ftcal's tags gets the defaults: a costly model of unknown kind
    from sklearn.linear_model import Ridge
    unknown = calibration_tags(Ridge())
    assert unknown.cost == "heavy" and unknown.min_training_rows(8) == 200 and not unknown.uses_groups


TOY_MODULE = '''
"""A toy calibrator: the LTM fitted on twice the readings (one module; nothing else in ftcal edited)."""
import numpy as np
from ftcal.calibrators import BaseCalibrator, declare


class ToyCalibrator(BaseCalibrator):
    _fitted_state = ("matrix_",)

    def __init__(self, *, alpha=None, zero_reading=None, random_state=None):
        self.alpha = alpha
        self.zero_reading = zero_reading
        self.random_state = random_state

    def __sklearn_tags__(self):
        return declare(super().__sklearn_tags__(), cost="closed_form", min_training_rows=lambda n: n + 2)

    def _fit(self, X, y):
        design = np.column_stack([2 * X, np.ones(len(X))])
        self.matrix_ = np.linalg.lstsq(design, y, rcond=None)[0]

    def _predict_wrench(self, X):
        return np.column_stack([2 * X, np.ones(len(X))]) @ self.matrix_
'''


@pytest.fixture
def toy_module(tmp_path, monkeypatch):
    (tmp_path / "toy_calibrator_module.py").write_text(TOY_MODULE)
    monkeypatch.syspath_prepend(str(tmp_path))
    module = importlib.import_module("toy_calibrator_module")
    yield module
    for table in (_FACTORIES, _CANDIDATES, _SEARCH_SPACES):
        table.pop("toy", None)
    sys.modules.pop("toy_calibrator_module", None)


def test_a_new_calibrator_is_one_module_and_one_registry_line(toy_module, tmp_path, capsys):
    # the one registry line
    ftcal.register_calibrator("toy", toy_module.ToyCalibrator, candidates=[(15, "toy", {})],
                              search_space={"alpha": [1.0, 2.0]})
    # auto's candidates follow from the registry, in their complexity place (after the LTM and its twin)
    names = [name for name, _ in ftcal.compose.default_candidates()]
    assert names[:2] == ["linear", "toy"]
    raw, w = _data()
    auto = ftcal.AutoCalibrator(baselines=False, stack=False, candidates=None, cv=3)
    auto.set_params(candidates=[(n, e) for n, e in ftcal.compose.default_candidates() if n in ("linear", "toy")])
    auto.fit(raw, w)
    assert "toy" in auto.comparison_["name"]
    # model files: the class is known by the registry; saved and loaded, it predicts the same
    model = make_calibrator("toy").fit(raw, w)
    path = ftcal.save_model(model, tmp_path / "toy.npz")
    assert np.array_equal(ftcal.load_model(path).predict(raw[:5]), model.predict(raw[:5]))
    # the search space and the CLI lists
    from ftcal.compose._registry import registered_search_spaces
    assert registered_search_spaces()["toy"] == {"alpha": [1.0, 2.0]}
    assert "toy" in CALIBRATOR_NAMES
    from ftcal.cli import main
    capsys.readouterr()
    assert main(["fit", "--help"]) in (0, None)
    listed = capsys.readouterr().out
    assert "toy" in listed and "gaussian_process" in listed


@pytest.mark.parametrize("name", STOCK_BASELINE_NAMES)
def test_a_stock_calibrator_predicts_what_its_stock_pipeline_predicts_and_saves_without_pickle(name, tmp_path):
    raw, w = _data(n=90, channels=5)
    raw = raw * np.logspace(-3, 3, 5)  # channel scales far apart, as real sensors' are
    test = raw[:10] * 1.2  # beyond the training rows too
    model = StockCalibrator(baseline=name).fit(raw, w)
    stock = stock_baselines(5)[name].fit(raw, w)
    assert np.allclose(model.predict(test), stock.predict(test), rtol=1e-7, atol=1e-7 * np.abs(w).max())
    path = ftcal.save_model(model, tmp_path / f"{name}.npz")
    with np.load(path, allow_pickle=False) as archive:
        assert all(archive[k].dtype != object for k in archive.files)
    assert np.array_equal(ftcal.load_model(path).predict(test), model.predict(test))


def test_a_stock_kernel_calibrator_stores_at_most_its_subsample(tmp_path):
    raw, w = _data(n=300, channels=4)
    model = StockCalibrator(baseline="sk_kernel_ridge", max_kernel_samples=50).fit(raw, w)
    assert model.train_inputs_.shape == (50, 4) and model.dual_coef_.shape == (50, 6)


def test_a_stock_calibrator_refuses_an_unknown_baseline_name():
    raw, w = _data(n=30)
    with pytest.raises(ftcal.core.CalibrationInputError, match="sk_linear, sk_poly2"):
        StockCalibrator(baseline="sk_forest").fit(raw, w)


# ------------------------------------------------------------------ one after-fit adoption
def test_a_fitted_temperature_compensated_model_answers_out_of_range():
    rng = np.random.default_rng(0)
    w = rng.normal(size=(200, 6))
    raw = w @ rng.normal(size=(6, 6))
    temperature = rng.uniform(15, 35, size=200)
    drift = ThermalDrift(offset_per_deg=np.full(6, 0.02), gain_per_deg=np.full(6, 2e-3))
    X = np.column_stack([drift.apply(raw, temperature), temperature])
    model = TemperatureCompensatedCalibrator(alpha=1.0).fit(X, w)
    hot = X[:2].copy()
    hot[1, -1] = 80.0  # far beyond the temperatures of calibration
    far = X[:1].copy()
    far[0, 0] = 10 * np.abs(X[:, 0]).max()
    assert model.out_of_range(np.vstack([hot, far])).tolist() == [False, True, True]
    assert model.calibrated_range_.shape == (2, 7)


def test_every_wrapper_adopts_the_same_after_fit_state():
    from ftcal import EnsembleCalibrator
    from ftcal.compose._auto import AutoCalibrator

    raw, w = _data()
    for model in (EnsembleCalibrator(LinearCalibrator(), n_members=2, random_state=0),
                  AutoCalibrator(candidates=[("linear", LinearCalibrator())], baselines=False, cv=3)):
        model.fit(raw, w)
        for name in ("alpha_", "zero_reading_", "reading_noise_", "calibrated_range_"):
            assert name in model.__dict__, (type(model).__name__, name)
        assert np.array_equal(model.calibrated_range_, [raw.min(axis=0), raw.max(axis=0)])


@pytest.mark.parametrize("name, fit_rows", [("sk_poly3", 400), ("sk_kernel_ridge", 300)])
def test_a_stock_calibrator_predicts_many_rows_in_bounded_memory(name, fit_rows):
    import tracemalloc

    from ftcal.calibrators._baselines import PREDICT_BLOCK_BYTES

    raw, w = _data(n=fit_rows, channels=8)
    model = StockCalibrator(baseline=name).fit(raw, w)
    many = np.random.default_rng(1).normal(size=(100_000, 8)) * raw.std(axis=0) + raw.mean(axis=0)
    tracemalloc.start()
    try:
        wrench = model.predict(many)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    # the input's validated copies and the output, plus a few blocks' temporaries; predicting in one piece would
    # need 100 000 x 165 x 8 powers (1 GB) or a 100 000 x 300 kernel matrix (240 MB) and its exponential
    assert peak < 4 * many.nbytes + 3 * wrench.nbytes + 4 * PREDICT_BLOCK_BYTES, peak
    # the blocks beyond the first predict what the rows alone do (which is the stock pipeline's prediction, above)
    assert np.allclose(wrench[-5000:], model.predict(many[-5000:]), rtol=1e-9, atol=1e-9 * np.abs(w).max())
