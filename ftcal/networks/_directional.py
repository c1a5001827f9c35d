"""The directional DNN calibrator of the thesis (section III-A to III-C)."""

from __future__ import annotations

import warnings
from numbers import Integral, Real

import numpy as np
from numpy.typing import NDArray
from sklearn.utils._param_validation import Interval

from ..core._exceptions import CalibrationInputError
from ._base import NetworkCalibrator
from ._modules import DirectionalNet
from ..core._wrench import scale_torques, unscale_torques

__all__ = ["DirectionalCalibrator"]


def _unit_rows(a: NDArray[np.float64]) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Row norms and unit rows of ``a``; an all-zero row stays zero (no NaN)."""
    norm = np.linalg.norm(a, axis=1)
    unit = np.divide(a, norm[:, None], out=np.zeros_like(a), where=norm[:, None] > 0)
    return norm, unit


class DirectionalCalibrator(NetworkCalibrator):
    """Directional DNN: learns the wrench direction and a scale factor (Kolff 2024, III).

    The unit reading ``x_c / v_in`` (``x_c = X - zero_reading_``, ``v_in = ||x_c||``, eq. 3-4) is mapped to the unit
    direction of the torque-scaled wrench ``y_s = [F, alpha_ T]`` and the scale ``s = ||y_s|| / v_in`` (eq. 5-8),
    trained on ``s / scale_reference_`` with loss eq. 9; ``predict`` gives ``s_hat * v_in * direction_hat``, torques
    divided by ``alpha_`` (III-B). Zero-load rows are dropped from ``fit`` with a ``UserWarning``; a zero reading
    predicts the zero wrench, never NaN. Equations and design (scale normalisation, zero-load rows, defaults):
    ``docs/architecture.md``, "The network calibrators".

    Parameters
    ----------
    hidden_layer_sizes : tuple of int, default=(64, 64, 64)
        Width of each hidden layer; the last one uses tanh.
    lr : float, default=1e-3
        Adam learning rate of phase 1.
    batch_size : int, default=32
        Mini-batch size.
    phase1_epochs : int or None, default=None
        Phase 1's length (constant ``lr``) [epochs]; None: 1700 (the thesis; 3000 for the comparative DNN).
    max_epochs : int or None, default=None
        Cap on the epochs of the whole training (all three phases); None: no cap beyond the schedule's
        ``phase1_epochs + plateau_epochs + max_recover_epochs`` (skorch's meaning: ``max_epochs=2`` trains 2
        epochs).
    plateau_epochs : int, default=100
        Phase 2 length (``ReduceLROnPlateau``).
    plateau_patience : int, default=30
        Epochs without improvement before phase 2 reduces the rate.
    plateau_factor : float, default=0.1
        Factor of each reduction.
    min_lr : float, default=1e-5
        Floor of the learning rate.
    recover_tolerance : float, default=0.05
        Phase 3 stops at the first epoch whose monitored loss is within this fraction of the best one.
    max_recover_epochs : int, default=500
        Hard cap on phase 3 epochs (0 = no phase 3).
    validation_fraction : float or None, default=0.2
        Share of samples held out (``ValidSplit``) for the monitored loss; ``None`` monitors the training loss.
    min_relative_magnitude : float, default=1e-3
        Relative threshold of the zero-load rows dropped in ``fit``.
    alpha : float or None, default=None
        Torque scale ``Fmax / Tmax`` [m⁻¹]; ``None`` derives it from ``y``.
    zero_reading : array-like of shape (N,) or None, default=None
        Raw reading at zero load; ``None`` estimates it (see :mod:`ftcal.calibrators._zero_load`). Give it for
        sensors with asymmetric gains.
    random_state : int, RandomState or None, default=None
        Seed of initialisation, shuffling and validation split.
    verbose : int, default=0
        skorch's per-epoch log when > 0.
    callbacks : list or None, default=None
        Extra skorch callbacks (instances or ``(name, callback)`` pairs), e.g. a progress bar, called at skorch's
        documented points (``on_batch_*`` every batch, ``on_grad_computed`` every step, ``on_epoch_*`` after the
        epoch's phase and ``lr`` are recorded). Not stored in model files; ensembles fit such an estimator alone.
    device : str, default='cpu'
        Torch device.
    n_threads : int or None, default=1
        Threads torch may use in ``fit``, limited in the fitting thread alone (OpenMP keeps a count per thread): one
        is fastest for these nets. Other threads of the process and the BLAS keep theirs; None leaves torch as it is.

    Attributes
    ----------
    net_ : NetworkRegressor (a skorch ``NeuralNetRegressor``)
        The trained net; ``net_.history`` has ``phase``, ``lr`` per epoch.
    scale_reference_ : float
        Median training scale factor ``s`` (normalises the scale target to ~1).
    alpha_, zero_reading_, n_features_in_
        As for every calibrator.
    n_epochs_, best_epoch_, stop_reason_
        Epochs run, epoch whose weights were kept, why training ended.
    n_dropped_zero_load_ : int
        Training rows dropped as zero-load rows.

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import DirectionalCalibrator
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(40, 6)); raw = w @ rng.normal(size=(6, 6))
    >>> model = DirectionalCalibrator(phase1_epochs=2, plateau_epochs=1, max_recover_epochs=1, random_state=0).fit(raw, w)
    >>> model.predict(raw[:2]).shape
    (2, 6)
    """

    _module_class = DirectionalNet
    _parameter_constraints: dict = {**NetworkCalibrator._parameter_constraints,
                                    "min_relative_magnitude": [Interval(Real, 0, 1, closed="both")]}

    def __init__(self, *, hidden_layer_sizes=(64, 64, 64), lr=1e-3, batch_size=32, phase1_epochs=None,
                 max_epochs=None, plateau_epochs=100, plateau_patience=30, plateau_factor=0.1, min_lr=1e-5,
                 recover_tolerance=0.05, max_recover_epochs=500, validation_fraction=0.2,
                 min_relative_magnitude=1e-3, alpha=None, zero_reading=None, random_state=None, verbose=0,
                 callbacks=None, device="cpu", n_threads=1):
        super().__init__(
            hidden_layer_sizes=hidden_layer_sizes, lr=lr, batch_size=batch_size, phase1_epochs=phase1_epochs,
            max_epochs=max_epochs, plateau_epochs=plateau_epochs, plateau_patience=plateau_patience,
            plateau_factor=plateau_factor, min_lr=min_lr, recover_tolerance=recover_tolerance,
            max_recover_epochs=max_recover_epochs, validation_fraction=validation_fraction, alpha=alpha,
            zero_reading=zero_reading, random_state=random_state, verbose=verbose, callbacks=callbacks, device=device,
            n_threads=n_threads)
        self.min_relative_magnitude = min_relative_magnitude

    def _network_outputs(self) -> int:
        return int(getattr(self, "n_outputs_", 6)) + 1  # the direction and the scale

    def _loss_weights(self) -> list[float]:
        return [1.0] * self._network_outputs()  # eq. 9: direction (6) and normalised scale (1) alike

    def _training_pairs(self, X, y):
        threshold = float(self.min_relative_magnitude)
        v_in, unit_in = _unit_rows(X - self.zero_reading_)
        v_out, unit_out = _unit_rows(scale_torques(y, self.alpha_, self.axes_))
        keep = (v_in > threshold * v_in.max()) & (v_out > threshold * v_out.max())
        self.n_dropped_zero_load_ = int(np.count_nonzero(~keep))
        if np.count_nonzero(keep) < 2:
            raise CalibrationInputError(
                f"only {np.count_nonzero(keep)} of {len(keep)} training rows have a non-zero load and a "
                f"non-zero reading (|X - zero_reading_| and |y| above {threshold} of their largest); the "
                f"directional model needs loaded samples. Fix: record load cases, or check zero_reading.")
        if self.n_dropped_zero_load_:
            warnings.warn(
                f"DirectionalCalibrator: dropped {self.n_dropped_zero_load_} of {len(keep)} training rows with "
                f"(near-)zero reading or load (below {threshold} of the largest): their direction is undefined.",
                UserWarning, stacklevel=6)  # the caller of fit (_training_setup, train_networks, _fit, fit)
        scale = v_out[keep] / v_in[keep]
        self.scale_reference_ = float(np.median(scale))
        targets = np.hstack([unit_out[keep], (scale / self.scale_reference_)[:, None]])
        return unit_in[keep], targets

    def _network_inputs(self, X):
        return _unit_rows(X - self.zero_reading_)[1]

    _fitted_state = ("scale_reference_", "n_dropped_zero_load_")
    _fitted_constraints: dict = {"scale_reference_": [Interval(Real, 0, None, closed="neither")],
                                 "n_dropped_zero_load_": [Interval(Integral, 0, None, closed="left")]}

    def _emit_onnx(self, g, x: str) -> str:
        xc = g.op("Sub", x, g.const(self.zero_reading_))
        v_in = g.op("ReduceL2", xc, axes=[1], keepdims=1)
        unit = g.op("Where", g.op("Greater", v_in, g.const(0.0)), g.op("Div", xc, v_in), g.const(0.0))
        out = g.mlp(unit, self._numpy_layers())
        k = self._network_outputs() - 1
        magnitude = g.op("Mul", g.op("Mul", g.columns(out, k, k + 1), g.const(self.scale_reference_)), v_in)
        return g.unscale_torques(g.op("Mul", g.columns(out, 0, k), magnitude), self.alpha_, k, self.axes_)

    def _predict_wrench(self, X):
        # the input norm is computed once (eq. 3) and serves both the unit input and the decoding (III-B)
        v_in, unit = _unit_rows(X - self.zero_reading_)
        outputs = self._forward(unit)
        return unscale_torques(outputs[:, :-1] * (outputs[:, -1] * self.scale_reference_ * v_in)[:, None], self.alpha_,
                               self.axes_)
