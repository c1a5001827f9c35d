"""A Gaussian-process calibrator that chooses its own mean and kernel and reports a calibrated uncertainty."""

from __future__ import annotations

from numbers import Integral, Real
import warnings

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.exceptions import ConvergenceWarning
from sklearn.gaussian_process import GaussianProcessRegressor
from sklearn.gaussian_process.kernels import RBF, ConstantKernel, DotProduct, Matern, WhiteKernel
from sklearn.linear_model import LinearRegression
from sklearn.utils import check_random_state
from sklearn.utils._param_validation import Interval, StrOptions
from sklearn.utils.validation import check_is_fitted

from ._base import BaseCalibrator, GroupsFit, declare
from ..core._exceptions import ModelFileError
from ..core._memory import check_allocation, rows_within_limit
from ..core._validation import check_bool, check_finite_output, validate_readings
from ..core._wrench import scale_torques, unscale_torques

__all__ = ["GaussianProcessCalibrator", "GP_MEANS", "GP_KERNELS", "GP_BOUNDS"]

#: Mean functions the GP may use: none (a constant) or the LTM fitted on every row.
GP_MEANS: tuple[str, ...] = ("none", "linear")
#: Kernel families: ARD squared exponential or Matérn 5/2, each alone or plus a linear (dot-product) term.
GP_KERNELS: tuple[str, ...] = ("rbf", "matern52", "rbf+linear", "matern52+linear")
#: (mean, kernel) pairs tried by ``mean="auto"`` / ``kernel="auto"``: with a constant mean the kernel carries a
#: linear term (so that the GP extrapolates like the LTM; its amplitude may fit to ~0, the stock GP), with the
#: LTM mean a stationary kernel models what the LTM leaves.
_AUTO_COMBINATIONS: tuple[tuple[str, str], ...] = (
    ("none", "rbf+linear"), ("none", "matern52+linear"), ("linear", "rbf"), ("linear", "matern52"))
#: Hyperparameter bounds and starting values: ftcal's (for standardised data, see :func:`make_kernel`) or
#: scikit-learn's defaults (the stock GP's: every bound 1e-5..1e5, every start 1).
GP_BOUNDS: tuple[str, ...] = ("ftcal", "stock")
#: Rows on which ``per_output="auto"`` compares shared and per-output hyperparameters.
_PER_OUTPUT_ROWS = 150
#: Rows of each prediction chunk are chosen so that one chunk's cross-kernel stays under this size [bytes].
_CHUNK_BYTES = 2**26
#: Held-out rows (outside the GP's subset) on which the predictive std is calibrated, at most.
_STD_ROWS = 1000
#: The std is calibrated so that this share of the calibration rows' errors lies within ``_STD_Z`` std.
_STD_COVERAGE, _STD_Z = 0.95, 1.96


def make_kernel(family: str, n_channels: int, bounds: str = "ftcal"):
    """The kernel ``C · k(ℓ_1..ℓ_N) [+ C_lin · (x·x + σ₀²)] + White`` of a family in :data:`GP_KERNELS`.

    ``bounds="ftcal"``: bounds for standardised inputs and outputs, length
    scales 1e-2..1e3 (a channel without nonlinearity reaches the upper bound),
    amplitudes 1e-4..1e3, noise 1e-8..1, starting from a low noise (0.01).
    ``bounds="stock"``: scikit-learn's defaults, every bound 1e-5..1e5 and
    every start 1 (the stock GP ``ConstantKernel() * RBF(ones(N)) + WhiteKernel()``).

    Examples
    --------
    >>> make_kernel("matern52+linear", 2)
    1**2 * Matern(length_scale=[1, 1], nu=2.5) + 0.1**2 * DotProduct(sigma_0=1) + WhiteKernel(noise_level=0.01)
    >>> make_kernel("rbf", 2, "stock")
    1**2 * RBF(length_scale=[1, 1]) + WhiteKernel(noise_level=1)
    """
    base, _, linear = family.partition("+")
    if bounds == "stock":
        kernel = ConstantKernel() * (RBF(np.ones(n_channels)) if base == "rbf" else Matern(np.ones(n_channels), nu=2.5))
        return (kernel + ConstantKernel() * DotProduct() if linear else kernel) + WhiteKernel()
    stationary = (RBF(np.ones(n_channels), (1e-2, 1e3)) if base == "rbf"
                  else Matern(np.ones(n_channels), (1e-2, 1e3), nu=2.5))
    kernel = ConstantKernel(1.0, (1e-4, 1e3)) * stationary
    if linear:
        kernel = kernel + ConstantKernel(1e-2, (1e-6, 1e3)) * DotProduct(1.0, (1e-3, 1e3))
    return kernel + WhiteKernel(1e-2, (1e-8, 1.0))


def onnx_kernel(g, u: str, train: NDArray[np.float64], length_scale: NDArray[np.float64], amplitude: float,
                matern: bool = False) -> str:
    """The ONNX graph of ``amplitude * k(u, train)`` (n, m), ``k`` the RBF kernel (with ``matern`` the Matérn 5/2)
    of these length scales, from the squared scaled distances (rounding below 0 clipped): the kernel term of the
    GP's graph and of the stock kernel baselines'."""
    train = train / length_scale
    scaled = g.op("Div", u, g.const(length_scale))
    squared = g.op("Add", g.op("ReduceSumSquare", scaled, axes=[1], keepdims=1), g.const((train * train).sum(axis=1)))
    d2 = g.op("Max", g.op("Sub", squared, g.op("Mul", g.const(2.0), g.op("MatMul", scaled, g.const(train.T)))),
              g.const(0.0))
    if matern:  # (1 + sqrt(5) d + 5/3 d^2) exp(-sqrt(5) d)
        d = g.op("Sqrt", d2)
        poly = g.op("Add", g.op("Add", g.const(1.0), g.op("Mul", g.const(np.sqrt(5.0)), d)),
                    g.op("Mul", g.const(5.0 / 3.0), d2))
        shape = g.op("Mul", poly, g.op("Exp", g.op("Mul", g.const(-np.sqrt(5.0)), d)))
    else:
        shape = g.op("Exp", g.op("Mul", g.const(-0.5), d2))
    return g.op("Mul", g.const(float(amplitude)), shape)


class _Regressor(GaussianProcessRegressor):
    """:class:`~sklearn.gaussian_process.GaussianProcessRegressor` whose log-marginal-likelihood gradient, for the
    kernels of :func:`make_kernel`, is computed from ``m x m`` matrices and matrix products.

    The same function and gradient as scikit-learn's (Rasmussen & Williams eq. 5.9: ``½ tr((ααᵀ - K⁻¹) ∂K/∂θ)``,
    summed over the outputs), to rounding, without the ``(m, m, n_θ)`` kernel-gradient tensor and the ``(m, m,
    n_outputs)`` inner term scikit-learn builds at every step of the optimiser: the outputs are summed first,
    ``W = ααᵀ - k K⁻¹``, and for a length scale ``ℓ_d``, ``∂K_ij/∂log ℓ_d = c F_ij (z_id - z_jd)²`` (``z = x / ℓ``;
    ``F = k`` for the RBF, ``5/3 (1 + √5 r) e^{-√5 r}`` for the Matérn 5/2), so the trace is
    ``½ Σ_ij W_ij c F_ij (z_id - z_jd)²``, one ``m x m`` pass a channel. Any other kernel takes scikit-learn's
    path.
    """

    def log_marginal_likelihood(self, theta=None, eval_gradient=False, clone_kernel=True):
        if not eval_gradient or theta is None or _kernel_parts(self.kernel_) is None:
            return super().log_marginal_likelihood(theta, eval_gradient, clone_kernel)
        from scipy.linalg import cho_solve, cholesky
        from scipy.linalg.lapack import dpotri
        from scipy.spatial.distance import cdist

        kernel = self.kernel_.clone_with_theta(theta) if clone_kernel else self.kernel_
        kernel.theta = theta
        constant, stationary, linear_constant, dot, white = _kernel_parts(kernel)
        X = self.X_train_
        m, n_channels = X.shape
        scaled = X / np.broadcast_to(np.asarray(stationary.length_scale, dtype=float), (n_channels,))
        squared = cdist(scaled, scaled, "sqeuclidean")
        if type(stationary) is RBF:  # (Matern is a subclass of RBF)
            shape = slope = np.exp(-0.5 * squared)
        else:  # Matérn 5/2 (_kernel_parts admits no other)
            t = np.sqrt(5.0 * squared)
            decay = np.exp(-t)
            shape = (1.0 + t + t * t / 3.0) * decay
            slope = 5.0 / 3.0 * (1.0 + t) * decay
        c = float(constant.constant_value)
        K = c * shape
        if dot is not None:
            K_linear = float(linear_constant.constant_value) * (X @ X.T + float(dot.sigma_0) ** 2)
            K = K + K_linear
        noise = float(white.noise_level)
        K[np.diag_indices_from(K)] += noise + self.alpha
        try:
            L = cholesky(K, lower=True, check_finite=False)
        except np.linalg.LinAlgError:
            return -np.inf, np.zeros_like(theta)
        y = self.y_train_ if self.y_train_.ndim == 2 else self.y_train_[:, None]
        alpha = cho_solve((L, True), y, check_finite=False)
        log_likelihood = float(np.sum(-0.5 * np.einsum("ik,ik->k", y, alpha) - np.log(np.diag(L)).sum()
                                      - m / 2 * np.log(2 * np.pi)))
        inverse, info = dpotri(L, lower=1)  # K⁻¹ from its Cholesky factor (a third of cho_solve(L, I)'s work)
        if info != 0:
            return -np.inf, np.zeros_like(theta)
        inverse = np.tril(inverse) + np.tril(inverse, -1).T  # dpotri fills the lower triangle only
        W = alpha @ alpha.T - y.shape[1] * inverse
        G = W * (c * slope)
        # Σ_ij G_ij (z_id - z_jd)², one channel at a time: exact (expanding the square into products cancels
        # catastrophically for near-duplicate rows and short length scales), O(m² N) without the tensor
        length = np.empty(n_channels)
        difference = np.empty_like(G)
        for d in range(n_channels):
            np.subtract(scaled[:, d, None], scaled[None, :, d], out=difference)
            np.multiply(difference, difference, out=difference)
            length[d] = 0.5 * np.vdot(G, difference)
        if np.ndim(stationary.length_scale) == 0 or np.size(stationary.length_scale) == 1:
            length = np.atleast_1d(length.sum())  # one length scale for every channel
        gradient = [0.5 * np.sum(W * (c * shape)), *length]
        if dot is not None:
            gradient += [0.5 * np.sum(W * K_linear),
                         0.5 * float(linear_constant.constant_value) * 2.0 * float(dot.sigma_0) ** 2 * W.sum()]
        gradient.append(0.5 * noise * np.trace(W))
        return log_likelihood, np.asarray(gradient, dtype=float)


def _kernel_parts(kernel):
    """``(C, stationary, C_lin or None, DotProduct or None, White)`` of a kernel built as :func:`make_kernel` builds
    them, every hyperparameter free; ``None`` for any other kernel."""
    from sklearn.gaussian_process.kernels import Product, Sum

    if not (isinstance(kernel, Sum) and isinstance(kernel.k2, WhiteKernel)) or any(
            h.fixed for h in kernel.hyperparameters):
        return None
    body, linear_constant, dot = kernel.k1, None, None
    if isinstance(body, Sum):
        body, linear = body.k1, body.k2
        if not (isinstance(linear, Product) and isinstance(linear.k1, ConstantKernel)
                and isinstance(linear.k2, DotProduct)):
            return None
        linear_constant, dot = linear.k1, linear.k2
    if not (isinstance(body, Product) and isinstance(body.k1, ConstantKernel)
            and (type(body.k2) is RBF or (type(body.k2) is Matern and body.k2.nu == 2.5))):
        return None
    return body.k1, body.k2, linear_constant, dot, kernel.k2


def _regressor(kernel, random_state, optimizer="fmin_l_bfgs_b") -> GaussianProcessRegressor:
    """The GP of this kernel (``normalize_y``; its optimiser from the kernel's own start only: ftcal draws the
    restarts itself, :meth:`GaussianProcessCalibrator._starts`)."""
    return _Regressor(kernel, normalize_y=True, copy_X_train=False, random_state=random_state, optimizer=optimizer)


def _fit_quietly(kernel, seed, u, target, optimizer="fmin_l_bfgs_b") -> GaussianProcessRegressor:
    """:func:`_regressor` of ``kernel`` fitted on ``u``, ``target``, without the optimiser's convergence warnings."""
    with warnings.catch_warnings():
        # a length scale at its upper bound is the expected answer for a channel without nonlinearity
        warnings.simplefilter("ignore", ConvergenceWarning)
        return _regressor(kernel, seed, optimizer).fit(u, target)


def _mean_basis(mean: str, u: NDArray[np.float64]) -> NDArray[np.float64]:
    """The basis ``H`` of a mean in :data:`GP_MEANS` at standardised readings ``u`` (m, N): the constant, plus the
    channels with the linear mean. Standardised, not raw, channels: the same span (so the same left-out errors),
    but columns of one scale, where raw channels of scales 1e-4..1e4 make ``H`` numerically rank-deficient."""
    ones = np.ones((len(u), 1))
    return np.hstack([ones, u]) if mean == "linear" else ones


def _left_out(gp: GaussianProcessRegressor, basis: NDArray[np.float64], groups: NDArray | None):
    """Each training row's error when left out of the fit (rows of one group together), and its variance.

    Exact, with the hyperparameters fixed, for the GP whose mean ``Hβ`` on the basis ``H`` (the constant
    ``normalize_y`` removes, plus the channels with the linear mean, :func:`_mean_basis`) has its coefficients
    ``β`` refitted by generalised least squares without the left-out rows (Rasmussen & Williams eq. 5.12, §2.7
    with a vague prior on ``β``, §5.4.2): with ``P = K⁻¹ - K⁻¹H (HᵀK⁻¹H)⁻¹ HᵀK⁻¹``, leaving out the rows ``G``,
    their errors are ``(P_GG)⁻¹ (P y)_G`` with covariance ``(P_GG)⁻¹``. ``P`` is computed as
    ``L⁻ᵀ (I - QQᵀ) L⁻¹`` from an orthonormal basis ``Q`` of ``L⁻¹H`` (``K = LLᵀ``; SVD of the column-equilibrated
    ``L⁻¹H``, directions below rounding dropped), never from the normal matrix ``HᵀK⁻¹H``, whose condition
    number is the square of ``L⁻¹H``'s. Returns ``(errors, variances)``, each ``(m, k)`` in the target's own
    units (NaN for rows of a group without which the basis is rank-deficient: the refit cannot predict them);
    ``None`` when ``H`` leaves no degree of freedom.
    """
    from scipy.linalg import cho_solve, solve_triangular

    m = len(basis)
    if m <= basis.shape[1] + 1:
        return None
    L = np.asarray(gp.L_)
    whitened = solve_triangular(L, basis, lower=True, check_finite=False)  # L⁻¹H
    norms = np.linalg.norm(whitened, axis=0)
    whitened = whitened[:, norms > 0] / norms[norms > 0]  # column scaling does not change the span
    Q, s, _ = np.linalg.svd(whitened, full_matrices=False)
    rank_tol = max(whitened.shape) * np.finfo(float).eps * (s[0] if s.size else 0.0)
    Q = Q[:, s > rank_tol]
    B = solve_triangular(L.T, Q, lower=False, check_finite=False)  # L⁻ᵀQ: P = K⁻¹ - BBᵀ
    P = cho_solve((L, True), np.eye(m), check_finite=False) - B @ B.T
    alpha = np.asarray(gp.alpha_).reshape(m, -1)  # K⁻¹y, so L⁻¹y = Lᵀα and P y = α - B Qᵀ Lᵀα
    Py = alpha - B @ (Q.T @ (L.T @ alpha))
    scale = np.atleast_1d(np.asarray(gp._y_train_std, dtype=float))  # normalize_y's: back to the target's units
    if groups is None:  # one row at a time: (P_ii)⁻¹ is a scalar
        with np.errstate(divide="ignore", invalid="ignore"):
            diag = np.diag(P)[:, None]
            return Py / diag * scale, np.broadcast_to(1.0 / diag, Py.shape) * scale**2
    rank = Q.shape[1]
    errors, variances = np.full_like(Py, np.nan), np.full_like(Py, np.nan)
    for rows in (np.flatnonzero(groups == g) for g in np.unique(groups)):
        rest = np.ones(m, dtype=bool)
        rest[rows] = False
        if np.linalg.matrix_rank(basis[rest] / np.maximum(np.abs(basis[rest]).max(axis=0), np.finfo(float).tiny)) \
                < rank:  # a group the basis cannot do without: its refit cannot predict it
            continue
        try:
            cov = np.linalg.inv(P[np.ix_(rows, rows)])
        except np.linalg.LinAlgError:
            continue
        errors[rows] = cov @ Py[rows] * scale
        variances[rows] = np.maximum(np.diag(cov), np.finfo(float).tiny)[:, None] * scale**2
    return errors, variances


def _left_out_z(gp: GaussianProcessRegressor, basis: NDArray[np.float64], groups: NDArray | None) -> NDArray:
    """Each training row's left-out error over its predictive std (:func:`_left_out`), rows with a finite one."""
    left_out = _left_out(gp, basis, groups)
    if left_out is None:
        return np.empty((0, np.asarray(gp.alpha_).reshape(len(basis), -1).shape[1]))
    with np.errstate(divide="ignore", invalid="ignore"):
        z = np.abs(left_out[0]) / np.sqrt(left_out[1])
    return z[np.isfinite(z).all(axis=1)]


def _held_out_mse(gp: GaussianProcessRegressor, basis: NDArray[np.float64], groups: NDArray | None) -> float:
    """Mean squared left-out error over the rows and outputs (target units²; inf when it cannot be computed)."""
    left_out = _left_out(gp, basis, groups)
    if left_out is None:
        return float("inf")
    errors = left_out[0][np.isfinite(left_out[0]).all(axis=1)]
    return float(np.mean(errors**2)) if errors.size else float("inf")


def _log_evidence(gp: GaussianProcessRegressor, target: NDArray[np.float64]) -> float:
    """Log marginal likelihood of ``target`` in its own units (sklearn's is of the standardised target)."""
    scale = target.std(axis=0)
    return float(gp.log_marginal_likelihood_value_ - len(target) * np.log(np.where(scale > 0, scale, 1.0)).sum())


class GaussianProcessCalibrator(GroupsFit, BaseCalibrator):
    """A Gaussian process over the readings, with its mean, kernel and hyperparameters chosen by held-out error.

    Strain-gauge sensors are linear to first order and smoothly nonlinear
    beyond (creep, hysteresis, the compliance of soft sensors). The model is a
    :class:`~sklearn.gaussian_process.GaussianProcessRegressor` (``normalize_y``)
    on the torque-scaled wrench ``y_s = [F, alpha_ T]`` over the tare-corrected
    channels standardised by their spread, ``u = (X - zero_reading_ - input_mean_) / input_scale_``:

    * **mean**: ``"none"`` (a constant) or ``"linear"`` (the LTM, eq. 1-2,
      fitted on *all* rows; the GP then models what it leaves);
    * **kernel**: ARD squared exponential (``"rbf"``) or Matérn 5/2
      (``"matern52"``), one length scale per channel, optionally plus a linear
      term (``"+linear"``: the GP then extrapolates linearly, like the LTM,
      beyond the calibrated range instead of reverting to a constant), plus a
      noise term (see :func:`make_kernel`);
    * **kernel bounds**: ftcal's (tight bounds for standardised data, a low
      starting noise) or ``"stock"``, scikit-learn's defaults (bounds 1e-5..1e5,
      every start 1: what ``StandardScaler() + GaussianProcessRegressor(
      ConstantKernel() * RBF(ones(N)) + WhiteKernel(), normalize_y=True)``
      uses); ``mean="none", kernel="rbf", per_output=False,
      kernel_bounds="stock"`` *is* that stock GP (a test checks the
      predictions agree);
    * with ``"auto"`` the combinations constant mean + (RBF or Matérn) + linear
      term and LTM mean + (RBF or Matérn), each with both bounds, are fitted
      (marginal likelihood) on at most ``selection_samples`` rows, and the one
      of **least held-out error** wins: the closed-form leave-one-out error of
      each row (Rasmussen & Williams eq. 5.12; exact, hyperparameters fixed,
      for the GP whose mean's coefficients, the constant or the constant and
      the channels, are refitted by generalised least squares without the row:
      §2.7), or with ``fit(..., groups=...)`` leave-one-group-out. (The fitted
      model's LTM is the ordinary least-squares one on every row: the same
      basis, weighted otherwise.) On a few
      hundred rows of correlated channels the likelihood overfits: a higher
      optimum (ftcal's bounds on a real soft sensor) predicted new rows 1.5x
      worse than the stock GP's lower one, so the likelihood only fits the
      hyperparameters, never chooses;
    * **per output**: with ``per_output="auto"`` each of the six components
      gets its own hyperparameters when that lowers the held-out error on the
      selection rows (``True``/``False`` force it);
    * **final fit** on ``max_samples`` rows, from the winner's
      hyperparameters, from the kernel's own start and from
      ``n_restarts_optimizer`` random starts within the bounds: the optimum of
      least held-out error is kept (``held_out_rmse_``).

    ``predict(X, return_std=True)`` also returns the predictive standard
    deviation of each component in [N] and [N·m], from
    :meth:`GaussianProcessRegressor.predict(return_std=True) <sklearn.gaussian_process.GaussianProcessRegressor.predict>`:
    the posterior variance plus the noise term, i.e. the spread of the error
    against a reference measured like the training references, **calibrated**
    on rows the GP did not see: each component's std is multiplied by
    ``std_scale_``, the smallest factor (at least 1) with which 95 % of those
    rows' errors fall within 1.96 std. The rows are every row of the subset
    left out in turn (closed form, its mean's coefficients refitted without it by
    generalised least squares: Rasmussen & Williams §2.7, §5.4.2), with ``fit(..., groups=...)`` every group left out
    together, plus up to 1000 training rows outside the subset (of groups the
    subset does not hold). A marginal-likelihood fit tends to
    make the std too narrow where the errors have heavier tails than a
    Gaussian (e.g. a sign-dependent gain); the factor is never below 1, because
    rows held out at random are closer to the training rows than a new
    recording (a held-out group) is. (The rows outside the subset did take
    part in the LTM mean's fit, over all rows: a small, O(N / n) optimism.) The coverage (share of held-out errors
    within two std on grouped folds) is measured by
    ``benchmarks/auto_vs_stock.py`` (``gp_coverage_2std``) and recorded in ``benchmarks/RESULTS.md``.

    **Large data sets.** An exact GP costs ``O(m³)`` time and ``O(m² N)``
    memory (the kernel gradient). The GP is fitted on a random subset of
    ``max_samples`` rows (the *subset of data* approximation, Rasmussen &
    Williams §8.3.1) while the linear mean uses every row; the memory a fit
    and a prediction need is checked before allocating
    (:func:`ftcal.core.check_allocation`), and ``predict`` works in chunks, so
    it never holds more than a few tens of MB of kernel at once.

    Parameters
    ----------
    mean : {"auto", "none", "linear"}, default="auto"
        Mean function (see above).
    kernel : {"auto", "rbf", "matern52", "rbf+linear", "matern52+linear"}, default="auto"
        Kernel family (see above).
    per_output : {"auto"} or bool, default="auto"
        Separate hyperparameters per output component.
    max_samples : int, default=1000
        Rows the GP is fitted on (a random subset when the data has more; 10 to 20 000).
    selection_samples : int, default=250
        Rows the ``"auto"`` choices are made on (a subset of the ``max_samples``).
    kernel_bounds : {"auto", "ftcal", "stock"}, default="auto"
        Hyperparameter bounds and starting values (see above).
    n_restarts_optimizer : int, default=0
        Extra random starts of the marginal-likelihood optimiser for the final fit (the one of least held-out
        error is kept, not the one of most likelihood).
    alpha : float or None, default=None
        Torque scale ``Fmax / Tmax`` [m⁻¹]; ``None`` derives it from ``y``.
    zero_reading : array-like of shape (N,) or None, default=None
        Raw reading at zero load; ``None`` estimates it (see :mod:`ftcal.calibrators._zero_load`).
    random_state : int, RandomState or None, default=None
        Seed of the subsets and of the optimiser's restarts.

    Attributes
    ----------
    mean_ : str
        The mean function used.
    kernel_ : str
        The kernel family used.
    per_output_ : bool
        Whether each component has its own hyperparameters.
    kernel_bounds_ : str
        The bounds used (``"ftcal"`` or ``"stock"``).
    log_marginal_likelihood_ : dict
        ``"mean/kernel/bounds"`` -> log marginal likelihood (target units) of each combination tried.
    held_out_rmse_ : dict
        ``"mean/kernel/bounds"`` -> held-out RMSE (leave-one-out or leave-one-group-out, torque-scaled [N]) of
        each combination tried on the selection rows, ``"per_output_shared"`` / ``"per_output_separate"`` when
        compared, and ``"final"``: that of the fitted GP on its ``max_samples`` rows.
    linear_matrix_ : ndarray of shape (6, N)
        LTM mean in the torque-scaled space, per raw unit (zeros with ``mean_ == "none"``).
    linear_offset_ : ndarray of shape (6,)
        Its offset [N].
    input_mean_, input_scale_ : ndarray of shape (N,)
        Standardisation of the tare-corrected channels.
    train_inputs_ : ndarray of shape (m, N)
        The standardised readings the GP was fitted on.
    theta_ : ndarray of shape (k, n_hyperparameters)
        Log-hyperparameters of the fitted kernel(s) (``k = 6`` per output, else 1).
    dual_coef_ : ndarray of shape (m, 6)
        ``K⁻¹ y`` of the standardised targets.
    cholesky_ : ndarray of shape (k, m, m)
        Lower Cholesky factor(s) of ``K`` (noise included).
    target_mean_, target_scale_ : ndarray of shape (6,)
        Standardisation of the GP's targets [N].
    std_scale_ : ndarray of shape (6,)
        Factor (>= 1) of each component's predictive std, from rows the GP did not see (see above).
    alpha_, zero_reading_, n_features_in_
        As for every calibrator.

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import GaussianProcessCalibrator
    >>> rng = np.random.default_rng(0)
    >>> w = rng.uniform(-1, 1, size=(200, 6))
    >>> raw = (w + 0.1 * w**3) @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(200, 6))
    >>> gp = GaussianProcessCalibrator(alpha=1.0, random_state=0).fit(raw, w)
    >>> wrench, std = gp.predict(raw[:2], return_std=True)
    >>> wrench.shape, std.shape, bool((std > 0).all())
    ((2, 6), (2, 6), True)
    """

    _fitted_state = ("mean_", "kernel_", "per_output_", "kernel_bounds_", "held_out_rmse_", "linear_matrix_", "linear_offset_", "input_mean_",
                     "input_scale_", "train_inputs_", "theta_", "dual_coef_", "cholesky_", "target_mean_",
                     "target_scale_", "log_marginal_likelihood_", "std_scale_")
    _fitted_constraints: dict = {
        "mean_": [StrOptions(set(GP_MEANS))], "kernel_": [StrOptions(set(GP_KERNELS))],
        "kernel_bounds_": [StrOptions(set(GP_BOUNDS))], "per_output_": ["boolean"],
        "input_scale_": [Interval(Real, 0, None, closed="neither")],
        "target_scale_": [Interval(Real, 0, None, closed="neither")],
        "std_scale_": [Interval(Real, 1, None, closed="left")],
        # log-hyperparameters: every bound of make_kernel lies within exp(-30)..exp(30)
        "theta_": [Interval(Real, -30, 30, closed="both")],
    }
    #: What overflows for a reading far outside the training range (see ``check_finite_output``).
    _overflow_note = ("its kernel squares the distance from the reading to the training readings, in units of its "
                      "length scales, which exceeds float64's ~1.8e308 from a distance of ~1.3e154")

    _parameter_constraints: dict = {
        **BaseCalibrator._parameter_constraints,
        "mean": [StrOptions({"auto", *GP_MEANS})],
        "kernel": [StrOptions({"auto", *GP_KERNELS})],
        "per_output": [StrOptions({"auto"}), "boolean"],
        "kernel_bounds": [StrOptions({"auto", *GP_BOUNDS})],
        "max_samples": [Interval(Integral, 10, 20000, closed="both")],
        "selection_samples": [Interval(Integral, 10, 20000, closed="both")],
        "n_restarts_optimizer": [Interval(Integral, 0, 20, closed="both")],
    }

    def __init__(self, *, mean="auto", kernel="auto", per_output="auto", kernel_bounds="auto", max_samples=1000,
                 selection_samples=250, n_restarts_optimizer=0, alpha=None, zero_reading=None, random_state=None):
        self.mean = mean
        self.kernel = kernel
        self.per_output = per_output
        self.kernel_bounds = kernel_bounds
        self.max_samples = max_samples
        self.selection_samples = selection_samples
        self.n_restarts_optimizer = n_restarts_optimizer
        super().__init__(alpha=alpha, zero_reading=zero_reading, random_state=random_state)

    def _fit(self, X: NDArray[np.float64], y: NDArray[np.float64], groups: NDArray | None = None) -> None:
        n, n_channels = X.shape
        m = min(n, int(self.max_samples))
        n_theta = n_channels + 4
        # the optimiser holds K, its Cholesky factor and the gradient dK/dθ (m x m x n_theta) at once
        fits = rows_within_limit(8.0 * (n_theta + 3))  # the advice names a value that fits (GP's bound: >= 10)
        check_allocation(8.0 * m * m * (n_theta + 3), f"the GP's kernel and its gradient ({m} rows, {n_channels} "
                         "channels)", ("pass {max_samples} (the most rows within the limit), or use fewer channels"
                                       if fits >= 10 else "use fewer channels (a GP over this many channels does "
                                       "not fit the limit on 10 rows)"),
                         settings={"max_samples": fits} if fits >= 10 else None)
        xc = X - self.zero_reading_
        ys = scale_torques(y, self.alpha_, self.axes_)
        self.input_mean_ = xc.mean(axis=0)
        scale = xc.std(axis=0)
        self.input_scale_ = np.where(scale > 0, scale, 1.0)
        ltm = LinearRegression().fit(xc, ys)
        rng = check_random_state(self.random_state)
        rows = np.sort(rng.choice(n, size=m, replace=False)) if n > m else np.arange(n)
        u = (xc[rows] - self.input_mean_) / self.input_scale_
        targets = {"none": ys[rows], "linear": ys[rows] - ltm.predict(xc[rows])}
        seed = rng.randint(np.iinfo(np.int32).max)
        sel = np.sort(check_random_state(seed).choice(m, size=int(self.selection_samples), replace=False)) \
            if m > self.selection_samples else np.arange(m)
        group_rows = None if groups is None else groups[rows]
        bases = {mean: _mean_basis(mean, u) for mean in GP_MEANS}
        mean, family, bounds, per_output, theta = self._choose(
            u[sel], {k: v[sel] for k, v in targets.items()}, {k: v[sel] for k, v in bases.items()},
            None if group_rows is None else group_rows[sel], seed)
        target, basis = targets[mean], bases[mean]
        # the kernel's own start again only where it can reach another optimum: a shared fit on more rows than the
        # choice saw (on the same rows, the chosen optimum is that start's)
        starts = self._starts(family, bounds, theta, n_channels, seed, own_start=not per_output and len(sel) < m)
        columns = [[j] for j in range(target.shape[1])] if per_output else [list(range(target.shape[1]))]
        regressors, errors = [], []
        for j, cols in enumerate(columns):  # each from the start of least held-out error (not of most likelihood)
            tried = [_fit_quietly(make_kernel(family, n_channels, bounds).clone_with_theta(start[j]), seed, u,
                                  target[:, cols]) for start in starts]
            scores = [_held_out_mse(gp, basis, group_rows) for gp in tried]
            best = int(np.argmin(scores))
            regressors.append(tried[best])
            errors.append(scores[best] * len(cols))
        self.held_out_rmse_["final"] = float(np.sqrt(sum(errors) / target.shape[1]))
        self.kernel_bounds_ = bounds
        self.mean_, self.kernel_, self.per_output_ = mean, family, len(regressors) > 1
        linear = mean == "linear"
        self.linear_matrix_ = np.asarray(ltm.coef_) if linear else np.zeros((ys.shape[1], n_channels))
        self.linear_offset_ = np.asarray(ltm.intercept_) if linear else np.zeros(ys.shape[1])
        self.train_inputs_ = u
        self.theta_ = np.stack([g.kernel_.theta for g in regressors])
        self.dual_coef_ = np.column_stack([np.asarray(g.alpha_).reshape(m, -1) for g in regressors])
        self.cholesky_ = np.stack([np.asarray(g.L_) for g in regressors])
        self.target_mean_ = np.concatenate([np.atleast_1d(g._y_train_mean) for g in regressors])
        self.target_scale_ = np.concatenate([np.atleast_1d(g._y_train_std) for g in regressors])
        self.std_scale_ = np.ones(target.shape[1])  # the GP's own std, to be calibrated
        z = [_left_out_z(g, basis, group_rows) for g in regressors]
        z = [np.column_stack(z)] if all(len(part) for part in z) else []
        unseen = np.setdiff1d(np.arange(n), rows)
        if groups is not None:  # a row of a group the subset holds is not new: only unseen groups count
            unseen = unseen[~np.isin(groups[unseen], groups[rows])]
        if unseen.size:  # rows outside the subset: held out for real
            unseen = np.sort(check_random_state(seed).choice(unseen, size=min(unseen.size, _STD_ROWS),
                                                             replace=False))
            mean_u, std_u = self._predict_scaled(X[unseen], True)
            z.append(np.abs(mean_u - ys[unseen]) / np.maximum(std_u, np.finfo(float).tiny))
        if z:
            self.std_scale_ = np.maximum(1.0, np.quantile(np.vstack(z), _STD_COVERAGE, axis=0) / _STD_Z)
        else:
            warnings.warn(f"GaussianProcessCalibrator: {n} rows leave no degree of freedom beyond the {mean} mean's "
                          f"{basis.shape[1]} coefficients, so the predictive std could not be calibrated: it is "
                          "likely too narrow. Record more rows.", UserWarning, stacklevel=4)

    def _choose(self, u, targets, bases, groups, seed):
        """Mean, kernel family, bounds, per-output flag and start hyperparameters (one row per regressor), by
        **held-out error** on ``u``: each combination's closed-form leave-one-out error (leave-one-group-out with
        ``groups``; Rasmussen & Williams eq. 5.12) at its marginal-likelihood optimum. The likelihood alone
        overfits on a few hundred rows of correlated channels (an optimum of higher likelihood that predicts new
        rows worse), so it only fits the hyperparameters; the choice is by the errors on rows left out."""
        n, n_channels = u.shape
        k = targets["none"].shape[1]  # outputs (6 for a wrench)
        combos = [(mean, family) for mean, family in _AUTO_COMBINATIONS
                  if self.mean in ("auto", mean) and self.kernel in ("auto", family)]
        combos = combos or [(self.mean, self.kernel)]  # a combination outside the automatic list, asked for explicitly
        combos = [(mean, family, bounds) for mean, family in combos for bounds in GP_BOUNDS
                  if self.kernel_bounds in ("auto", bounds)]
        self.log_marginal_likelihood_, self.held_out_rmse_ = {}, {}
        if len(combos) == 1 and self.per_output is False:  # nothing to choose: the final fit starts from the default
            mean, family, bounds = combos[0]
            return mean, family, bounds, False, make_kernel(family, n_channels, bounds).theta[None, :]
        errors, fitted = {}, {}
        for combo in combos:
            mean, family, bounds = combo
            fitted[combo] = gp = _fit_quietly(make_kernel(family, n_channels, bounds), seed, u, targets[mean])
            errors[combo] = _held_out_mse(gp, bases[mean], groups)
            self.log_marginal_likelihood_["/".join(combo)] = _log_evidence(gp, targets[mean])
            self.held_out_rmse_["/".join(combo)] = float(np.sqrt(errors[combo]))
        mean, family, bounds = best = min(errors, key=errors.get)
        shared = fitted[best]
        if self.per_output is False or k == 1:
            return mean, family, bounds, False, shared.kernel_.theta[None, :]
        # per-output fits from the shared optimum on at most _PER_OUTPUT_ROWS rows (six fits: kept cheap)
        few = slice(None) if n <= _PER_OUTPUT_ROWS else np.sort(
            check_random_state(seed).choice(n, size=_PER_OUTPUT_ROWS, replace=False))
        u, target, basis = u[few], targets[mean][few], bases[mean][few]
        groups = None if groups is None else groups[few]
        shared_few = _fit_quietly(shared.kernel_, seed, u, target, optimizer=None)
        separate = [_fit_quietly(shared.kernel_, seed, u, target[:, [j]]) for j in range(k)]
        shared_error = _held_out_mse(shared_few, basis, groups)
        separate_error = float(np.mean([_held_out_mse(g, basis, groups) for g in separate]))
        self.held_out_rmse_["per_output_shared"] = float(np.sqrt(shared_error))
        self.held_out_rmse_["per_output_separate"] = float(np.sqrt(separate_error))
        if self.per_output is True or separate_error < shared_error:
            return mean, family, bounds, True, np.stack([g.kernel_.theta for g in separate])
        return mean, family, bounds, False, shared.kernel_.theta[None, :]

    def _starts(self, family: str, bounds: str, theta: NDArray[np.float64], n_channels: int, seed: int,
                own_start: bool = True) -> list[NDArray]:
        """Starting hyperparameters of the final fit, one row per regressor in each: the chosen ones, the kernel's
        own start (with ``own_start``, when it differs: an optimum reached from there may predict better), and
        ``n_restarts_optimizer`` drawn uniformly (in log) within the bounds; ``fit`` keeps the start whose
        optimum has the least held-out error."""
        kernel = make_kernel(family, n_channels, bounds)
        default = np.broadcast_to(kernel.theta, theta.shape)
        starts = [theta] + ([default] if own_start and not np.allclose(default, theta) else [])
        rng = check_random_state(seed)
        low, high = kernel.bounds[:, 0], kernel.bounds[:, 1]
        starts += [rng.uniform(low, high, size=theta.shape) for _ in range(int(self.n_restarts_optimizer))]
        return starts

    def __sklearn_tags__(self):
        # one length scale per channel to learn: 10 rows per channel; cubic in its rows; chooses its mean and
        # kernel once (structure_params)
        return declare(super().__sklearn_tags__(), cost="kernel", family="kernel", provides_std=True,
                       chooses_structure=True,
                       min_training_rows=lambda n_channels: 10 * n_channels)

    def structure_params(self) -> dict:
        """The choices ``fit`` made (mean, kernel family, per output) as parameters.

        :class:`~ftcal.AutoCalibrator` lets the GP choose them on its first
        training fold (that fold's model), then scores the other folds and
        refits with these fixed (their hyperparameters still fitted on each
        training fold alone).
        """
        check_is_fitted(self)
        return {"mean": self.mean_, "kernel": self.kernel_, "per_output": bool(self.per_output_),
                "kernel_bounds": self.__dict__.get("kernel_bounds_", "ftcal")}

    def latent_covariance(self, X: ArrayLike):
        """Posterior covariance of the GP part at raw readings ``X`` (n, N), summed over the outputs.

        In the torque-scaled units of the fit [N²]: per regressor, ``s² (K_xx - K_xt K_tt⁻¹ K_tx)`` with its
        kernel less the white noise and ``s`` its output scale (``normalize_y``) times the calibration factor
        ``std_scale_``. The diagonal plus ``noise`` is the sum over the outputs of ``predict(X,
        return_std=True)``'s variance (torque-scaled). It leaves out the uncertainty of the linear mean. Used to
        choose where to measure next.

        Returns
        -------
        columns : callable
            ``columns(idx)`` -> the (n, len(idx)) block of the covariance with the rows ``idx``.
        diagonal : ndarray of shape (n,)
        noise : float
            The fitted noise variance, summed over the outputs [N²].
        """
        from scipy.linalg import solve_triangular

        check_is_fitted(self)
        X = np.asarray(X, dtype=float)
        u = (X - self.zero_reading_ - self.input_mean_) / self.input_scale_
        regressors = self.regressors()
        parts, noise = [], 0.0
        calibration = self._std_factors()
        for i, gp in enumerate(regressors):
            cols = slice(None) if len(regressors) == 1 else slice(i, i + 1)
            s2 = float(np.sum((self.target_scale_[cols] * calibration[cols]) ** 2))
            kernel = gp.kernel_.k1  # the white noise is the last term of every kernel family
            noise += float(gp.kernel_.k2.noise_level) * s2
            V = solve_triangular(gp.L_, kernel(self.train_inputs_, u), lower=True, check_finite=False)
            parts.append((kernel, V, s2, np.maximum(kernel.diag(u) - np.sum(V * V, axis=0), 0.0) * s2))
        diagonal = sum(p[3] for p in parts)

        def columns(idx):
            return sum((kernel(u, u[idx]) - V.T @ V[:, idx]) * s2 for kernel, V, s2, _ in parts)

        return columns, diagonal, noise

    def regressors(self) -> list[GaussianProcessRegressor]:
        """The fitted :class:`~sklearn.gaussian_process.GaussianProcessRegressor` (one, or one per component).

        Rebuilt from the fitted arrays on each call (cheap: no computation), so a loaded model has them too
        and ``predict`` changes nothing in the calibrator.
        """
        check_is_fitted(self)
        n_channels = self.train_inputs_.shape[1]
        k = self.theta_.shape[0]
        regressors = []
        for i in range(k):
            gp = _regressor(make_kernel(self.kernel_, n_channels).clone_with_theta(self.theta_[i]), None)
            cols = slice(None) if k == 1 else slice(i, i + 1)
            gp.kernel_, gp.X_train_, gp.L_ = gp.kernel, self.train_inputs_, self.cholesky_[i]
            gp.alpha_, gp._y_train_mean = self.dual_coef_[:, cols], self.target_mean_[cols]
            gp._y_train_std, gp.n_features_in_ = self.target_scale_[cols], n_channels
            regressors.append(gp)
        return regressors

    def _std_factors(self) -> NDArray[np.float64]:
        """``std_scale_``, checked (a model file may have been edited); ones for files saved before it existed."""
        scale = self.__dict__.get("std_scale_")
        if scale is None:
            return np.ones_like(self.target_scale_)
        if np.shape(scale) != self.target_scale_.shape or not np.all(np.isfinite(scale)) or not np.all(
                np.asarray(scale) >= 1.0):
            raise ModelFileError(f"std_scale_ must hold {self.target_scale_.size} finite factors >= 1, one per "
                                 f"output; it is {np.asarray(scale)!r}. The model file is damaged or was edited: fit "
                                 "and save the model again.")
        return np.asarray(scale, dtype=float)

    def _predict_scaled(self, X: NDArray[np.float64], return_std: bool):
        xc = X - self.zero_reading_
        u = (xc - self.input_mean_) / self.input_scale_
        chunk = max(1, _CHUNK_BYTES // (8 * len(self.train_inputs_)))  # rows whose cross-kernel fits the bytes
        mean = xc @ self.linear_matrix_.T + self.linear_offset_
        std = np.empty_like(mean) if return_std else None
        scale = self._std_factors() if return_std else None
        regressors = self.regressors()
        for start in range(0, len(u), chunk):
            rows = slice(start, start + chunk)
            for i, gp in enumerate(regressors):
                cols = slice(None) if len(regressors) == 1 else slice(i, i + 1)
                if return_std:
                    with warnings.catch_warnings():
                        warnings.simplefilter("ignore", UserWarning)  # "negative variance set to 0"
                        mu, sd = gp.predict(u[rows], return_std=True)
                    std[rows, cols] = sd.reshape(mu.shape[0], -1) * scale[cols]
                else:
                    mu = gp.predict(u[rows])
                mean[rows, cols] += mu.reshape(mu.shape[0], -1)
        return mean, std

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        return unscale_torques(self._predict_scaled(X, False)[0], self.alpha_, self.axes_)

    def _emit_onnx(self, g, x: str) -> str:
        """The predictive mean as ONNX: the linear mean plus each regressor's ``k(u, X_train) @ alpha`` (the white
        noise term is zero between distinct points), de-normalised as ``normalize_y`` does."""
        xc = g.op("Sub", x, g.const(self.zero_reading_))
        u = g.op("Div", g.op("Sub", xc, g.const(self.input_mean_)), g.const(self.input_scale_))
        columns = []
        for gp in self.regressors():  # each from its kernel less the noise, de-normalised by its own scale
            constant, stationary, linear_constant, dot, _ = _kernel_parts(gp.kernel_)  # make_kernel's terms
            ell = np.asarray(stationary.length_scale, dtype=float) * np.ones(self.train_inputs_.shape[1])
            kernel = onnx_kernel(g, u, self.train_inputs_, ell, float(constant.constant_value),
                                 matern=type(stationary) is Matern)
            if dot is not None:
                linear = g.op("Add", g.op("MatMul", u, g.const(self.train_inputs_.T)), g.const(float(dot.sigma_0) ** 2))
                kernel = g.op("Add", kernel, g.op("Mul", g.const(float(linear_constant.constant_value)), linear))
            columns.append(g.op("Add", g.op("Mul", g.op("MatMul", kernel, g.const(gp.alpha_)),
                                             g.const(gp._y_train_std)), g.const(gp._y_train_mean)))
        residual = columns[0] if len(columns) == 1 else g.op("Concat", *columns, axis=1)
        mean = g.op("Add", g.affine(xc, self.linear_matrix_.T, self.linear_offset_), residual)
        return g.unscale_torques(mean, self.alpha_, int(getattr(self, "n_outputs_", 6)), self.axes_)

    def predict(self, X: ArrayLike, return_std: bool = False):
        """Wrench in [N] and [N·m] for raw readings ``X`` (n, N); with ``return_std`` also its standard deviation.

        Parameters
        ----------
        X : array-like of shape (n_samples, n_channels)
        return_std : bool, default=False
            ``True`` or ``False`` (numpy booleans too); anything else raises
            :class:`~ftcal.core.CalibrationInputError`.

        Returns
        -------
        wrench : ndarray of shape (n_samples, 6)
        std : ndarray of shape (n_samples, 6), only with ``return_std=True``
            Predictive standard deviation of each component, [N] and [N·m].
            (Both ``(n_samples,)`` for a calibrator fitted on a 1-D ``y``.)
        """
        if not check_bool(return_std, "return_std"):
            return super().predict(X)
        check_is_fitted(self)
        X = self._retared(validate_readings(self, X))
        with np.errstate(over="ignore", invalid="ignore"):  # an overflow is reported below, naming the reading
            mean, std = self._predict_scaled(X, True)
            wrench, std = unscale_torques(mean, self.alpha_, self.axes_), unscale_torques(std, self.alpha_, self.axes_)
        check_finite_output(X, wrench, self)
        check_finite_output(X, std, self, what="standard deviation")
        return (wrench[:, 0], std[:, 0]) if self.__dict__.get("y_1d_") else (wrench, std)
