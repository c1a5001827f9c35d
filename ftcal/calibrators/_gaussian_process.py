"""A Gaussian-process calibrator that reports its own uncertainty (issue 12)."""

from __future__ import annotations

from numbers import Integral
import warnings

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.utils._param_validation import Interval
from scipy.linalg import solve_triangular
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel
from sklearn.utils import check_random_state
from sklearn.utils.validation import check_is_fitted
from threadpoolctl import threadpool_limits

from ._base import BaseCalibrator
from ..core._validation import check_finite_output, validate_readings
from ..core._wrench import scale_torques, unscale_torques

__all__ = ["GaussianProcessCalibrator"]


def _squared_distances(a: NDArray[np.float64], b: NDArray[np.float64]) -> NDArray[np.float64]:
    d = (a * a).sum(axis=1)[:, None] + (b * b).sum(axis=1)[None, :] - 2.0 * a @ b.T
    return np.maximum(d, 0.0)


class GaussianProcessCalibrator(BaseCalibrator):
    """Linear calibration plus a Gaussian process on its residuals, with a per-component standard deviation.

    Strain-gauge sensors are linear to first order and smoothly nonlinear
    beyond (creep, hysteresis, the compliance of soft sensors), so the model is

    1. a **linear part**: the LTM (eq. 1-2) fitted on *all* rows, in the
       torque-scaled space ``y_s = [F, alpha_ T]``;
    2. a **Gaussian process** on what the LTM leaves, over the tare-corrected
       channels scaled by their spread, ``u = (X - zero_reading_) / input_scale_``,
       with the kernel ``C · RBF(ℓ_1..ℓ_N) + White``: an ARD squared
       exponential (one length scale per channel, so a channel that carries no
       nonlinearity gets a long one) and a noise term. The hyperparameters are
       fitted by maximum marginal likelihood (:class:`sklearn.gaussian_process.GaussianProcessRegressor`),
       shared by the six outputs (each standardised); each output then gets its
       own maximum-likelihood amplitude, so a component whose residual is pure
       noise reports its own noise level.

    ``predict(X, return_std=True)`` also returns the predictive standard
    deviation of each component in [N] and [N·m]: the GP's posterior variance
    plus its noise term, i.e. the spread of the error against a reference
    measured like the training references. On held-out data about 95 % of the
    errors fall within two standard deviations (tested on simulated data;
    ``benchmarks/RESULTS.md``).

    **Large data sets.** An exact GP costs ``O(m³)`` time and ``O(m²)`` memory.
    The GP is therefore fitted on a random subset of ``max_samples`` rows
    (the *subset of data* approximation, Rasmussen & Williams §8.3.1), while
    the linear part uses every row. With the default 1000 rows a fit takes
    seconds on 2 cores whatever the data set's size (the 90 000-row robot
    data set included); raise ``max_samples`` for smoother residual maps at
    cubic cost. Prediction is ``O(m)`` per row.

    Parameters
    ----------
    max_samples : int, default=1000
        Rows the GP is fitted on (a random subset when the data has more).
    n_restarts_optimizer : int, default=0
        Extra random starts of the marginal-likelihood optimiser.
    alpha : float or None, default=None
        Torque scale ``Fmax / Tmax`` [m⁻¹]; ``None`` derives it from ``y``.
    zero_reading : array-like of shape (N,) or None, default=None
        Raw reading at zero load; ``None`` estimates it (see :mod:`ftcal.calibrators._zero_load`).
    random_state : int, RandomState or None, default=None
        Seed of the subset and of the optimiser's restarts.

    Attributes
    ----------
    linear_matrix_ : ndarray of shape (6, N)
        LTM in the torque-scaled space, per raw unit (on tare-corrected readings).
    linear_offset_ : ndarray of shape (6,)
        Its offset [N].
    input_scale_ : ndarray of shape (N,)
        Standard deviation of each tare-corrected channel.
    train_inputs_ : ndarray of shape (m, N)
        The scaled readings the GP was fitted on.
    dual_coef_ : ndarray of shape (m, 6)
        ``K⁻¹ y`` of the standardised residuals.
    cholesky_ : ndarray of shape (m, m)
        Lower Cholesky factor of ``K`` (noise included).
    residual_mean_, residual_scale_ : ndarray of shape (6,)
        Standardisation of the residuals [N].
    output_variance_ : ndarray of shape (6,)
        Maximum-likelihood amplitude of each output (standardised units).
    constant_, length_scale_, noise_level_
        Fitted kernel hyperparameters (``length_scale_`` of shape (N,)).
    alpha_, zero_reading_, n_features_in_
        As for every calibrator.

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import GaussianProcessCalibrator
    >>> rng = np.random.default_rng(0)
    >>> w = rng.uniform(-1, 1, size=(300, 6))
    >>> raw = (w + 0.1 * w**3) @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(300, 6))
    >>> gp = GaussianProcessCalibrator(alpha=1.0, random_state=0).fit(raw, w)
    >>> wrench, std = gp.predict(raw[:2], return_std=True)
    >>> wrench.shape, std.shape, bool((std > 0).all())
    ((2, 6), (2, 6), True)
    """

    _fitted_state = ("constant_", "noise_level_", "linear_matrix_", "linear_offset_", "input_scale_",
                     "train_inputs_", "dual_coef_", "cholesky_", "residual_mean_", "residual_scale_",
                     "output_variance_", "length_scale_")
    _parameter_constraints: dict = {
        **BaseCalibrator._parameter_constraints,
        "max_samples": [Interval(Integral, 10, None, closed="left")],
        "n_restarts_optimizer": [Interval(Integral, 0, None, closed="left")],
    }

    def __init__(self, *, max_samples=1000, n_restarts_optimizer=0, alpha=None, zero_reading=None,
                 random_state=None):
        self.max_samples = max_samples
        self.n_restarts_optimizer = n_restarts_optimizer
        self.alpha = alpha
        self.zero_reading = zero_reading
        self.random_state = random_state

    def _fit(self, X: NDArray[np.float64], y: NDArray[np.float64]) -> None:
        xc = X - self.zero_reading_
        ys = scale_torques(y, self.alpha_)
        coef, *_ = np.linalg.lstsq(np.hstack([xc, np.ones((len(xc), 1))]), ys, rcond=None)
        self.linear_matrix_, self.linear_offset_ = coef[:-1].T, coef[-1]
        residual = ys - (xc @ self.linear_matrix_.T + self.linear_offset_)
        scale = xc.std(axis=0)
        self.input_scale_ = np.where(scale > 0, scale, 1.0)
        u = xc / self.input_scale_
        rng = check_random_state(self.random_state)
        if len(u) > self.max_samples:
            keep = np.sort(rng.choice(len(u), size=int(self.max_samples), replace=False))
            u, residual = u[keep], residual[keep]
        self.residual_mean_ = residual.mean(axis=0)
        r_scale = residual.std(axis=0)
        self.residual_scale_ = np.where(r_scale > 0, r_scale, 1.0)
        target = (residual - self.residual_mean_) / self.residual_scale_
        n_channels = u.shape[1]
        kernel = (ConstantKernel(1.0, (1e-3, 1e3)) * RBF(np.ones(n_channels), (1e-2, 1e3))
                  + WhiteKernel(1e-1, (1e-6, 1e1)))
        gp = GaussianProcessRegressor(kernel, n_restarts_optimizer=int(self.n_restarts_optimizer),
                                      random_state=rng.randint(np.iinfo(np.int32).max), copy_X_train=False)
        with threadpool_limits(2, user_api="blas"), warnings.catch_warnings():
            # a length scale at its upper bound is the expected answer for a channel without nonlinearity
            warnings.simplefilter("ignore", ConvergenceWarning)
            gp.fit(u, target)
        k = gp.kernel_
        self.constant_ = float(k.k1.k1.constant_value)
        self.length_scale_ = np.atleast_1d(np.asarray(k.k1.k2.length_scale, dtype=float)) * np.ones(n_channels)
        self.noise_level_ = float(k.k2.noise_level)
        self.train_inputs_ = u
        self.cholesky_ = np.asarray(gp.L_)
        self.dual_coef_ = np.asarray(gp.alpha_).reshape(len(u), -1)
        # Maximum-likelihood amplitude per output for the shared kernel shape: y_jᵀ K⁻¹ y_j / m.
        self.output_variance_ = np.maximum((target * self.dual_coef_).sum(axis=0) / len(u), 1e-12)

    def _cross_kernel(self, u: NDArray[np.float64]) -> NDArray[np.float64]:
        ls = self.length_scale_
        return self.constant_ * np.exp(-0.5 * _squared_distances(u / ls, self.train_inputs_ / ls))

    def _predict_scaled(self, X: NDArray[np.float64], return_std: bool):
        xc = X - self.zero_reading_
        u = xc / self.input_scale_
        k_star = self._cross_kernel(u)
        mean = xc @ self.linear_matrix_.T + self.linear_offset_
        mean += (k_star @ self.dual_coef_) * self.residual_scale_ + self.residual_mean_
        if not return_std:
            return mean, None
        v = solve_triangular(self.cholesky_, k_star.T, lower=True, check_finite=False)
        var = np.maximum(self.constant_ + self.noise_level_ - (v * v).sum(axis=0), 0.0)
        std = np.sqrt(var[:, None] * self.output_variance_[None, :]) * self.residual_scale_
        return mean, std

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        return unscale_torques(self._predict_scaled(X, False)[0], self.alpha_)

    def _emit_onnx(self, g, x: str) -> str:
        xc = g.op("Sub", x, g.const(self.zero_reading_))
        scaled = g.op("Div", xc, g.const(self.input_scale_ * self.length_scale_))
        train = self.train_inputs_ / self.length_scale_
        cross = g.op("MatMul", scaled, g.const(train.T))
        squared = g.op("Add", g.op("ReduceSumSquare", scaled, axes=[1], keepdims=1),
                       g.const((train * train).sum(axis=1)))
        distances = g.op("Max", g.op("Sub", squared, g.op("Mul", g.const(2.0), cross)), g.const(0.0))
        kernel = g.op("Mul", g.const(self.constant_), g.op("Exp", g.op("Mul", g.const(-0.5), distances)))
        residual = g.op("Add", g.op("Mul", g.op("MatMul", kernel, g.const(self.dual_coef_)),
                                    g.const(self.residual_scale_)), g.const(self.residual_mean_))
        mean = g.op("Add", g.affine(xc, self.linear_matrix_.T, self.linear_offset_), residual)
        return g.unscale_torques(mean, self.alpha_, int(getattr(self, "n_outputs_", 6)))

    def predict(self, X: ArrayLike, return_std: bool = False):
        """Wrench in [N] and [N·m] for raw readings ``X`` (n, N); with ``return_std`` also its standard deviation.

        Returns
        -------
        wrench : ndarray of shape (n_samples, 6)
        std : ndarray of shape (n_samples, 6), only with ``return_std=True``
            Predictive standard deviation of each component, [N] and [N·m].
        """
        if not return_std:
            return super().predict(X)
        check_is_fitted(self)
        X = self._retared(validate_readings(self, X))
        mean, std = self._predict_scaled(X, True)
        wrench = unscale_torques(mean, self.alpha_)
        check_finite_output(X, wrench, self)
        return wrench, unscale_torques(std, self.alpha_)
