"""Polynomial calibration: polynomial features of the raw channels with a ridge penalty."""

from __future__ import annotations

import math
import warnings
from numbers import Integral, Real

import numpy as np
from numpy.typing import NDArray
from sklearn.utils._param_validation import Interval
from sklearn.preprocessing import PolynomialFeatures

from ..core._memory import check_allocation
from ._base import BaseCalibrator, GroupsFit, declare
from ..core._exceptions import CalibrationInputError
from ._ridge import group_means, ridge_least_squares

__all__ = ["PolynomialCalibrator"]

#: Batch size of ``predict`` (degree 5 on 6 channels makes 461 features per row).
_PREDICT_CHUNK = 8192
#: Largest batch of monomials ``predict`` builds at once [bytes].
_PREDICT_BYTES = 256 * 2**20


#: Least share (in standard deviation) of the wrench's spread, along every direction in which it varies, that must
#: vary *within* the groups for ``group_offsets``: below it an offset and a load are told apart by less than the
#: ~1 % accuracy of a good reference load, i.e. not at all.
MIN_WITHIN_FRACTION = 0.01


def within_group_load_fraction(y: NDArray[np.float64], groups: NDArray) -> float:
    """The smallest share of the wrench's spread (standard deviation) that varies within the groups, over the
    directions in which the wrench varies at all (a wrench of rank < 6, e.g. one tool's torques ``c x F``, is fine).

    Examples
    --------
    >>> y = np.array([[0.0], [1.0], [10.0], [11.0]])
    >>> round(within_group_load_fraction(y, np.array([0, 0, 1, 1])), 4)  # squares: 1 within, 101 in all
    0.0995
    """
    z = y - y.mean(axis=0)
    values, vectors = np.linalg.eigh(z.T @ z)
    keep = values > 1e-9 * max(values.max(initial=0.0), np.finfo(float).tiny)
    if not keep.any():
        return 0.0
    whitened = z @ vectors[:, keep] / np.sqrt(values[keep])  # unit spread along each varying direction
    means, index = group_means(whitened, groups)
    within = whitened - means[index]
    return float(np.sqrt(max(np.linalg.eigvalsh(within.T @ within).min(), 0.0)))


def onnx_monomials(g, u: str, powers: NDArray[np.integer]) -> str:
    """The ONNX graph of the monomials ``prod_c u[:, c] ** powers[j, c]`` (n, n_monomials) of the rows ``u`` (n, N):
    the features of this model's graph and of the stock polynomial baselines'."""
    expanded = g.op("Unsqueeze", u, g.const([1], np.int64))  # (n, 1, N) ** (n_monomials, N)
    return g.op("ReduceProd", g.op("Pow", expanded, g.const(np.asarray(powers, dtype=np.float64))), axes=[2],
                keepdims=0)


class PolynomialCalibrator(GroupsFit, BaseCalibrator):
    """Wrench as a polynomial of the zero-corrected raw channels, fitted by ridge least squares.

    The model published for in-situ calibration of humanoid-robot sensors
    (a 4th-degree polynomial halved the affine model's RMSE). It is a thin
    composition of scikit-learn's :class:`~sklearn.preprocessing.PolynomialFeatures`
    and ridge least squares:

    1. ``u = (X - zero_reading_) / input_scale_``, where ``input_scale_`` is the
       largest absolute zero-corrected training reading of each channel, so
       ``|u| <= 1`` on the training data and the monomials stay well conditioned;
    2. all monomials of ``u`` up to ``degree`` (without the constant),
       ``PolynomialFeatures(degree, include_bias=False)``;
    3. ``W = P(u) @ coef_ + intercept_`` minimising
       ``||W - P(u) coef - b||² + ridge * ||coef_nonlinear||²``: the penalty
       acts on the coefficients of the monomials of degree >= 2 only (not on
       the linear terms nor the intercept), so ``degree=1`` is exactly the LTM
       (:class:`~ftcal.LinearCalibrator`) for any ``ridge``.

    Every output component is fitted separately (the torque scale ``alpha_``
    only enters the metrics, as for the LTM). A polynomial extrapolates
    poorly beyond the training range; keep test loads inside the calibrated
    range or prefer :class:`~ftcal.AxisNonlinearCalibrator`.

    Parameters
    ----------
    degree : int, default=3
        Highest total degree of the monomials, 1 to 5 (1 = LTM). The number
        of features grows fast: 83 (degree 3), 209 (4), 461 (5) for 6 channels.
    ridge : float, default=1e-4
        Penalty on the nonlinear coefficients; ``u`` is dimensionless, and the
        penalty is multiplied by the number of samples. Tuned on the
        artificial presets (5 datasets each, degree 3): 1e-3 is best on
        ``thesis`` / ``asymmetric`` by ~1 % but 28 % worse on ``stress``;
        1e-6 overfits (see ``benchmarks/RESULTS.md``, "beyond the thesis"). Use
        ``ftcal tune --model polynomial`` for your data.
    group_offsets : bool, default=False
        With ``fit(X, y, groups=...)``: every group (a pose, a session, a
        mounting) may shift all its readings by an offset of its own, as a
        re-mounted, re-tared or warmed-up sensor does. The map is then fitted
        on the variation *within* the groups only (one free intercept per
        group, the fixed-effects estimator: an offset can no longer be
        mistaken for the load a pose carries, e.g. its tool's weight), and
        ``predict`` uses the mean of the groups' intercepts. It needs loads
        that vary within the groups along every direction the wrench takes
        (:data:`MIN_WITHIN_FRACTION`; else an error says so); without groups it
        changes nothing (with a warning). Every group
        weighs the same in the mean offset, whatever its number of rows; the
        estimated tare (``zero_reading=None``) is the mean group's too, so a
        re-tare stays exact. ``degree=1`` with it is the LTM with group
        offsets. :class:`~ftcal.AutoCalibrator` tries it when given groups.
    alpha : float or None, default=None
        Torque scale ``Fmax / Tmax`` [m⁻¹]; ``None`` derives it from ``y``.
    zero_reading : array-like of shape (N,) or None, default=None
        Raw reading at zero load; ``None`` estimates it (see :mod:`ftcal.calibrators._zero_load`).
    random_state : None
        Unused (the fit is deterministic); accepted for a common signature.

    Attributes
    ----------
    input_scale_ : ndarray of shape (N,)
        Normalisation of each zero-corrected channel (raw units).
    coef_ : ndarray of shape (n_monomials, 6)
        Coefficients in [N] / [N·m], in ``PolynomialFeatures`` order.
    intercept_ : ndarray of shape (6,)
        [N] / [N·m].
    alpha_, zero_reading_, n_features_in_
        As for every calibrator.

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import PolynomialCalibrator
    >>> rng = np.random.default_rng(0)
    >>> raw = rng.uniform(-1, 1, size=(200, 6))
    >>> wrench = raw + 0.1 * raw**2
    >>> model = PolynomialCalibrator(degree=2, ridge=0.0, zero_reading=np.zeros(6)).fit(raw, wrench)
    >>> bool(np.allclose(model.predict(raw), wrench))
    True
    """

    _fitted_state = ("input_scale_", "coef_", "intercept_")
    _fitted_constraints: dict = {"input_scale_": [Interval(Real, 0, None, closed="neither")]}
    _parameter_constraints: dict = {
        **BaseCalibrator._parameter_constraints,
        "degree": [Interval(Integral, 1, 5, closed="both")],
        "ridge": [Interval(Real, 0, None, closed="left")],
        "group_offsets": ["boolean"],
    }

    def __init__(self, *, degree=3, ridge=1e-4, group_offsets=False, alpha=None, zero_reading=None,
                 random_state=None):
        self.degree = degree
        self.ridge = ridge
        self.group_offsets = group_offsets
        super().__init__(alpha=alpha, zero_reading=zero_reading, random_state=random_state)

    _groups_purpose = ("one offset per group", "fit without group_offsets")
    #: Takes ``sample_weight`` and asks for it through metadata routing by default (``groups`` too: GroupsFit).
    __metadata_request__fit = {"sample_weight": True}

    def fit(self, X, y, groups=None, sample_weight=None):
        """Fit on raw readings ``X`` (n, N) and wrenches ``y`` (n, 6).

        Parameters
        ----------
        groups : array-like of shape (n,) or None
            Group of each row (pose, session): one offset per group with ``group_offsets=True``; else only
            checked for its length.
        sample_weight : array-like of shape (n,) or None
            Weight of each row's squared residual (weighted least squares; the penalty is ``ridge`` times the
            sum of the weights, so weights that are all equal give the unweighted fit). ``None``: all rows alike.

        Returns
        -------
        self
        """
        return self._checked_fit(X, y, groups, sample_weight)

    def _uses_groups(self) -> bool:
        return bool(self.group_offsets)

    def __sklearn_tags__(self):
        degree = self.degree  # its feature count (with the intercept) training rows
        family = "linear" if degree == 1 else f"polynomial{degree}"
        return declare(super().__sklearn_tags__(), cost="closed_form", family=family,
                       min_training_rows=lambda n_channels: math.comb(n_channels + int(degree), int(degree)))

    def _monomials(self) -> PolynomialFeatures:
        # Fitted on one row only to learn the channel count: the monomials depend on nothing else.
        return PolynomialFeatures(int(self.degree), include_bias=False).fit(np.zeros((1, self.n_features_in_)))

    def _fit(self, X: NDArray[np.float64], y: NDArray[np.float64], groups: NDArray | None = None,
             sample_weight: NDArray[np.float64] | None = None) -> None:
        n, n_channels = X.shape
        n_features = self._monomials().n_output_features_  # degree 1..d of N variables: C(N + d, d) - 1
        penalised = n_features - n_channels
        # the features, their centred copy and the ridge-augmented system lstsq copies, plus its identity block
        check_allocation(
            8.0 * (3.0 * (n + penalised) * n_features + float(penalised) ** 2),
            f"PolynomialCalibrator(degree={self.degree}) on {n} samples x {n_channels} channels "
            f"({n_features} monomials)",
            "lower degree (degree=1 is the LTM), use fewer channels, or try AxisNonlinearCalibrator",
        )
        if self.group_offsets and groups is None:
            warnings.warn("PolynomialCalibrator: group_offsets=True but fit() got no groups, so the fit has one "
                          "offset for all rows. Pass fit(X, y, groups=...) (a pose or session per row).",
                          UserWarning, stacklevel=4)
        if groups is not None:
            fraction = within_group_load_fraction(y, groups)
            if fraction < MIN_WITHIN_FRACTION:
                raise CalibrationInputError(
                    f"group_offsets=True: along some direction of the wrench, the loads vary within the "
                    f"{np.unique(groups).size} groups by {fraction:.2%} of their spread across all rows (at least "
                    f"{MIN_WITHIN_FRACTION:.0%} is needed), so a group's offset cannot be told from its load. Fix: fit "
                    "without group_offsets, or record loads that vary within each group (pose).")
            if self.zero_reading is None:  # the tare of the mean group, as the intercept is (re-tare stays exact)
                self.zero_reading_ = ridge_least_squares(y, X, 0.0, n_unpenalised=y.shape[1], groups=groups)[1]
        xc = X - self.zero_reading_
        scale = np.abs(xc).max(axis=0)
        self.input_scale_ = np.where(scale > 0, scale, 1.0)
        features = self._monomials().transform(xc / self.input_scale_)
        total = len(y) if sample_weight is None else float(sample_weight.sum())  # the penalty per unit of weight
        self.coef_, self.intercept_ = ridge_least_squares(features, y, float(self.ridge) * total,
                                                          n_unpenalised=X.shape[1], groups=groups,
                                                          sample_weight=sample_weight)

    def _predict_wrench(self, X: NDArray[np.float64]) -> NDArray[np.float64]:
        monomials = self._monomials()
        u = (X - self.zero_reading_) / self.input_scale_
        # rows per batch: at most _PREDICT_CHUNK, and a batch of monomials of at most 256 MiB
        chunk = int(max(1, min(_PREDICT_CHUNK, _PREDICT_BYTES // (8 * max(len(self.coef_), 1)))))
        out = [monomials.transform(u[i : i + chunk]) @ self.coef_ for i in range(0, len(u), chunk)]
        return (np.concatenate(out) if out else np.zeros((0, len(self.intercept_)))) + self.intercept_

    def _emit_onnx(self, g, x: str) -> str:
        u = g.op("Div", g.op("Sub", x, g.const(self.zero_reading_)), g.const(self.input_scale_))
        return g.affine(onnx_monomials(g, u, self._monomials().powers_), self.coef_, self.intercept_)
