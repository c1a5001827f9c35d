"""The torque scale (eq. 5-6, 18) applies whenever a wrench holds forces and torques, whatever its axis subset: a
plate's Fz, Tx, Ty named by the target's columns (as X's columns name the features) is scaled like Fx..Tz."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

import ftcal
from ftcal import AxisNonlinearCalibrator, ComparativeCalibrator, LinearCalibrator, load_model, save_model
from ftcal.core import ModelFileError
from ftcal.cli import main
from ftcal.core._wrench import named_targets, scale_torques, target_axes

PLATE = ("Fz", "Tx", "Ty")


def _plate(n=160, seed=0):
    """A 4-channel plate: |Fz| <= 100 N, |Tx|, |Ty| <= 2 N·m (Fmax / Tmax = 50 1/m), mildly nonlinear."""
    rng = np.random.default_rng(seed)
    w = rng.uniform(-1, 1, (n, 3)) * [100.0, 2.0, 2.0]
    gain = rng.normal(size=(3, 4)) * [[1.0], [50.0], [50.0]]
    raw = w @ gain + 0.002 * (w @ gain) ** 2 / 100 + 1e-3 * rng.normal(size=(n, 4))
    return raw, w


def test_the_axes_a_target_names_and_their_torque_columns():
    w = np.array([[100.0, 2.0, -1.0]])
    assert target_axes(pd.DataFrame(w, columns=list(PLATE))) == PLATE
    assert target_axes(pd.DataFrame(w, columns=["Fx", "Fy", "Fz"])) is None  # the default of three columns
    assert target_axes(pd.DataFrame(w, columns=["a", "b", "c"])) is None and target_axes(w) is None
    np.testing.assert_array_equal(scale_torques(w, 50.0, PLATE), [[100.0, 100.0, -50.0]])
    np.testing.assert_array_equal(scale_torques(w, 50.0), w)  # unnamed: three columns are forces


def test_a_plate_named_by_its_columns_is_torque_scaled_and_keeps_its_axes_in_the_model_file(tmp_path):
    raw, w = _plate()
    model = LinearCalibrator().fit(raw, named_targets(w, PLATE))
    assert model.alpha_ == pytest.approx(np.abs(w[:, 0]).max() / np.abs(w[:, 1:]).max())  # ~50, not 1
    assert tuple(model.axes_) == PLATE
    assert LinearCalibrator().fit(raw, w).alpha_ == 1.0  # unnamed three columns: forces only, as before
    loaded = load_model(save_model(model, tmp_path / "plate.npz"))
    assert tuple(loaded.axes_) == PLATE and loaded.alpha_ == model.alpha_
    # a network's loss weighs the plate's torques by alpha_ (eq. 10), as a 6-axis wrench's
    net = ComparativeCalibrator(hidden_layer_sizes=(4,), phase1_epochs=1, plateau_epochs=1, max_recover_epochs=1,
                                random_state=0).fit(raw, named_targets(w, PLATE))
    weights = np.asarray(net._loss_weights()) / net.target_scale_ ** 2
    assert weights[1] / weights[0] == pytest.approx(net.alpha_) and weights[2] == pytest.approx(weights[1])


def test_a_tampered_axes_field_is_refused(tmp_path):
    raw, w = _plate(n=40)
    path = save_model(LinearCalibrator().fit(raw, named_targets(w, PLATE)), tmp_path / "plate.npz")
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    meta = json.loads(str(arrays["__metadata__"]))
    meta["fitted"]["axes_"] = {"strings": ["Fz", "Tx", "Qq"]}
    arrays["__metadata__"] = np.array(json.dumps(meta))
    np.savez(tmp_path / "bad.npz", **arrays)
    with pytest.raises(ModelFileError, match="axes_"):
        load_model(tmp_path / "bad.npz")


def test_scaled_predictions_round_trip_and_the_onnx_graph_unscales_the_plates_torques(tmp_path):
    pytest.importorskip("onnxruntime")
    import onnxruntime as ort

    raw, w = _plate()
    model = AxisNonlinearCalibrator().fit(raw, named_targets(w, PLATE))
    assert tuple(model.axes_) == PLATE and model.alpha_ > 10
    path = ftcal.export_onnx(model, tmp_path / "plate.onnx")
    session = ort.InferenceSession(str(path), providers=["CPUExecutionProvider"])
    got = session.run(None, {session.get_inputs()[0].name: raw[:20]})[0]
    np.testing.assert_allclose(got, model.predict(raw[:20]), rtol=1e-6, atol=1e-6 * np.abs(w).max())
    assert ftcal.core.wrench_rmse(w, model.predict(raw), alpha=model.alpha_, axes=PLATE) < 0.05 * model.alpha_


def test_fit_of_a_plate_on_the_command_line_scales_its_torques(tmp_path, capsys):
    raw, w = _plate()
    data = tmp_path / "plate.csv"
    pd.DataFrame(np.c_[raw, w], columns=["s0", "s1", "s2", "s3", *PLATE]).to_csv(data, index=False)
    assert main(["fit", str(data), "--model", "linear", "--out", str(tmp_path / "m")]) == 0
    err = capsys.readouterr().err
    fitted = json.loads((tmp_path / "m" / "linear.fit.json").read_text())
    assert fitted["alpha"] == pytest.approx(np.abs(w[:, 0]).max() / np.abs(w[:, 1:]).max())
    assert f"(torque-scaled, alpha={fitted['alpha']:.4g})" in err
    auto = ftcal.AutoCalibrator(candidates=[("linear", LinearCalibrator())], baselines=False, stack=False,
                                cv=3).fit(raw, named_targets(w, PLATE))
    assert auto.alpha_ == pytest.approx(fitted["alpha"]) and tuple(auto.axes_) == PLATE
    assert tuple(auto.best_estimator_.axes_) == PLATE  # the chosen model refitted on the named table


def test_the_scorer_and_a_search_scale_the_plates_torques():
    from sklearn.model_selection import GridSearchCV

    from ftcal.core._metrics import neg_scaled_rmse

    raw, w = _plate()
    model = LinearCalibrator().fit(raw[:120], named_targets(w[:120], PLATE))
    pred = model.predict(raw[120:])
    assert -neg_scaled_rmse(model, raw[120:], w[120:]) == pytest.approx(
        ftcal.core.wrench_rmse(w[120:], pred, alpha=model.alpha_, axes=PLATE))
    assert -neg_scaled_rmse(model, raw[120:], w[120:]) > ftcal.core.wrench_rmse(w[120:], pred)  # the torques weigh more
    # a search hands each fold a slice of the named table: every fitted calibrator knows its torques
    search = GridSearchCV(AxisNonlinearCalibrator(), {"ridge": [1e-3, 1e-1]}, scoring=neg_scaled_rmse, cv=3)
    search.fit(raw, named_targets(w, PLATE))
    assert tuple(search.best_estimator_.axes_) == PLATE and search.best_estimator_.alpha_ > 10
