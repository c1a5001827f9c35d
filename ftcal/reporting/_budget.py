"""The uncertainty budget of a calibration, per output axis, in the form of the GUM (JCGM 100:2008) as EURAMET
cg-4 applies it to force: components with their standard uncertainty and degrees of freedom, their combination,
the Welch-Satterthwaite effective degrees of freedom and the coverage factor of the t-distribution.

The model of the budget (stated on the certificate too)
------------------------------------------------------
The quantity certified is the error of one indicated load of the calibrated sensor. Its components:

reproducibility (held-out)
    The held-out RMS error of the calibration (every row predicted by a model fitted without its group or
    fold) with the repeatability taken out: ``sqrt(max(rms² - s_r², 0))``. Across groups (poses, sessions)
    when the folds hold out groups. Type A; degrees of freedom: Satterthwaite's for a difference of two mean
    squares (at most the independent units minus one: the groups, else the load cases).
repeatability
    ``s_r``, the pooled standard deviation of the held-out errors of rows of one load case within one group
    (the same load read again). Type A; degrees of freedom ``sum(n_i - 1)``. With the reproducibility it adds
    up to the held-out RMS error (exactly, unless the repeatability exceeds it): neither is counted twice.
resolution
    The channels' least significant bit (the smallest step of each channel's values in the data) through the
    model's sensitivity (a finite-difference Jacobian at readings of the data): ``u = sqrt(sum_c (J_c LSB_c)²
    / 12)`` (a rectangular distribution of width one LSB, GUM 4.3.7 and F.2.2.1). The held-out error already
    holds the readings' quantisation, so only the part the held-out error does not show is added:
    ``sqrt(max(u_res² - rms², 0))`` (the usual floor when the scatter is below the resolution). Type B.
reference standard
    The reference load's own uncertainty, given as an expanded uncertainty at k = 2 (as a reference's
    certificate states it), relative (of the largest applied load of the axis) or absolute: ``u = U / 2``.
    Type B, its degrees of freedom taken as infinite. Not in the held-out error (the reference is the truth
    the errors are measured against), so it is added.
temperature
    When a temperature coefficient of the indication and a temperature range of use are known: a rectangular
    distribution over the range, ``u = |c| a / sqrt(3)`` with ``a`` the half-width. Type B.

The components are uncorrelated by construction (the two Type A ones are a split of one sum of squares), so
``u_c = sqrt(sum u_i²)``; ``nu_eff = u_c⁴ / sum(u_i⁴ / nu_i)``; ``k = t_{nu_eff}`` at the coverage probability
:data:`COVERAGE_PROBABILITY` (95.45 %: k = 2 for infinite degrees of freedom, EA-4/02); ``U = k u_c``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = ["COVERAGE_PROBABILITY", "BudgetComponent", "AxisBudget", "coverage_factor", "welch_satterthwaite",
           "channel_lsb", "resolution_uncertainty", "uncertainty_budget", "BUDGET_MODEL"]

#: Coverage probability of the expanded uncertainty (k = 2.00 for infinite degrees of freedom; EA-4/02).
COVERAGE_PROBABILITY = 0.9545
#: One paragraph for the page: how the budget is built and why nothing is counted twice.
BUDGET_MODEL = (
    "Budget model (GUM, JCGM 100; EURAMET cg-4): the held-out RMS error of the calibration is split into "
    "repeatability s_r (pooled scatter of the rows of one load case within one group) and reproducibility "
    "(the rest, sqrt(max(rms² − s_r², 0)): across groups when the folds hold out groups; Satterthwaite's dof), so "
    "the two add up to the held-out error. The readings' resolution (channel LSB/√12 through the model's "
    "sensitivity) is already inside that error; only its part beyond the held-out error is added. The reference standard (its expanded uncertainty at k = 2, "
    "halved) and, when known, a temperature term are added. The components are uncorrelated; u_c is their root "
    "sum of squares, k the t-factor at 95.45 % for the Welch-Satterthwaite degrees of freedom, U = k·u_c. "
    "dof '∞': a Type B component taken as exactly known.")


@dataclass(frozen=True)
class BudgetComponent:
    """One line of a budget: ``standard_uncertainty`` in the axis' unit; ``dof`` its degrees of freedom
    (``math.inf`` for a Type B component taken as exactly known; ``None`` in JSON)."""

    name: str
    standard_uncertainty: float
    dof: float
    source: str

    def to_dict(self) -> dict:
        """``{"name", "standard_uncertainty", "dof", "source"}`` (dof ``None`` when infinite)."""
        return {"name": self.name, "standard_uncertainty": float(self.standard_uncertainty),
                "dof": None if math.isinf(self.dof) else float(self.dof), "source": self.source}


@dataclass(frozen=True)
class AxisBudget:
    """The budget of one output axis: its components, ``u_c``, ``nu_eff``, ``k`` and ``U = k u_c``."""

    axis: str
    components: tuple
    combined_standard_uncertainty: float
    effective_dof: float
    coverage_factor: float
    expanded_uncertainty: float

    @classmethod
    def combine(cls, axis: str, components: list[BudgetComponent]) -> "AxisBudget":
        """Root sum of squares, Welch-Satterthwaite and the t-factor of ``components``.

        Examples
        --------
        >>> b = AxisBudget.combine("Fz", [BudgetComponent("held-out", 0.3, 14, "data"),
        ...                               BudgetComponent("reference", 0.1, math.inf, "certificate")])
        >>> round(b.combined_standard_uncertainty, 4), round(b.effective_dof, 1), b.coverage_factor > 2
        (0.3162, 17.3, True)
        """
        u = np.array([c.standard_uncertainty for c in components], dtype=float)
        dof = np.array([c.dof for c in components], dtype=float)
        uc = float(np.sqrt(np.sum(u**2)))
        nu = welch_satterthwaite(u, dof)
        k = coverage_factor(nu)
        return cls(axis, tuple(components), uc, nu, k, k * uc)

    def to_dict(self) -> dict:
        """Exactly ``{"axis", "components", "combined_standard_uncertainty", "effective_dof", "coverage_factor",
        "expanded_uncertainty"}`` (``effective_dof`` ``None`` when infinite)."""
        return {"axis": self.axis, "components": [c.to_dict() for c in self.components],
                "combined_standard_uncertainty": self.combined_standard_uncertainty,
                "effective_dof": None if math.isinf(self.effective_dof) else self.effective_dof,
                "coverage_factor": self.coverage_factor, "expanded_uncertainty": self.expanded_uncertainty}


def welch_satterthwaite(u: NDArray, dof: NDArray) -> float:
    """Effective degrees of freedom ``u_c⁴ / sum(u_i⁴ / nu_i)`` (GUM G.4.1); infinite when every component with
    a finite ``nu_i`` is zero.

    Examples
    --------
    >>> welch_satterthwaite(np.array([1.0, 1.0]), np.array([10.0, 10.0]))
    20.0
    """
    u, dof = np.asarray(u, dtype=float), np.asarray(dof, dtype=float)
    finite = np.isfinite(dof) & (u > 0)
    denominator = float(np.sum(u[finite] ** 4 / np.maximum(dof[finite], 1.0)))
    return math.inf if denominator <= 0 else float(np.sum(u**2) ** 2 / denominator)


def coverage_factor(dof: float, probability: float = COVERAGE_PROBABILITY) -> float:
    """``k``: the two-sided ``probability`` quantile of the t-distribution with ``dof`` degrees of freedom (GUM
    G.3); the normal quantile for infinite ``dof``.

    Examples
    --------
    >>> round(coverage_factor(math.inf), 2), round(coverage_factor(14), 2)
    (2.0, 2.2)
    """
    from scipy import stats

    q = 0.5 + probability / 2
    return float(stats.norm.ppf(q) if math.isinf(dof) else stats.t.ppf(q, max(float(dof), 1.0)))


def channel_lsb(X: NDArray) -> NDArray:
    """Per column, the quantisation step of the readings: the smallest step between two distinct values when every
    value is a whole number of such steps from the smallest (an ADC's counts, scaled or not); 0 for continuous
    values (no step shows) or a column of one value.

    Examples
    --------
    >>> channel_lsb(np.array([[0.0, 1.5, 0.1], [3.0, 1.5, 0.25], [9.0, 1.5, 0.27]]))
    array([3., 0., 0.])
    """
    out = np.zeros(X.shape[1])
    for c in range(X.shape[1]):
        values = np.unique(X[:, c])
        steps = np.diff(values)
        steps = steps[steps > 0]
        if not steps.size:
            continue
        counts = (values - values[0]) / steps.min()
        if np.max(np.abs(counts - np.round(counts))) < 0.01:
            out[c] = float(steps.min())
    return out


def resolution_uncertainty(model: Any, X: NDArray, lsb: NDArray, *, rows: int = 16) -> NDArray:
    """Standard uncertainty per output axis of one LSB of every channel through ``model``: ``sqrt(sum_c (J_c
    LSB_c)² / 12)``, ``J`` the finite-difference Jacobian of ``model.predict`` (any model), its square averaged
    over up to ``rows`` readings spread through the data.

    Examples
    --------
    >>> from sklearn.linear_model import LinearRegression
    >>> X = np.arange(20.0).reshape(10, 2); X[:, 1] = X[:, 1] ** 2 / 7
    >>> model = LinearRegression().fit(X, X @ [[2.0], [0.0]])
    >>> np.round(resolution_uncertainty(model, X, np.array([1.0, 0.0])), 4)
    array([0.5774])
    """
    X = np.asarray(X, dtype=float)
    pick = X[np.unique(np.linspace(0, len(X) - 1, min(rows, len(X))).astype(int))]
    base = np.asarray(model.predict(pick), dtype=float).reshape(len(pick), -1)
    span = np.ptp(X, axis=0)
    total = np.zeros(base.shape[1])
    for c in np.flatnonzero(lsb > 0):
        h = max(float(lsb[c]), 1e-6 * float(span[c]))
        moved = pick.copy()
        moved[:, c] += h
        slope = (np.asarray(model.predict(moved), dtype=float).reshape(base.shape) - base) / h
        total += np.mean(slope**2, axis=0) * lsb[c] ** 2
    return np.sqrt(total / 12.0)


def _type_a(errors: NDArray, cases: NDArray, n_units: int) -> tuple[NDArray, NDArray, int, int]:
    """``(reproducibility u, repeatability s_r, dof of the first (per axis), dof of the second)`` per axis."""
    _, case, count = np.unique(cases, return_inverse=True, return_counts=True)
    means = np.zeros((count.size, errors.shape[1]))
    np.add.at(means, case, errors)
    means /= count[:, None]
    dof_r = int(len(errors) - count.size)
    s_r = np.sqrt(np.sum((errors - means[case]) ** 2, axis=0) / dof_r) if dof_r > 0 else np.zeros(errors.shape[1])
    ms = np.mean(errors**2, axis=0)
    u2 = np.maximum(ms - s_r**2, 0.0)
    nu = max(int(n_units) - 1, 1)
    # a difference of two mean squares: Satterthwaite's dof (fewer than the units' when the repeatability is a
    # large part of the held-out error), at least 1; a zero component keeps the units' dof (it weighs nothing)
    denom = ms**2 / nu + (s_r**4 / dof_r if dof_r > 0 else 0.0)
    ratio = np.divide(u2**2, denom, out=np.full_like(u2, float(nu)), where=denom > 0)
    dof = np.where((u2 > 0) & (s_r > 0), np.clip(ratio, 1.0, nu), float(nu))
    return np.sqrt(u2), s_r, dof, dof_r


def uncertainty_budget(errors: NDArray, *, axes: list[str], cases: NDArray, n_units: int, units_name: str,
                       resolution: NDArray | None = None, resolution_note: str = "",
                       reference: NDArray | None = None, reference_note: str = "",
                       temperature: NDArray | None = None, temperature_note: str = "") -> list[AxisBudget]:
    """The budget of every axis from the held-out ``errors`` (pred - applied, shape (n, k)).

    Parameters
    ----------
    errors : ndarray of shape (n, k)
        Held-out errors in the axes' units.
    axes : list of str
    cases : ndarray of shape (n,)
        The load case of each row (rows of one group under one applied load share it).
    n_units : int
        Independent units of the held-out error (groups when whole groups are held out, else load cases).
    units_name : str
        What they are ("groups", "load cases"), for the source text.
    resolution, reference, temperature : ndarray of shape (k,), optional
        Standard uncertainties of those components (``reference`` already halved from its k = 2), each with a
        note saying where it comes from.

    Returns
    -------
    list of AxisBudget

    Examples
    --------
    >>> rng = np.random.default_rng(0)
    >>> b = uncertainty_budget(rng.normal(size=(15, 1)), axes=["Fz"], cases=np.arange(15), n_units=15,
    ...                        units_name="load cases", reference=np.array([0.05]), reference_note="0.1 N, k = 2")
    >>> [c.name for c in b[0].components], b[0].coverage_factor > 2
    (['reproducibility (held-out)', 'repeatability', 'resolution', 'reference standard'], True)
    """
    repro, s_r, dof_repro, dof_r = _type_a(np.asarray(errors, dtype=float), np.asarray(cases), n_units)
    out = []
    for j, axis in enumerate(axes):
        comps = [BudgetComponent("reproducibility (held-out)", float(repro[j]), float(dof_repro[j]), (
            f"held-out RMS error less the repeatability, over {n_units} {units_name} (Type A)")),
                 BudgetComponent("repeatability", float(s_r[j]), float(dof_r) if dof_r > 0 else math.inf, (
                     f"pooled scatter of rows of one load case within a group, {dof_r} dof (Type A)" if dof_r > 0
                     else "no load case read twice within a group: not observable apart (it stays inside the "
                     "held-out error)"))]
        if resolution is None:
            comps.append(BudgetComponent("resolution", 0.0, math.inf, resolution_note or (
                "the readings show no quantisation step (continuous values): no resolution term")))
        else:
            held = float(repro[j]) ** 2 + float(s_r[j]) ** 2  # the held-out error's variance: it holds the resolution
            extra = math.sqrt(max(float(resolution[j]) ** 2 - held, 0.0))
            comps.append(BudgetComponent("resolution", extra, math.inf, (
                f"{resolution_note}: {float(resolution[j]):.3g} through the model; the part beyond the held-out "
                "error (the rest is inside it) (Type B, rectangular)")))
        if reference is not None:
            comps.append(BudgetComponent("reference standard", float(reference[j]), math.inf, reference_note))
        if temperature is not None:
            comps.append(BudgetComponent("temperature", float(temperature[j]), math.inf, temperature_note))
        out.append(AxisBudget.combine(axis, comps))
    return out
