"""The three-phase schedule (III-A-d): phases, learning-rate drops, the phase-3 stop rules, best weights."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import torch
from skorch.history import History

from ftcal import ComparativeCalibrator, DirectionalCalibrator
from ftcal.compose import training_schedule
from ftcal.networks._schedule import RecoverStop, phase_of_epoch

from conftest import affine_sensor_data


def fit_with(cls=DirectionalCalibrator, **params):
    raw, wrench, _, _ = affine_sensor_data(n_samples=80, seed=11)
    base = dict(hidden_layer_sizes=(16,), batch_size=16, random_state=0)
    return cls(**{**base, **params}).fit(raw, wrench)


def test_phases_run_in_order_and_plateau_lowers_the_rate():
    model = fit_with(lr=0.05, phase1_epochs=5, plateau_epochs=25, plateau_patience=0, min_lr=1e-4,
                     recover_tolerance=0.05, max_recover_epochs=5)
    history = model.net_.history
    phases = history[:, "phase"]
    lrs = np.array(history[:, "lr"])
    assert phases[:5] == [1] * 5 and phases[5:30] == [2] * 25 and set(phases[30:]) <= {3}
    assert np.all(lrs[:6] == 0.05)  # phase 1 (and the first phase-2 epoch) at the initial rate
    assert lrs.min() < 0.05  # ReduceLROnPlateau reduced it in phase 2
    assert np.all(np.diff(lrs) <= 0)  # never raised again
    steps = np.log10(0.05 / lrs)
    np.testing.assert_allclose(steps[steps < 2.6], np.round(steps[steps < 2.6]), atol=1e-6)  # factor 0.1 drops
    assert lrs.min() >= 1e-4 * (1 - 1e-9)  # min_lr floor
    assert model.n_epochs_ == len(history)


def test_phase_three_stops_by_the_tolerance_rule():
    model = fit_with(phase1_epochs=4, plateau_epochs=2, recover_tolerance=100.0, max_recover_epochs=50)
    assert model.stop_reason_ == "within_tolerance"
    assert model.n_epochs_ == 4 + 2 + 1  # the first phase-3 epoch is within 10000 % of the best
    losses = model.net_.history[:, "valid_loss"]
    assert losses[-1] <= 101.0 * min(losses)


def test_phase_three_cap_and_no_phase_three():
    capped = fit_with(phase1_epochs=3, plateau_epochs=0, recover_tolerance=0.0, max_recover_epochs=4)
    assert capped.stop_reason_ in {"within_tolerance", "recover_cap"}
    assert capped.n_epochs_ <= 3 + 4
    none = fit_with(phase1_epochs=3, plateau_epochs=2, max_recover_epochs=0)
    assert none.stop_reason_ == "schedule_end" and none.n_epochs_ == 5


class _Holder:
    """Minimal owner of a real skorch History and one member's stop state, as the callback sees a net."""

    def __init__(self):
        self.history = History()
        self.optimizers_ = [None]
        self.stop_reasons_ = [None]


def run_recover_stop(losses, tolerance, cap, phase_3_start):
    net, callback = _Holder(), RecoverStop(tolerance, cap, phase_3_start, monitor="member_valid_loss")
    callback.on_train_begin(net)
    for loss in losses:
        net.history.new_epoch()
        net.history.record("member_valid_loss", [loss])
        try:
            callback.on_epoch_end(net)
        except KeyboardInterrupt:
            return len(net.history), net.history[-1, "stop_reason"]
    return len(net.history), None


def test_recover_stop_rule_and_cap_on_given_losses():
    # best 1.0 at epoch 2; phase 3 from epoch 4: 1.2 (20 % off), 1.06 (6 %), 1.04 (within 5 %) -> stop at 6
    assert run_recover_stop([2.0, 1.0, 1.5, 1.2, 1.06, 1.04, 0.5], 0.05, 10, 4) == (6, "within_tolerance")
    # never within 5 %: the cap of 3 phase-3 epochs ends it at epoch 3 + 3
    assert run_recover_stop([2.0, 1.0, 1.5, 1.5, 1.5, 1.5, 1.5], 0.05, 3, 4) == (6, "recover_cap")


def test_best_weights_are_restored():
    model = fit_with(lr=0.05, phase1_epochs=12, plateau_epochs=0, max_recover_epochs=0)
    losses = np.array(model.net_.history[:, "valid_loss"])
    assert model.best_epoch_ == int(np.argmin(losses)) + 1
    best = dict(model.net_.callbacks_)["restore_best_weights"]
    assert best.best_epoch_ == [model.best_epoch_]
    for value, kept in zip(model.net_.module_.parameters(), best.best_state_[0]):
        assert torch.equal(value, kept)


def test_phase_of_epoch_boundaries():
    assert [phase_of_epoch(e, 1700, 100) for e in (1, 1700, 1701, 1800, 1801)] == [1, 1, 2, 2, 3]


def test_named_schedules_match_the_thesis():
    thesis = training_schedule("thesis", "directional")
    assert (thesis["phase1_epochs"], thesis["plateau_epochs"], thesis["plateau_patience"]) == (1700, 100, 30)
    assert (thesis["lr"], thesis["batch_size"], thesis["plateau_factor"], thesis["min_lr"]) == (1e-3, 32, 0.1, 1e-5)
    assert thesis["recover_tolerance"] == 0.05
    assert training_schedule("thesis", "comparative")["phase1_epochs"] == 3000  # III-E-a
    short = training_schedule("short", "comparative")
    assert short["phase1_epochs"] + short["plateau_epochs"] + short["max_recover_epochs"] <= 400
    assert DirectionalCalibrator()._schedule_epochs() == (1700, 1700 + 100 + 500)
    assert ComparativeCalibrator()._schedule_epochs()[0] == 3000
    with pytest.raises(ValueError, match="unknown schedule 'long'"):
        training_schedule("long", "directional")


def test_max_epochs_caps_the_whole_training_when_phase1_epochs_is_given():
    model = fit_with(phase1_epochs=5, max_epochs=3, plateau_epochs=4, max_recover_epochs=4)
    assert model.n_epochs_ == 3 and {row["phase"] for row in model.net_.history} == {1}
    into_phase_two = fit_with(phase1_epochs=2, max_epochs=4, plateau_epochs=5, max_recover_epochs=9)
    assert [row["phase"] for row in into_phase_two.net_.history] == [1, 1, 2, 2]


def test_max_epochs_alone_caps_the_whole_training_as_in_skorch():
    # phase 1 would be 1700 epochs: max_epochs=2 stops the training after two, with no warning
    with warnings.catch_warnings():
        warnings.simplefilter("error", FutureWarning)
        model = fit_with(max_epochs=2, plateau_epochs=2, recover_tolerance=0.0, max_recover_epochs=3)
    assert model.n_epochs_ == 2 and [row["phase"] for row in model.net_.history] == [1, 1]


@pytest.mark.parametrize("cls", [DirectionalCalibrator, ComparativeCalibrator])
def test_network_calibrators_have_explicit_keyword_only_signatures(cls):
    import inspect

    assert "__init__" in cls.__dict__ or "__init__" in cls.__mro__[1].__dict__
    parameters = list(inspect.signature(cls.__init__).parameters.values())[1:]
    assert parameters and all(p.kind is p.KEYWORD_ONLY for p in parameters)
    names = [p.name for p in parameters]
    assert {"phase1_epochs", "max_epochs", "plateau_epochs", "max_recover_epochs", "n_threads"} <= set(names)
    assert sorted(cls().get_params()) == sorted(names)
    with pytest.raises(TypeError):
        cls(no_such_parameter=1)
