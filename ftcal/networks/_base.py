"""The network calibrators' base: ``fit`` and :func:`~ftcal.networks.fit_stacked` both run :func:`train_networks` (the
one engine, in a forked torch RNG, torch's threads limited in the fitting thread alone); float32 training, float64
numpy inference."""

from __future__ import annotations

from collections.abc import Sequence
from numbers import Integral, Real

import numpy as np
import torch
from numpy.typing import NDArray
from skorch.history import History
from sklearn.utils import check_random_state
from sklearn.utils.validation import check_is_fitted
from sklearn.utils._param_validation import Interval, StrOptions

from ..calibrators._base import BaseCalibrator, declare
from ..core._exceptions import CalibrationInputError, ModelFileError
from ..core._memory import check_allocation
from ..core._threads import limit_threads_here
from ..core._validation import validate_readings
from ._engine import MemberSquaredError, NetworkRegressor
from ._modules import mlp_layers
from ._schedule import Callback, schedule_callbacks

__all__ = ["NetworkCalibrator", "train_networks", "device_available"]

#: Rows per chunk of the numpy forward pass: a chunk's float64 activations (1024 x 64 x 8 B = 512 KiB for the
#: default width) stay in the CPU's cache; 16384-row chunks made a 100 000-row predict twice as slow.
_PREDICT_CHUNK = 1024
#: A net whose best loss exceeds this multiple of the loss of predicting zero has diverged.
_DIVERGENCE_FACTOR = 100.0
#: The per-epoch entries of a network's history that model files keep.
_HISTORY_KEYS = ("epoch", "phase", "lr", "train_loss", "valid_loss", "stop_reason")
#: Largest magnitude of a network input or target that float32 training handles with room to spare.
_FLOAT32_SAFE = 1e30


def device_available(device: str) -> bool:
    """Whether torch can place tensors on ``device`` here (``"cuda"`` on a CPU-only build: False)."""
    try:
        torch.empty(0, device=device)
    except (RuntimeError, AssertionError, ValueError, TypeError):
        return False
    return True


def train_networks(estimators: Sequence["NetworkCalibrator"], datasets: Sequence[tuple]) -> None:
    """Train ``K >= 1`` network calibrators of one kind as one engine run; each ends fitted as by its own ``fit``.

    ``datasets``: one validated ``(X, y)`` per estimator (after ``_prepare_fit``); the estimators share the
    architecture and schedule (checked by :func:`~ftcal.networks.fit_stacked`). A Ctrl-C raises ``KeyboardInterrupt``; a
    callback ending training at an epoch's end (``EarlyStopping``) leaves ``stop_reason_ == "callback"``."""
    setups = [est._training_setup(X, y) for est, (X, y) in zip(estimators, datasets)]
    template = estimators[0]
    net = template._build_net(setups[0][0].shape[1], [seed for _, _, seed in setups],
                              [est._loss_weights() for est in estimators])
    with torch.random.fork_rng(devices=[]), template._thread_limit():
        net.fit([inputs.astype(np.float32) for inputs, _, _ in setups],
                [targets.astype(np.float32) for _, targets, _ in setups])
    best = dict(net.callbacks_)["restore_best_weights"]
    if not all(net.stop_reasons_) and not (len(net.history) and best.monitor in net.history[-1]):  # mid-epoch
        raise KeyboardInterrupt(f"{type(template).__name__}.fit interrupted at epoch {len(net.history)}")
    net.stop_reasons_ = [reason or "callback" for reason in net.stop_reasons_]  # the epoch ended: a callback stopped
    for k, (est, (_, targets, seed)) in enumerate(zip(estimators, setups)):
        member = net if len(estimators) == 1 else est._member_net(net, k, seed)
        est._finish_training(member, targets, best.best_loss_[k], best.best_epoch_[k], net.stop_reasons_[k])


def _hook(name: str):  # a method a NetworkCalibrator subclass must implement: calling it says so
    def missing(self, *args, **kwargs):
        raise NotImplementedError(f"{type(self).__name__} must implement {name}() (see NetworkCalibrator).")
    return missing


class NetworkCalibrator(BaseCalibrator):
    """Base of the skorch-trained calibrators. Subclasses set ``_module_class`` and implement
    ``_training_pairs(X, y) -> (inputs, targets)``, ``_network_inputs(X)``, ``_decode(outputs, X) -> wrench``
    (or override ``_predict_wrench``), ``_network_outputs()`` (the output layer's width for ``n_outputs_``
    targets) and ``_loss_weights()``; a missing one is a ``NotImplementedError`` naming it.
    """

    _training_pairs, _network_inputs, _decode, _network_outputs, _loss_weights = map(_hook, (
        "_training_pairs", "_network_inputs", "_decode", "_network_outputs", "_loss_weights"))

    _module_class: type[torch.nn.Module]
    _overflow_note = "the network computes in float32, at most ~3.4e38"
    #: The training engine (a subclass may override skorch's ``get_loss``, ``train_step``, ...: they are honoured).
    _net_class: type[NetworkRegressor] = NetworkRegressor
    #: Parameters that only affect one training run and are not stored in model files.
    _transient_params: tuple[str, ...] = ("callbacks",)
    #: Stored by model files (``net_``: the weights and the history).
    _fitted_state = ("n_epochs_", "best_epoch_", "stop_reason_", "net_")
    _fitted_constraints: dict = {"n_epochs_": [Interval(Integral, 1, None, closed="left")],
                                 "best_epoch_": [Interval(Integral, 0, None, closed="left")],
                                 "stop_reason_": [StrOptions({"schedule_end", "within_tolerance", "recover_cap",
                                                              "callback"})]}

    #: Phase 1's length when ``phase1_epochs`` is None [epochs] (the thesis' schedule, III-A-d).
    _default_phase1_epochs = 1700

    def __init__(self, *, hidden_layer_sizes=(64, 64, 64), lr=1e-3, batch_size=32, phase1_epochs=None,
                 max_epochs=None, plateau_epochs=100, plateau_patience=30, plateau_factor=0.1, min_lr=1e-5,
                 recover_tolerance=0.05, max_recover_epochs=500, validation_fraction=0.2, alpha=None,
                 zero_reading=None, random_state=None, verbose=0, callbacks=None, device="cpu", n_threads=1):
        self.hidden_layer_sizes = hidden_layer_sizes
        self.lr = lr
        self.batch_size = batch_size
        self.phase1_epochs = phase1_epochs
        self.max_epochs = max_epochs
        self.plateau_epochs = plateau_epochs
        self.plateau_patience = plateau_patience
        self.plateau_factor = plateau_factor
        self.min_lr = min_lr
        self.recover_tolerance = recover_tolerance
        self.max_recover_epochs = max_recover_epochs
        self.validation_fraction = validation_fraction
        super().__init__(alpha=alpha, zero_reading=zero_reading, random_state=random_state)
        self.verbose = verbose
        self.callbacks = callbacks
        self.device = device
        self.n_threads = n_threads

    def _schedule_epochs(self) -> tuple[int, int]:
        """``(phase 1's length, the cap on all epochs)`` from ``phase1_epochs`` and ``max_epochs``."""
        phase1 = self._default_phase1_epochs if self.phase1_epochs is None else int(self.phase1_epochs)
        full = phase1 + self.plateau_epochs + self.max_recover_epochs
        cap = full if self.max_epochs is None else int(self.max_epochs)
        return phase1, cap

    _parameter_constraints: dict = {
        **BaseCalibrator._parameter_constraints,
        "hidden_layer_sizes": [tuple, list],
        "lr": [Interval(Real, 0, None, closed="neither")],
        "batch_size": [Interval(Integral, 1, None, closed="left")],
        "phase1_epochs": [Interval(Integral, 1, None, closed="left"), None],
        "max_epochs": [Interval(Integral, 1, None, closed="left"), None],
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
        "n_threads": [Interval(Integral, 1, None, closed="left"), None],
    }

    def _check_params(self) -> None:
        """What the table cannot say: at least one layer, widths integers >= 1; callbacks skorch's."""
        bad = [w for w in self.hidden_layer_sizes if isinstance(w, bool) or not isinstance(w, Integral) or w < 1]
        if len(self.hidden_layer_sizes) == 0 or bad:
            raise CalibrationInputError(f"hidden_layer_sizes must be a non-empty tuple, each entry of it an integer >= 1, e.g. (64, 64); got {self.hidden_layer_sizes!r}.")
        pair = lambda c: isinstance(c, tuple) and len(c) == 2 and isinstance(c[0], str)  # noqa: E731  (name, callback)
        odd = [c for c in self.callbacks or () if not isinstance(c[1] if pair(c) else c, Callback)]
        if odd:
            raise CalibrationInputError(f"callbacks must hold skorch callbacks or (name, callback) pairs; got {odd[0]!r}.")

    def _thread_limit(self):
        """A context limiting torch's threads (OpenMP, per thread) to ``n_threads`` in the calling thread, and BLAS
        when no other thread runs; never another thread's (:func:`~ftcal.core._threads.limit_threads_here`)."""
        return limit_threads_here(self.n_threads, openmp=True)

    def _build_net(self, n_inputs: int, seed: int | Sequence[int], loss_weights: Sequence | None = None
                   ) -> NetworkRegressor:
        """The (unfitted) engine with this estimator's module, loss, optimiser and schedule; ``seed``: one, or one
        per member of a stack; ``loss_weights``: one row per member (default: this one's)."""
        seeds = [int(seed)] if isinstance(seed, Integral) else [int(s) for s in seed]
        return self._net_class(
            module=self._module_class, module__n_inputs=n_inputs, module__n_outputs=self._network_outputs(),
            module__hidden_layer_sizes=tuple(int(w) for w in self.hidden_layer_sizes),
            criterion=MemberSquaredError, criterion__weights=[list(w) for w in loss_weights or [self._loss_weights()]],
            # the fused CPU kernel does Adam's update in one pass: 2.5x faster steps for these small nets
            optimizer=torch.optim.Adam, optimizer__fused=self.device == "cpu", lr=self.lr, batch_size=self.batch_size,
            max_epochs=self._schedule_epochs()[1], seeds=seeds,
            validation_fraction=self.validation_fraction, train_split=None, callbacks=schedule_callbacks(self),
            verbose=self.verbose, device=self.device)

    def _training_setup(self, X: NDArray[np.float64], y: NDArray[np.float64]):
        """Checks, network inputs and targets, and the seed of one fit: ``(inputs, targets, seed)``, float64."""
        if not device_available(self.device):
            raise CalibrationInputError(f"device={self.device!r} is not available on this machine (this torch build "
                                        f"has {'CUDA' if torch.cuda.is_available() else 'no CUDA'}); use device='cpu'.")
        inputs, targets = self._training_pairs(X, y)
        if max(np.abs(inputs).max(initial=0.0), np.abs(targets).max(initial=0.0)) > _FLOAT32_SAFE:
            raise CalibrationInputError(
                f"the network inputs or targets of {type(self).__name__} exceed {_FLOAT32_SAFE:g} after scaling, "
                "beyond what float32 training handles; check the units of X and y.")
        self._check_network_memory(inputs.shape[1], len(inputs))
        return inputs, targets, int(check_random_state(self.random_state).randint(np.iinfo(np.int32).max))

    def _check_network_memory(self, n_inputs: int, n_rows: int, members: int = 1) -> None:
        """Refuse, before any allocation, ``members`` such networks whose training would exceed ftcal's memory limit."""
        widths = [n_inputs, *(int(w) for w in self.hidden_layer_sizes), self._network_outputs()]
        n_params = float(sum((a + 1) * b for a, b in zip(widths[:-1], widths[1:])))
        # float32 weights, gradients, Adam's moments, best copy; float64 layers of predict; a batch's activations
        n_bytes = members * (n_params * (5 * 4 + 8) + 2 * 4 * float(min(self.batch_size, n_rows)) * sum(widths))
        check_allocation(n_bytes, f"{members} x {type(self).__name__}, hidden_layer_sizes={self.hidden_layer_sizes!r}"
                         f" ({n_params:.3g} weights each)", "use fewer members, or narrower or fewer hidden layers")

    def __sklearn_tags__(self):
        # trained for epochs; without callbacks several train as one stacked module (fit_stacked)
        return declare(super().__sklearn_tags__(), cost="network", family="network", network=True,
                       stackable=not self.callbacks)

    def _fit(self, X: NDArray[np.float64], y: NDArray[np.float64]) -> None:
        train_networks([self], [(X, y)])

    # -- model files: this class encodes and decodes its own network (ftcal.save_model / load_model) --------
    #: Fitted attributes a model file holds through :meth:`_state_to_arrays` / :meth:`_state_from_arrays`.
    _encoded_state = ("net_",)

    def _state_to_arrays(self) -> tuple[dict[str, NDArray], dict]:
        """The fitted network as model-file arrays (``state_dict`` name -> float32 array) and JSON (the history)."""
        arrays = {k: v.detach().cpu().numpy() for k, v in self.net_.module_.state_dict().items()}
        history = [{k: row[k] for k in _HISTORY_KEYS if k in row} for row in self.net_.history]
        return arrays, {"history": history}

    def _array_shapes(self) -> dict[str, tuple[int, ...]]:
        """Names and shapes of the arrays :meth:`_state_from_arrays` takes, from the parameters and fitted sizes
        (checked by the model loader before it reads or allocates anything)."""
        sizes = self.hidden_layer_sizes
        if not isinstance(sizes, (tuple, list)) or not all(
                isinstance(w, Integral) and not isinstance(w, bool) and 1 <= w <= 1_000_000 for w in sizes):
            raise ModelFileError(f"hidden_layer_sizes {sizes!r:.80} is not a tuple of positive widths; the file is "
                                 "damaged.")
        shapes = self._module_class.state_shapes(int(self.n_features_in_), sizes, self._network_outputs())
        check_allocation(4.0 * sum(float(np.prod(shape)) for shape in shapes.values()),
                         f"the network of hidden_layer_sizes={tuple(sizes)}", "this is not a model ftcal wrote")
        return shapes

    def _state_from_arrays(self, arrays: dict[str, NDArray], extra: dict) -> None:
        """Rebuild ``net_`` from :meth:`_state_to_arrays`' output (shapes already checked), torch's global random
        generator left as it was (building a net seeds torch)."""
        with torch.random.fork_rng(devices=[]):
            net = self._build_net(int(self.n_features_in_), seed=0)
            net.initialize()
        net.module_.load_state_dict({k: torch.from_numpy(np.asarray(v, dtype=np.float32)) for k, v in arrays.items()})
        net.history = History(list(extra.get("history") or []))
        self.net_ = net
        self._cache_numpy_layers()

    def _member_net(self, stack: NetworkRegressor, k: int, seed: int) -> NetworkRegressor:
        """This estimator's net as member ``k`` of a trained stack: its weights, its slice of the history (its own
        values of the ``member_*`` lists, as ``lr``, ``train_loss``, ..., up to the epoch it stopped at)."""
        net = self._build_net(stack.module_.layout[0][0], seed)
        with torch.random.fork_rng(devices=[]):
            net.initialize()
        stack.module_.load_member(stack.module_.member_row(k), net.module_)
        rows = []
        for row in stack.history:
            own = {key[7:]: v[k] for key, v in row.items() if key.startswith("member_") and v[k] is not None}
            rows.append({"epoch": row["epoch"], "phase": row["phase"], "dur": row["dur"], **own})
            if "stop_reason" in rows[-1]:
                break
        net.history = History(rows)
        return net

    def _finish_training(self, net: NetworkRegressor, targets: NDArray[np.float64], best: float,
                         best_epoch: int, stop_reason: str) -> None:
        """Keep the trained net and its schedule's outcome, or refuse a diverged run (a NaN or inf loss, or a best
        loss over :data:`_DIVERGENCE_FACTOR` times that of predicting zero; why: ``docs/architecture.md``)."""
        fix = f"with lr={self.lr}. Fix: lower lr (the thesis uses 1e-3), or check the data's units."
        for key in ("train_loss", "valid_loss"):
            losses = np.asarray([row.get(key, 0.0) for row in net.history], dtype=float)
            bad = np.flatnonzero(~np.isfinite(losses))
            if bad.size:
                raise CalibrationInputError(f"{type(self).__name__} training diverged: {key} became {losses[bad[0]]} "
                                            f"at epoch {bad[0] + 1} {fix}")
        nothing = float(np.mean((targets**2) @ np.asarray(self._loss_weights(), dtype=float)))
        if nothing > 0 and best > _DIVERGENCE_FACTOR * nothing:
            raise CalibrationInputError(
                f"{type(self).__name__} training diverged: the best loss {best:.3g} is over {_DIVERGENCE_FACTOR:g} "
                f"times that of predicting zero ({nothing:.3g}) {fix}")
        self.net_, self.n_epochs_ = net, len(net.history)
        self.best_epoch_, self.stop_reason_ = int(best_epoch), stop_reason
        self._cache_numpy_layers()

    def _numpy_layers(self) -> list[tuple[NDArray, NDArray, str]]:
        """The fitted layers as float64 numpy arrays ``(W.T, b, activation)``, built once per fitted net."""
        cached = self.__dict__.get("_numpy_layers_cache")
        return cached[1] if cached is not None and cached[0] is self.net_.module_ else self._cache_numpy_layers()

    def _cache_numpy_layers(self) -> list[tuple[NDArray, NDArray, str]]:
        """Build the numpy copy of the fitted layers now (after fit or load), so that ``predict`` changes nothing."""
        layers = [(layer.weight.detach().cpu().double().numpy().T.copy(),
                   layer.bias.detach().cpu().double().numpy().copy(), activation)
                  for layer, activation in mlp_layers(self.net_.module_)]
        self.__dict__["_numpy_layers_cache"] = (self.net_.module_, layers)
        return layers

    def _forward(self, inputs: NDArray[np.float64]) -> NDArray[np.float64]:
        """The forward pass in numpy with the fitted (float32) weights, computed in float64, in chunks (a row out of
        float32's range gives inf, as the float32 net would; why: ``docs/architecture.md``)."""
        layers = self._numpy_layers()
        out = np.empty((len(inputs), layers[-1][1].shape[0]))
        with np.errstate(over="ignore"):
            for start in range(0, len(inputs), _PREDICT_CHUNK):
                h = inputs[start:start + _PREDICT_CHUNK].astype(np.float32)  # the net's input precision
                for weight, bias, activation in layers:
                    h = h @ weight + bias  # float64 arithmetic (the weights are float64 copies)
                    if activation == "relu":
                        np.maximum(h, 0.0, out=h)
                    elif activation == "tanh":
                        np.tanh(h, out=h)
                out[start:start + _PREDICT_CHUNK] = h.astype(np.float32)  # the net's output precision and range
        return out

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        return self._decode(self._forward(self._network_inputs(X)), X)

    def network_inputs(self, X) -> NDArray[np.float64]:
        """What the fitted network sees for raw readings ``X`` (n, N): the pre-processing of ``predict``.

        For a deployment that runs the network elsewhere (with :meth:`fitted_layers`); the re-tare is applied as
        in ``predict``.

        Returns
        -------
        ndarray of shape (n_samples, n_network_inputs), float64
        """
        check_is_fitted(self)
        return self._network_inputs(self._retared(validate_readings(self, X)))

    def fitted_layers(self) -> list[tuple[NDArray[np.float64], NDArray[np.float64], str]]:
        """The fitted network as ``(weight (n_in, n_out), bias (n_out,), activation)`` per layer, float64 copies.

        ``activation`` is ``"relu"``, ``"tanh"`` or ``"identity"``; ``h = activation(h @ weight + bias)`` layer
        after layer maps :meth:`network_inputs` to the network's outputs.
        """
        check_is_fitted(self)
        return [(w.copy(), b.copy(), a) for w, b, a in self._numpy_layers()]
