"""The network calibrators: architecture, eq. 3-10 preprocessing and losses, the science, reproducibility."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
import torch
from torch import nn

from ftcal import ComparativeCalibrator, DirectionalCalibrator, LinearCalibrator
from ftcal.core import wrench_rmse
from ftcal.networks._modules import ComparativeNet, DirectionalNet, WeightedSquaredError

from conftest import TINY_SCHEDULE, affine_sensor_data

FULL_SCALE = np.array([100.0] * 3 + [2.0] * 3)  # [N] x3, [N·m] x3


def homogeneous_loads(n: int, seed: int) -> np.ndarray:
    """Wrenches in random 6-D directions with magnitudes 20-100 % of full scale."""
    rng = np.random.default_rng(seed)
    direction = rng.normal(size=(n, 6))
    direction /= np.linalg.norm(direction, axis=1, keepdims=True)
    return direction * rng.uniform(0.2, 1.0, size=(n, 1)) * FULL_SCALE


def asymmetric_sensor(wrench: np.ndarray) -> np.ndarray:
    """Positively homogeneous, nonlinear: Fz and Ty have half the gain under negative load."""
    gains = np.array([1.0, 1.0, 0.5, 1.0, 0.5, 1.0])
    u = wrench / FULL_SCALE
    u = np.where(u > 0, u, gains * u)
    mixing = np.random.default_rng(42).normal(size=(6, 6)) + 3.0 * np.eye(6)
    return u @ mixing.T


def test_asymmetric_sensor_is_positively_homogeneous_but_not_linear():
    w = homogeneous_loads(5, 0)
    np.testing.assert_allclose(asymmetric_sensor(2.5 * w), 2.5 * asymmetric_sensor(w))
    assert not np.allclose(asymmetric_sensor(-w), -asymmetric_sensor(w))


def test_directional_beats_ltm_on_direction_dependent_gains():
    train, test = homogeneous_loads(1000, 1), homogeneous_loads(400, 2)
    x_train, x_test = asymmetric_sensor(train), asymmetric_sensor(test)
    ltm = LinearCalibrator().fit(x_train, train)
    directional = DirectionalCalibrator(
        hidden_layer_sizes=(64, 64), lr=1e-2, batch_size=128, phase1_epochs=150, plateau_epochs=30,
        plateau_patience=5, max_recover_epochs=10, zero_reading=np.zeros(6), random_state=0,
    ).fit(x_train, train)
    ltm_rmse = wrench_rmse(test, ltm.predict(x_test), 50.0)
    dnn_rmse = wrench_rmse(test, directional.predict(x_test), 50.0)
    assert ltm_rmse > 1.0  # [N]: the asymmetry is far outside what an affine map can absorb
    assert dnn_rmse < 0.6 * ltm_rmse, (dnn_rmse, ltm_rmse)


def test_directional_net_architecture():
    net = DirectionalNet(n_inputs=8, hidden_layer_sizes=(16, 12, 10))
    kinds = [type(m) for m in net.layers]
    assert kinds == [nn.Linear, nn.ReLU, nn.Linear, nn.ReLU, nn.Linear, nn.Tanh, nn.Linear]
    assert net.layers[0].in_features == 8 and net.layers[-1].out_features == 7
    comparative = ComparativeNet(n_inputs=12, hidden_layer_sizes=(5,))
    assert [type(m) for m in comparative.layers] == [nn.Linear, nn.ReLU, nn.Linear]
    assert comparative.layers[-1].out_features == 6


def test_directional_training_targets_follow_eq_3_to_8():
    raw, wrench, _, _ = affine_sensor_data(n_samples=30, seed=1)
    model = DirectionalCalibrator(alpha=10.0, zero_reading=np.zeros(6))
    model.alpha_, model.zero_reading_ = 10.0, np.zeros(6)
    inputs, targets = model._training_pairs(raw, wrench)
    np.testing.assert_allclose(inputs, raw / np.linalg.norm(raw, axis=1, keepdims=True))  # eq. 4
    scaled = wrench * [1, 1, 1, 10, 10, 10]  # eq. 6
    np.testing.assert_allclose(targets[:, :6], scaled / np.linalg.norm(scaled, axis=1, keepdims=True))  # eq. 8
    s = np.linalg.norm(scaled, axis=1) / np.linalg.norm(raw, axis=1)  # v_out / v_in
    np.testing.assert_allclose(targets[:, 6] * model.scale_reference_, s)
    assert np.median(targets[:, 6]) == pytest.approx(1.0)  # the normalised scale target is ~1


def test_comparative_loss_is_eq_10_up_to_a_constant():
    raw, wrench, _, _ = affine_sensor_data(n_samples=40, seed=2)
    model = ComparativeCalibrator(**TINY_SCHEDULE, alpha=20.0, random_state=0).fit(raw, wrench)
    pred = model.predict(raw)
    err = (wrench - pred) ** 2
    eq10 = np.mean(err[:, :3].sum(1) + 20.0 * err[:, 3:].sum(1))
    criterion = WeightedSquaredError(model._loss_weights())
    to_net = lambda w: torch.tensor((w - model.target_mean_) / model.target_scale_, dtype=torch.float64)
    internal = float(criterion.double()(to_net(pred), to_net(wrench)))
    weights = np.array([1, 1, 1, 20, 20, 20.0]) * model.target_scale_**2
    assert internal * weights.mean() == pytest.approx(eq10, rel=1e-6)


def test_zero_load_rows_dropped_with_warning_and_zero_reading_predicts_zero():
    raw, wrench, _, _ = affine_sensor_data(n_samples=60, seed=3)
    tare = np.full(6, 0.25)
    raw = raw + tare
    raw[:4], wrench[:4] = tare, 0.0  # zero-load rows: reading == tare, wrench == 0
    with pytest.warns(UserWarning, match="dropped 4 of 60 training rows"):
        model = DirectionalCalibrator(**TINY_SCHEDULE, random_state=0).fit(raw, wrench)
    assert model.n_dropped_zero_load_ == 4
    np.testing.assert_allclose(model.zero_reading_, tare)
    at_zero = model.predict(np.vstack([tare, tare + 1e-9]))
    assert np.all(np.isfinite(at_zero))
    np.testing.assert_array_equal(at_zero[0], np.zeros(6))
    assert np.abs(at_zero[1]).max() < 1e-3  # near-zero reading -> near-zero wrench [N], [N·m]


@pytest.mark.parametrize("cls", [ComparativeCalibrator, DirectionalCalibrator])
def test_same_seed_same_predictions_and_global_rng_untouched(cls):
    raw, wrench, _, _ = affine_sensor_data(n_samples=50, seed=4)
    torch.manual_seed(123)
    before = torch.rand(1)
    torch.manual_seed(123)
    first = cls(**TINY_SCHEDULE, random_state=7).fit(raw, wrench).predict(raw)
    assert torch.rand(1) == before  # fit forked the global torch RNG
    second = cls(**TINY_SCHEDULE, random_state=7).fit(raw, wrench).predict(raw)
    other = cls(**TINY_SCHEDULE, random_state=8).fit(raw, wrench).predict(raw)
    np.testing.assert_array_equal(first, second)
    assert not np.array_equal(first, other)
    assert first.dtype == np.float64


def test_fit_restores_callers_torch_thread_count():
    raw, wrench, _, _ = affine_sensor_data(n_samples=30, seed=5)
    threads = torch.get_num_threads()
    DirectionalCalibrator(**TINY_SCHEDULE, random_state=0).fit(raw, wrench)
    assert torch.get_num_threads() == threads


def test_networks_fit_every_channel_count():
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # no zero-load rows here: no warning expected
        for n_channels in (3, 12):
            raw, wrench, _, _ = affine_sensor_data(n_samples=40, n_channels=n_channels, seed=n_channels)
            for cls in (ComparativeCalibrator, DirectionalCalibrator):
                assert cls(**TINY_SCHEDULE, random_state=0).fit(raw, wrench).predict(raw[:3]).shape == (3, 6)


@pytest.mark.parametrize("cls", [ComparativeCalibrator, DirectionalCalibrator])
def test_extra_callbacks_run_every_epoch_and_are_not_saved(cls, tmp_path):
    from skorch.callbacks import Callback

    from ftcal import load_model, save_model

    class EpochCounter(Callback):
        def initialize(self):
            self.epochs = 0
            return self

        def on_epoch_end(self, net, **kwargs):
            self.epochs += 1

    counter = EpochCounter()
    raw, wrench, _, _ = affine_sensor_data(n_samples=60, seed=3)
    model = cls(**TINY_SCHEDULE, callbacks=[("counter", counter)], random_state=0).fit(raw, wrench)
    assert counter.epochs == model.n_epochs_ >= TINY_SCHEDULE["phase1_epochs"]
    loaded = load_model(save_model(model, tmp_path / "m.npz"))
    assert loaded.callbacks is None
    np.testing.assert_array_equal(loaded.predict(raw), model.predict(raw))


def test_callbacks_must_be_a_list():
    raw, wrench, _, _ = affine_sensor_data(n_samples=60, seed=3)
    with pytest.raises(ValueError, match=r"'callbacks' parameter of DirectionalCalibrator must be an instance of "
                                         r"'list', an instance of 'tuple' or None\. Got 'progress' instead"):
        DirectionalCalibrator(**TINY_SCHEDULE, callbacks="progress").fit(raw, wrench)


# ------------------------------------------------------------------ lean loop, numpy inference
@pytest.mark.parametrize("cls", [DirectionalCalibrator, ComparativeCalibrator])
def test_numpy_forward_matches_torch(cls):
    rng = np.random.default_rng(0)
    w = rng.normal(size=(300, 6))
    raw = w @ rng.normal(size=(6, 6))
    model = cls(hidden_layer_sizes=(16, 8), phase1_epochs=3, plateau_epochs=1, max_recover_epochs=1,
                random_state=0).fit(raw, w)
    inputs = model._network_inputs(raw)
    with torch.no_grad():
        net = model.net_.module_(torch.as_tensor(inputs, dtype=torch.float32)).numpy()
    # both compute with the float32 weights (numpy in float64): equal to float32 rounding
    np.testing.assert_allclose(model._forward(inputs), net, rtol=1e-5, atol=1e-5 * np.abs(net).max())
    # a row's result does not depend on the batch around it
    np.testing.assert_array_equal(model.predict(raw[:1]), model.predict(np.repeat(raw[:1], 300, axis=0))[:1])


def test_engine_trains_like_skorchs_own_loop():
    """The engine is skorch's loop with pre-sliced batches: the same optimiser on the same data, the same losses."""
    import torch
    from skorch import NeuralNetRegressor

    from ftcal.networks import NetworkRegressor
    from ftcal.networks._engine import MemberSquaredError
    from ftcal.networks._modules import ComparativeNet, WeightedSquaredError

    rng = np.random.default_rng(0)
    X = rng.normal(size=(400, 6)).astype(np.float32)
    y = (X @ rng.normal(size=(6, 6))).astype(np.float32)
    common = dict(module__n_inputs=6, module__hidden_layer_sizes=(32,), optimizer=torch.optim.Adam, lr=3e-3,
                  batch_size=32, max_epochs=30, train_split=None, verbose=0)
    torch.manual_seed(0)
    plain = NeuralNetRegressor(ComparativeNet, criterion=WeightedSquaredError, criterion__weights=(1.0,) * 6,
                               iterator_train__shuffle=True, **common).fit(X, y)
    engine = NetworkRegressor(ComparativeNet, criterion=MemberSquaredError, criterion__weights=[[1.0] * 6],
                              seeds=[0], **common).fit([X], [y])
    plain, lean = np.array(plain.history[:, "train_loss"]), np.array(engine.history[:, "train_loss"])
    assert len(lean) == len(plain) == 30
    np.testing.assert_allclose(engine.history[:, "member_train_loss"], lean[:, None], rtol=1e-6)
    # the same initial weights (seed 0) and the same first batches' losses cannot differ by more than the shuffle
    assert lean[0] == pytest.approx(plain[0], rel=0.2)
    # both cut the loss by orders of magnitude, to the same level (within a factor 2: different shuffles)
    assert lean[-1] < 0.02 * lean[0] and plain[-1] < 0.02 * plain[0]
    assert 0.5 < lean[-1] / plain[-1] < 2.0


@pytest.mark.parametrize("cls", [DirectionalCalibrator, ComparativeCalibrator])
def test_a_users_skorch_callback_sees_every_batch_epoch_and_gradient(cls):
    """skorch's contract: on_batch_begin/end per batch, on_grad_computed per step, on_epoch_* per epoch."""
    from skorch.callbacks import Callback

    class Count(Callback):
        def initialize(self):
            self.calls = {"batch_begin": 0, "batch_end": 0, "train_batches": 0, "grad": 0, "epoch_begin": 0,
                          "epoch_end": 0, "lrs": []}
            return self

        def on_batch_begin(self, net, batch=None, training=False, **kwargs):
            self.calls["batch_begin"] += 1

        def on_batch_end(self, net, batch=None, training=False, **kwargs):
            self.calls["batch_end"] += 1
            self.calls["train_batches"] += bool(training)

        def on_grad_computed(self, net, named_parameters, **kwargs):
            self.calls["grad"] += all(p.grad is not None for _, p in named_parameters)

        def on_epoch_begin(self, net, **kwargs):
            self.calls["epoch_begin"] += 1

        def on_epoch_end(self, net, **kwargs):
            self.calls["epoch_end"] += 1
            self.calls["lrs"].append(net.history[-1, "lr"])

    raw, wrench, _, _ = affine_sensor_data(n_samples=90, seed=3)
    count = Count()
    # a hook set on an instance (not in its class) is a hook too
    patched, patched_calls = Callback(), []
    patched.on_batch_end = lambda net, **kwargs: patched_calls.append(kwargs.get("training"))
    model = cls(phase1_epochs=3, plateau_epochs=2, plateau_patience=0, max_recover_epochs=2, batch_size=8,
                callbacks=[count, ("patched", patched)], random_state=0).fit(raw, wrench)
    assert len(patched_calls) == count.calls["batch_end"]
    n_train = len(raw) - int(np.ceil(0.2 * len(raw)))  # ValidSplit(0.2) holds out ceil(20 %)
    per_epoch = -(-n_train // 8)
    calls, epochs = count.calls, model.n_epochs_
    assert calls["epoch_begin"] == calls["epoch_end"] == epochs >= 5
    assert calls["train_batches"] == calls["grad"] == per_epoch * epochs
    assert calls["batch_begin"] == calls["batch_end"] == (per_epoch + 1) * epochs  # + one validation batch
    assert calls["lrs"] == model.net_.history[:, "lr"]


def test_skorch_overrides_of_the_engine_are_honoured():
    """A calibrator whose engine overrides skorch's get_loss / train_step: both run for every batch."""
    from ftcal.networks import NetworkRegressor

    calls = {"get_loss": 0, "train_step": 0}

    class Penalised(NetworkRegressor):
        def get_loss(self, y_pred, y_true, *args, **kwargs):
            calls["get_loss"] += 1
            return super().get_loss(y_pred, y_true, *args, **kwargs) + 0.0 * y_pred.sum()

        def train_step(self, batch, **fit_params):
            calls["train_step"] += 1
            return super().train_step(batch, **fit_params)

    class Calibrator(DirectionalCalibrator):
        _net_class = Penalised

    raw, wrench, _, _ = affine_sensor_data(n_samples=60, seed=3)
    model = Calibrator(**{**TINY_SCHEDULE, "batch_size": 8}, random_state=0).fit(raw, wrench)
    batches = sum(row["train_batch_count"] for row in model.net_.history)
    assert calls["train_step"] == batches
    assert calls["get_loss"] == batches + model.n_epochs_  # and once per validation batch


def test_a_network_calibrator_missing_a_hook_says_which():
    from ftcal.networks._base import NetworkCalibrator
    from ftcal.networks._modules import ComparativeNet

    class Unfinished(NetworkCalibrator):
        _module_class = ComparativeNet

    raw, wrench, _, _ = affine_sensor_data(n_samples=40, seed=1)
    with pytest.raises(NotImplementedError, match=r"Unfinished must implement _training_pairs\(\)"):
        Unfinished(phase1_epochs=1).fit(raw, wrench)
    assert not hasattr(Unfinished(), "no_such_attribute") and hasattr(Unfinished(), "_decode")


def test_skorch_early_stopping_ends_the_fit_cleanly_with_the_best_weights():
    # skorch's EarlyStopping ends training with a KeyboardInterrupt at an epoch's end: a finished fit, not a Ctrl-C
    from skorch.callbacks import EarlyStopping

    raw, wrench, _, _ = affine_sensor_data(n_samples=150, seed=0)
    model = DirectionalCalibrator(phase1_epochs=40, plateau_epochs=2, plateau_patience=0, max_recover_epochs=2,
                                  callbacks=[EarlyStopping(patience=1)], random_state=0).fit(raw, wrench)
    assert model.stop_reason_ == "callback" and model.n_epochs_ < 40 and model.best_epoch_ <= model.n_epochs_
    assert np.isfinite(model.predict(raw[:3])).all()
