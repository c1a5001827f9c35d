"""Which poses next: sequential design from a dataset recorded so far and a fitted model.

Given the calibration dataset measured so far (load minus no-load readings and
the reference wrenches, :func:`ftcal.experiment.prepare_dataset`) and a model fitted on
it, :func:`propose_next_poses` ranks the reachable candidate directions of a
dense sphere by how uncertain the model's wrench would be there, and proposes
``n_poses`` of them.

What a candidate pose would give
--------------------------------
A pose is a gravity direction ``u`` in the sensor frame, run (as every pose)
with each load configuration ``c`` of the dataset. Its reference wrench is
known from physics (eq. 15-16): ``F = m |g| u``, ``tau = r_c x F``, with the
load mass, gravity and load positions recorded in the dataset's metadata. The
raw reading it would give is predicted by the dataset's own affine
wrench -> raw map, ``x = B^T [w, 1]`` (least squares over the dataset; the
sensor is linear to first order, and only the *location* of the candidate in
the model's input space matters here, not its fine detail). The model's
uncertainty is then evaluated at those predicted readings.

The uncertainty
---------------
* Any model: the linear model's predictive covariance on the dataset's
  regressors, ``s^2 phi_a^T (Phi^T Phi)^-1 phi_b`` with ``phi = [1, x]`` and
  ``s^2`` the LTM's residual variance on the dataset: proposing by it alone is
  sequential D-optimal design for the LTM (``uncertainty="linear"``).
* A Gaussian-process model (:class:`ftcal.GaussianProcessCalibrator`, or a
  wrapper whose ``best_estimator_`` / ``estimator_`` is one)
  adds the posterior covariance of its GP part (its ``latent_covariance``),
  ``K_cc - K_ct K_tt^-1 K_tc`` (its
  ``predict(X, return_std=True)`` is the diagonal of this plus the noise; it
  leaves out the uncertainty of the GP's linear part, which the first term
  carries). ``uncertainty="gaussian_process"``; the noise is the GP's.

Variances are summed over the six wrench components in the torque-scaled
space ``[F, alpha T]`` [N²] (``alpha`` the model's torque scale), the
project's convention for one error figure.

Batch choice
------------
The poses are chosen one at a time: the pose whose configurations have the
largest summed predictive variance, then the posterior is conditioned on
measuring it (for a GP the posterior variance does not depend on the values
that will be measured, so this is exact for fixed hyperparameters), and so on.
The **expected gain** of each proposal is the fraction of the summed
predictive variance over all candidate poses and configurations that
measuring it removes, given the proposals before it.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import NO_SETTING, Placeholder, PlanningError
from ..io._dataset import CalibrationDataset
from ..robot._loads import STANDARD_GRAVITY
from ..robot._pose_planning import (CalibrationPlan, CandidatePoses, pitch_yaw_from_gravity_in_sensor,
                                     reachable_candidates)
from ..robot._robot import RobotModel

__all__ = ["PoseProposal", "propose_next_poses"]

@dataclass
class PoseProposal(CalibrationPlan):
    """The poses proposed next, most informative first: a :class:`ftcal.robot.CalibrationPlan` plus the gains.

    Its ``q`` are reachable (IK residual and joint limits checked), so it can be run (and simulated,
    ``simulate_experiment(plan=...)``) like any plan; ``unreachable`` are the candidates IK missed.

    Attributes
    ----------
    predicted_std : ndarray of shape (k,)
        Predictive standard deviation of the wrench at the pose before measuring it:
        RMS over its load configurations of the summed torque-scaled variance [N].
    expected_gain : ndarray of shape (k,)
        Fraction of the candidates' summed predictive variance that measuring the pose
        removes, given the proposals before it.
    uncertainty : str
        ``"gaussian_process"`` or ``"linear"`` (see the module docstring).
    total_variance_before, total_variance_after : float
        Summed predictive variance over all candidates and configurations [N²].
    """

    predicted_std: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    expected_gain: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    uncertainty: str = "linear"
    total_variance_before: float = 0.0
    total_variance_after: float = 0.0


def _gaussian_process_of(model):
    """The fitted GP calibrator inside ``model`` (itself, or what a wrapper chose), or None."""
    for candidate in (model, *(getattr(model, a, None) for a in ("best_estimator_", "estimator_"))):
        if candidate is not None and callable(getattr(candidate, "latent_covariance", None)):
            return candidate
    return None


def _torque_scale(model, wrench: NDArray[np.float64]) -> float:
    alpha = getattr(model, "alpha_", None)
    if alpha is not None and np.isfinite(alpha) and alpha > 0:
        return float(alpha)
    f, t = np.abs(wrench[:, :3]).max(), np.abs(wrench[:, 3:]).max()
    return float(f / t) if t > 0 and f > 0 else 1.0


def _covariance_linear(dataset: CalibrationDataset, y_scaled: NDArray[np.float64], raw: NDArray[np.float64]
                       ) -> tuple[Callable, NDArray[np.float64], float]:
    """The LTM's predictive covariance at raw readings (its residual variance summed over the outputs)."""
    Phi = np.hstack([np.ones((dataset.n_samples, 1)), dataset.raw])
    coef, *_ = np.linalg.lstsq(Phi, y_scaled, rcond=None)
    dof = max(dataset.n_samples - Phi.shape[1], 1)
    s2 = float(np.sum((y_scaled - Phi @ coef) ** 2) / dof)
    u, sing, vt = np.linalg.svd(Phi, full_matrices=False)
    keep = sing > 1e-12 * sing[0]
    F = (np.hstack([np.ones((len(raw), 1)), raw]) @ vt[keep].T / sing[keep]) * np.sqrt(s2)
    return (lambda idx: F @ F[idx].T), np.sum(F * F, axis=1), s2


def propose_next_poses(
    robot: RobotModel,
    dataset: CalibrationDataset,
    model,
    n_poses: int,
    *,
    candidates: CandidatePoses | None = None,
    candidate_subdivisions: int = 3,
    load_positions_in_sensor: ArrayLike | None = None,
    load_mass: float | None = None,
    gravity_in_base: ArrayLike | None = None,
) -> PoseProposal:
    """Propose the ``n_poses`` reachable poses where the model's predicted wrench is most uncertain.

    Parameters
    ----------
    robot : RobotModel
    dataset : CalibrationDataset
        What was measured so far (``raw`` = load minus no-load reading, ``wrench`` the reference).
    model : fitted calibrator
        Trained on ``dataset``'s channels; a Gaussian-process model gives its own uncertainty,
        any other the LTM's (module docstring).
    n_poses : int
        How many poses to propose, 1 .. number of reachable candidates.
    candidates : CandidatePoses, optional
        Precomputed :func:`ftcal.robot.reachable_candidates`; default level ``candidate_subdivisions``.
    load_positions_in_sensor : array-like of shape (n_configurations, 3), optional
        Load positions [m] run at every pose; default ``dataset.meta["load_positions_in_sensor_m"]``.
    load_mass : float, optional
        [kg]; default ``dataset.meta["load_mass_kg"]``.
    gravity_in_base : array-like of shape (3,), optional
        [m/s²]; default ``dataset.meta["gravity_in_base_m_s2"]`` or standard gravity.

    Returns
    -------
    PoseProposal

    Raises
    ------
    PlanningError
        Model and dataset of different channel counts, a dataset without load mass or positions
        (and none given), ``n_poses`` not in ``1 .. n_candidates``.

    Examples
    --------
    >>> import tempfile
    >>> from ftcal import LinearCalibrator
    >>> from ftcal.robot import load_robot, plan_calibration_poses, reachable_candidates
    >>> from ftcal.experiment import prepare_dataset, simulate_experiment
    >>> robot = load_robot()
    >>> plan = plan_calibration_poses(robot, subdivisions=0, excluded_cap_deg=0)
    >>> ds = prepare_dataset(simulate_experiment(tempfile.mkdtemp(), robot=robot, plan=plan, random_state=0), robot)
    >>> model = LinearCalibrator().fit(ds.raw, ds.wrench)
    >>> cands = reachable_candidates(robot, subdivisions=1, excluded_cap_deg=0)
    >>> nxt = propose_next_poses(robot, ds, model, 3, candidates=cands)
    >>> nxt.n_poses, nxt.uncertainty, bool(nxt.expected_gain.min() > 0)
    (3, 'linear', True)
    """
    if not isinstance(dataset, CalibrationDataset):
        raise PlanningError(f"dataset must be a CalibrationDataset; got {type(dataset).__name__}.")
    _check_model_channels(model, dataset)
    r, load_mass = _load_of(dataset, load_positions_in_sensor, load_mass)
    g = np.asarray(gravity_in_base if gravity_in_base is not None
                   else (dataset.meta or {}).get("gravity_in_base_m_s2", (0.0, 0.0, -STANDARD_GRAVITY)), dtype=float)
    if dataset.n_samples <= 7:
        raise PlanningError(f"the dataset has {dataset.n_samples} rows; at least 8 are needed to predict the raw "
                            "reading of a new pose (an affine map from the 6 wrench components).")
    if candidates is None:
        candidates = reachable_candidates(robot, subdivisions=candidate_subdivisions,
                                          gravity_in_base=g / np.linalg.norm(g))
    m, n_cfg = len(candidates), len(r)
    if isinstance(n_poses, bool) or not isinstance(n_poses, (int, np.integer)) or not 1 <= n_poses <= m:
        raise PlanningError(f"{{n_poses}} must be an integer in 1..{m} (the reachable candidates); got {n_poses!r}.",
                            parameter="n_poses", value=n_poses,
                            fix=f"ask for at most {m} poses, or rank the candidates of a denser sphere (a larger "
                            "{candidate_subdivisions})", settings={"candidate_subdivisions": NO_SETTING})

    # Reference wrench of every candidate x configuration (eq. 15-16), then the reading it would give.
    force = float(load_mass) * float(np.linalg.norm(g)) * candidates.gravity_in_sensor
    forces = np.repeat(force, n_cfg, axis=0)
    wrench = np.hstack([forces, np.cross(np.tile(r, (m, 1)), forces)])
    B, *_ = np.linalg.lstsq(np.hstack([dataset.wrench, np.ones((dataset.n_samples, 1))]), dataset.raw, rcond=None)
    raw = np.hstack([wrench, np.ones((len(wrench), 1))]) @ B

    gp = _gaussian_process_of(model)
    alpha = float(gp.alpha_) if gp is not None else _torque_scale(model, dataset.wrench)
    y_scaled = np.hstack([dataset.wrench[:, :3], alpha * dataset.wrench[:, 3:]])
    columns, diag, noise = _covariance_linear(dataset, y_scaled, raw)
    kind = "linear"
    if gp is not None:  # the GP's residual covariance on top of its linear part's parameter uncertainty
        lin_columns, (gp_columns, gp_diag, noise) = columns, gp.latent_covariance(raw)
        columns = lambda idx: lin_columns(idx) + gp_columns(idx)  # noqa: E731
        diag = diag + gp_diag
        kind = "gaussian_process"
    noise = max(noise, 1e-12 * max(float(diag.max()), 1e-300))

    total_before = float(diag.sum())
    chosen, stds, gains, var = _greedy_poses(diag, columns, noise, m, n_cfg, int(n_poses))

    pick = np.array(chosen, dtype=int)
    gsens = candidates.gravity_in_sensor[pick]
    pitch, yaw = pitch_yaw_from_gravity_in_sensor(gsens)
    return PoseProposal(
        q=candidates.q[pick], gravity_in_sensor=gsens, pitch=pitch, yaw=yaw, unreachable=candidates.unreachable,
        anchor_position_in_base=candidates.anchor_position_in_base, robot_name=robot.name,
        sensor_frame=robot.sensor_frame, anchor_frame=robot.anchor_frame, n_candidates=candidates.n_candidates,
        predicted_std=np.array(stds),
        expected_gain=np.array(gains), uncertainty=kind, total_variance_before=total_before,
        total_variance_after=float(var.sum()),
        settings={"strategy": "next", "uncertainty": kind, "n_poses": int(n_poses), **candidates.settings,
                  "n_reachable_candidates": m, "load_mass_kg": float(load_mass),
                  "load_positions_in_sensor_m": r.tolist(), "dataset_rows": dataset.n_samples},
    )


def _check_model_channels(model, dataset: CalibrationDataset) -> None:
    """Refuse a model that is not fitted, or reads another number of raw channels than the dataset holds."""
    n_in = getattr(model, "n_features_in_", None)
    if n_in is None:
        raise PlanningError(f"model must be a fitted calibrator (no n_features_in_ on {type(model).__name__}); "
                            "fit it on the dataset first (ftcal fit).")
    # its last input is the temperature: read from the model's own tags (no calibrator import in this layer)
    tags = model.__sklearn_tags__() if hasattr(model, "__sklearn_tags__") else None
    takes_temperature = bool(getattr(getattr(tags, "ftcal", None), "temperature_column", False))
    n_raw = int(n_in) - int(takes_temperature)
    if n_raw != dataset.n_channels:
        also = " and the temperature" if takes_temperature else ""
        raise PlanningError(f"the model reads {n_raw} raw channels{also} but the dataset has {dataset.n_channels} "
                            f"raw channels (raw shape {dataset.raw.shape}).", parameter="model",
                            fix="pass the model trained on this dataset's sensor")


def _load_of(dataset: CalibrationDataset, load_positions_in_sensor: ArrayLike | None, load_mass: float | None
             ) -> tuple[NDArray[np.float64], float]:
    """The load positions (n_configurations, 3) [m] and the load mass [kg]: as given, else from the dataset's
    metadata (what :func:`prepare_dataset` records)."""
    meta = dataset.meta or {}
    if load_positions_in_sensor is None:
        positions = meta.get("load_positions_in_sensor_m")
        if not positions:
            raise PlanningError("the dataset's metadata holds no load_positions_in_sensor_m (it was not made by "
                                "prepare_dataset from run logs, which records them).",
                                parameter="load_positions_in_sensor",
                                fix="prepare the dataset from the run logs, or pass {load_positions_in_sensor}",
                                settings={"load_positions_in_sensor": Placeholder("<(n_configurations, 3) array [m]>")})
        load_positions_in_sensor = [positions[k] for k in sorted(positions, key=lambda k: int(k))]
    r = np.asarray(load_positions_in_sensor, dtype=float)
    if r.ndim != 2 or r.shape[1] != 3 or not len(r) or not np.isfinite(r).all():
        raise PlanningError(f"load_positions_in_sensor must be a finite (n_configurations, 3) array [m]; "
                            f"got shape {r.shape}.")
    if load_mass is None:
        load_mass = meta.get("load_mass_kg")
        if load_mass is None:
            raise PlanningError("the dataset's metadata holds no load_mass_kg.", parameter="load_mass",
                                fix="pass {load_mass}", settings={"load_mass": Placeholder("<mass [kg]>")})
    if not np.isfinite(load_mass) or load_mass <= 0:
        raise PlanningError(f"load_mass must be a positive mass in kg; got {load_mass!r}.")
    return r, load_mass


def _greedy_poses(diag: NDArray, columns, noise: float, m: int, n_cfg: int, n_poses: int
                  ) -> tuple[list[int], list[float], list[float], NDArray]:
    """Greedy choice of ``n_poses`` of ``m`` candidates (``n_cfg`` predicted points each): each step takes the pose
    of largest remaining predictive variance and conditions on it. The chosen poses, their predicted std before
    being chosen, each one's share of the total variance removed, and the variance left (m * n_cfg,)."""
    var = diag.copy()
    total_before = float(var.sum())
    updates = np.zeros((len(var), 0))
    chosen, stds, gains = [], [], []
    for _ in range(n_poses):
        per_pose = var.reshape(m, n_cfg).sum(axis=1)
        per_pose[chosen] = -np.inf
        k = int(np.argmax(per_pose))
        idx = np.arange(k * n_cfg, (k + 1) * n_cfg)
        stds.append(float(np.sqrt(np.mean(var[idx] + noise))))
        cols = columns(idx) - updates @ updates[idx].T  # current posterior covariance with the pose's points
        L = np.linalg.cholesky(cols[idx] + noise * np.eye(n_cfg))
        new = np.linalg.solve(L, cols.T).T
        reduction = np.sum(new * new, axis=1)
        gains.append(float(reduction.sum() / total_before) if total_before > 0 else 0.0)
        var = np.maximum(var - reduction, 0.0)
        updates = np.hstack([updates, new])
        chosen.append(k)
    return chosen, stds, gains, var
