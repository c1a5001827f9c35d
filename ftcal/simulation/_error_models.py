"""Sensor error models of the artificial datasets (thesis section IV-A-c, eq. 11-14, and II-A-d).

Two objects: :class:`ErrorModel` holds the *nominal* error configuration a
preset names (means, how many axes are hit, the relative spread), and
:meth:`ErrorModel.sample` draws the *per-dataset* parameters, a
:class:`SampledErrors`, which then maps true wrenches to erroneous ones.

All errors act in the **torque-scaled** wrench space (torques times
``alpha``), where the six components share one unit; that makes the
crosstalk of eq. 13 between a force and a torque dimensionally sound and lets
one full-scale value serve every axis. Every parameter is drawn from a
normal distribution with a standard deviation of ``spread`` (10 %) of its
mean; the affected axes (and crosstalk pairs) are drawn per dataset.

The errors, in the order they are applied
-----------------------------------------
1. Asymmetric sensitivity (II-A-d; not simulated in the thesis):
   ``C' = C (1 + a/2)`` for ``C > 0`` and ``C (1 - a/2)`` for ``C < 0`` on
   ``asymmetry_axes`` random axes: + and - loads stress different gauges
   whose gains differ by ``a``. A linear model can only fit the mean gain.
2. Creep (eq. 11): ``C' = C (1 + δ)`` on ``creep_axes`` random axes.
3. Crosstalk (eq. 13): ``C_j' = C_j + k_ij C_i`` for ``crosstalk_pairs``
   random ordered pairs ``i != j`` (all pairs read the pre-crosstalk values).
4. Nonlinearity (eq. 14), normalised by full scale:
   ``C' = C (1 + γ |C / FS|^(n-1))`` on ``nonlinearity_axes`` random axes.
   The error at full scale is ``γ FS``, so ``γ`` *is* the maximum error in
   fractions of full scale. Read literally with ``C`` in newtons, the thesis'
   ``γ = 1e-3, n = 2.5`` would multiply a 2000 N load by 90; its text says
   that ``γ``'s mean corresponds to 1 % FS and that the maximum is 1.2 % FS,
   so the ``thesis`` preset uses ``γ ~ N(1 %, 0.1 %)``: 1 % FS at the mean,
   1.2 % FS at the +2σ tail of the datasets.
5. Multiplicative noise (eq. 12): ``w_noisy = w' + w' η`` with
   ``η_i ~ N(0, σ_s²)`` independently per component and sample; ``σ_s`` is
   drawn per sample from ``N(σ_d, (spread σ_d)²)`` ("the exact value for each
   sample", IV-A-c) around the dataset's ``σ_d ~ N(σ, (spread σ)²)``. Noise is
   applied last, to the wrench the gauges see, so that the noise floor (what
   a perfect calibrator would still miss) is exactly the difference between
   the noisy and the noise-free erroneous wrench.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, field, fields
from numbers import Integral

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import CalibrationInputError
from ..core._files import is_finite_number
from ..core._wrench import WRENCH_LABELS, scale_torques, unscale_torques

__all__ = ["ErrorModel", "SampledErrors"]


def _check_wrench(wrench: ArrayLike) -> NDArray[np.float64]:
    w = np.asarray(wrench, dtype=float)
    if w.ndim != 2 or w.shape[1] != 6:
        raise CalibrationInputError(f"wrench must have shape (n_samples, 6) {list(WRENCH_LABELS)}; got shape {w.shape}.")
    if not np.all(np.isfinite(w)):
        raise CalibrationInputError(f"wrench contains NaN or inf (first at row {int(np.argwhere(~np.isfinite(w))[0, 0])}).")
    return w


@dataclass(frozen=True)
class ErrorModel:
    """Nominal error configuration; every magnitude ``0`` switches that error off.

    Parameters
    ----------
    creep : float
        Mean creep factor δ (eq. 11), relative gain; thesis 0.003.
    creep_axes : int
        Axes (of 6) given creep per dataset.
    noise : float
        Mean relative noise σ (eq. 12); thesis 0.01.
    crosstalk : float
        Mean crosstalk factor k (eq. 13); thesis 0.05.
    crosstalk_pairs : int
        Ordered axis pairs coupled per dataset.
    nonlinearity : float
        Mean γ of eq. 14 normalised by full scale = error at full scale / FS.
    nonlinearity_exponent : float
        Exponent ``n`` of eq. 14; thesis 2.5.
    nonlinearity_axes : int
        Axes given nonlinearity per dataset.
    asymmetry : float
        Mean gain difference ``a`` between + and - loads.
    asymmetry_axes : int
        Axes given the asymmetric sensitivity per dataset.
    spread : float
        Standard deviation of every drawn parameter relative to its mean; thesis 0.10.

    Examples
    --------
    >>> m = ErrorModel(creep=0.003, creep_axes=2)
    >>> e = m.sample(np.full(6, 2000.0), 50.0, np.random.default_rng(0))
    >>> int(np.sum(e.creep_gain != 1.0))
    2
    """

    creep: float = 0.0
    creep_axes: int = 3
    noise: float = 0.0
    crosstalk: float = 0.0
    crosstalk_pairs: int = 3
    nonlinearity: float = 0.0
    nonlinearity_exponent: float = 2.5
    nonlinearity_axes: int = 3
    asymmetry: float = 0.0
    asymmetry_axes: int = 3
    spread: float = 0.10

    def __post_init__(self) -> None:
        # plain checks, not scikit-learn's: the presets are built when the CLI starts.
        # Relative magnitudes: 1 is 100 %; a sign-dependent gain of a = 1 already means gains of 1.5 and 0.5
        # (beyond 2 a gain changes sign): a larger value is a unit mistake. Rows: (name, low, high, integer, allowed).
        magnitude = "a number from 0 to 1 (a relative magnitude, 1 = 100 %)"
        checks = [(name, 0, 1, False, magnitude)
                  for name in ("creep", "noise", "crosstalk", "nonlinearity", "asymmetry", "spread")]
        checks += [(name, 0, top, True, f"an integer from 0 to {top}") for name, top in
                   (("creep_axes", 6), ("nonlinearity_axes", 6), ("asymmetry_axes", 6), ("crosstalk_pairs", 30))]
        checks.append(("nonlinearity_exponent", 1, 10, False, "a number from 1 to 10 (thesis: 2.5)"))
        for name, low, high, integer, allowed in checks:
            value = getattr(self, name)
            if not (is_finite_number(value) and (isinstance(value, Integral) or not integer) and low <= value <= high):
                raise CalibrationInputError(f"ErrorModel.{name} must be {allowed}; got {value!r} "
                                            f"({type(value).__name__}).")

    def to_dict(self) -> dict:
        """Plain-JSON form."""
        return asdict(self)

    def _draw(self, mean: float, size: int, rng: np.random.Generator) -> NDArray[np.float64]:
        return rng.normal(mean, self.spread * mean, size=size)

    def _on_axes(self, mean: float, count: int, n: int, rng: np.random.Generator) -> NDArray[np.float64]:
        """``n`` values, zero but on ``count`` of them drawn at random, which get draws around ``mean``."""
        values = np.zeros(n)
        if mean > 0 and count:
            chosen = rng.choice(n, count, replace=False)
            values[chosen] = self._draw(mean, chosen.size, rng)
        return values

    def sample(self, full_scale: ArrayLike, alpha: float, rng: np.random.Generator) -> "SampledErrors":
        """Draw one dataset's error parameters.

        Parameters
        ----------
        full_scale : array-like of shape (6,)
            Rated range per axis [N] x3, [N·m] x3.
        alpha : float
            Torque scale [m⁻¹] of the space the errors act in.
        rng : numpy.random.Generator
            Random source.
        """
        creep_gain = 1.0 + self._on_axes(self.creep, self.creep_axes, 6, rng)
        # the ordered pairs (j, i), i != j, in row-major order: the off-diagonal entries of the coupling matrix
        coupling = np.zeros((6, 6))
        coupling[~np.eye(6, dtype=bool)] = self._on_axes(self.crosstalk, self.crosstalk_pairs, 30, rng)
        gamma = self._on_axes(self.nonlinearity, self.nonlinearity_axes, 6, rng)
        asym = self._on_axes(self.asymmetry, self.asymmetry_axes, 6, rng)
        sigma = float(max(self._draw(self.noise, 1, rng)[0], 0.0)) if self.noise > 0 else 0.0
        return SampledErrors(alpha=float(alpha), full_scale=np.asarray(full_scale, dtype=float), creep_gain=creep_gain,
                             crosstalk=coupling, nonlinearity_gamma=gamma, asymmetry=asym,
                             nonlinearity_exponent=float(self.nonlinearity_exponent), noise_sigma=sigma,
                             noise_sigma_spread=self.spread * sigma)


@dataclass
class SampledErrors:
    """One dataset's concrete error parameters (from :meth:`ErrorModel.sample`).

    Attributes
    ----------
    alpha : float
        Torque scale [m⁻¹] of the space the errors act in.
    full_scale : tuple of 6 floats
        Rated range per axis [N] / [N·m] (eq. 14's normaliser).
    creep_gain : ndarray (6,)
        ``1 + δ`` per axis (1 where no creep).
    crosstalk : ndarray (6, 6)
        ``crosstalk[j, i] = k_ij``: share of component ``i`` added to ``j``.
    nonlinearity_gamma : ndarray (6,)
        γ per axis (0 where none), error at full scale / FS.
    nonlinearity_exponent : float
        ``n`` of eq. 14.
    asymmetry : ndarray (6,)
        Gain difference between + and - loads per axis.
    noise_sigma : float
        The dataset's mean relative noise σ_d.
    noise_sigma_spread : float
        Standard deviation of the per-sample σ_s around σ_d.
    """

    alpha: float
    full_scale: tuple
    creep_gain: NDArray[np.float64] = field(default_factory=lambda: np.ones(6))
    crosstalk: NDArray[np.float64] = field(default_factory=lambda: np.zeros((6, 6)))
    nonlinearity_gamma: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    nonlinearity_exponent: float = 2.5
    asymmetry: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    noise_sigma: float = 0.0
    noise_sigma_spread: float = 0.0

    def __post_init__(self) -> None:
        for name, shape in (("creep_gain", 6), ("crosstalk", (6, 6)), ("nonlinearity_gamma", 6), ("asymmetry", 6)):
            setattr(self, name, np.asarray(getattr(self, name), dtype=float).reshape(shape))
        self.full_scale = tuple(float(v) for v in self.full_scale)

    def apply_deterministic(self, wrench: ArrayLike) -> NDArray[np.float64]:
        """Erroneous wrench without noise (errors 1-4 of the module notes), [N] / [N·m]."""
        c = scale_torques(_check_wrench(wrench), self.alpha)
        c = c * np.where(c >= 0, 1.0 + self.asymmetry / 2, 1.0 - self.asymmetry / 2)
        c = c * self.creep_gain
        c = c + c @ self.crosstalk.T
        fs_scaled = scale_torques(np.asarray(self.full_scale)[None, :], self.alpha)[0]
        c = c * (1.0 + self.nonlinearity_gamma * np.abs(c / fs_scaled) ** (self.nonlinearity_exponent - 1.0))
        return unscale_torques(c, self.alpha)

    def apply_noise(self, wrench: ArrayLike, rng: np.random.Generator) -> NDArray[np.float64]:
        """Add the multiplicative noise of eq. 12 to (already erroneous) wrenches."""
        w = _check_wrench(wrench)
        if self.noise_sigma == 0.0:
            return w.copy()
        sigma = rng.normal(self.noise_sigma, self.noise_sigma_spread, size=(w.shape[0], 1))
        eta = rng.standard_normal(w.shape) * np.abs(sigma)
        return w + w * eta

    def to_dict(self) -> dict:
        """Plain-JSON form, with the affected axes named."""
        d = {k: (v.tolist() if isinstance(v, np.ndarray) else v) for k, v in asdict(self).items()}
        d["crosstalk_pairs"] = [
            f"{WRENCH_LABELS[i]}->{WRENCH_LABELS[j]}" for j, i in zip(*np.nonzero(self.crosstalk))
        ]
        for name, hit in (("creep", self.creep_gain != 1.0), ("nonlinearity", self.nonlinearity_gamma),
                          ("asymmetry", self.asymmetry)):
            d[f"{name}_axes"] = [WRENCH_LABELS[i] for i in np.flatnonzero(hit)]
        return d

    @classmethod
    def from_dict(cls, d: dict) -> "SampledErrors":
        """Inverse of :meth:`to_dict` (the derived axis lists are ignored)."""
        keys = {f.name for f in fields(cls)}
        return cls(**{k: v for k, v in d.items() if k in keys})
