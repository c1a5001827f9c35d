"""Checks of an in-situ identification the user did not ask for: the wrench's frame, and a drift in the row order.

* :func:`check_wrench_frame`: a wrench logged in the base frame but declared in the sensor frame (or the reverse)
  still gives a tool, but a wrong one, and compensates into large "external" forces. Gravity tells the frames
  apart: a constant bias and a tool fit the wrench in the right frame to its noise, and in the wrong frame the
  bias turns with the sensor and the fit leaves a residual of the bias' and the tool's size.
* :func:`drift_in_recording_order`: static poses without times are usually in recording order; a bias that
  drifts over the recording (warm-up) then shows as a drift in the row order. When a drift over the row order cuts
  the held-out residual by more than its paired standard error, it is named with the change of mass and centre
  of mass it brings.
* :func:`tool_load_observability`: what a pose set can tell of each parameter block (mass, centre of mass,
  biases, mounting rotation, drift) before fitting (:mod:`ftcal.experiment._mounting`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import CalibrationInputError
from ._drift import fit_gravity_blocks, held_out_residual, per_pose_mean, spline_basis
from ._mounting import Observability, _jacobian, block_observability
from ._tool_load import _check_inputs, _gravity_in_sensor, identify_tool_load

__all__ = ["FrameCheck", "check_wrench_frame", "OrderDrift", "drift_in_recording_order", "FRAME_RATIO",
           "tool_load_observability"]

#: The other frame is "far better" when its force residual is at most the declared frame's divided by this.
FRAME_RATIO = 3.0
_FRAMES = ("sensor", "base")


@dataclass(frozen=True)
class FrameCheck:
    """The residual of the tool's gravity in the declared frame of the wrench and in the other one.

    Attributes
    ----------
    declared, other : {"sensor", "base"}
    residual_declared, residual_other : ndarray of shape (2,)
        RMS force [N] and torque [N·m] residual under each hypothesis (of a tool identified with a constant bias,
        or of the given tool's compensation).
    """

    declared: str
    other: str
    residual_declared: NDArray[np.float64]
    residual_other: NDArray[np.float64]

    @property
    def other_fits_better(self) -> bool:
        """Whether the other frame's force residual is :data:`FRAME_RATIO` times smaller than the declared one's."""
        return bool(self.residual_other[0] * FRAME_RATIO < self.residual_declared[0])

    def words(self, option: str = "wrench_frame") -> str:
        """One sentence: both residuals and the setting to use (``option`` spells it, e.g. ``--wrench-frame``)."""
        d, o = self.residual_declared, self.residual_other
        return (f"gravity fits the wrench far better in the {self.other} frame than in the declared {self.declared} "
                f"frame (residual RMS {o[0]:.3g} N, {o[1]:.3g} N·m against {d[0]:.3g} N, {d[1]:.3g} N·m): the wrench "
                f"is probably written in the {self.other} frame; use {option} {self.other}")


def _other_frame_wrench(R: NDArray, W: NDArray, declared: str) -> NDArray:
    """The wrench (sensor frame under ``declared``) as it would be in the sensor frame had the input been written
    in the other frame."""
    turn = "nji,nkj->nki" if declared == "sensor" else "nij,nkj->nki"  # Rᵀ (the input was in base) or R (in sensor)
    return np.einsum(turn, R, W.reshape(-1, 2, 3)).reshape(-1, 6)  # force and torque turned alike


def check_wrench_frame(sensor_rotations: ArrayLike, wrenches: ArrayLike, declared: str = "sensor", *,
                       gravity: ArrayLike = (0.0, 0.0, -9.81), tool=None, times: ArrayLike | None = None,
                       temperatures: ArrayLike | None = None) -> FrameCheck:
    """Compare how gravity fits the wrench in the declared frame and in the other (sensor vs base).

    Parameters
    ----------
    sensor_rotations : array-like of shape (n, 3, 3)
        Sensor to base frame at each row.
    wrenches : array-like of shape (n, 6)
        The wrench in the sensor frame as the declared frame made it (turned into the sensor frame when
        ``declared="base"``) [N, N·m].
    declared : {"sensor", "base"}
    gravity : array-like of shape (3,)
        [m/s²], base frame (ignored with ``tool``, which has its own).
    tool : ToolLoad, optional
        A known tool (compensation): each hypothesis' residual is its compensated wrench. ``None``: a tool with a
        constant bias is identified under each hypothesis.
    times, temperatures : array-like of shape (n,), optional
        Each row's time or temperature, for a ``tool`` whose bias drifts (:meth:`ToolLoad.bias_at`).

    Returns
    -------
    FrameCheck

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.spatial.transform import Rotation
    >>> from ftcal.experiment import ToolLoad, wrench_in_sensor_frame
    >>> R = Rotation.random(20, random_state=0).as_matrix()
    >>> tool = ToolLoad(mass=1.0, center_of_mass=np.array([0.0, 0.0, 0.1]), bias=np.array([3.0, 0, 0, 0, 0, 0.1]))
    >>> W = tool.gravity_wrench(R)                    # in the sensor frame, but declared in the base frame:
    >>> check = check_wrench_frame(R, wrench_in_sensor_frame(R, W), "base")
    >>> check.other_fits_better, check.other, check.residual_other.round(9).tolist()
    (True, 'sensor', [0.0, 0.0])
    """
    if declared not in _FRAMES:
        raise CalibrationInputError(f"declared must be 'sensor' or 'base'; got {declared!r}.", parameter="declared",
                                    value=declared)
    R, W = _check_inputs(sensor_rotations, wrenches)
    other = _FRAMES[1 - _FRAMES.index(declared)]
    W_other = _other_frame_wrench(R, W, declared)
    if tool is not None:
        import warnings

        with warnings.catch_warnings():  # the drift's extrapolation is the compensation's to say, once
            warnings.simplefilter("ignore")
            rms = [np.sqrt(np.mean(tool.compensate(R, w, times=times, temperatures=temperatures) ** 2,
                                   axis=0).reshape(2, 3).mean(axis=1)) for w in (W, W_other)]
    else:
        g_s = _gravity_in_sensor(R, gravity)
        rms = [fit_gravity_blocks(g_s, w, np.zeros((len(w), 0)))["residual_rms"] for w in (W, W_other)]
    return FrameCheck(declared=declared, other=other, residual_declared=np.asarray(rms[0]),
                      residual_other=np.asarray(rms[1]))


@dataclass(frozen=True)
class OrderDrift:
    """A bias drift over the row order that the held-out residual supports, and what it changes.

    Attributes
    ----------
    description : str
        The drift model, e.g. ``"spline in time (4 knots)"`` (time = the row's position).
    held_out_constant, held_out_drift : ndarray of shape (2,)
        Leave-poses-out residual RMS [N, N·m] with a constant bias and with the drift.
    paired_se : ndarray of shape (2,)
        Paired standard error (over poses) of their difference [N, N·m].
    mass_constant, mass_drift : float
        The tool's mass [kg] under each.
    center_of_mass_shift : ndarray of shape (3,)
        Centre of mass with the drift minus without [m].
    tool : ToolLoad
        The tool identified with the drift (``time_unit="pose"``).
    """

    description: str
    held_out_constant: NDArray[np.float64]
    held_out_drift: NDArray[np.float64]
    paired_se: NDArray[np.float64]
    mass_constant: float
    mass_drift: float
    center_of_mass_shift: NDArray[np.float64]
    tool: object

    def words(self, option: str = "times=range(n), time_unit='pose'") -> str:
        """One sentence: the cut of the held-out residual with its paired SE, the mass and centre of mass change,
        and the setting that uses it (``option``)."""
        c, d, se = self.held_out_constant, self.held_out_drift, self.paired_se
        change = 100.0 * (self.mass_drift - self.mass_constant) / self.mass_constant
        return (f"the rows look like a recording whose bias drifts: a bias drift over the row order ({self.description}) "
                f"cuts the held-out residual from {c[0]:.3g} to {d[0]:.3g} N (paired SE {se[0]:.2g} N) and from "
                f"{c[1]:.3g} to {d[1]:.3g} N·m (paired SE {se[1]:.2g} N·m); with it the mass is {self.mass_drift:.4f} kg "
                f"instead of {self.mass_constant:.4f} kg ({change:+.1f} %) and the centre of mass moves by "
                f"{1e3 * np.linalg.norm(self.center_of_mass_shift):.1f} mm; use it with {option}")


def drift_in_recording_order(sensor_rotations: ArrayLike, wrenches: ArrayLike, gravity: ArrayLike = (0.0, 0.0, -9.81),
                             *, groups: ArrayLike | None = None, cv: int = 20, random_state: int | None = 0
                             ) -> OrderDrift | None:
    """A bias drift over the rows' order (taken as the recording order) when the held-out residual supports it.

    The drift is chosen as :func:`ftcal.experiment.identify_tool_load` chooses it (``times`` the row positions,
    ``time_unit="pose"``: leave-poses-out CV, one-SE rule); it is returned when it cuts the held-out force or
    torque residual by more than the paired standard error of the cut (per pose), else ``None``.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.spatial.transform import Rotation
    >>> from ftcal.experiment import ToolLoad
    >>> R = Rotation.random(60, random_state=0).as_matrix()
    >>> W = ToolLoad(mass=1.0, center_of_mass=np.zeros(3), bias=np.zeros(6)).gravity_wrench(R)
    >>> W += np.random.default_rng(0).normal(0, 0.02, W.shape)
    >>> drift_in_recording_order(R, W) is None                     # no drift: nothing said
    True
    >>> W[:, 0] += np.linspace(0.0, 1.0, 60)                       # 1 N of drift over the recording
    >>> found = drift_in_recording_order(R, W)
    >>> found.description, bool(found.held_out_drift[0] < found.held_out_constant[0] - found.paired_se[0])
    ('linear in time', True)
    """
    R, W = _check_inputs(sensor_rotations, wrenches)
    if groups is not None:
        groups = np.asarray(groups)
        _, first, inverse = np.unique(groups, return_index=True, return_inverse=True)
        order = np.argsort(np.argsort(first))[inverse].astype(float)  # each row's pose, in order of appearance
    else:
        order = np.arange(len(W), dtype=float)
    settings = dict(gravity=gravity, groups=groups, cv=cv, random_state=random_state)
    drifting = identify_tool_load(R, W, times=order, time_unit="pose", drift="auto", **settings)
    if drifting.drift is None:
        return None
    constant = identify_tool_load(R, W, drift="none", **settings)
    g_s = _gravity_in_sensor(R, gravity)
    e_c = held_out_residual(g_s, W, np.zeros((len(W), 0)), groups=groups, cv=cv, random_state=random_state)
    e_d = held_out_residual(g_s, W, spline_basis(order, drifting.drift.knots), groups=groups, cv=cv,
                            random_state=random_state)
    if e_c is None or e_d is None:
        return None
    # each pose's mean squared force and torque error (poses, 2), with a constant bias and with the drift
    f_c, f_d = (per_pose_mean(np.mean(e.reshape(-1, 2, 3) ** 2, axis=2), groups) for e in (e_c, e_d))
    rms_c, rms_d = np.sqrt(f_c.mean(axis=0)), np.sqrt(f_d.mean(axis=0))
    u = f_c / (2 * np.maximum(rms_c, 1e-300)) - f_d / (2 * np.maximum(rms_d, 1e-300))  # delta method
    se = u.std(axis=0, ddof=1) / np.sqrt(len(u)) if len(u) > 1 else np.full(2, np.inf)
    if not ((rms_c - rms_d) > se).any():
        return None
    return OrderDrift(description=drifting.drift.description, held_out_constant=rms_c, held_out_drift=rms_d,
                      paired_se=se, mass_constant=constant.mass, mass_drift=drifting.mass,
                      center_of_mass_shift=drifting.center_of_mass - constant.center_of_mass, tool=drifting)


def tool_load_observability(sensor_rotations: ArrayLike, gravity: ArrayLike = (0.0, 0.0, -9.81), *,
                            mass: float = 1.0, center_of_mass: ArrayLike = (0.0, 0.0, 0.0),
                            mounting: bool = True, basis: ArrayLike | None = None,
                            noise: ArrayLike = (0.05, 0.005)) -> "Observability":
    """What a pose set can tell of a tool identification: rank and condition of each parameter block.

    Parameters
    ----------
    sensor_rotations : array-like of shape (n, 3, 3)
        The robot's sensor frame in the base frame at each pose.
    gravity : array-like of shape (3,)
        [m/s²] in the base frame.
    mass, center_of_mass : float, array-like of shape (3,)
        The tool the Jacobian is taken at [kg, m] (the closed-form estimate, or the expected tool).
    mounting : bool, default=True
        Whether the mounting rotation is a parameter.
    basis : array-like of shape (n, k), optional
        A bias drift's basis (:mod:`ftcal.experiment._drift`); ``None``: a constant bias.
    noise : array-like of shape (2,)
        The residual RMS of force [N] and torque [N·m] the expected standard errors are scaled to.

    Returns
    -------
    Observability

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.spatial.transform import Rotation
    >>> R = Rotation.from_euler("z", np.linspace(0, 300, 6)[:, None], degrees=True).as_matrix()  # never tilted
    >>> obs = tool_load_observability(R, mass=1.0, center_of_mass=[0.0, 0.0, 0.1])
    >>> obs.problems()[0]
    'the mass is not identifiable from these 6 poses: the force bias absorbs it'
    >>> R = Rotation.random(11, random_state=0).as_matrix()                                      # well spread
    >>> obs = tool_load_observability(R, mass=1.0, center_of_mass=[0.0, 0.0, 0.1], noise=[0.05, 0.005])
    >>> obs.problems(), obs.block("mounting rotation").rank
    ([], 3)
    """
    R, _ = _check_inputs(sensor_rotations)
    g_s = _gravity_in_sensor(R, gravity)
    b = np.zeros((len(R), 0)) if basis is None else np.asarray(basis, dtype=float)
    scale = np.maximum(np.asarray(noise, dtype=float), 1e-12)
    c = np.asarray(center_of_mass, dtype=float)
    J, blocks = _jacobian(g_s, float(mass), float(mass) * c, b, scale, mounting)
    return Observability(blocks=tuple(block_observability(J, blocks, noise=1.0)), n_poses=len(R))
