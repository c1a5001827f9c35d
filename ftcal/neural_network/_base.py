"""Training and inference shared by the two network calibrators (skorch, composed).

A :class:`NetworkCalibrator` builds a ``skorch.NeuralNetRegressor`` inside
``fit`` and keeps it as ``net_``. Subclasses say which torch module, which
loss weights, and how readings/wrenches map to network inputs/targets.

* float32 inside the network, float64 out of ``predict``;
* ``random_state`` seeds the weight initialisation, the batch shuffling and
  the validation split; the global torch RNG is forked, so a fit leaves the
  caller's torch random state untouched; the same seed twice gives the same
  predictions;
* torch runs single-threaded during ``fit`` and ``predict`` (the nets are
  small: batch 32 in training, ~64-wide layers; on a shared 2-core machine
  two threads made a 10 000-sample predict 6x slower); the caller's thread
  count is restored afterwards, and nothing is changed at import;
* the schedule (III-A-d) is :mod:`ftcal.neural_network._schedule`; ``validation_fraction``
  of the samples (``ValidSplit``) are held out for the monitored loss, or
  none with ``validation_fraction=None`` (then the training loss is
  monitored).
"""

from __future__ import annotations

import numbers
from numbers import Integral, Real
from collections.abc import Iterator
from contextlib import contextmanager

import numpy as np
import torch
from numpy.typing import NDArray
from skorch import NeuralNetRegressor
from skorch.dataset import ValidSplit
from sklearn.utils import check_random_state
from sklearn.utils.validation import check_is_fitted
from sklearn.utils._param_validation import Interval
from torch.optim.adam import adam as _functional_adam

from ..calibrators._base import BaseCalibrator
from ..core._exceptions import CalibrationInputError
from ..core._validation import validate_readings
from ._modules import WeightedSquaredError, activate, activation_backward, mlp_layers
from ._schedule import schedule_callbacks

__all__ = ["NetworkCalibrator", "LeanNeuralNetRegressor", "torch_threads", "device_available"]

_PREDICT_CHUNK = 65536
#: Batches up to this many rows are predicted by the numpy forward pass (:meth:`NetworkCalibrator._forward_numpy`).
_NUMPY_FORWARD_ROWS = 256
#: A net whose best loss exceeds this multiple of the loss of predicting zero has diverged.
_DIVERGENCE_FACTOR = 100.0
#: Largest magnitude of a network input or target that float32 training handles with room to spare.
_FLOAT32_SAFE = 1e30


def device_available(device: str) -> bool:
    """Whether torch can place tensors on ``device`` here (``"cuda"`` on a CPU-only build: False)."""
    try:
        torch.empty(0, device=device)
    except (RuntimeError, AssertionError, ValueError, TypeError):
        return False
    return True


@contextmanager
def torch_threads(n_threads: int) -> Iterator[None]:
    """Run the block with ``torch.set_num_threads(n_threads)``, restoring the old count."""
    old = torch.get_num_threads()
    torch.set_num_threads(n_threads)
    try:
        yield
    finally:
        torch.set_num_threads(old)


def _tensors(dataset, device) -> tuple[torch.Tensor, torch.Tensor]:
    """``(X, y)`` tensors on ``device`` of a skorch ``Dataset`` or of a ``Subset`` of one (``ValidSplit``), loaded once."""
    indices = None
    if isinstance(dataset, torch.utils.data.Subset):
        dataset, indices = dataset.dataset, np.asarray(dataset.indices)
    cache = dataset.__dict__.setdefault("_ftcal_tensors", {})
    key = None if indices is None else indices.tobytes()
    if key not in cache:
        X = np.asarray(dataset.X if indices is None else dataset.X[indices])
        y = np.asarray(dataset.y if indices is None else dataset.y[indices])
        cache[key] = (torch.as_tensor(X, device=device), torch.as_tensor(y, device=device))
    return cache[key]


def _manual_layers(module, criterion) -> list[tuple[torch.nn.Linear, str]] | None:
    """The layers of ``module`` when it is an MLP trained on the weighted squared error, else None.

    Then :func:`_mlp_backward` computes the gradients by hand; anything else (a user's own module or loss)
    goes through autograd.
    """
    return mlp_layers(module) if isinstance(criterion, WeightedSquaredError) else None


def _mlp_backward(layers: list[tuple[torch.nn.Linear, str]], weights: torch.Tensor, X: torch.Tensor,
                  y: torch.Tensor) -> torch.Tensor:
    """Forward pass, loss ``mean_i sum_j w_j (f(x_i)_j - y_ij)²`` and its gradients, set on the layers' ``.grad``.

    The same arithmetic as autograd's (a ``Linear`` is ``addmm``; ReLU's derivative is ``h > 0``, tanh's
    ``1 - h²``) in half the calls: autograd's bookkeeping costs as much as the arithmetic of these small
    nets. Returns the loss.
    """
    with torch.no_grad():
        hs, h = [X], X
        for layer, activation in layers:
            h = activate(torch.addmm(layer.bias, h, layer.weight.t()), activation)
            hs.append(h)
        error = h - y
        loss = (error * error * weights).sum(dim=1).mean()
        grad = error * (weights * (2.0 / len(X)))
        for i in range(len(layers) - 1, -1, -1):
            layer, activation = layers[i]
            grad = activation_backward(grad, hs[i + 1], activation)
            layer.weight.grad = grad.t().mm(hs[i])
            layer.bias.grad = grad.sum(dim=0)
            if i:
                grad = grad.mm(layer.weight)
    return loss


class _FusedAdamStep:
    """``optimizer.step()`` of a plain fused ``torch.optim.Adam`` as one call of torch's functional ``adam``.

    The same kernel, state and learning rate (read from the param group at every step, so schedulers keep
    working) without ``Optimizer.step``'s per-call bookkeeping, which costs as much as the update of these
    small nets. Any other optimiser, or options this does not handle, keeps its own ``step``.
    """

    def __init__(self, optimizer: torch.optim.Adam) -> None:
        self.optimizer = optimizer
        self.group = optimizer.param_groups[0]
        self.params = list(self.group["params"])
        for p in self.params:
            state = optimizer.state[p]
            if not state:  # what Adam's _init_group creates
                state["step"] = torch.zeros((), dtype=torch.float32)
                state["exp_avg"] = torch.zeros_like(p, memory_format=torch.preserve_format)
                state["exp_avg_sq"] = torch.zeros_like(p, memory_format=torch.preserve_format)
        states = [optimizer.state[p] for p in self.params]
        self.exp_avgs = [s["exp_avg"] for s in states]
        self.exp_avg_sqs = [s["exp_avg_sq"] for s in states]
        self.steps = [s["step"] for s in states]

    @classmethod
    def of(cls, optimizer):
        g = optimizer.param_groups[0] if len(optimizer.param_groups) == 1 else None
        plain = (type(optimizer) is torch.optim.Adam and g is not None and g.get("fused") and not g["amsgrad"]
                 and not g["maximize"] and g["weight_decay"] == 0 and not g["capturable"] and not g["differentiable"]
                 and not g.get("decoupled_weight_decay", False) and all(p.device.type == "cpu" for p in g["params"]))
        return cls(optimizer).__call__ if plain else optimizer.step

    def __call__(self) -> None:
        g = self.group
        with torch.no_grad():
            _functional_adam(self.params, [p.grad for p in self.params], self.exp_avgs, self.exp_avg_sqs, [],
                             self.steps, fused=True, amsgrad=False, beta1=g["betas"][0], beta2=g["betas"][1],
                             lr=g["lr"], weight_decay=0.0, eps=g["eps"], maximize=False)


class LeanNeuralNetRegressor(NeuralNetRegressor):
    """skorch's ``NeuralNetRegressor`` with a lean inner loop: tensors loaded once, batches sliced from them.

    skorch's loop builds every mini-batch with a ``DataLoader`` (one ``__getitem__``
    and a collate per sample) and calls the batch-level callbacks and history
    twice per batch; for ftcal's small nets and batches of 32 that costs several
    times the arithmetic. This subclass keeps everything epoch-level as it is
    (``fit_loop``, the history, every callback, the three-phase schedule, early
    stopping, ``net.history[-1, 'train_loss']``) and replaces only the inner
    loop of an epoch: the training tensors are loaded once, each epoch shuffles
    them with ``torch.randperm`` (seeded by the caller's torch RNG) and runs
    ``zero_grad / forward / loss / backward / step`` per batch; validation is
    one forward pass. The epoch's losses are recorded as one batch of the
    epoch's size (the batch-size-weighted mean, as skorch computes it).
    ``on_batch_begin`` / ``on_batch_end`` callbacks are not called. For
    ftcal's own nets (an MLP of ``Linear`` / ``ReLU`` / ``Tanh`` layers on the
    weighted squared error) the gradients are computed by hand
    (:func:`_mlp_backward`), the same arithmetic as autograd's in half the
    torch calls; any other module or loss goes through autograd.
    """

    def notify(self, method_name, **cb_kwargs):
        # skorch's convention: a callback ends training by raising KeyboardInterrupt at the end of an epoch
        # (EarlyStopping, the three-phase schedule); note that it was a callback, not the user's Ctrl-C.
        try:
            super().notify(method_name, **cb_kwargs)
        except KeyboardInterrupt:
            if method_name == "on_epoch_end":
                self.__dict__["_stopped_by_callback"] = True
            raise

    def fit_loop(self, X, y=None, **fit_params):
        """skorch's loop, except that a Ctrl-C is not swallowed: skorch's ``partial_fit`` ends a fit quietly on
        any ``KeyboardInterrupt`` (the callbacks' way to stop), which would return a half-trained net as if it
        had finished. A ``KeyboardInterrupt`` that no callback raised is recorded in ``interrupted_epoch_`` and
        re-raised by :meth:`NetworkCalibrator._fit` after skorch's loop returns. No signal handler is installed."""
        self.__dict__["_stopped_by_callback"] = False
        self.__dict__.pop("interrupted_epoch_", None)
        try:
            return super().fit_loop(X, y, **fit_params)
        except KeyboardInterrupt:
            if not self.__dict__.get("_stopped_by_callback", False):
                self.__dict__["interrupted_epoch_"] = len(self.history)
            raise
        finally:
            self.__dict__.pop("_stopped_by_callback", None)

    def run_single_epoch(self, iterator, training, prefix, step_fn, **fit_params):
        if iterator is None:
            return
        X, y = _tensors(iterator.dataset, self.device)
        n = len(X)
        module, criterion = self.module_, self.criterion_
        if training:
            module.train()
            order = torch.randperm(n) if getattr(self, "iterator_train__shuffle", False) else torch.arange(n)
            order = order.to(X.device)
            total = torch.zeros((), device=X.device)
            batch = int(self.batch_size)
            manual = _manual_layers(module, criterion)
            step = _FusedAdamStep.of(self.optimizer_) if manual is not None else self.optimizer_.step
            X_epoch, y_epoch = X[order], y[order]  # shuffled once; the batches are views
            for start in range(0, n, batch):
                X_batch, y_batch = X_epoch[start:start + batch], y_epoch[start:start + batch]
                if manual is None:
                    self.optimizer_.zero_grad(set_to_none=True)
                    loss = criterion(module(X_batch), y_batch)
                    loss.backward()
                else:  # sets every .grad afresh: no zero_grad needed
                    loss = _mlp_backward(manual, criterion.weights, X_batch, y_batch)
                step()
                total += loss.detach() * len(X_batch)
            mean = float(total) / max(n, 1)
            batches = -(-n // batch)
        else:
            module.eval()
            with torch.no_grad():
                mean = float(criterion(module(X), y)) if n else 0.0
            batches = 1
        self.history.new_batch()
        self.history.record_batch(prefix + "_loss", mean)
        self.history.record_batch(prefix + "_batch_size", n)
        self.history.record(prefix + "_batch_count", batches)


class NetworkCalibrator(BaseCalibrator):
    """Base of the skorch-trained calibrators. Subclasses set ``_module_class`` and implement
    ``_training_pairs(X, y) -> (inputs, targets)``, ``_network_inputs(X)``,
    ``_decode(outputs, X) -> wrench`` (or override ``_predict_wrench``), ``_network_outputs()`` and
    ``_loss_weights()``.
    """

    _module_class: type[torch.nn.Module]
    #: Parameters that only affect one training run and are not stored in model files.
    _transient_params: tuple[str, ...] = ("callbacks",)

    _parameter_constraints: dict = {
        **BaseCalibrator._parameter_constraints,
        "hidden_layer_sizes": [tuple, list],
        "lr": [Interval(Real, 0, None, closed="neither")],
        "batch_size": [Interval(Integral, 1, None, closed="left")],
        "max_epochs": [Interval(Integral, 1, None, closed="left")],
        "plateau_epochs": [Interval(Integral, 0, None, closed="left")],
        "plateau_patience": [Interval(Integral, 0, None, closed="left")],
        "plateau_factor": [Interval(Real, 0, 1, closed="right")],
        "min_lr": [Interval(Real, 0, None, closed="left")],
        "recover_tolerance": [Interval(Real, 0, None, closed="left")],
        "max_recover_epochs": [Interval(Integral, 0, None, closed="left")],
        "validation_fraction": [Interval(Real, 0, 0.5, closed="right"), None],
        "verbose": ["verbose"],
        "callbacks": [list, tuple, None],
        "device": [str],
    }

    def _check_params(self) -> None:
        """What the table cannot say: the layer widths are positive integers, and there is at least one."""
        sizes = self.hidden_layer_sizes
        if len(sizes) == 0:
            raise CalibrationInputError(
                f"hidden_layer_sizes must be a non-empty tuple of layer widths, e.g. (64, 64); got {sizes!r}."
            )
        for width in sizes:
            if isinstance(width, bool) or not isinstance(width, numbers.Integral) or width < 1:
                raise CalibrationInputError(f"each entry of hidden_layer_sizes must be an integer >= 1; got {width!r}.")

    def _network_outputs(self) -> int:
        """Width of the network's output layer for this estimator's ``n_outputs_`` targets (6: the wrench)."""
        raise NotImplementedError

    def _seed(self) -> int:
        return int(check_random_state(self.random_state).randint(np.iinfo(np.int32).max))

    def _build_net(self, n_inputs: int, seed: int) -> NeuralNetRegressor:
        """The skorch net with this estimator's module, loss, optimiser and schedule."""
        monitor = "train_loss" if self.validation_fraction is None else "valid_loss"
        split = None if self.validation_fraction is None else ValidSplit(self.validation_fraction, random_state=seed)
        return LeanNeuralNetRegressor(
            module=self._module_class,
            module__n_inputs=n_inputs,
            module__hidden_layer_sizes=tuple(int(w) for w in self.hidden_layer_sizes),
            module__n_outputs=self._network_outputs(),
            criterion=WeightedSquaredError,
            criterion__weights=tuple(self._loss_weights()),
            optimizer=torch.optim.Adam,
            # the fused CPU kernel does Adam's update in one pass: 2.5x faster steps for these small nets
            optimizer__fused=True,
            lr=self.lr,
            batch_size=self.batch_size,
            max_epochs=self.max_epochs + self.plateau_epochs + self.max_recover_epochs,
            train_split=split,
            iterator_train__shuffle=True,
            callbacks=schedule_callbacks(
                max_epochs=self.max_epochs,
                plateau_epochs=self.plateau_epochs,
                plateau_patience=self.plateau_patience,
                plateau_factor=self.plateau_factor,
                min_lr=self.min_lr,
                recover_tolerance=self.recover_tolerance,
                max_recover_epochs=self.max_recover_epochs,
                monitor=monitor,
                extra=list(self.callbacks or []),
            ),
            verbose=self.verbose,
            device=self.device,
        )

    def _training_setup(self, X: NDArray[np.float64], y: NDArray[np.float64]):
        """Checks, network inputs and targets, seed and the (unfitted) skorch net of one fit.

        Shared by :meth:`_fit` and :func:`ftcal.fit_stacked` (several nets trained as one module).
        Returns ``(inputs, targets, seed, net)``, inputs and targets float64.
        """
        if not device_available(self.device):
            raise CalibrationInputError(
                f"device={self.device!r} is not available on this machine (this torch build has "
                f"{'CUDA' if torch.cuda.is_available() else 'no CUDA'}); use device='cpu'."
            )
        inputs, targets = self._training_pairs(X, y)
        too_large = np.abs(inputs).max(initial=0.0) > _FLOAT32_SAFE or np.abs(targets).max(initial=0.0) > _FLOAT32_SAFE
        if too_large:
            raise CalibrationInputError(
                f"the network inputs or targets of {type(self).__name__} exceed {_FLOAT32_SAFE:g} after scaling, "
                "beyond what float32 training handles; check the units of X and y."
            )
        seed = self._seed()
        return inputs, targets, seed, self._build_net(inputs.shape[1], seed)

    def _fit(self, X: NDArray[np.float64], y: NDArray[np.float64]) -> None:
        inputs, targets, seed, net = self._training_setup(X, y)
        with torch.random.fork_rng(devices=[]), torch_threads(1):
            torch.manual_seed(seed)
            net.fit(inputs.astype(np.float32), targets.astype(np.float32))
        interrupted_at = net.__dict__.pop("interrupted_epoch_", None)
        if interrupted_at is not None:  # a Ctrl-C that skorch's loop swallowed: the caller must see it
            raise KeyboardInterrupt(f"{type(self).__name__}.fit interrupted at epoch {interrupted_at}")
        self._finish_training(net, targets)

    def _finish_training(self, net: NeuralNetRegressor, targets: NDArray[np.float64]) -> None:
        """Refuse a diverged run; keep the trained net and its schedule's outcome."""
        self._check_converged(net, targets)
        self.net_ = net
        self.n_epochs_ = len(net.history)
        self.stop_reason_ = net.history[-1].get("stop_reason", "max_epochs")
        self.best_epoch_ = int(dict(net.callbacks_)["restore_best_weights"].best_epoch_)
        self._cache_numpy_layers()

    def _check_converged(self, net: NeuralNetRegressor, targets: NDArray[np.float64]) -> None:
        """A diverged run is an error that names the epoch, not a model predicting NaN or nonsense.

        Diverged means a NaN or inf loss, or a best loss more than
        :data:`_DIVERGENCE_FACTOR` times the loss of predicting zero (the
        mean squared target): such a net is worse than no net at all. (The
        loss of predicting the mean would be too strict a yardstick: the
        directional model's targets can be nearly constant, e.g. a single
        positive output, and a short schedule does not beat it 100-fold.)
        """
        fix = f"with lr={self.lr}. Fix: lower lr (the thesis uses 1e-3), or check the data's units."
        for key in ("train_loss", "valid_loss"):
            losses = np.asarray([row.get(key, 0.0) for row in net.history], dtype=float)
            bad = np.flatnonzero(~np.isfinite(losses))
            if bad.size:
                raise CalibrationInputError(
                    f"{type(self).__name__} training diverged: {key} became {losses[bad[0]]} at epoch {bad[0] + 1} {fix}"
                )
        weights = np.asarray(self._loss_weights(), dtype=float)
        nothing = float(np.mean((targets**2) @ weights))
        best = float(dict(net.callbacks_)["restore_best_weights"].best_loss_)
        if nothing > 0 and best > _DIVERGENCE_FACTOR * nothing:
            raise CalibrationInputError(
                f"{type(self).__name__} training diverged: the best loss {best:.3g} is over {_DIVERGENCE_FACTOR:g} "
                f"times that of predicting zero ({nothing:.3g}) {fix}"
            )

    def _cache_numpy_layers(self) -> None:
        """Build the numpy copy of the fitted layers now (after fit or load), so that ``predict`` changes nothing."""
        self.__dict__.pop("_numpy_layers_cache", None)
        self._numpy_layers()

    def _numpy_layers(self) -> list[tuple[NDArray, NDArray, str]]:
        """The fitted layers as float64 numpy arrays ``(W.T, b, activation)``, built once per fitted net."""
        cached = self.__dict__.get("_numpy_layers_cache")
        if cached is not None and cached[0] is self.net_.module_:
            return cached[1]
        layers = [(layer.weight.detach().cpu().double().numpy().T.copy(),
                   layer.bias.detach().cpu().double().numpy().copy(), activation)
                  for layer, activation in mlp_layers(self.net_.module_)]
        self.__dict__["_numpy_layers_cache"] = (self.net_.module_, layers)
        return layers

    def _forward_numpy(self, inputs: NDArray[np.float64]) -> NDArray[np.float64]:
        """The forward pass in numpy with the fitted (float32) weights, computed in float64.

        No torch dispatch, no thread changes. float64 keeps each row's result
        independent of the other rows (float32 BLAS kernels round a row
        differently depending on where it sits in the batch); it agrees with
        the float32 torch pass of large batches to ~1e-7 relative. A row whose
        inputs or outputs leave float32's range gives inf, as the float32
        pass (and the exported ONNX graph) would, so that ``predict`` refuses
        it whatever the batch size.
        """
        with np.errstate(over="ignore"):
            h = inputs.astype(np.float32)  # the network's input precision; beyond float32's range: inf
            for weight, bias, activation in self._numpy_layers():
                h = h @ weight + bias  # float64 arithmetic (the weights are float64 copies)
                if activation == "relu":
                    np.maximum(h, 0.0, out=h)
                elif activation == "tanh":
                    np.tanh(h, out=h)
            return h.astype(np.float32).astype(np.float64)  # the network's output precision and range

    def _forward(self, inputs: NDArray[np.float64]) -> NDArray[np.float64]:
        if inputs.shape[0] <= _NUMPY_FORWARD_ROWS:  # small batches (a control loop): numpy is ~20x cheaper
            return self._forward_numpy(inputs)
        module = self.net_.module_
        module.eval()
        out = []
        with torch.inference_mode(), torch_threads(1):
            for start in range(0, inputs.shape[0], _PREDICT_CHUNK):
                batch = torch.as_tensor(inputs[start : start + _PREDICT_CHUNK], dtype=torch.float32, device=self.device)
                out.append(module(batch).cpu().numpy())
        if not out:
            return np.zeros((0, module.layers[-1].out_features))
        return np.concatenate(out).astype(np.float64)

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        return self._decode(self._forward(self._network_inputs(X)), X)

    def network_inputs(self, X) -> NDArray[np.float64]:
        """What the fitted network sees for raw readings ``X`` (n, N): the pre-processing of ``predict``.

        For a deployment that runs the network elsewhere (with
        :meth:`fitted_layers`); the re-tare is applied as in ``predict``.

        Returns
        -------
        ndarray of shape (n_samples, n_network_inputs), float64
        """
        check_is_fitted(self)
        return self._network_inputs(self._retared(validate_readings(self, X)))

    def fitted_layers(self) -> list[tuple[NDArray[np.float64], NDArray[np.float64], str]]:
        """The fitted network as ``(weight (n_in, n_out), bias (n_out,), activation)`` per layer, float64 copies.

        ``activation`` is ``"relu"``, ``"tanh"`` or ``"identity"``;
        ``h = activation(h @ weight + bias)`` layer after layer maps
        :meth:`network_inputs` to the network's outputs.
        """
        check_is_fitted(self)
        return [(w.copy(), b.copy(), a) for w, b, a in self._numpy_layers()]
