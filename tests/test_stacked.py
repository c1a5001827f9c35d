"""Several nets trained as one stacked module: the same nets as separate fits, much cheaper.

Both run the one engine (a separate fit is K = 1). Tolerance: the stacked
step does the same arithmetic as a separate fit in another summation order
(``baddbmm`` instead of ``addmm``), so the two runs
start out equal up to float32 rounding (~1e-7 relative; we measured <= 2e-5
over the first epochs). Later a ReLU that switches on one run and not on the
other can lift the difference in one epoch (measured: to 3e-4 in the losses,
1e-3 in the predictions), after which it stays there. A real defect (another
batch order, learning rate, split or initialisation) moves the very first
epoch's loss by several percent (a wrong last batch did: 6 %, and the
predictions by 5-15 %). Hence two tiers: the first epochs within 1e-4, the
whole history within 3e-3 and the predictions within 2e-2.
"""

from __future__ import annotations

import numpy as np
import pytest
from sklearn.base import clone

from ftcal.core import CalibrationInputError
from ftcal import ComparativeCalibrator, DirectionalCalibrator, EnsembleCalibrator, LinearCalibrator
from ftcal.networks import StackedMLP, fit_stacked
from ftcal.benchmark import run_artificial_benchmark

EARLY_EPOCHS, EARLY_LOSS_RTOL = 5, 1e-4
LOSS_RTOL = 3e-3
PREDICTION_RTOL = 2e-2
# short schedule with all three phases: phase 2's plateau patience is short enough that the rate drops
SCHEDULE = dict(phase1_epochs=12, plateau_epochs=8, plateau_patience=0, max_recover_epochs=6, batch_size=16)


def _data(n: int, seed: int):
    rng = np.random.default_rng(seed)
    w = rng.normal(size=(n, 6)) * [50, 50, 50, 2, 2, 2]
    raw = (w + 1e-3 * w * np.abs(w)) @ np.random.default_rng(7).normal(size=(6, 6)) + 0.05 * rng.normal(size=(n, 6))
    return raw, w


def _relative(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.abs(a - b).max() / np.abs(a).max())


def _assert_same_training(separate, stacked, X_test):
    assert stacked.n_epochs_ == separate.n_epochs_
    assert stacked.best_epoch_ == separate.best_epoch_
    assert stacked.stop_reason_ == separate.stop_reason_
    for a, b in zip(separate.net_.history, stacked.net_.history):
        assert (a["phase"], a["lr"]) == (b["phase"], pytest.approx(b["lr"], rel=1e-12))
        for key in ("train_loss", "valid_loss"):
            rtol = EARLY_LOSS_RTOL if a["epoch"] <= EARLY_EPOCHS else LOSS_RTOL
            assert b[key] == pytest.approx(a[key], rel=rtol)
    assert _relative(separate.predict(X_test), stacked.predict(X_test)) < PREDICTION_RTOL


@pytest.mark.parametrize("cls", [DirectionalCalibrator, ComparativeCalibrator])
def test_stacked_members_equal_separate_fits_on_one_dataset(cls):
    X, y = _data(200, 0)
    template = cls(**SCHEDULE)
    seeds = [3, 4, 5]
    separate = [clone(template).set_params(random_state=s).fit(X, y) for s in seeds]
    stacked = fit_stacked([clone(template).set_params(random_state=s) for s in seeds], X, y)
    for a, b in zip(separate, stacked):
        _assert_same_training(a, b, X)
    # the schedule's phases all happened, and phase 2 lowered some member's rate
    phases = {row["phase"] for row in stacked[0].net_.history}
    assert phases == {1, 2, 3}
    assert any(row["lr"] < template.lr for m in stacked for row in m.net_.history)


def test_members_whose_rates_drop_together_then_stop_apart_train_as_separate_fits():
    # phase 2 drops every member's rate at once (the optimiser stays over the stacked tensors), then in phase 3
    # one member stops first: from that batch on each member steps at its own, dropped, rate (a stale initial
    # rate there once made the stacked member's losses drift 20 % from its separate fit's)
    rng = np.random.default_rng(0)
    w = rng.normal(size=(96, 6))
    raw = (w + 0.05 * w**3) @ rng.normal(size=(6, 6))
    template = DirectionalCalibrator(hidden_layer_sizes=(16, 16), phase1_epochs=6, plateau_epochs=2, plateau_patience=0,
                                     min_lr=1e-2, lr=0.1, max_recover_epochs=4, recover_tolerance=0.0, batch_size=16)
    members = [clone(template).set_params(random_state=s) for s in (4000, 4001)]
    separate = [clone(m).fit(raw, w) for m in members]
    stacked = fit_stacked([clone(m) for m in members], raw, w)
    assert separate[0].n_epochs_ != separate[1].n_epochs_  # they stop apart
    assert all(min(row["lr"] for row in m.net_.history) < template.lr for m in separate)  # after a drop
    for a, b in zip(separate, stacked):
        _assert_same_training(a, b, raw)


def test_stacked_fits_datasets_of_different_sizes():
    datasets = [_data(n, seed) for n, seed in ((150, 1), (233, 2), (181, 3))]
    template = DirectionalCalibrator(**SCHEDULE, random_state=0)
    separate = [clone(template).fit(X, y) for X, y in datasets]
    stacked = fit_stacked([clone(template) for _ in datasets], [X for X, _ in datasets], [y for _, y in datasets])
    for a, b, (X, _) in zip(separate, stacked, datasets):
        _assert_same_training(a, b, X)
        np.testing.assert_array_equal(a.zero_reading_, b.zero_reading_)
        assert a.scale_reference_ == b.scale_reference_


def test_stacked_module_is_the_members_forward():
    import torch

    from ftcal.networks._modules import ComparativeNet

    nets = [ComparativeNet(5, (7, 3)) for _ in range(4)]
    stacked = StackedMLP(nets)
    x = torch.randn(4, 9, 5)
    out = stacked(x)
    assert out.shape == (4, 9, 6)
    for k, net in enumerate(nets):
        torch.testing.assert_close(out[k], net(x[k]))
    copy = ComparativeNet(5, (7, 3))
    stacked.load_member(stacked.member_row(2), copy)
    torch.testing.assert_close(copy(x[0]), nets[2](x[0]))


def test_ensemble_trains_its_network_members_together_and_they_differ():
    X, y = _data(200, 0)
    member = DirectionalCalibrator(**SCHEDULE)
    ensemble = EnsembleCalibrator(member, n_members=3, random_state=0).fit(X, y)
    separate = [clone(member).set_params(random_state=int(s)).fit(X, y) for s in ensemble.member_seeds_]
    for a, b in zip(separate, ensemble.estimators_):
        _assert_same_training(a, b, X)
    predictions = [m.predict(X) for m in ensemble.estimators_]
    assert _relative(predictions[0], predictions[1]) > 3 * PREDICTION_RTOL  # members differ (their seeds)
    np.testing.assert_allclose(ensemble.predict(X), np.mean(predictions, axis=0))


def test_ensemble_with_callbacks_fits_members_one_by_one():
    from skorch.callbacks import Callback

    class CountEpochs(Callback):
        def initialize(self):
            self.epochs = 0
            return self

        def on_epoch_end(self, net, **kwargs):
            self.epochs += 1

    X, y = _data(120, 0)
    member = DirectionalCalibrator(**SCHEDULE, callbacks=[("count", CountEpochs())])
    ensemble = EnsembleCalibrator(member, n_members=2, random_state=0).fit(X, y)
    for m in ensemble.estimators_:  # the callback ran in each member's own skorch loop
        assert dict(m.net_.callbacks_)["count"].epochs == m.n_epochs_


@pytest.mark.parametrize(
    ("estimators", "X_kind", "match"),
    [
        ([], "array", r"at least one estimator \(K >= 1\)"),
        ([DirectionalCalibrator(), LinearCalibrator()], "array", "estimator 1 is LinearCalibrator"),
        ([DirectionalCalibrator(), DirectionalCalibrator(lr=1e-2)], "array", "estimator 1 differs"),
        ([DirectionalCalibrator(), ComparativeCalibrator()], "array", "estimator 1 differs"),
        ([DirectionalCalibrator(), DirectionalCalibrator()], "three lists", "2 estimators need 2 datasets; got 3"),
        ([DirectionalCalibrator()], "mixed", "both as arrays"),
    ],
)
def test_bad_stacks_are_clear_errors(estimators, X_kind, match):
    X, y = _data(60, 0)
    if X_kind == "three lists":
        X, y = [X] * 3, [y] * 3
    elif X_kind == "mixed":
        X = [X]
    with pytest.raises(CalibrationInputError, match=match):
        fit_stacked(estimators, X, y)


def test_ensemble_needs_at_least_one_member():
    X, y = _data(60, 0)
    with pytest.raises(CalibrationInputError, match=r"'n_members' parameter of EnsembleCalibrator must be an int in "
                                                     r"the range \[1, inf\)\. Got 0 instead"):
        EnsembleCalibrator(DirectionalCalibrator(), n_members=0).fit(X, y)


def test_benchmark_stacks_datasets_with_the_results_of_separate_fits(tmp_path):
    common = dict(n_datasets=3, presets=["thesis"], models=["directional"], schedule="short", quick=True,
                  plot=False)
    one = run_artificial_benchmark(out_dir=tmp_path / "one", **common)
    stacked = run_artificial_benchmark(out_dir=tmp_path / "stacked", stack=3, **common)
    for a, b in zip(one["results"], stacked["results"]):
        assert (a["dataset"], a["stacked"], b["stacked"]) == (b["dataset"], 1, 3)
        assert b["rmse"] == pytest.approx(a["rmse"], rel=PREDICTION_RTOL)
        assert b["epochs"] == a["epochs"]


@pytest.mark.parametrize("value", ["0", "-3", "two"])
def test_cli_stack_must_be_a_positive_integer(value, capsys, tmp_path):
    from ftcal.cli import main

    assert main(["benchmark", "artificial", "--quick", "--stack", value, "--out", str(tmp_path / "b")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("ftcal: error: ") and "stack" in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "b").exists()


def test_benchmark_refuses_a_bad_stack_before_any_work(tmp_path):
    with pytest.raises(CalibrationInputError, match=r"'stack' parameter of run_artificial_benchmark must be an int in the range \[1, inf\)\. Got 0"):
        run_artificial_benchmark(n_datasets=1, quick=True, stack=0, out_dir=tmp_path / "b", plot=False)
