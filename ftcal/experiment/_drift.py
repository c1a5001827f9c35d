"""The sensor bias drift of a tool identification: a bias that moves with time or temperature.

Real sensors drift (warm-up, a restart, the room warming): a tool identified
with a *constant* bias leaves that drift in every compensated wrench. Here the
bias of :func:`ftcal.experiment.identify_tool_load` may move with a variable ``v`` (the
time of each pose, or the sensor's temperature)::

    bias(v) = b + (B(v) - B(v_ref)) @ D

with ``B`` a natural (restricted) cubic spline basis in ``v`` with ``K`` knots
(``K = 2``: a straight line, ``B(v) = u``; ``K > 2``: ``u`` and ``K - 2``
cubic terms that are linear beyond the outer knots, so the drift extrapolates
with its end slope), ``u = (v - knot_0) / (knot_K - knot_0)``, ``D`` (K-1, 6)
[N, N·m per unit of ``u``] and ``b`` the bias at ``v_ref`` (the end of the
recording, or the time of the last re-tare). The gravity wrench is linear in
the mass ``m`` and in ``p = m c``, so mass, centre of mass, bias and drift are
one linear least-squares problem per block (force: ``m, b_F, D_F``; torque:
``p, b_τ, D_τ``).

Whether the drift pays, and how flexible it may be, is decided by held-out
error, never by the fit: leave-poses-out cross-validation over the candidates
(constant bias; linear and 3-, 4-, 5-knot splines in time; linear and 3-knot
in temperature when temperatures are given), each pose's held-out error the
sum of its force and torque squared errors, each in units of the constant
bias' held-out mean, and ftcal's one-standard-error rule
(:func:`ftcal.model_selection._selection.simplest_within_one_se`): the fewest drift
parameters whose error is within one paired standard error of the best. With
few poses a flexible drift overfits; its held-out error shows it and the rule
keeps the simpler one.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import NO_SETTING, CalibrationInputError

__all__ = ["BiasDrift", "DriftExtrapolationWarning", "DRIFT_CHOICES", "MAX_KNOTS", "drift_candidates",
           "fit_gravity_blocks", "select_drift", "tool_onnx_model", "held_out_predictions", "held_out_residual",
           "pose_folds"]

#: Values of ``drift=`` of :func:`ftcal.experiment.identify_tool_load`: ``auto`` chooses among every candidate the data
#: allow (the constant bias included); ``none`` keeps the bias constant; ``linear`` (in time), ``spline`` (in time)
#: and ``temperature`` force a drift of that family (the number of knots still chosen by held-out error).
DRIFT_CHOICES = ("auto", "none", "linear", "spline", "temperature")
#: Largest number of spline knots of a drift (a tool file with more is refused).
MAX_KNOTS = 6
#: Knot quantiles of the restricted cubic spline by number of knots (Harrell's choice).
_KNOT_QUANTILES = {3: (0.10, 0.50, 0.90), 4: (0.05, 0.35, 0.65, 0.95), 5: (0.05, 0.275, 0.5, 0.725, 0.95)}
#: Units a drift variable may be given in: seconds, the pose's position in the recording, degrees Celsius.
DRIFT_UNITS = {"time": ("s", "pose"), "temperature": ("degC",)}
#: Largest magnitude of a drift variable (a time stamp in seconds since 1970 is ~1.8e9) and of a coefficient.
_VARIABLE_LIMIT = 1e12
_COEFFICIENT_LIMIT = 1e9
_SECONDS_PER_HOUR = 3600.0


class DriftExtrapolationWarning(UserWarning):
    """A tool's bias drift is evaluated outside the span it was identified (and re-tared) over."""


def _skew(v: ArrayLike) -> NDArray[np.float64]:
    """``[v]×`` of a vector (3,) -> (3, 3), or of each row of ``v`` (n, 3) -> (n, 3, 3)."""
    return np.cross(np.asarray(v, dtype=float)[..., None, :], np.eye(3)).swapaxes(-1, -2)  # column j: v × e_j


def mounting_matrix(rotation_vector: ArrayLike) -> NDArray[np.float64]:
    """The rotation matrix (3, 3) of a mounting rotation vector [rad] (the sensor's frame in the robot's)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_rotvec(np.asarray(rotation_vector, dtype=float)).as_matrix()


def _spline_matrix(knots: NDArray[np.float64]) -> NDArray[np.float64]:
    """``A`` (K, K-2) with the cubic columns of the restricted cubic spline = ``relu(u - κ)³ @ A``.

    ``κ`` are the knots scaled to ``[0, 1]``; each column is linear beyond the last knot."""
    k = (knots - knots[0]) / (knots[-1] - knots[0])
    n = k.size
    A = np.zeros((n, max(n - 2, 0)))
    last = k[-1] - k[-2]
    for j in range(n - 2):
        A[j, j] += 1.0
        A[n - 2, j] -= (k[-1] - k[j]) / last
        A[n - 1, j] += (k[-2] - k[j]) / last
    return A


def spline_basis(values: ArrayLike, knots: ArrayLike) -> NDArray[np.float64]:
    """The drift basis ``B(v)`` (n, K-1): ``u`` and the ``K - 2`` restricted cubic terms.

    Examples
    --------
    >>> spline_basis([0.0, 5.0, 10.0], [0.0, 10.0]).ravel().tolist()  # two knots: a straight line in u
    [0.0, 0.5, 1.0]
    >>> b = spline_basis([20.0, 30.0, 40.0], [0.0, 2.0, 5.0, 10.0])  # linear beyond the outer knots
    >>> bool(np.allclose(b[1] - b[0], b[2] - b[1]))
    True
    """
    v = np.asarray(values, dtype=float).reshape(-1)
    knots = np.asarray(knots, dtype=float)
    k = (knots - knots[0]) / (knots[-1] - knots[0])
    u = (v - knots[0]) / (knots[-1] - knots[0])
    cubes = np.maximum(u[:, None] - k[None, :], 0.0) ** 3
    return np.hstack([u[:, None], cubes @ _spline_matrix(knots)])  # two knots: no cubic term, a straight line


@dataclass(frozen=True)
class BiasDrift:
    """How the bias of a :class:`ftcal.experiment.ToolLoad` moves with time or temperature.

    ``bias(v) = tool.bias + offset(v)``, ``offset(v) = (B(v) - B(reference)) @ coefficients``.

    Attributes
    ----------
    variable : {"time", "temperature"}
    unit : str
        ``"s"`` (seconds), ``"pose"`` (the pose's position in the recording) or ``"degC"``.
    knots : ndarray of shape (K,)
        Spline knots in ``unit`` (``K = 2``: linear; the span of the identification).
    coefficients : ndarray of shape (K-1, 6)
        ``D`` [N, N·m per unit of the scaled variable ``u``].
    coefficient_std_error : ndarray of shape (K-1, 6)
    reference : float
        The value of the variable at which ``tool.bias`` holds (``offset = 0``).
    span : ndarray of shape (2,)
        The range of the variable the drift was identified over (in ``unit``).
    mean_rate, mean_rate_std_error : ndarray of shape (6,)
        The drift's average rate over the span [N, N·m per ``unit``] and its standard error.
    retared_at : float or None
        The value of the variable at the last re-tare (:meth:`ftcal.experiment.ToolLoad.retare`).
    selection : tuple of dict
        The candidates' held-out errors that chose this drift (for the record).

    Examples
    --------
    >>> drift = BiasDrift(variable="time", unit="s", knots=np.array([0.0, 3600.0]),
    ...                   coefficients=np.array([[0.5, 0, 0, 0, 0, 0]]), coefficient_std_error=np.zeros((1, 6)),
    ...                   reference=3600.0, span=np.array([0.0, 3600.0]))
    >>> drift.description, drift.offset([0.0, 1800.0])[:, 0].tolist()  # 0.5 N/h: the bias half an hour earlier
    ('linear in time', [-0.5, -0.25])
    """

    variable: str
    unit: str
    knots: NDArray[np.float64]
    coefficients: NDArray[np.float64]
    coefficient_std_error: NDArray[np.float64]
    reference: float
    span: NDArray[np.float64]
    mean_rate: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    mean_rate_std_error: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    retared_at: float | None = None
    selection: tuple = ()

    def __post_init__(self) -> None:
        """Check every field (a drift read from a file is checked here too): bounded, finite, consistent shapes."""
        if self.variable not in DRIFT_UNITS:
            raise CalibrationInputError(f"drift variable must be 'time' or 'temperature'; got {self.variable!r}.")
        if self.unit not in DRIFT_UNITS[self.variable]:
            raise CalibrationInputError(f"drift unit of {self.variable} must be one of {DRIFT_UNITS[self.variable]}; "
                                        f"got {self.unit!r}.")

        def array(name: str, shape, limit: float, nonnegative: bool = False) -> NDArray:
            value = getattr(self, name)
            try:
                a = np.array(value, dtype=float)
            except (TypeError, ValueError):
                raise CalibrationInputError(f"drift {name} must be numbers; got {str(value)[:80]}.") from None
            if (a.shape != shape or not np.isfinite(a).all() or (np.abs(a) > limit).any()
                    or (nonnegative and (a < 0).any())):
                raise CalibrationInputError(
                    f"drift {name} must be {'x'.join(map(str, shape)) or 'one'} finite number(s)"
                    f"{' >= 0' if nonnegative else ''} of magnitude at most {limit:g}; got shape {a.shape}: "
                    f"{str(value)[:80]}.")
            object.__setattr__(self, name, float(a) if shape == () else a)
            return a

        knots = np.array(self.knots, dtype=float) if np.ndim(self.knots) == 1 else np.zeros((0,))
        if not 2 <= knots.size <= MAX_KNOTS:
            raise CalibrationInputError(f"drift knots must be 2 to {MAX_KNOTS} numbers; got {str(self.knots)[:80]}.")
        knots = array("knots", (knots.size,), _VARIABLE_LIMIT)
        if not (np.diff(knots) > 0).all():
            raise CalibrationInputError(f"drift knots must increase strictly; got {knots.tolist()}.")
        array("coefficients", (knots.size - 1, 6), _COEFFICIENT_LIMIT)
        array("coefficient_std_error", (knots.size - 1, 6), _COEFFICIENT_LIMIT, nonnegative=True)
        array("reference", (), _VARIABLE_LIMIT)
        span = array("span", (2,), _VARIABLE_LIMIT)
        if not span[1] >= span[0]:
            raise CalibrationInputError(f"drift span must be [first, last]; got {span.tolist()}.")
        array("mean_rate", (6,), _COEFFICIENT_LIMIT)
        array("mean_rate_std_error", (6,), _COEFFICIENT_LIMIT, nonnegative=True)
        if self.retared_at is not None:
            array("retared_at", (), _VARIABLE_LIMIT)
        object.__setattr__(self, "selection", tuple(self.selection))

    @property
    def n_parameters(self) -> int:
        """Drift coefficients per axis (1 for a linear drift)."""
        return self.knots.size - 1

    @property
    def description(self) -> str:
        """E.g. ``"linear in time"``, ``"spline in temperature (4 knots)"``."""
        return _describe(self.variable, self.knots.size)

    def offset(self, values: ArrayLike, *, warn: bool = True) -> NDArray[np.float64]:
        """The bias change from :attr:`reference` to each value (n, 6) [N, N·m]; warns beyond the covered span."""
        v = np.asarray(values, dtype=float).reshape(-1)
        name = "times" if self.variable == "time" else "temperatures"
        if not np.isfinite(v).all():
            raise CalibrationInputError(f"{name} holds NaN or inf (first at row {int(np.argmin(np.isfinite(v)))}); "
                                        "every wrench needs its value to compensate the bias drift.")
        if warn and v.size:
            lo, hi = self.covered
            outside = (v < lo) | (v > hi)
            if outside.any():
                worst = float(v[outside][np.argmax(np.maximum(lo - v[outside], v[outside] - hi))])
                warnings.warn(
                    f"{int(outside.sum())} of {v.size} {name} lie outside the span the bias drift was identified "
                    f"over ({_format_value(lo, self.unit)} to {_format_value(hi, self.unit)}"
                    f"{'' if self.retared_at is None else ', re-tare included'}; e.g. {_format_value(worst, self.unit)}"
                    f"): the drift ({self.description}) is extrapolated there. Fix: re-tare (ftcal retare TOOL "
                    "READINGS) or identify the tool again.", DriftExtrapolationWarning, stacklevel=3)
        basis = spline_basis(v, self.knots) - spline_basis([self.reference], self.knots)
        return basis @ self.coefficients

    @property
    def covered(self) -> tuple[float, float]:
        """The range of the variable the drift is trusted over: the identification span and the last re-tare."""
        lo, hi = float(self.span[0]), float(self.span[1])
        if self.retared_at is not None:
            lo, hi = min(lo, self.retared_at), max(hi, self.retared_at)
        return lo, hi

    def rate_per_hour(self) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
        """The mean rate and its standard error [N/h, N·m/h] (a drift in seconds; ``None`` otherwise)."""
        if self.unit != "s":
            return None
        return self.mean_rate * _SECONDS_PER_HOUR, self.mean_rate_std_error * _SECONDS_PER_HOUR

    def to_dict(self) -> dict:
        """JSON-able form (the ``drift`` block of a tool file)."""
        return {"variable": self.variable, "unit": self.unit, "model": self.description,
                "knots": self.knots.tolist(), "coefficients": self.coefficients.tolist(),
                "coefficient_std_error": self.coefficient_std_error.tolist(), "reference": self.reference,
                "span": self.span.tolist(), "mean_rate_per_unit": self.mean_rate.tolist(),
                "mean_rate_std_error_per_unit": self.mean_rate_std_error.tolist(), "retared_at": self.retared_at,
                "selection": list(self.selection)}

    @classmethod
    def from_dict(cls, d: object) -> "BiasDrift":
        """Read the ``drift`` block of a tool file (every field checked)."""
        if not isinstance(d, dict):
            raise CalibrationInputError(f"drift must be a JSON object; got {type(d).__name__}.")
        try:
            selection = d.get("selection", [])
            if not isinstance(selection, list) or len(selection) > 16:
                raise CalibrationInputError("drift selection must be a list of at most 16 candidates.")
            return cls(variable=d["variable"], unit=d["unit"], knots=d["knots"], coefficients=d["coefficients"],
                       coefficient_std_error=d["coefficient_std_error"], reference=d["reference"], span=d["span"],
                       mean_rate=d.get("mean_rate_per_unit", [0.0] * 6),
                       mean_rate_std_error=d.get("mean_rate_std_error_per_unit", [0.0] * 6),
                       retared_at=d.get("retared_at"), selection=tuple(selection))
        except KeyError as exc:
            raise CalibrationInputError(f"the drift block lacks {exc}.") from None


def _format_value(v: float, unit: str) -> str:
    return {"s": f"t = {v:.6g} s", "pose": f"pose {v:.6g}", "degC": f"{v:.4g} deg C"}[unit]


def _describe(variable: str, n_knots: int) -> str:
    if n_knots == 0:
        return "constant"
    return f"linear in {variable}" if n_knots == 2 else f"spline in {variable} ({n_knots} knots)"


# ---------------------------------------------------------------------------------------------- fitting
def _least_squares(A: NDArray, b: NDArray, clusters: NDArray | None = None) -> tuple[NDArray, NDArray, NDArray, float]:
    """Coefficients, their covariance, the residual and its RMS of ``A x ≈ b``.

    ``clusters`` (len(b),): rows of one cluster (one axis of the samples of one static pose) share an error, so
    they count as one observation: the covariance is that of the cluster means' least squares (weights = rows per
    cluster), whose residual variance includes the error they share. ``None``: every row is independent.
    """
    coef, *_ = np.linalg.lstsq(A, b, rcond=None)
    residual = b - A @ coef
    if clusters is None:
        design, res, weight = A, residual, np.ones(len(b))
    else:
        design, res = per_pose_mean(A, clusters), per_pose_mean(residual, clusters)
        weight = np.unique(clusters, return_counts=True)[1].astype(float)
    dof = max(len(res) - A.shape[1], 1)
    sigma2 = float(weight @ res**2) / dof
    cov = sigma2 * np.linalg.pinv(design.T @ (design * weight[:, None]))
    return coef, cov, residual, float(np.sqrt(np.mean(residual**2)))


def _block_designs(g_s: NDArray, basis: NDArray) -> tuple[NDArray, NDArray]:
    """Force design (3n, 4 + 3k): ``[m, b_F, D_F]``; torque design (3n, 6 + 3k): ``[p = m c, b_τ, D_τ]``.

    ``D`` is laid out basis-major: coefficient ``3 j + a`` is basis ``j`` on axis ``a``."""
    n, k = basis.shape
    eye = np.tile(np.eye(3), (n, 1))
    drift = np.einsum("nk,ab->nakb", basis, np.eye(3)).reshape(3 * n, 3 * k)
    force = np.hstack([g_s.reshape(-1, 1), eye, drift])
    torque = np.hstack([(-_skew(g_s)).reshape(-1, 3), eye, drift])
    return force, torque


def fit_gravity_blocks(g_s: NDArray, wrenches: NDArray, basis: NDArray, groups: NDArray | None = None) -> dict:
    """The joint least squares of the tool's gravity wrench, the bias and a drift with basis ``basis`` (n, k).

    Returns ``mass``, ``p`` (= m c), ``bias`` (6,) (at ``basis = 0``), ``drift`` (k, 6), their covariances
    per block (``force_cov``, ``torque_cov``), the fitted wrenches and the residual RMS (force, torque).
    ``groups`` (n,): the static pose of each row when several rows are samples of one pose; the covariances then
    count each pose once (its samples share the pose's error: orientation, settling), not each sample."""
    force_A, torque_A = _block_designs(g_s, basis)
    clusters = None
    if groups is not None:
        _, inverse = np.unique(np.asarray(groups), return_inverse=True)
        clusters = (3 * inverse[:, None] + np.arange(3)).reshape(-1)  # one cluster per pose and axis
    f_coef, f_cov, f_res, f_rms = _least_squares(force_A, wrenches[:, :3].reshape(-1), clusters)
    t_coef, t_cov, t_res, t_rms = _least_squares(torque_A, wrenches[:, 3:].reshape(-1), clusters)
    k = basis.shape[1]
    drift = np.hstack([f_coef[4:].reshape(k, 3), t_coef[6:].reshape(k, 3)])
    return {"mass": float(f_coef[0]), "p": t_coef[:3], "bias": np.concatenate([f_coef[1:4], t_coef[3:6]]),
            "drift": drift, "force_cov": f_cov, "torque_cov": t_cov,
            "residual": np.hstack([f_res.reshape(-1, 3), t_res.reshape(-1, 3)]),
            "residual_rms": np.array([f_rms, t_rms]), "force_rank": np.linalg.matrix_rank(force_A),
            "n_force_columns": force_A.shape[1], "torque_rank": np.linalg.matrix_rank(torque_A),
            "n_torque_columns": torque_A.shape[1]}


def drift_standard_errors(fit: dict) -> NDArray[np.float64]:
    """Standard errors (k, 6) of the drift coefficients of :func:`fit_gravity_blocks`."""
    f_se = np.sqrt(np.maximum(np.diag(fit["force_cov"]), 0.0))[4:]
    t_se = np.sqrt(np.maximum(np.diag(fit["torque_cov"]), 0.0))[6:]
    k = fit["drift"].shape[0]
    return np.hstack([f_se.reshape(k, 3), t_se.reshape(k, 3)])


def functional_se(fit: dict, weights: NDArray, bias_weight: float = 0.0) -> NDArray[np.float64]:
    """Standard error (6,) of ``bias_weight * bias[axis] + weights @ drift[:, axis]`` for each axis (weights (k,)),
    from :func:`fit_gravity_blocks`' covariances (e.g. the mean drift rate, or the bias at some time)."""
    out = np.empty(6)
    w = np.concatenate([[bias_weight], weights])
    for a in range(6):
        cov, bias_at, start = (fit["force_cov"], 1, 4) if a < 3 else (fit["torque_cov"], 3, 6)
        index = np.concatenate([[bias_at + a % 3], start + 3 * np.arange(weights.size) + a % 3])
        out[a] = math.sqrt(max(float(w @ cov[np.ix_(index, index)] @ w), 0.0))
    return out


@dataclass(frozen=True)
class _Candidate:
    variable: str | None  # None: the constant bias
    knots: NDArray[np.float64]

    @property
    def n_parameters(self) -> int:
        return max(self.knots.size - 1, 0)

    @property
    def name(self) -> str:
        return _describe(self.variable or "", self.knots.size)

    def basis(self, values: dict) -> NDArray[np.float64]:
        n = len(next(iter(values.values())))
        if self.variable is None:
            return np.zeros((n, 0))
        return spline_basis(values[self.variable], self.knots)


def _knots(values: NDArray, n_knots: int) -> NDArray | None:
    """Knots of an ``n_knots`` spline over ``values`` (the span for 2), or None when the values do not allow it."""
    lo, hi = float(values.min()), float(values.max())
    if not hi > lo:
        return None
    if n_knots == 2:
        return np.array([lo, hi])
    if np.unique(values).size < n_knots + 2:
        return None
    knots = np.quantile(values, _KNOT_QUANTILES[n_knots])
    return knots if (np.diff(knots) > 1e-9 * (hi - lo)).all() else None


def drift_candidates(n_poses: int, times: NDArray | None, temperatures: NDArray | None,
                     choice: str = "auto") -> list[_Candidate]:
    """The drift models to compare: the constant bias first (unless a drift is forced), then the allowed ones.

    A spline needs enough poses for its parameters (3 per axis and knot beyond the line), so few poses get few
    candidates."""
    if choice not in DRIFT_CHOICES:
        raise CalibrationInputError(f"drift must be one of {', '.join(DRIFT_CHOICES)}; got {choice!r}.")
    out = [] if choice in ("linear", "spline", "temperature") else [_Candidate(None, np.zeros(0))]
    if choice == "none":
        return out
    max_knots = max(2, min(5, (n_poses - 4) // 2 + 1))  # a few poses per drift parameter
    families = []
    if times is not None and choice in ("auto", "linear", "spline"):
        sizes = {"auto": range(2, max_knots + 1), "linear": [2], "spline": range(3, max(max_knots, 3) + 1)}[choice]
        families.append(("time", times, sizes))
    if temperatures is not None and choice in ("auto", "temperature"):
        families.append(("temperature", temperatures, range(2, min(max_knots, 3) + 1)))
    for variable, values, sizes in families:
        for n_knots in sizes:
            knots = _knots(values, n_knots)
            if knots is not None:
                out.append(_Candidate(variable, knots))
    return out


def held_out_predictions(g_s: NDArray, W: NDArray, basis: NDArray, folds) -> NDArray[np.float64] | None:
    """The gravity wrench plus bias (and drift with ``basis`` (n, k)) of each row predicted by the fit on the other
    folds' rows (n, 6) [N, N·m]; ``None`` when some training set cannot determine every parameter."""
    pred = np.empty_like(W)
    for train, test in folds:
        fit = fit_gravity_blocks(g_s[train], W[train], basis[train])
        if (fit["force_rank"] < fit["n_force_columns"] or fit["torque_rank"] < fit["n_torque_columns"]
                or 3 * len(train) <= fit["n_torque_columns"]):
            return None
        force_A, torque_A = _block_designs(g_s[test], basis[test])
        f_coef = np.concatenate([[fit["mass"]], fit["bias"][:3], fit["drift"][:, :3].reshape(-1)])
        t_coef = np.concatenate([fit["p"], fit["bias"][3:], fit["drift"][:, 3:].reshape(-1)])
        pred[test, :3] = (force_A @ f_coef).reshape(-1, 3)
        pred[test, 3:] = (torque_A @ t_coef).reshape(-1, 3)
    return pred


def pose_folds(n: int, groups: NDArray | None, cv: int, random_state: int | None):
    """The leave-poses-out folds: ``min(cv, poses)`` folds holding each pose's rows out together (leave-one-pose-out
    when there are at most ``cv`` poses)."""
    from ..model_selection._selection import calibration_folds

    n_units = n if groups is None else np.unique(groups).size
    return calibration_folds(n, groups, n_splits=min(int(cv), n_units), random_state=random_state)


def held_out_residual(g_s: NDArray, W: NDArray, basis: NDArray, *, groups: NDArray | None = None, cv: int = 20,
                      random_state: int | None = 0) -> NDArray[np.float64] | None:
    """Each row's wrench minus its leave-poses-out prediction (n, 6) [N, N·m] (:func:`held_out_predictions` over
    :func:`pose_folds`), ``None`` when a fold cannot be fitted (too few poses)."""
    pred = held_out_predictions(g_s, W, basis, pose_folds(len(W), groups, cv, random_state))
    return None if pred is None else W - pred


def _held_out_errors(g_s: NDArray, W: NDArray, values: dict, candidates: list[_Candidate], folds) -> NDArray:
    """Held-out squared force and torque errors (n_candidates, n_poses, 2) per pose (NaN: not scorable)."""
    errors = np.full((len(candidates), len(W), 2), np.nan)
    for c, cand in enumerate(candidates):
        pred = held_out_predictions(g_s, W, cand.basis(values), folds)
        if pred is not None:
            errors[c] = ((pred - W) ** 2).reshape(-1, 2, 3).sum(axis=2)
    return errors


def select_drift(g_s: NDArray, W: NDArray, times: NDArray | None, temperatures: NDArray | None, *,
                 choice: str = "auto", cv: int = 20, random_state: int | None = 0, groups: NDArray | None = None
                 ) -> tuple[_Candidate, list[dict]]:
    """The drift model chosen by leave-poses-out cross-validation and the one-SE rule, and the table of candidates.

    ``groups`` labels the rows of one pose (several samples of a static pose): they are held out together and
    count as one unit of the standard error; ``None``: every row is a pose."""
    from ..model_selection._selection import check_groups, simplest_within_one_se

    candidates = drift_candidates(len(W), times, temperatures, choice)
    values = {k: v for k, v in (("time", times), ("temperature", temperatures)) if v is not None}
    if not candidates:
        values_of = "temperatures" if choice == "temperature" else "times"
        raise CalibrationInputError(
            f"{{drift}} {choice!r} needs {values_of} that vary over the poses (and enough poses for its parameters); "
            f"got {len(W)} poses.", parameter="drift", value=choice, fix=f"give {{{values_of}}}, or {{drift}}",
            settings={values_of: NO_SETTING, "drift": "auto"})
    if len(candidates) == 1:
        return candidates[0], [{"model": candidates[0].name, "n_parameters": 6 * candidates[0].n_parameters,
                                "status": "the only candidate"}]
    if groups is not None:
        groups = check_groups(groups, len(W), purpose="leave-poses-out cross-validation of the drift",
                              fix="pass groups=None when every row is a pose")
    folds = pose_folds(len(W), groups, cv, random_state)
    errors = _held_out_errors(g_s, W, values or {"time": np.zeros(len(W))}, candidates, folds)
    scorable = ~np.isnan(errors).any(axis=(1, 2))
    if not scorable.any():
        raise CalibrationInputError(f"none of the drift models could be cross-validated on {len(W)} poses; add poses.")
    reference = int(np.argmax(scorable))  # the simplest scorable candidate sets the units
    score = (errors / np.maximum(errors[reference].mean(axis=0), 1e-300)).sum(axis=2)  # force and torque in its units
    best = simplest_within_one_se(score, groups, complexity=[c.n_parameters for c in candidates])
    table = []
    for c, cand in enumerate(candidates):
        row = {"model": cand.name, "n_parameters": 6 * cand.n_parameters}
        if scorable[c]:
            excess = per_pose_mean(score[c] - score[best], groups)  # over the units (groups, else rows)
            row.update(status="chosen" if c == best else "scored",
                       held_out_rms_force_N=float(np.sqrt(np.mean(errors[c, :, 0]) / 3)),
                       held_out_rms_torque_Nm=float(np.sqrt(np.mean(errors[c, :, 1]) / 3)),
                       score=float(np.mean(score[c])),
                       score_excess_se=float(excess.std(ddof=1) / np.sqrt(excess.size)) if excess.size > 1 else None)
        else:
            row["status"] = "not enough poses for its parameters"
        table.append(row)
    return candidates[best], table


def per_pose_mean(values: NDArray, groups: NDArray | None) -> NDArray:
    """The mean of ``values`` (n,) or (n, k) over the rows of each pose (``groups``, in the order of their sorted
    labels; ``None``: every row is a pose)."""
    if groups is None:
        return values
    _, inverse, count = np.unique(groups, return_inverse=True, return_counts=True)
    out = np.zeros((count.size, *np.shape(values)[1:]))
    np.add.at(out, inverse.ravel(), values)
    return out / count.reshape(-1, *[1] * (out.ndim - 1))


def build_drift(candidate: _Candidate, fit: dict, values: NDArray, unit: str, table: list[dict]) -> BiasDrift:
    """The :class:`BiasDrift` of a fitted candidate, referenced to the end of the span (``fit['bias']`` moved there)."""
    lo, hi = float(values.min()), float(values.max())
    ends = spline_basis([lo, hi], candidate.knots)
    weights = (ends[1] - ends[0]) / (hi - lo)
    return BiasDrift(variable=candidate.variable, unit=unit, knots=candidate.knots, coefficients=fit["drift"],
                     coefficient_std_error=drift_standard_errors(fit), reference=hi, span=np.array([lo, hi]),
                     mean_rate=weights @ fit["drift"], mean_rate_std_error=functional_se(fit, weights),
                     selection=tuple(table))


# ---------------------------------------------------------------------------------------------- ONNX
def tool_onnx_model(tool):
    """An ONNX graph of the tool's compensation: external wrench = wrench - gravity wrench - bias(time or temperature).

    Inputs ``rotation`` float64 (n, 3, 3) (sensor to base frame), ``wrench`` float64 (n, 6) [N, N·m] in the
    sensor frame, and ``time`` (n,) [the drift's unit] or ``temperature`` (n,) [deg C] when the tool's bias
    drifts; output ``external`` (n, 6). The graph extrapolates the drift silently beyond the covered span (no
    warning is possible inside it): the span is in the model's metadata (``drift_span``)."""
    import onnx
    from onnx import TensorProto, helper, numpy_helper

    m, c, g = tool.mass, np.asarray(tool.center_of_mass), np.asarray(tool.gravity, dtype=float)
    # gravity wrench = g_s @ M, g_s = Rᵀ g: force m g_s, torque c × (m g_s) = m g_s @ [c]×ᵀ
    # gravity in the mounted sensor frame: (Rᵀ g)ᵀ Q, so Q M (Q = I without a mounting rotation)
    M = mounting_matrix(tool.mounting_rotation) @ np.hstack([m * np.eye(3), m * _skew(c).T])
    drift = tool.drift
    bias = np.asarray(tool.bias, dtype=float)
    inits = {"g": g.reshape(3, 1), "M": M, "flat": np.array([-1, 3], dtype=np.int64)}
    nodes = [helper.make_node("Transpose", ["rotation"], ["Rt"], perm=[0, 2, 1]),
             helper.make_node("MatMul", ["Rt", "g"], ["gs3"]),
             helper.make_node("Reshape", ["gs3", "flat"], ["gs"]),
             helper.make_node("MatMul", ["gs", "M"], ["gravity_wrench"]),
             helper.make_node("Sub", ["wrench", "gravity_wrench"], ["w1"])]
    inputs = [helper.make_tensor_value_info("rotation", TensorProto.DOUBLE, ["n", 3, 3]),
              helper.make_tensor_value_info("wrench", TensorProto.DOUBLE, ["n", 6])]
    last = "w1"
    if drift is not None:
        name = "time" if drift.variable == "time" else "temperature"
        inputs.append(helper.make_tensor_value_info(name, TensorProto.DOUBLE, ["n"]))
        knots = drift.knots
        bias = bias - (spline_basis([drift.reference], knots) @ drift.coefficients)[0]
        inits.update(k0=np.array(knots[0]), width=np.array(knots[-1] - knots[0]), col=np.array([-1, 1], dtype=np.int64),
                     lin=drift.coefficients[:1])
        nodes += [helper.make_node("Reshape", [name, "col"], ["v"]),
                  helper.make_node("Sub", ["v", "k0"], ["v0"]),
                  helper.make_node("Div", ["v0", "width"], ["u"]),
                  helper.make_node("MatMul", ["u", "lin"], ["d_lin"]),
                  helper.make_node("Sub", [last, "d_lin"], ["w2"])]
        last = "w2"
        if knots.size > 2:
            scaled = (knots - knots[0]) / (knots[-1] - knots[0])
            inits.update(kappa=scaled.reshape(1, -1), cubic=_spline_matrix(knots) @ drift.coefficients[1:])
            nodes += [helper.make_node("Sub", ["u", "kappa"], ["uk"]), helper.make_node("Relu", ["uk"], ["r"]),
                      helper.make_node("Mul", ["r", "r"], ["r2"]), helper.make_node("Mul", ["r2", "r"], ["r3"]),
                      helper.make_node("MatMul", ["r3", "cubic"], ["d_cubic"]),
                      helper.make_node("Sub", [last, "d_cubic"], ["w3"])]
            last = "w3"
    inits["bias"] = bias.reshape(1, 6)
    nodes.append(helper.make_node("Sub", [last, "bias"], ["external"]))
    graph = helper.make_graph(nodes, "ftcal_tool_compensation", inputs,
                              [helper.make_tensor_value_info("external", TensorProto.DOUBLE, ["n", 6])],
                              [numpy_helper.from_array(np.asarray(v), name=k) for k, v in inits.items()])
    model = helper.make_model(graph, producer_name="ftcal", opset_imports=[helper.make_opsetid("", 17)])
    model.ir_version = min(model.ir_version, 8)
    meta = {"ftcal_format": "ftcal-tool-compensation", "mass_kg": repr(m)}
    if drift is not None:
        meta.update(drift_model=drift.description, drift_unit=drift.unit,
                    drift_span=",".join(repr(float(v)) for v in drift.covered))
    onnx.helper.set_model_props(model, meta)
    onnx.checker.check_model(model)
    return model
