"""The sensor's mounting rotation identified with the tool, and what a pose set can tell.

A sensor is bolted to the flange a few degrees off the frame the robot model gives it (a dowel pin's play, an
adapter plate, a cable clamp). The tool's gravity wrench then reads as if gravity came from a slightly wrong
direction, and mass, centre of mass and bias absorb the error. With ``mounting=True``,
:func:`ftcal.experiment.identify_tool_load` estimates that rotation jointly with the tool: the sensor's true
orientation is ``R Q`` (``R`` the robot's sensor frame, ``Q = exp([r]×)`` with the rotation vector ``r``
[rad]), so gravity in the sensor frame is ``g_s = Qᵀ Rᵀ g`` and

* force:  ``F = m g_s + b_F (+ drift)``,
* torque: ``τ = p × g_s + b_τ (+ drift)``, ``p = m c``,

a non-linear least-squares problem in ``r`` (Gauss-Newton by :func:`scipy.optimize.least_squares`, started at
``r = 0`` from the closed-form tool) whose other parameters are linear. Each block's residual is weighted by the
inverse of its closed-form residual RMS, and the standard errors come from the Jacobian and the residual
variance at the optimum (``s² (JᵀJ)⁻¹``).

**Observability** (:func:`ftcal.experiment.tool_load_observability`): before fitting, the Jacobian at the closed-form tool says
what the poses can tell. For each parameter block (mass, centre of mass, force bias, torque bias, mounting
rotation, drift) the block's columns are projected off the others' span; the smallest singular value of what
remains, relative to the block's own scale, is its *identifiability* (1: independent of the others; 0: not
identifiable), and its right singular vector names the direction the poses cannot tell (a rotation axis, a
centre-of-mass axis). Its inverse, scaled by the residual noise, is the standard error that direction would get.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ._drift import _skew, mounting_matrix, per_pose_mean

__all__ = ["ParameterBlock", "Observability", "fit_mounting_rotation", "identify_mounting", "block_observability",
           "UNIDENTIFIABLE", "MAX_MOUNTING_SE_DEG"]

#: A block whose identifiability (smallest singular value of its columns off the others', relative) is below this
#: cannot be told from the other parameters by these poses at all.
UNIDENTIFIABLE = 1e-6
#: A mounting rotation whose expected standard error on its weakest axis exceeds this [deg] cannot be told by the
#: poses (a mounting error is a few degrees).
MAX_MOUNTING_SE_DEG = 1.0

_BLOCK_UNITS = {"mass": ("kg", 1.0), "centre of mass": ("mm", 1e3), "force bias": ("N", 1.0),
                "torque bias": ("N·m", 1.0), "mounting rotation": ("deg", float(np.degrees(1.0))),
                "drift": ("N, N·m", 1.0)}


@dataclass(frozen=True)
class ParameterBlock:
    """What the poses can tell of one parameter block.

    Attributes
    ----------
    name : str
        ``"mass"``, ``"centre of mass"``, ``"force bias"``, ``"torque bias"``, ``"mounting rotation"``, ``"drift"``.
    n_parameters : int
    rank : int
        Rank of the block's columns after projecting out the other blocks' (``n_parameters``: identifiable).
    identifiability : float
        Smallest singular value of those columns relative to the block's own scale (0 to 1).
    weakest_direction : ndarray of shape (n_parameters,)
        The combination of the block's parameters the poses tell worst (unit vector).
    expected_std_error : float
        The standard error that combination would get at the closed-form residual noise (in ``unit``).
    unit : str
    confused_with : str
        The other block that best imitates the weakest direction.
    """

    name: str
    n_parameters: int
    rank: int
    identifiability: float
    weakest_direction: NDArray[np.float64]
    expected_std_error: float
    unit: str
    confused_with: str

    @property
    def condition(self) -> float:
        """``1 / identifiability`` (inf when not identifiable)."""
        return float(np.inf) if self.identifiability <= 0 else 1.0 / self.identifiability

    @property
    def identifiable(self) -> bool:
        return self.identifiability >= UNIDENTIFIABLE

    def direction_text(self) -> str:
        """The weakest direction in words: ``"about the sensor's x axis"`` for a rotation, ``"along ..."`` for the
        centre of mass or a bias (empty for a one-parameter block)."""
        if self.n_parameters != 3:
            return ""
        axis = axis_text(self.weakest_direction)
        axis = f"{axis} axis" if len(axis) == 1 else f"axis {axis}"
        return f" about the sensor's {axis}" if self.name == "mounting rotation" else f" along the sensor's {axis}"


@dataclass(frozen=True)
class Observability:
    """Rank and condition of each parameter block of a tool identification at a pose set
    (:func:`ftcal.experiment.tool_load_observability`)."""

    blocks: tuple[ParameterBlock, ...]
    n_poses: int

    def block(self, name: str) -> ParameterBlock:
        return next(b for b in self.blocks if b.name == name)

    def problems(self) -> list[str]:
        """One sentence per block the poses cannot tell (not identifiable, or a mounting rotation whose expected
        standard error exceeds :data:`MAX_MOUNTING_SE_DEG`); empty when every block is told."""
        out = []
        for b in self.blocks:
            if not b.identifiable:
                out.append(f"the {b.name}{b.direction_text()} is not identifiable from these {self.n_poses} poses: "
                           f"the {b.confused_with} absorbs it")
            elif b.name == "mounting rotation" and b.expected_std_error > MAX_MOUNTING_SE_DEG:
                out.append(f"the {b.name}{b.direction_text()} is barely told by these {self.n_poses} poses: its "
                           f"standard error would be about {b.expected_std_error:.2g} deg (more than "
                           f"{MAX_MOUNTING_SE_DEG:g} deg; identifiability {b.identifiability:.2g}, confused with the "
                           f"{b.confused_with})")
        return out

    def to_dict(self) -> dict:
        return {"n_poses": self.n_poses, "blocks": [
            {"name": b.name, "n_parameters": b.n_parameters, "rank": b.rank, "identifiability": b.identifiability,
             "condition": None if not np.isfinite(b.condition) else b.condition,
             "weakest_direction": b.weakest_direction.tolist(), "expected_std_error": b.expected_std_error,
             "unit": b.unit, "confused_with": b.confused_with} for b in self.blocks]}


def axis_text(v: NDArray[np.float64]) -> str:
    """An axis (a unit vector, either sign) as ``x`` when it lies along one (within 10 deg), else as components."""
    k = int(np.argmax(np.abs(v)))
    if abs(v[k]) >= np.cos(np.radians(10.0)):
        return "xyz"[k]
    return "[" + ", ".join(f"{c:.2f}" for c in np.sign(v[k]) * v) + "]"


def _jacobian(g_s: NDArray, mass: float, p: NDArray, basis: NDArray, scale: NDArray, mounting: bool
              ) -> tuple[NDArray, dict[str, slice]]:
    """The weighted Jacobian (6n, n_params) of the predicted wrenches at ``g_s`` (the mounted frame's gravity) with
    respect to the blocks, and each block's columns. A small extra rotation ``δ`` of the mounting turns ``g_s`` by
    ``g_s × δ``: ``dF/dδ = m [g_s]×``, ``dτ/dδ = [p]× [g_s]×``."""
    n, k = len(g_s), basis.shape[1]
    S = _skew(g_s)  # (n, 3, 3)
    zeros = np.zeros((n, 3, 3))
    eye = np.broadcast_to(np.eye(3), (n, 3, 3))
    cols = {"mass": (g_s[:, :, None], np.zeros((n, 3, 1))), "centre of mass": (zeros, -S),
            "force bias": (eye, zeros), "torque bias": (zeros, eye)}
    if mounting:
        cols["mounting rotation"] = (mass * S, _skew(p) @ S)
    if k:
        drift = np.einsum("nk,ab->nakb", basis, np.eye(3)).reshape(n, 3, 3 * k)
        cols["drift"] = (np.concatenate([drift, np.zeros_like(drift)], axis=2),
                         np.concatenate([np.zeros_like(drift), drift], axis=2))
    blocks, parts, start = {}, [], 0
    for name, (force, torque) in cols.items():
        width = force.shape[2]
        blocks[name] = slice(start, start + width)
        start += width
        parts.append(np.concatenate([force / scale[0], torque / scale[1]], axis=1).reshape(6 * n, width))
    return np.hstack(parts), blocks


def block_observability(J: NDArray, blocks: dict[str, slice], noise: float) -> list[ParameterBlock]:
    out = []
    for name, sl in blocks.items():
        Jk, keep = J[:, sl], np.ones(J.shape[1], dtype=bool)
        keep[sl] = False
        others = J[:, keep]
        coef, *_ = np.linalg.lstsq(others, Jk, rcond=None)
        rest = Jk - others @ coef
        own = np.linalg.norm(Jk, axis=0)
        own = np.where(own > 0, own, 1.0)
        _, sv, vt = np.linalg.svd(rest / own, full_matrices=False)
        ratio = float(sv[-1])
        direction = vt[-1] / own
        direction /= np.linalg.norm(direction)
        # the standard error of the weakest combination: noise / |P⊥ J_k v| (v a unit vector in the block's units)
        size = float(np.linalg.norm(rest @ direction))
        unit, factor = _BLOCK_UNITS[name]
        se = float("inf") if size <= 0 else noise / size * factor
        # which other block imitates Jk v best
        imitation = np.zeros(J.shape[1])
        imitation[keep] = coef @ direction
        parts = {other: np.linalg.norm(J[:, osl] @ imitation[osl]) for other, osl in blocks.items() if other != name}
        best = max(parts, key=parts.get) if parts else "other parameters"
        rank = int(np.sum(sv >= UNIDENTIFIABLE))
        out.append(ParameterBlock(name=name, n_parameters=sl.stop - sl.start, rank=rank, identifiability=ratio,
                                  weakest_direction=direction, expected_std_error=se, unit=unit, confused_with=best))
    return out


def fit_mounting_rotation(g_robot: NDArray, W: NDArray, basis: NDArray, start: dict, scale: NDArray
                          ) -> tuple[NDArray, NDArray, NDArray]:
    """The mounting rotation vector [rad] minimising the weighted residual, its covariance (3, 3), and the
    covariance (13, 13) of ``[r, m, p, b_F, b_τ]`` (drift coefficients profiled out of the joint covariance).

    ``g_robot`` (n, 3): gravity in the robot's sensor frame per pose; ``start``: the closed-form fit
    (:func:`ftcal.experiment._drift.fit_gravity_blocks`); ``scale``: force and torque residual RMS weights."""
    import pinocchio as pin
    from scipy.optimize import least_squares

    n, k = basis.shape

    def unpack(x):
        return x[:3], x[3], x[4:7], x[7:13], x[13:].reshape(k, 6)

    def residual(x):
        r, m, p, b, D = unpack(x)
        g_s = g_robot @ mounting_matrix(r)  # Qᵀ g per pose, as rows: g Q
        pred = np.hstack([m * g_s, np.cross(p, g_s)]) + b + basis @ D
        res = W - pred
        return np.concatenate([res[:, :3] / scale[0], res[:, 3:] / scale[1]], axis=1).ravel()

    x0 = np.concatenate([np.zeros(3), [start["mass"]], start["p"], start["bias"], start["drift"].reshape(-1)])
    sol = least_squares(residual, x0, method="lm", x_scale="jac")
    r, m, p, _, _ = unpack(sol.x)
    g_s = g_robot @ mounting_matrix(r)
    J, blocks = _jacobian(g_s, m, p, basis, scale, mounting=True)
    # the analytic Jacobian is in the local rotation δ (Q exp δ); r's Jacobian differs by the right Jacobian of
    # SO(3), negligible at a few degrees but applied: dr = J_r(r)⁻¹ δ
    order = [blocks["mounting rotation"], blocks["mass"], blocks["centre of mass"], blocks["force bias"],
             blocks["torque bias"]] + ([blocks["drift"]] if k else [])
    J = np.hstack([J[:, sl] for sl in order])
    dof = max(J.shape[0] - J.shape[1], 1)
    s2 = float(np.sum(residual(sol.x) ** 2)) / dof
    cov = s2 * np.linalg.pinv(J.T @ J)
    T = np.eye(cov.shape[0])
    T[:3, :3] = np.linalg.inv(pin.Jexp3(r))  # the right Jacobian of SO(3): exp(r + dr) ≈ exp(r) exp(J_r dr)
    cov = T @ cov @ T.T
    return r, cov[:3, :3], cov[:13, :13]


def identify_mounting(g_s: NDArray, W: NDArray, basis: NDArray, fit: dict, groups: NDArray | None = None
                      ) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """The mounting rotation of a closed-form identification ``fit`` (of gravity ``g_s`` in the robot's sensor
    frame): checks what the poses can tell first (:func:`ftcal.experiment.tool_load_observability`'s blocks at the fitted tool,
    refused with the block and the axis they cannot tell), then fits it (:func:`fit_mounting_rotation`; the
    samples of one pose averaged when ``groups`` label them).

    Returns ``g_s`` in the mounted sensor frame, the rotation vector [rad], its covariance (3, 3) and the joint
    covariance (13, 13) of ``[r, m, p, b_F, b_τ]``."""
    from ..core._exceptions import CalibrationInputError

    scale = np.maximum(np.asarray(fit["residual_rms"], dtype=float),
                       1e-9 * np.array([1.0, 0.1]) * max(abs(fit["mass"]), 1e-3) * np.linalg.norm(g_s[0]))
    gp, Wp, bp = (per_pose_mean(a, groups) for a in (g_s, W, basis))
    J, blocks = _jacobian(gp, fit["mass"], fit["p"], bp, scale, mounting=True)
    dof = max(J.shape[0] - J.shape[1], 1)
    observability = Observability(blocks=tuple(block_observability(J, blocks, noise=float(
        np.sqrt(np.sum(fit["residual"] ** 2 / np.repeat(scale, 3) ** 2) / dof)))), n_poses=len(gp))
    problems = observability.problems()
    if problems:
        raise CalibrationInputError(
            f"the poses cannot tell the sensor's mounting rotation: {'; '.join(problems)}.", parameter="mounting",
            value=True, fix="add poses that tilt the tool about the axis named (two tilt axes, large angles, e.g. the "
            "11 of a plan with {subdivisions}), or identify with {mounting}",
            settings={"subdivisions": 0, "mounting": False})
    r, r_cov, joint_cov = fit_mounting_rotation(gp, Wp, bp, fit, scale)
    return g_s @ mounting_matrix(r), r, r_cov, joint_cov
