"""Capabilities are tags, never class guesses: a subclass of an ftcal calibrator keeps its parent's tags, and a
user's regressor composed into a calibrator is a candidate of ``auto`` and a member of an ensemble, while the
named stock baselines say that they are stock baselines."""

from __future__ import annotations

import numpy as np
from sklearn.linear_model import Ridge

from ftcal import AutoCalibrator, EnsembleCalibrator, LinearCalibrator
from ftcal.calibrators import StockCalibrator, as_calibrator, calibration_tags


def _data():
    rng = np.random.default_rng(7)
    w = rng.normal(size=(90, 6)) * [20, 20, 20, 1, 1, 1]
    return w @ rng.normal(size=(6, 6)) / 20 + 1e-3 * rng.normal(size=(90, 6)), w


class MyLinear(LinearCalibrator):
    """A user's subclass that changes nothing the prediction computes."""


def test_a_linear_calibrator_subclass_keeps_its_tags():
    from dataclasses import asdict

    tags, parent = calibration_tags(MyLinear()), calibration_tags(LinearCalibrator())
    rows = "min_training_rows"  # a function of the channel count
    assert {k: v for k, v in asdict(tags).items() if k != rows} == {k: v for k, v in asdict(parent).items() if k != rows}
    assert [tags.min_training_rows(n) for n in (3, 6, 9)] == [parent.min_training_rows(n) for n in (3, 6, 9)]
    assert tags.onnx and tags.cost == "closed_form" and tags.family == "linear" and not tags.stock_baseline


def test_only_the_named_baselines_are_tagged_stock():
    assert calibration_tags(StockCalibrator(baseline="sk_poly2")).stock_baseline
    assert not calibration_tags(as_calibrator(Ridge())).stock_baseline


def test_a_users_regressor_is_a_candidate_of_auto_and_a_member_of_an_ensemble():
    raw, w = _data()
    auto = AutoCalibrator(candidates=[("linear", LinearCalibrator()), ("my_ridge", Ridge(alpha=1e-6)),
                                      ("sk_poly2", StockCalibrator(baseline="sk_poly2"))],
                          stack=False, baselines=False, random_state=0).fit(raw, w)
    kinds = {row.name: row.kind for row in auto.comparison_.rows}
    assert kinds == {"linear": "candidate", "my_ridge": "candidate", "sk_poly2": "stock"}, kinds
    ensemble = EnsembleCalibrator(Ridge(alpha=1e-6), n_members=2, random_state=0).fit(raw, w)
    np.testing.assert_allclose(ensemble.predict(raw), Ridge(alpha=1e-6).fit(raw, w).predict(raw),
                               rtol=0, atol=1e-9 * np.abs(w).max())


def test_a_users_regressor_is_fitted_on_the_torque_scaled_wrench_once():
    from sklearn.linear_model import LinearRegression
    from ftcal.calibrators import declare

    raw, w = _data()
    model = as_calibrator(LinearRegression()).fit(raw, w)
    direct = LinearRegression().fit(raw, w)
    alpha = model.alpha_
    assert alpha != 1.0
    scale = np.array([1, 1, 1, alpha, alpha, alpha])
    # the regressor saw the torques times alpha_ (eq. 6): its torque rows are alpha_ times the direct fit's
    np.testing.assert_allclose(model.estimator_.coef_, direct.coef_ * scale[:, None], rtol=1e-9)
    # and the composition scales its predictions back: a per-axis fit predicts what it predicts unscaled
    np.testing.assert_allclose(model.predict(raw), direct.predict(raw), rtol=1e-9, atol=1e-9 * np.abs(w).max())

    class OwnScale(LinearRegression):  # declares that it handles the torque scale itself
        def __sklearn_tags__(self):
            return declare(super().__sklearn_tags__(), scales_torques=True)

    own = as_calibrator(OwnScale()).fit(raw, w)
    np.testing.assert_allclose(own.estimator_.coef_, direct.coef_, rtol=1e-12)
    # ftcal's calibrators and the named stock baselines handle (or deliberately skip) the scale themselves
    assert calibration_tags(LinearCalibrator()).scales_torques
    assert calibration_tags(StockCalibrator(baseline="sk_linear")).scales_torques


def test_a_users_regressor_of_a_family_keeps_its_own_rank_only_a_stock_baseline_takes_its_familys():
    from sklearn.linear_model import LinearRegression

    from ftcal import LinearCalibrator, PolynomialCalibrator
    from ftcal.calibrators import StockCalibrator, as_calibrator, declare
    from ftcal.compose._auto import complexity_of

    class LinearFamily(LinearRegression):
        def __sklearn_tags__(self):
            return declare(super().__sklearn_tags__(), cost="closed_form", family="linear")

    candidates = [("linear", LinearCalibrator()), ("poly2", PolynomialCalibrator(degree=2)),
                  ("mine", as_calibrator(LinearFamily())), ("sk_linear", StockCalibrator(baseline="sk_linear"))]
    ranks = complexity_of(candidates, 100)
    assert ranks[3] == ranks[0]  # the named stock baseline: as simple as ftcal's LTM
    assert ranks[2] > ranks[1]  # a user's regressor: its own place, after the candidates before it
