"""ONNX export: onnxruntime gives what ``predict`` gives, for every calibrator.

Tolerance: 1e-5 relative to each wrench component's range. The float64 parts
of the graph agree with numpy to ~1e-15; the networks run in float32 in both
(numpy or torch in ftcal, onnxruntime's Gemm in the export), whose different
summation orders differ by a few float32 ulps (~1e-7 relative).
"""

from __future__ import annotations

import sys
import warnings

import numpy as np
import onnxruntime as ort  # the [onnx] extra, part of [test]
import pytest

from ftcal import (ComparativeCalibrator, DirectionalCalibrator, EnsembleCalibrator, LinearCalibrator,
                   TemperatureCompensatedCalibrator, export_onnx, load_model, save_model)
from ftcal.core import ExportError
from ftcal.calibrators import STOCK_BASELINE_NAMES, StockCalibrator
from ftcal.cli import main

from conftest import CALIBRATOR_KINDS, TINY_SCHEDULE, tiny_calibrators
from ftcal.calibrators._base import calibration_tags


RTOL = 1e-5


def _sensor(n: int = 300, seed: int = 0):
    rng = np.random.default_rng(seed)
    w = rng.normal(size=(n, 6)) * [100, 100, 100, 2, 2, 2]
    mixing = np.random.default_rng(11).normal(size=(6, 6)) * 0.01
    raw = (w + 1e-4 * w * np.abs(w)) @ mixing + 0.3 + 1e-3 * rng.normal(size=(n, 6))
    return raw, w


def _onnx_predict(path, X: np.ndarray) -> np.ndarray:
    session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    return session.run(["wrench"], {"readings": np.ascontiguousarray(X, dtype=np.float64)})[0]


def _assert_parity(model, path, X, scale=None):
    """ONNX == predict within RTOL of each component's range (over ``X``, or ``scale`` for a few rows)."""
    expected = model.predict(X)
    got = _onnx_predict(path, X)
    assert got.shape == expected.shape and got.dtype == np.float64
    scale = np.abs(expected).max(axis=0) if scale is None else scale
    assert np.all(np.abs(got - expected) <= RTOL * scale), np.abs(got - expected).max(axis=0) / scale


@pytest.fixture(scope="module")
def fitted_models():
    raw, w = _sensor()
    models = {}
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        for kind, model in zip(CALIBRATOR_KINDS, tiny_calibrators()):
            if kind in ONNX_KINDS:
                models[kind] = model.fit(raw, w)
        models["comparative_ensemble"] = EnsembleCalibrator(
            ComparativeCalibrator(**TINY_SCHEDULE), n_members=2, random_state=0).fit(raw, w)
    return models


#: Every calibrator whose tags declare an ONNX graph.
ONNX_KINDS = [kind for kind, model in zip(CALIBRATOR_KINDS, tiny_calibrators()) if calibration_tags(model).onnx]


@pytest.mark.parametrize("kind", [*ONNX_KINDS, "comparative_ensemble"])
def test_onnx_output_equals_predict(fitted_models, kind, tmp_path):
    model = fitted_models[kind]
    path = export_onnx(model, tmp_path / f"{kind}.onnx")
    raw, _ = _sensor(400, seed=1)  # new readings: 1 row (numpy forward), 400 rows (torch forward)
    _assert_parity(model, path, raw)
    _assert_parity(model, path, raw[:1], scale=np.abs(model.predict(raw)).max(axis=0))


@pytest.mark.parametrize("baseline", STOCK_BASELINE_NAMES)
def test_onnx_of_every_stock_model_equals_predict(baseline, tmp_path):
    raw, w = _sensor()
    model = StockCalibrator(baseline=baseline, max_kernel_samples=200).fit(raw, w)
    path = export_onnx(model, tmp_path / f"{baseline}.onnx")
    new, _ = _sensor(300, seed=1)
    _assert_parity(model, path, new)


def test_onnx_of_a_retared_model_includes_the_new_tare(fitted_models, tmp_path):
    model = fitted_models["directional"]
    raw, _ = _sensor(400, seed=2)
    drifted = model.zero_reading_ + 0.02 + 1e-4 * np.random.default_rng(0).normal(size=(20, 6))
    try:
        model.retare(drifted)
        path = export_onnx(model, tmp_path / "retared.onnx")
        _assert_parity(model, path, raw + 0.02)
    finally:
        del model.tare_reading_


def test_onnx_predict_and_retare_agree_on_a_retared_model_file(tmp_path, capsys):
    """The one re-tare shift: what 'ftcal retare' reports, what 'ftcal predict' and predict subtract, and what
    the ONNX graph subtracts."""
    from ftcal.calibrators import retare_shift

    raw, w = _sensor(200, seed=4)
    model = LinearCalibrator(zero_reading=np.full(6, 0.3)).fit(raw, w)
    save_model(model, tmp_path / "lin.model.npz")
    moved = np.array([0.01, -0.02, 0.005, 0.0, 0.015, -0.01])
    zero = 0.3 + moved + 1e-4 * np.random.default_rng(5).normal(size=(30, 6))
    np.savetxt(tmp_path / "zero.csv", zero, delimiter=",")
    assert main(["retare", str(tmp_path / "lin.model.npz"), str(tmp_path / "zero.csv"),
                 "--output", str(tmp_path / "re.model.npz")]) == 0
    reported = capsys.readouterr().err.split("moved by [")[1].split("]")[0]
    retared = load_model(tmp_path / "re.model.npz")
    shift = retare_shift(retared)
    np.testing.assert_allclose(shift, zero.mean(axis=0) - 0.3, rtol=0, atol=1e-12)
    assert reported == ", ".join(f"{v:.4g}" for v in shift)
    new = raw[:20] + shift  # the same loads, read after the zero moved
    np.savetxt(tmp_path / "new.csv", new, delimiter=",")
    assert main(["predict", str(tmp_path / "re.model.npz"), str(tmp_path / "new.csv"),
                 "--output", str(tmp_path / "w.csv")]) == 0
    written = np.loadtxt(tmp_path / "w.csv", delimiter=",", skiprows=1)
    onnx = _onnx_predict(export_onnx(retared, tmp_path / "re.onnx"), new)
    before = model.predict(raw[:20])  # the model before the re-tare, on the readings before the zero moved
    scale = np.abs(w).max(axis=0)
    np.testing.assert_allclose(retared.predict(new), before, rtol=0, atol=1e-9 * scale.max())
    assert np.all(np.abs(onnx - before) <= RTOL * scale)
    assert np.all(np.abs(written - before) <= RTOL * scale)  # the CLI writes a few significant digits


def test_onnx_of_a_temperature_compensated_model_takes_the_temperature_last(tmp_path):
    raw, w = _sensor()
    temperature = np.random.default_rng(3).uniform(15, 35, size=(len(raw), 1))
    drifted = raw + (temperature - 25) * 1e-3
    X = np.hstack([drifted, temperature])
    model = TemperatureCompensatedCalibrator(LinearCalibrator(), reference_temperature=25.0).fit(X, w)
    path = export_onnx(model, tmp_path / "thermal.onnx")
    _assert_parity(model, path, X)


def test_directional_onnx_maps_the_zero_load_reading_to_zero(fitted_models, tmp_path):
    model = fitted_models["directional"]
    path = export_onnx(model, tmp_path / "d.onnx")
    out = _onnx_predict(path, model.zero_reading_[None, :])
    np.testing.assert_array_equal(out, np.zeros((1, 6)))  # no NaN from the 0/0 unit vector


def test_export_refuses_unknown_types_unfitted_models_and_existing_files(fitted_models, tmp_path):
    class MyCalibrator(LinearCalibrator):  # a subclass that computes something else says so by its tags
        def __sklearn_tags__(self):
            from ftcal.calibrators import declare

            return declare(super().__sklearn_tags__(), onnx=False)

    raw, w = _sensor()
    with pytest.raises(ExportError, match="MyCalibrator cannot be exported to ONNX: ftcal knows how"):
        export_onnx(MyCalibrator().fit(raw, w), tmp_path / "x.onnx")
    with pytest.raises(ValueError, match="not fitted"):
        export_onnx(DirectionalCalibrator(), tmp_path / "y.onnx")
    target = tmp_path / "kept.onnx"
    target.write_text("mine")
    with pytest.raises(ExportError, match="overwrite=True") as refused:
        export_onnx(fitted_models["linear"], target)
    assert isinstance(refused.value, FileExistsError)  # callers catching either keep working
    assert target.read_text() == "mine"
    assert not (tmp_path / "x.onnx").exists() and not (tmp_path / "y.onnx").exists()


def test_export_without_the_onnx_package_says_how_to_install_it(fitted_models, tmp_path, monkeypatch):
    monkeypatch.setitem(sys.modules, "onnx", None)  # what a Python without the package raises on import
    with pytest.raises(ExportError, match=r'pip install "ftcal\[onnx\]"'):
        export_onnx(fitted_models["linear"], tmp_path / "z.onnx")


def test_cli_export_writes_the_onnx_beside_the_model(fitted_models, tmp_path, capsys):
    model_path = save_model(fitted_models["ensemble"], tmp_path / "ens.model.npz")
    assert main(["export", str(model_path), "--format", "onnx"]) == 0
    onnx_path = tmp_path / "ens.onnx"
    raw, _ = _sensor(50, seed=4)
    _assert_parity(load_model(model_path), onnx_path, raw)
    # a second export does not replace the first without --force; the model file is never a target
    assert main(["export", str(model_path)]) == 2
    assert "exists" in capsys.readouterr().err
    assert main(["export", str(model_path), "--output", str(model_path), "--force"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ftcal: error: ") and "model file itself" in err
    assert main(["export", str(model_path), "--force"]) == 0


def test_cli_export_wants_an_onnx_file_name(fitted_models, tmp_path, capsys):
    model_path = save_model(fitted_models["linear"], tmp_path / "lin.model.npz")
    assert main(["export", str(model_path), "--output", str(tmp_path / "lin.txt")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ftcal: error: ") and "should end in .onnx" in err
    assert not (tmp_path / "lin.txt").exists()


class ClippedLinearCalibrator(LinearCalibrator):
    """A new calibrator as a user would add one: its state and its graph declared next to it, nothing else."""

    _fitted_state = ("limit_",)

    def _fit(self, X, y):
        super()._fit(X, y)
        self.limit_ = np.abs(y).max(axis=0)

    def _predict_wrench(self, X):
        return np.clip(super()._predict_wrench(X), -self.limit_, self.limit_)

    def _emit_onnx(self, g, x):
        out = g.affine(x, self.calibration_matrix_.T, self.offset_)
        return g.op("Min", g.op("Max", out, g.const(-self.limit_)), g.const(self.limit_))


def test_a_new_calibrator_exports_its_own_graph_and_needs_one_registry_line_to_be_saved(tmp_path):
    from ftcal.compose import _registry
    from ftcal.core import ModelFileError

    raw, w = _sensor()
    model = ClippedLinearCalibrator().fit(raw[:200], w[:200])
    far = raw * 3.0  # beyond the training loads: the clipping is in the graph
    _assert_parity(model, export_onnx(model, tmp_path / "before.onnx"), far)  # its tags say onnx: its own graph
    with pytest.raises((ModelFileError, ValueError), match="ClippedLinearCalibrator"):
        save_model(model, tmp_path / "before.model.npz")
    _registry.register_calibrator("clipped_linear", ClippedLinearCalibrator)
    try:
        _assert_parity(model, export_onnx(model, tmp_path / "clipped.onnx"), far)
        loaded = load_model(save_model(model, tmp_path / "clipped.model.npz"))
        np.testing.assert_array_equal(loaded.limit_, model.limit_)
        np.testing.assert_array_equal(loaded.predict(far), model.predict(far))
        assert np.any(np.abs(model.predict(far)) == model.limit_)  # the clipping is exercised
    finally:
        _registry._FACTORIES.pop("clipped_linear")
        _registry._SCHEDULES.pop("clipped_linear")
