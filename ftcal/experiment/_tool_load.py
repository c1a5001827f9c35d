"""Tool load identification and gravity compensation.

A sensor on a robot carries a tool (gripper, probe, mounting plate): its
weight shows in every reading and changes with the orientation. With the
sensor's orientation from forward kinematics (:func:`ftcal.robot.sensor_pose_in_base`),
the tool's mass ``m`` [kg], centre of mass ``c`` [m] (sensor frame) and the
reading's bias ``b`` (6,) [N, N·m] follow from a few static poses by linear
least squares, in closed form. With the gravity vector in the sensor frame
``g_s = Rᵀ g`` (``R`` maps sensor to base frame, ``g`` [m/s²] in the base frame):

* force rows:  ``F = m g_s + b_F``                   (unknowns ``m``, ``b_F``: 4)
* torque rows: ``τ = c × (m g_s) + b_τ = -[g_s]× p + b_τ`` with ``p = m c``
  (unknowns ``p``, ``b_τ``: 6), then ``c = p / m``.

Each block is an ordinary least-squares problem; the standard errors come
from its residual variance and ``(AᵀA)⁻¹`` (``c``'s by the delta method).
The problem is only solvable when the poses tilt the tool in two independent
directions: :func:`identify_tool_load` refuses poses whose gravity directions
(in the sensor frame) vary by less than :data:`MIN_TILT_DEG` in two
directions. The 11 poses of ``ftcal plan --subdivisions 0`` (the 12 vertices
of an icosahedron of gravity directions, minus the one straight up) are a
minimal well-conditioned set.

This is the method of the gravity-compensation tools robot users rely on
(ROS' force_torque_tools and ros2_control's GravityCompensation take the
same mass, centre of mass and bias); ftcal adds the identification from its
own pose planner, logs and calibrators, with standard errors.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import CalibrationInputError
from ..core._fields import numbers_field
from ..core._files import atomic_output
from ..core._validation import check_quiet
from ..core._wrench import MAX_LOAD_MASS_KG, WRENCH_LABELS
from ._mounting import axis_text, identify_mounting
from ._drift import (_SECONDS_PER_HOUR, BiasDrift, DriftExtrapolationWarning, build_drift, fit_gravity_blocks,
                     functional_se, held_out_predictions, held_out_residual, mounting_matrix, pose_folds, select_drift)

__all__ = ["ToolLoad", "identify_tool_load", "identification_summary", "MIN_TILT_DEG", "DEFAULT_GRAVITY", "ROTATION_TOLERANCE",
           "tool_gravity_compensation_yaml", "BiasDrift", "DriftExtrapolationWarning", "TOOL_FORMAT_VERSION",
           "wrench_in_sensor_frame"]

#: Version of the tool file: 1 without a bias drift (readable by older ftcal), 2 with one (older ftcal refuses it
#: rather than ignore the drift).
TOOL_FORMAT_VERSION = 2

#: Gravity in the base frame [m/s²] (z up).
DEFAULT_GRAVITY = (0.0, 0.0, -9.81)
#: Largest entry of ``RᵀR - I`` accepted as rounding of a rotation matrix (a 3-decimal log gives ~1e-3); the
#: matrix is then projected onto the nearest rotation.
ROTATION_TOLERANCE = 5e-3
#: The gravity directions (sensor frame) must vary by at least this much in two independent directions [deg].
MIN_TILT_DEG = 10.0
#: Largest mounting rotation a tool holds [rad] (20 deg): a mounting error is a few degrees; a larger turn belongs
#: in the robot model (``load_robot(sensor_mounting=...)``).
MAX_MOUNTING_ROTATION_RAD = float(np.radians(20.0))


def _check_inputs(sensor_rotations: ArrayLike, wrenches: ArrayLike | None = None):
    R = np.asarray(sensor_rotations, dtype=float)
    if R.ndim != 3 or R.shape[1:] != (3, 3):
        raise CalibrationInputError(
            f"sensor_rotations must have shape (n, 3, 3), one rotation (sensor to base frame) per pose; got "
            f"shape {R.shape}. Take them from ftcal.robot.sensor_pose_in_base(robot, q)[:, :3, :3]."
        )
    if not np.isfinite(R).all():
        raise CalibrationInputError("sensor_rotations holds NaN or inf.")
    R = _nearest_rotations(R)
    if wrenches is None:
        return R, None
    W = np.asarray(wrenches, dtype=float)
    if W.shape != (len(R), 6):
        raise CalibrationInputError(
            f"wrenches must have shape ({len(R)}, 6), one [Fx, Fy, Fz, Tx, Ty, Tz] per rotation; got {W.shape}."
        )
    if not np.isfinite(W).all():
        row = int(np.argwhere(~np.isfinite(W))[0, 0])
        raise CalibrationInputError(f"wrenches holds NaN or inf (first at row {row}); repair or drop that pose.")
    return R, W


def _nearest_rotations(R: NDArray[np.float64]) -> NDArray[np.float64]:
    """The nearest proper rotations (SVD projection onto SO(3)) of matrices that are rotations up to
    :data:`ROTATION_TOLERANCE` (rounding in a log file); a mirror (det = -1) or a matrix further off is refused."""
    orthonormal = np.abs(np.einsum("nji,njk->nik", R, R) - np.eye(3)).max(axis=(1, 2))
    if orthonormal.max() > ROTATION_TOLERANCE:
        i = int(np.argmax(orthonormal))
        raise CalibrationInputError(
            f"sensor_rotations[{i}] is not a rotation matrix (RᵀR differs from the identity by "
            f"{orthonormal[i]:.2g}, more than {ROTATION_TOLERANCE:g}); pass rotations, e.g. the upper-left 3x3 of "
            "the sensor poses."
        )
    det = np.linalg.det(R)
    if (det < 0).any():
        i = int(np.argmax(det < 0))
        raise CalibrationInputError(
            f"sensor_rotations[{i}] is a reflection (determinant {det[i]:.3g}), not a rotation: a mirrored frame "
            "(one axis flipped) would give a wrong mass and centre of mass. Check the handedness of the frames."
        )
    U, _, Vt = np.linalg.svd(R)
    return U @ Vt


#: Bounds of a tool file's values: beyond them a value is a unit or typing error, not a tool (a 10 t tool, a
#: centre of mass 100 m away, 100 g of gravity), and the compensation would overflow or be meaningless.
TOOL_LIMITS = {"mass": MAX_LOAD_MASS_KG, "center_of_mass": 100.0, "gravity": 1e3, "bias": 1e9}
_LIMIT_UNITS = {"mass": "kg", "center_of_mass": "m", "gravity": "m/s²", "bias": "N, N·m"}


def _check_limit(name: str, a: NDArray[np.float64], owner: str = "ToolLoad ") -> None:
    """Raise when ``a`` (a number, or a vector by its norm) exceeds ``TOOL_LIMITS[name]``."""
    size = float(np.abs(a).max(initial=0.0))
    if size > 0 and name in ("center_of_mass", "gravity"):
        size *= float(np.linalg.norm(a / size))  # the norm, without overflowing its squares
    if size > TOOL_LIMITS[name]:
        raise CalibrationInputError(
            f"{owner}{name} has magnitude {size:.3g} {_LIMIT_UNITS[name]}, beyond the {TOOL_LIMITS[name]:g} "
            f"{_LIMIT_UNITS[name]} a tool on a force/torque sensor can have. Fix: check the value and its unit."
        )


#: The magnitudes [m/s²] of gravity :func:`identify_tool_load` accepts: the Earth's surface spans 9.78 (equator)
#: to 9.84 (poles, and altitude lowers it); the margin allows a rounded value (9.8) and local surveys. Beyond it
#: a gravity is in another unit (cm/s², mm/s², g, ft/s², in/s²), and the mass would come out scaled by its inverse.
GRAVITY_MAGNITUDE_RANGE = (9.7, 9.9)


def _check_gravity_magnitude(gravity: ArrayLike) -> None:
    """Refuse a gravity whose magnitude is not the Earth's surface gravity, naming the likely unit slip."""
    g = np.asarray(gravity, dtype=float)
    if g.shape != (3,) or not np.isfinite(g).all() or not np.abs(g).max() > 0:
        return  # not a vector at all: _gravity_in_sensor says so
    size = float(np.abs(g).max() * np.linalg.norm(g / np.abs(g).max()))  # the norm, without overflowing its squares
    low, high = GRAVITY_MAGNITUDE_RANGE
    if low <= size <= high:
        return
    slips = [(980.665, "in cm/s² (divide by 100)"), (9806.65, "in mm/s² (divide by 1000)"),
             (1.0, "in g (multiply by 9.81)"), (0.00980665, "in km/s² (multiply by 1000)"),
             (32.174, "in ft/s² (multiply by 0.3048)"), (386.09, "in in/s² (multiply by 0.0254)")]
    near, words = min(slips, key=lambda item: abs(np.log(size / item[0])))
    slip = words if abs(np.log(size / near)) < np.log(1.5) else f"scaled by {size / 9.81:.3g}"
    raise CalibrationInputError(
        f"gravity has magnitude {size:.4g} m/s² ({g.tolist()}), not the Earth's surface gravity (9.78-9.84 m/s²; "
        f"{low:g}-{high:g} accepted): a gravity in another unit scales the identified mass by its inverse. It "
        f"looks to be {slip}; give gravity in m/s² (e.g. 0,0,-9.81 with z up).")


def _zero_mass_error(mass: float, mass_se: float, declared_frame: str, gravity: ArrayLike) -> CalibrationInputError:
    """The error of a mass not distinguishable from zero, its advice following the frame the wrenches were
    declared in (the other frame is the likely slip) and naming the gravity direction as the other cause."""
    g = np.asarray(gravity, dtype=float)
    if declared_frame == "base":
        cause = ("the wrenches were declared in the robot's base frame and turned into the sensor frame: wrenches recorded "
                 "in the sensor frame already look like this once turned")
    else:
        cause = "a wrench recorded in the robot's base frame, not turned into the sensor frame, looks like this"
    other = "sensor" if declared_frame == "base" else "base"
    return CalibrationInputError(
        f"the identified mass, {mass:.4g} ± {mass_se:.2g} kg, is not distinguishable from zero: the force does not "
        f"turn with the sensor's orientation as a tool's weight does (the bias took it). Either {cause}; or gravity "
        f"is not along {g.tolist()} m/s² (base frame) in these poses; or the tool is too light for these readings' "
        "noise.", fix=f"if the wrenches are in the {other} frame, declare it ({{declared_frame}}); else check the "
        "gravity's axis and sign", settings={"declared_frame": other})


def _gravity_in_sensor(R: NDArray[np.float64], gravity: ArrayLike) -> NDArray[np.float64]:
    g = np.asarray(gravity, dtype=float)
    if g.shape != (3,) or not np.isfinite(g).all() or not np.abs(g).max() > 0:
        raise CalibrationInputError(f"gravity must be a finite non-zero 3-vector in [m/s²]; got {gravity!r}.")
    _check_limit("gravity", g, owner="")
    return np.einsum("nji,j->ni", R, g)  # Rᵀ g per pose


#: Each array field of a ToolLoad: its shape, whether it must be >= 0, and its key in the tool file (in the order
#: of the checks and of the file's keys).
_FIELDS = {"mass": ((), True, "mass_kg"), "center_of_mass": ((3,), False, "center_of_mass_m"),
           "bias": ((6,), False, "bias"), "mass_std_error": ((), True, "mass_std_error_kg"),
           "center_of_mass_std_error": ((3,), True, "center_of_mass_std_error_m"),
           "bias_std_error": ((6,), True, "bias_std_error"), "gravity": ((3,), False, "gravity_m_s2"),
           "residual_rms": ((2,), True, "residual_rms"), "held_out_residual_rms": ((2,), True, "held_out_residual_rms"),
           "mounting_rotation": ((3,), False, "mounting_rotation_rad"),
           "mounting_rotation_std_error": ((3,), True, "mounting_rotation_std_error_rad")}
#: The fields a tool file must hold (the others have their defaults).
_REQUIRED = ("mass", "center_of_mass", "bias")


@dataclass(frozen=True)
class ToolLoad:
    """A tool's gravity load on the sensor, and the sensor's bias.

    Attributes
    ----------
    mass : float
        [kg].
    center_of_mass : ndarray of shape (3,)
        In the sensor frame [m].
    bias : ndarray of shape (6,)
        The reading's offset [N, N·m] (what the sensor reads with no load at all).
    mass_std_error, center_of_mass_std_error, bias_std_error
        Standard errors of the above (same units).
    gravity : ndarray of shape (3,)
        Gravity in the base frame [m/s²] used for the identification.
    residual_rms : ndarray of shape (2,)
        RMS of the force [N] and torque [N·m] residuals of the identification poses (in-sample).
    held_out_residual_rms : ndarray of shape (2,) or None
        The same RMS [N, N·m] of each pose's residual predicted by the identification on the other poses
        (leave-poses-out: K-fold over poses, leave-one-out on at most ``cv`` poses): how well the tool predicts
        a pose it has not seen. ``None`` when unknown (a tool file of an older ftcal, too few poses).
    mounting_rotation : ndarray of shape (3,)
        The sensor's mounting rotation relative to the robot's sensor frame, a rotation vector [rad]
        (``identify_tool_load(..., mounting=True)``; zero otherwise): the sensor's true orientation is
        ``R @ Rotation.from_rotvec(mounting_rotation).as_matrix()`` with ``R`` the robot's.
    mounting_rotation_std_error : ndarray of shape (3,)
        Its standard error [rad].
    drift : BiasDrift or None
        How the bias moves with time or temperature (``None``: a constant bias). With a drift, ``bias`` is
        the bias at ``drift.reference`` (the end of the identification, or the last re-tare) and every
        compensation needs the time (or temperature) of each wrench.
    """

    mass: float
    center_of_mass: NDArray[np.float64]
    bias: NDArray[np.float64]
    mass_std_error: float = 0.0
    center_of_mass_std_error: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    bias_std_error: NDArray[np.float64] = field(default_factory=lambda: np.zeros(6))
    gravity: NDArray[np.float64] = field(default_factory=lambda: np.asarray(DEFAULT_GRAVITY))
    residual_rms: NDArray[np.float64] = field(default_factory=lambda: np.zeros(2))
    drift: BiasDrift | None = None
    held_out_residual_rms: NDArray[np.float64] | None = None
    mounting_rotation: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))
    mounting_rotation_std_error: NDArray[np.float64] = field(default_factory=lambda: np.zeros(3))

    def __post_init__(self) -> None:
        """Check every field: finite values of the right shapes, a mass and standard errors >= 0, a gravity."""
        def array(name: str, shape: tuple[int, ...], nonnegative: bool = False) -> None:
            value = getattr(self, name)
            try:
                a = np.array(value, dtype=float)
            except (TypeError, ValueError):
                raise CalibrationInputError(f"ToolLoad {name} must be numbers; got {value!r}.") from None
            if a.shape != shape or not np.isfinite(a).all() or (nonnegative and (a < 0).any()):
                need = "finite number" if shape == () else f"{shape[0]} finite numbers"
                raise CalibrationInputError(
                    f"ToolLoad {name} must be {'a ' if shape == () else ''}{need}{' >= 0' if nonnegative else ''}; "
                    f"got {value!r}.")
            object.__setattr__(self, name, float(a) if shape == () else a)

        for name, (shape, nonnegative, _) in _FIELDS.items():
            if getattr(self, name) is not None or name != "held_out_residual_rms":
                array(name, shape, nonnegative)
        if np.linalg.norm(self.mounting_rotation) > MAX_MOUNTING_ROTATION_RAD:
            raise CalibrationInputError(
                f"ToolLoad mounting_rotation turns by {np.degrees(np.linalg.norm(self.mounting_rotation)):.3g} deg, "
                f"more than the {np.degrees(MAX_MOUNTING_ROTATION_RAD):g} deg a mounting error can be. Fix: give the "
                "sensor's mounting to the robot model (sensor_mounting) and identify the small rest.")
        if not np.abs(self.gravity).max() > 0:
            raise CalibrationInputError(f"ToolLoad gravity must be a non-zero vector in [m/s²]; got {self.gravity!r}.")
        for name in TOOL_LIMITS:
            _check_limit(name, getattr(self, name))
        if self.drift is not None and not isinstance(self.drift, BiasDrift):
            raise CalibrationInputError(f"ToolLoad drift must be a BiasDrift or None; got {type(self.drift).__name__}.")

    def bias_at(self, n: int, times: ArrayLike | None = None, temperatures: ArrayLike | None = None
                ) -> NDArray[np.float64]:
        """The bias [N, N·m] at each of ``n`` readings (n, 6): constant, or moved by the drift to each reading's
        time (``times``, in the drift's unit) or temperature (``temperatures`` [deg C]); warns
        (:class:`DriftExtrapolationWarning`) for values outside the span the drift covers."""
        bias = np.broadcast_to(np.asarray(self.bias), (n, 6))
        if self.drift is None:
            return bias.copy()
        given = times if self.drift.variable == "time" else temperatures
        if given is None:
            what = (f"the time of each wrench (times, in {'seconds' if self.drift.unit == 's' else 'pose order'})"
                    if self.drift.variable == "time" else "the temperature of each wrench (temperatures [deg C])")
            raise CalibrationInputError(
                f"this tool's bias drifts ({self.drift.description}): compensating needs {what}. Fix: pass it, "
                "or identify the tool with drift='none'.")
        v = np.asarray(given, dtype=float)
        if v.shape != (n,):
            raise CalibrationInputError(f"{'times' if self.drift.variable == 'time' else 'temperatures'} must have "
                                        f"shape ({n},), one value per wrench; got shape {v.shape}.")
        return bias + self.drift.offset(v)

    def gravity_wrench(self, sensor_rotations: ArrayLike, *, times: ArrayLike | None = None,
                       temperatures: ArrayLike | None = None) -> NDArray[np.float64]:
        """The wrench [N, N·m] the tool's weight plus the bias produce at each pose (n, 6), sensor frame
        (``times`` / ``temperatures``: see :meth:`bias_at`)."""
        R, _ = _check_inputs(sensor_rotations)
        return self._weight_wrench(R) + self.bias_at(len(R), times, temperatures)

    def _weight_wrench(self, R: NDArray[np.float64]) -> NDArray[np.float64]:
        """The tool's weight alone as a wrench in the sensor frame (n, 6) [N, N·m] (the sensor's frame turned by the
        mounting rotation from the robot's)."""
        force = self.mass * _gravity_in_sensor(R @ mounting_matrix(self.mounting_rotation), self.gravity)
        return np.hstack([force, np.cross(np.asarray(self.center_of_mass), force)])

    def compensate(self, sensor_rotations: ArrayLike, wrenches: ArrayLike, *, times: ArrayLike | None = None,
                   temperatures: ArrayLike | None = None) -> NDArray[np.float64]:
        """The external wrench: measured ``wrenches`` (n, 6) minus the tool's gravity wrench and the bias (at each
        wrench's time or temperature when the bias drifts, :meth:`bias_at`).

        Examples
        --------
        >>> import numpy as np
        >>> tool = ToolLoad(mass=1.0, center_of_mass=np.array([0.0, 0.0, 0.1]), bias=np.zeros(6))
        >>> R = np.eye(3)[None]                      # sensor frame = base frame, z up
        >>> tool.compensate(R, tool.gravity_wrench(R)).round(12)
        array([[0., 0., 0., 0., 0., 0.]])
        """
        R, W = _check_inputs(sensor_rotations, wrenches)
        return W - self.gravity_wrench(R, times=times, temperatures=temperatures)

    def retare(self, wrenches: ArrayLike, *, sensor_rotations: ArrayLike | None = None,
               time: float | None = None, temperature: float | None = None, max_spread: float = 5.0) -> "ToolLoad":
        """A copy whose bias is reset from a few no-load readings; the drift's shape (its rate) is kept.

        Parameters
        ----------
        wrenches : array-like of shape (n, 6)
            Calibrated readings [N, N·m] with nothing touching the tool (or no tool at all).
        sensor_rotations : array-like of shape (n, 3, 3) or (3, 3), optional
            The sensor's orientation (sensor to base) at each reading, when the tool is mounted: its weight is
            removed first. ``None``: the tool is off the sensor (the readings are the bias itself).
        time, temperature : float, optional
            When the readings were taken (the drift's unit) / the sensor's temperature [deg C]; required when
            the bias drifts in that variable. The drift is re-anchored there: ``bias(v) = new bias +
            offset(v) - offset(time)``.
        max_spread : float, default=5.0
            The readings must be quiet (the rule of a model's re-tare, :func:`ftcal.core._validation.check_quiet`):
            each axis's std at most ``max_spread`` times the identification's residual RMS (force or torque);
            a tool file without residuals (all zero) is not checked.

        Examples
        --------
        >>> tool = ToolLoad(mass=1.0, center_of_mass=np.zeros(3), bias=np.zeros(6))
        >>> tool.retare(np.full((5, 6), 0.2)).bias.tolist()  # the tool taken off: the readings are the bias
        [0.2, 0.2, 0.2, 0.2, 0.2, 0.2]
        """
        W = np.asarray(wrenches, dtype=float)
        if W.ndim != 2 or W.shape[1] != 6 or len(W) == 0:
            raise CalibrationInputError(f"wrenches must have shape (n, 6) with n >= 1, Fx..Tz [N, N·m] of no-load "
                                        f"readings; got shape {W.shape}.")
        if not np.isfinite(W).all():
            raise CalibrationInputError("wrenches holds NaN or inf; drop those readings.")
        if sensor_rotations is not None:
            R = np.asarray(sensor_rotations, dtype=float)
            R = np.broadcast_to(R, (len(W), 3, 3)) if R.shape == (3, 3) else R
            R, W = _check_inputs(R, W)
            W = W - self._weight_wrench(R)
        noise = np.repeat(np.asarray(self.residual_rms, dtype=float), 3)
        if noise.any():
            check_quiet(W, noise, max_spread=max_spread, name="wrenches", labels=list(WRENCH_LABELS),
                        noise_words="the residual RMS of the tool's identification")
        new_bias = W.mean(axis=0)
        new_se = W.std(axis=0, ddof=1) / np.sqrt(len(W)) if len(W) > 1 else np.zeros(6)
        if self.drift is None:
            return replace(self, bias=new_bias, bias_std_error=new_se)
        at = time if self.drift.variable == "time" else temperature
        if at is None:
            raise CalibrationInputError(
                f"this tool's bias drifts ({self.drift.description}): the re-tare needs the "
                f"{{{self.drift.variable}}} of the readings to anchor the drift.", parameter=self.drift.variable,
                fix=f"pass {{{self.drift.variable}}} ({'when the readings were taken, in ' + self.drift.unit if self.drift.variable == 'time' else 'the sensor temperature during the readings [deg C]'})")
        at = float(at)
        if not np.isfinite(at):
            raise CalibrationInputError(f"the re-tare's {self.drift.variable} must be finite; got {at!r}.")
        return replace(self, bias=new_bias, bias_std_error=new_se,
                       drift=replace(self.drift, reference=at, retared_at=at))

    def to_dict(self) -> dict:
        """JSON-able form (what :meth:`save` writes)."""
        out = {"format": "ftcal-tool-load", "format_version": 1 if self.drift is None else TOOL_FORMAT_VERSION}
        for name, (_, _, key) in _FIELDS.items():
            out[key] = None if getattr(self, name) is None else np.asarray(getattr(self, name)).tolist()
        if not np.any(self.mounting_rotation):
            del out["mounting_rotation_rad"], out["mounting_rotation_std_error_rad"]
        if self.drift is not None:
            out["drift"] = self.drift.to_dict()
        return out

    def save(self, path: str | os.PathLike, *, overwrite: bool = False) -> Path:
        """Write the tool file (JSON); an existing file is only replaced with ``overwrite=True``."""
        path = Path(path)
        if path.exists() and not overwrite:
            raise CalibrationInputError(f"{path} already exists.", parameter="path", value=str(path), fix="pass {overwrite} to replace it, or choose another path", settings={"overwrite": True})
        with atomic_output(path, overwrite=overwrite, error=CalibrationInputError) as tmp:
            tmp.write_text(json.dumps(self.to_dict(), indent=2) + "\n", encoding="utf-8")
        return path

    @classmethod
    def load(cls, path: str | os.PathLike) -> "ToolLoad":
        """Read a tool file written by :meth:`save`."""
        path = Path(path)
        try:
            d = json.loads(path.read_text(encoding="utf-8"))
        except FileNotFoundError:
            raise CalibrationInputError(f"{path}: no such tool file.") from None
        except (json.JSONDecodeError, UnicodeDecodeError, RecursionError) as exc:
            raise CalibrationInputError(f"{path}: not a tool file (not JSON: {str(exc)[:80]}).") from None
        if not isinstance(d, dict) or d.get("format") != "ftcal-tool-load":
            raise CalibrationInputError(f"{path}: not an ftcal tool file (written by 'ftcal identify-load').")
        version = d.get("format_version", 1)
        if version not in (1, TOOL_FORMAT_VERSION):
            raise CalibrationInputError(f"{path}: tool file format_version {str(version)[:20]} is not one this ftcal "
                                        f"reads (1, {TOOL_FORMAT_VERSION}); upgrade ftcal.")
        try:
            # typed: a bool or text is no number (core._fields); a field not written keeps its default
            fields = {name: numbers_field(d[key], key, shape, where=str(path)) for name, (shape, _, key) in
                      _FIELDS.items() if name in _REQUIRED
                      or (key in d and (d[key] is not None or name != "held_out_residual_rms"))}
            tool = cls(**fields, drift=None if d.get("drift") is None else BiasDrift.from_dict(d["drift"]))
        except CalibrationInputError as exc:  # a field out of range (ToolLoad checks them all): name its JSON key
            if str(exc).startswith(f"{path}: "):  # a field's type, said by core._fields with the file's name
                raise
            text = str(exc)
            for field_name, (_, _, key) in _FIELDS.items():
                text = text.replace(f"ToolLoad {field_name} ", f"{key} ", 1)
            raise CalibrationInputError(f"{path}: {text}") from None
        except KeyError as exc:
            raise CalibrationInputError(f"{path}: the tool file lacks {exc}; write it with 'ftcal identify-load'.") from None
        except (TypeError, ValueError) as exc:
            raise CalibrationInputError(f"{path}: the tool file holds a value that is not a number ({exc}).") from None
        return tool


def _missing_tilt(directions: NDArray[np.float64], tilt_deg: NDArray[np.float64]) -> str:
    """`` (tilted about the sensor's x axis only; none about z)`` for gravity directions that vary in one
    direction only (empty when they do not vary at all, or in two directions)."""
    if len(directions) < 2 or tilt_deg.size < 2 or tilt_deg[0] < MIN_TILT_DEG:
        return ""
    mean = directions.mean(axis=0)
    mean /= np.linalg.norm(mean)
    varied = np.linalg.svd(directions - directions.mean(axis=0))[2][0]  # gravity moves along this direction
    tilted_about = np.cross(mean, varied)  # a tilt about this axis moves gravity along `varied`
    return (f" (they tilt the tool about the sensor's {axis_text(tilted_about / np.linalg.norm(tilted_about))} axis "
            f"only, by {tilt_deg[0]:.3g} deg; none about {axis_text(varied)})")


def wrench_in_sensor_frame(sensor_rotations: ArrayLike, wrenches_in_base: ArrayLike) -> NDArray[np.float64]:
    """Wrenches written in the base frame (about the sensor origin) turned into the sensor frame: ``Rᵀ F``, ``Rᵀ τ``.

    Some robot software (and public gravity-compensation tools) log the sensor's wrench rotated into the base
    frame; :func:`identify_tool_load` takes it in the sensor frame.

    Examples
    --------
    >>> import numpy as np
    >>> R = np.array([[[1.0, 0, 0], [0, -1, 0], [0, 0, -1]]])   # sensor upside down
    >>> wrench_in_sensor_frame(R, [[0, 0, -9.81, 1, 0, 0]]).tolist()
    [[0.0, 0.0, 9.81, 1.0, 0.0, 0.0]]
    """
    R, W = _check_inputs(sensor_rotations, wrenches_in_base)
    return np.einsum("nji,nkj->nki", R, W.reshape(-1, 2, 3)).reshape(-1, 6)  # Rᵀ F and Rᵀ τ


def _check_poses(g_s: NDArray[np.float64], groups: ArrayLike | None) -> NDArray | None:
    """The pose labels (``groups`` as an array, or None), after refusing fewer than 4 poses and poses whose
    gravity directions ``g_s`` (n, 3) do not tilt the tool by :data:`MIN_TILT_DEG` in two directions."""
    n = len(g_s)
    if groups is not None:
        groups = np.asarray(groups)
        if groups.shape != (n,):
            raise CalibrationInputError(f"groups must have shape ({n},) (one pose label per row); got "
                                        f"{groups.shape}.", parameter="groups", value=groups.shape)
    # the poses are the groups (one group is a bad groups argument, refused by the drift selection)
    n_poses = n if groups is None or np.unique(groups).size < 2 else int(np.unique(groups).size)
    if n_poses < 4:
        raise CalibrationInputError(
            f"{n_poses} poses; at least 4 are needed (each tilting the tool differently) to identify the mass, "
            "centre of mass and bias.", parameter="rotations", value=n_poses,
            fix="record at least 4 poses tilted about two axes, e.g. the 11 of a plan with {subdivisions}",
            settings={"subdivisions": 0})
    directions = g_s / np.linalg.norm(g_s, axis=1, keepdims=True)
    spread = np.linalg.svd(directions - directions.mean(axis=0), compute_uv=False) / np.sqrt(max(n, 1))
    tilt_deg = np.degrees(np.arcsin(np.clip(spread, 0.0, 1.0)))
    if tilt_deg.size < 2 or tilt_deg[1] < MIN_TILT_DEG:
        second = float(tilt_deg[1]) if tilt_deg.size > 1 else 0.0
        raise CalibrationInputError(
            f"the {n_poses} poses do not excite the tool load{_missing_tilt(directions, tilt_deg)}: gravity (in the sensor "
            f"frame) varies by about {second:.1f} deg in its second direction, but mass, centre of mass and bias "
            f"need at least {MIN_TILT_DEG:g} deg in two independent directions.", parameter="rotations",
            value=n_poses, fix="add poses tilted about two axes, e.g. the 11 of a plan with {subdivisions}",
            settings={"subdivisions": 0},
        )
    return groups


def identify_tool_load(
    sensor_rotations: ArrayLike, wrenches: ArrayLike, gravity: ArrayLike = DEFAULT_GRAVITY, *,
    times: ArrayLike | None = None, temperatures: ArrayLike | None = None, drift: str = "auto",
    time_unit: str = "s", cv: int = 20, random_state: int | None = 0, groups: ArrayLike | None = None,
    mounting: bool = False, declared_frame: str = "sensor",
) -> ToolLoad:
    """Identify a tool's mass, centre of mass and the sensor bias (and its drift) from static poses.

    Closed form (linear least squares). With the time of each pose (``times``) or the sensor's temperature
    (``temperatures``), a bias that moves with it (linear, or a natural cubic spline) is fitted jointly with
    the tool when it pays under held-out error: leave-poses-out cross-validation and the one-SE rule choose
    among the constant bias and the drift models (:mod:`ftcal.experiment._drift`).

    Parameters
    ----------
    sensor_rotations : array-like of shape (n, 3, 3)
        Rotation from the sensor frame to the base frame at each pose
        (``ftcal.robot.sensor_pose_in_base(robot, q)[:, :3, :3]``).
    wrenches : array-like of shape (n, 6)
        Calibrated readings at those poses [N, N·m] (the tool mounted, nothing else touching it).
    gravity : array-like of shape (3,), default=(0, 0, -9.81)
        Gravity in the base frame [m/s²]; its magnitude must be the Earth's surface gravity,
        :data:`GRAVITY_MAGNITUDE_RANGE` (9.7-9.9 m/s²): a gravity in cm/s², mm/s² or g is refused, naming the slip.
    times : array-like of shape (n,), optional
        When each pose was recorded, in ``time_unit`` (seconds, e.g. the log's timestamps or bag stamps; or
        ``0, 1, 2, ...`` for the recording order with ``time_unit="pose"``).
    temperatures : array-like of shape (n,), optional
        The sensor's temperature at each pose [deg C].
    drift : {"auto", "none", "linear", "spline", "temperature"}, default="auto"
        ``auto``: the held-out choice among the constant bias and every drift the inputs allow; ``none``: a
        constant bias (the classic tools' model); the others force that family of drift.
    time_unit : {"s", "pose"}
    cv : int, default=20
        Folds of the leave-poses-out cross-validation (at most one per pose).
    random_state : int or None
        Seed of the folds.
    groups : array-like of shape (n,), optional
        The pose of each row when several rows are samples of one static pose (a run log's ``pose`` column):
        the cross-validation holds a pose's rows out together. ``None``: every row is a pose.
    mounting : bool, default=False
        Also estimate the sensor's small mounting rotation relative to the robot's sensor frame (a few degrees),
        jointly with mass, centre of mass and bias, with its standard error (:mod:`ftcal.experiment._mounting`).
        The poses are checked first: a rotation they cannot tell (the tilt axis missing, too few or too similar
        poses) is refused, naming the axis and the parameter that absorbs it.
    declared_frame : {"sensor", "base"}, default="sensor"
        The frame the wrenches were recorded in, as their source declared it (``"base"``: they were turned into
        the sensor frame with :func:`wrench_in_sensor_frame` before this call). Only the advice of a mass not
        told apart from zero depends on it: it names the other frame as a cause.

    Returns
    -------
    ToolLoad
        With ``drift`` set when a drift was chosen (its ``selection`` holds every candidate's held-out error),
        ``held_out_residual_rms`` the leave-poses-out residual of the chosen model (K-fold over the poses with
        ``cv`` folds; leave-one-pose-out on at most ``cv`` poses; the mounting rotation, when estimated, fitted
        again on each fold's training poses), and ``mounting_rotation`` with ``mounting=True``.

    Raises
    ------
    CalibrationInputError
        Bad shapes or values, or poses that do not tilt the tool in two
        independent directions by at least :data:`MIN_TILT_DEG`.

    Examples
    --------
    >>> import numpy as np
    >>> from scipy.spatial.transform import Rotation
    >>> R = Rotation.random(20, random_state=0).as_matrix()
    >>> truth = ToolLoad(mass=1.2, center_of_mass=np.array([0.01, -0.02, 0.08]), bias=np.arange(6.0) / 10)
    >>> tool = identify_tool_load(R, truth.gravity_wrench(R))
    >>> round(tool.mass, 9), tool.center_of_mass.round(9).tolist()
    (1.2, [0.01, -0.02, 0.08])
    """
    R, W = _check_inputs(sensor_rotations, wrenches)
    _check_gravity_magnitude(gravity)
    g_s = _gravity_in_sensor(R, gravity)
    if declared_frame not in ("sensor", "base"):
        raise CalibrationInputError(f"declared_frame must be 'sensor' or 'base'; got {declared_frame!r}.")
    n = len(R)
    times = _check_drift_values("times", times, n)
    temperatures = _check_drift_values("temperatures", temperatures, n)
    if time_unit not in ("s", "pose"):
        raise CalibrationInputError(f"time_unit must be 's' (seconds) or 'pose' (recording order); got {time_unit!r}.")
    groups = _check_poses(g_s, groups)
    candidate, table = select_drift(g_s, W, times, temperatures, choice=drift, cv=cv, random_state=random_state,
                                    groups=groups)
    values = {"time": times, "temperature": temperatures}.get(candidate.variable)
    basis = candidate.basis({"time": np.zeros(n)} if values is None else {candidate.variable: values})
    fit = fit_gravity_blocks(g_s, W, basis, groups)
    variance = float(fit["force_cov"][0, 0])
    mass_se = float(np.sqrt(variance)) if variance > 0 else 0.0  # NaN (no residual degrees of freedom): 0
    # a mass below zero by more than its noise: gravity points the other way; within 3 SE of zero (either sign):
    # no weight that turns with the poses at all
    if not np.isfinite(fit["mass"]) or fit["mass"] <= -3.0 * mass_se or (fit["mass"] <= 0 and mass_se == 0):
        raise CalibrationInputError(
            f"the identified mass is {fit['mass']:.4g} kg (not positive): the wrenches do not show a tool's weight. "
            "Check the gravity direction and that the wrenches are in the sensor frame."
        )
    if fit["mass"] < 3.0 * mass_se:  # not told apart from no weight at all: the force does not turn with the poses
        raise _zero_mass_error(fit["mass"], mass_se, declared_frame, gravity)
    rotation, rotation_cov, joint_cov, g_robot = np.zeros(3), np.zeros((3, 3)), None, g_s
    if mounting:
        g_s, rotation, rotation_cov, joint_cov = identify_mounting(g_s, W, basis, fit, groups)
        fit = fit_gravity_blocks(g_s, W, basis, groups)  # the tool given the rotation (the optimum's linear part)
    f_se = np.sqrt(np.maximum(np.diag(fit["force_cov"]), 0.0))
    t_se = np.sqrt(np.maximum(np.diag(fit["torque_cov"]), 0.0))
    mass, p = fit["mass"], fit["p"]
    com = p / mass
    com_se = np.sqrt((t_se[:3] / mass) ** 2 + (p * f_se[0] / mass**2) ** 2)
    bias, bias_se, bias_drift = fit["bias"], np.concatenate([f_se[1:4], t_se[3:6]]), None
    if joint_cov is not None:  # the tool's standard errors with the rotation's uncertainty in them
        f_se[0], com_se, bias_se = _joint_standard_errors(mass, p, joint_cov)
    if values is not None:
        unit = time_unit if candidate.variable == "time" else "degC"
        bias_drift = build_drift(candidate, fit, values, unit, table)
        bias = bias + (candidate.basis({candidate.variable: np.array([bias_drift.reference])}) @ fit["drift"])[0]
        bias_se = functional_se(fit, candidate.basis({candidate.variable: np.array([bias_drift.reference])})[0], 1.0)
    held_out = (_held_out_with_mounting(g_robot, W, basis, groups, cv, random_state, rotation) if mounting
                else held_out_residual(g_s, W, basis, groups=groups, cv=cv, random_state=random_state))
    return ToolLoad(
        mass=mass, center_of_mass=com, bias=bias, mass_std_error=float(f_se[0]), center_of_mass_std_error=com_se,
        bias_std_error=bias_se, gravity=np.asarray(gravity, dtype=float), residual_rms=fit["residual_rms"],
        drift=bias_drift, held_out_residual_rms=None if held_out is None else residual_rms_of(held_out),
        mounting_rotation=rotation, mounting_rotation_std_error=np.sqrt(np.maximum(np.diag(rotation_cov), 0.0)),
    )


def _held_out_with_mounting(g_robot: NDArray, W: NDArray, basis: NDArray, groups: NDArray | None, cv: int,
                            random_state: int | None, rotation: NDArray) -> NDArray[np.float64] | None:
    """Each row's leave-poses-out residual (n, 6) with the mounting rotation fitted again on every fold's training
    poses (a rotation fitted on all poses would see the held-out ones); a fold whose poses cannot tell the
    rotation apart keeps the all-poses rotation. ``None`` when a fold cannot be fitted."""
    residual = np.empty_like(W)
    for train, test in pose_folds(len(W), groups, cv, random_state):
        sub = None if groups is None else groups[train]
        r = rotation
        try:
            start = fit_gravity_blocks(g_robot[train], W[train], basis[train], sub)
            r = identify_mounting(g_robot[train], W[train], basis[train], start, sub)[1]
        except (CalibrationInputError, np.linalg.LinAlgError):
            pass
        pred = held_out_predictions(g_robot @ mounting_matrix(r), W, basis, [(train, test)])
        if pred is None:
            return None
        residual[test] = W[test] - pred[test]
    return residual


def residual_rms_of(residual: NDArray[np.float64]) -> NDArray[np.float64]:
    """RMS of the force [N] and torque [N·m] components of residual wrenches (n, 6) (as ``residual_rms``)."""
    return np.array([np.sqrt(np.mean(residual[:, :3] ** 2)), np.sqrt(np.mean(residual[:, 3:] ** 2))])


def _joint_standard_errors(mass: float, p: NDArray, cov: NDArray) -> tuple[float, NDArray, NDArray]:
    """Standard errors of mass, centre of mass (delta method for ``c = p / m``) and bias from the joint covariance
    of ``[r, m, p, b_F, b_τ]``."""
    J = np.hstack([-p[:, None] / mass**2, np.eye(3) / mass])  # dc / d(m, p)
    com_cov = J @ cov[3:7, 3:7] @ J.T
    diag = np.sqrt(np.maximum(np.diag(cov), 0.0))
    return float(diag[3]), np.sqrt(np.maximum(np.diag(com_cov), 0.0)), diag[7:13]


def _check_drift_values(name: str, values: ArrayLike | None, n: int) -> NDArray[np.float64] | None:
    """``times`` / ``temperatures``: one finite number per pose, or None."""
    if values is None:
        return None
    try:
        v = np.asarray(values, dtype=float)
    except (TypeError, ValueError):
        raise CalibrationInputError(f"{name} must be numbers, one per pose; got {str(values)[:80]}.") from None
    if v.shape != (n,):
        raise CalibrationInputError(f"{name} must have shape ({n},), one value per pose; got shape {v.shape}.")
    if not np.isfinite(v).all():
        row = int(np.argmin(np.isfinite(v)))
        raise CalibrationInputError(f"{name} holds NaN or inf (first at pose {row}); repair or drop that pose.")
    if np.abs(v).max(initial=0.0) > 1e12:
        raise CalibrationInputError(f"{name} holds {float(v[np.argmax(np.abs(v))]):.3g}, beyond 1e12: not a time in "
                                    "seconds or a temperature in deg C. Fix: check the column and its unit.")
    return v


def _drift_comment(tool: ToolLoad) -> list[str]:
    """YAML comment lines on a bias drift these formats cannot express (none without a drift)."""
    d = tool.drift
    if d is None:
        return []
    rate = d.rate_per_hour()
    rate_text = (f"{', '.join(f'{v:.3g}' for v in rate[0])} N/h, N·m/h" if rate is not None else
                 f"{', '.join(f'{v:.3g}' for v in d.mean_rate)} N, N·m per {'pose' if d.unit == 'pose' else 'deg C'}")
    return [f"# NOTE: the bias drifts ({d.description}, mean rate {rate_text}); these parameters cannot express a",
            f"# drift: 'bias' is the bias at {d.variable} {d.reference:.10g} {d.unit}. Re-tare periodically (ftcal retare)",
            "# or deploy the tool's ONNX export (ftcal export, format onnx), which carries the drift."]


def _mounting_comment(tool: ToolLoad) -> list[str]:
    """YAML comment lines on a mounting rotation these formats cannot express (none without one)."""
    if not np.any(tool.mounting_rotation):
        return []
    r = np.degrees(tool.mounting_rotation)
    return [f"# NOTE: the sensor is mounted turned by the rotation vector [{', '.join(f'{v:.3g}' for v in r)}] deg from",
            "# the robot's sensor frame; these formats take the frame from tf: add that rotation to the sensor frame's",
            "# transform (URDF), or deploy the tool's ONNX export (ftcal export, format onnx), which carries it."]


def tool_gravity_compensation_yaml(tool: ToolLoad, *, sensor_frame: str = "ft_sensor", world_frame: str = "world",
                                   node: str = "gravity_compensation") -> str:
    """The tool's parameters as the gravity-compensation YAML ROS users load (text).

    Two documents' worth of keys in one file:

    * ROS 1 ``force_torque_tools`` (``gravity_compensation`` node, as ``ft_calib`` writes them): ``bias``
      (6 values, N and N·m, sensor frame), ``gripper_mass`` [kg], ``gripper_com_frame_id``,
      ``gripper_com_pose`` (x, y, z [m] and roll, pitch, yaw = 0), ``gripper_com_child_frame_id``;
    * ROS 2 ``control_toolbox`` ``control_filters/GravityCompensation`` under ``<node>: ros__parameters``:
      ``world_frame``, ``sensor_frame``, ``CoG.pos`` [m] (sensor frame) and ``CoG.force`` (the tool's weight
      as a force in the world frame, m g [N]).

    The bias is not part of the ROS 2 filter; re-tare (``ftcal retare``) or subtract it upstream. Neither
    format can express a bias drift: the file holds the bias at the drift's reference (the end of the
    identification, or the last re-tare) and a comment with the drift and its rate; re-tare periodically or
    use the ONNX export (``ftcal export TOOL --format onnx``), which carries the drift.

    Examples
    --------
    >>> import numpy as np
    >>> text = tool_gravity_compensation_yaml(ToolLoad(mass=1.0, center_of_mass=np.array([0.0, 0.0, 0.1]),
    ...                                                bias=np.zeros(6)))
    >>> "gripper_mass: 1.0" in text and "pos: [0.0, 0.0, 0.1]" in text
    True
    """
    import yaml

    for name, value in (("sensor_frame", sensor_frame), ("world_frame", world_frame), ("node", node)):
        if not isinstance(value, str) or not value.strip() or not value.isprintable():
            raise CalibrationInputError(f"{name} {value!r} must be a frame / node name: printable text, not empty.",
                                        parameter=name, value=value)

    def block(mapping: dict) -> str:  # a YAML emitter quotes what a plain scalar would misread (null, yes, 0x10, *ref)
        return yaml.safe_dump(mapping, default_flow_style=None, sort_keys=False, allow_unicode=True, width=1 << 16)

    floats = lambda values: [float(v) for v in values]  # noqa: E731 - shortest round-trip decimals
    com = floats(tool.center_of_mass)
    comment_frame = yaml.safe_dump(sensor_frame, allow_unicode=True, width=1 << 16).splitlines()[0]
    text = "\n".join([
        "# Tool gravity compensation parameters written by ftcal (identify-load): sensor frame, SI units.",
        f"# mass {tool.mass:.6g} kg (± {tool.mass_std_error:.2g}), centre of mass in the frame {comment_frame} [m],",
        "# bias [N, N·m] = what the sensor reads with no load at all.",
        *_drift_comment(tool), *_mounting_comment(tool),
        "# --- ROS 1 force_torque_tools (gravity_compensation node) ---",
    ]) + "\n"
    text += block({"bias": floats(tool.bias), "gripper_mass": float(tool.mass), "gripper_com_frame_id": sensor_frame,
                   "gripper_com_pose": com + [0.0, 0.0, 0.0], "gripper_com_child_frame_id": "gripper_com"})
    text += "# --- ROS 2 control_toolbox control_filters/GravityCompensation ---\n"
    text += block({node: {"ros__parameters": {
        "world_frame": world_frame, "sensor_frame": sensor_frame,
        "CoG": {"pos": com, "force": [float(tool.mass * g) for g in np.asarray(tool.gravity, dtype=float)]}}}})
    return text


# ------------------------------------------------------------------------------ identification summary
#: Most poses a summary lists one by one (a longer recording is summarised by its RMS only).
MAX_LISTED_POSES = 100_000


def identification_summary(sensor_rotations: ArrayLike, wrenches: ArrayLike, tool, *, times: ArrayLike | None = None,
                          temperatures: ArrayLike | None = None, drift: str = "auto", cv: int = 20,
                          random_state: int | None = 0, groups: ArrayLike | None = None) -> dict:
    """The summary of an in-situ identification: each pose's residual against time (or temperature) with the
    constant bias and with the tool's drift, the drift rate with its standard error, and the held-out choice.

    ``tool`` is what :func:`ftcal.experiment.identify_tool_load` returned for these poses with these settings.

    Examples
    --------
    >>> from scipy.spatial.transform import Rotation
    >>> from ftcal.experiment import ToolLoad, identify_tool_load
    >>> R = Rotation.random(30, random_state=0).as_matrix()
    >>> t = np.linspace(0.0, 3600.0, 30)
    >>> W = ToolLoad(mass=1.0, center_of_mass=np.zeros(3), bias=np.zeros(6)).gravity_wrench(R)
    >>> W[:, 0] += 0.5 * t / 3600.0 + np.random.default_rng(0).normal(0, 0.01, 30)   # 0.5 N/h in Fx
    >>> tool = identify_tool_load(R, W, times=t)
    >>> summary = identification_summary(R, W, tool, times=t)
    >>> summary["drift_model"], round(summary["drift_rate"]["force"][0], 1), summary["drift_rate"]["unit_force"]
    ('linear in time', 0.5, 'N/h')
    """
    R, W = _check_inputs(sensor_rotations, wrenches)
    constant = identify_tool_load(R, W, tool.gravity, drift="none")
    residual_constant = W - constant.gravity_wrench(R)
    residual_drift = W - tool.gravity_wrench(R, times=times, temperatures=temperatures)
    d = tool.drift
    if d is not None:
        selection = list(d.selection)
    elif times is not None or temperatures is not None:
        g_s = np.einsum("nji,j->ni", R, np.asarray(tool.gravity, dtype=float))
        selection = select_drift(g_s, W, None if times is None else np.asarray(times, dtype=float),
                                 None if temperatures is None else np.asarray(temperatures, dtype=float),
                                 choice=drift, cv=cv, random_state=random_state, groups=groups)[1]
    else:
        selection = []
    if d is not None and d.variable == "temperature":
        axis, values = {"name": "temperature", "unit": "degC"}, np.asarray(temperatures, dtype=float)
    elif times is not None:
        axis = {"name": "time", "unit": d.unit if d is not None and d.variable == "time" else "s"}
        values = np.asarray(times, dtype=float)
    else:
        axis, values = {"name": "pose", "unit": "pose"}, np.arange(len(W), dtype=float)
    rate = None
    if d is not None:
        per = {"s": (_SECONDS_PER_HOUR, "h"), "pose": (1.0, "pose"), "degC": (1.0, "deg C")}[d.unit]
        halves = (("force", slice(3)), ("torque", slice(3, 6)))
        rate = {f"{part}{what}": (v[sl] * per[0]).tolist() for part, sl in halves
                for what, v in (("", d.mean_rate), ("_std_error", d.mean_rate_std_error))}
        rate.update(unit_force=f"N/{per[1]}", unit_torque=f"N·m/{per[1]}",
                    meaning="the drift's mean rate over the span (end minus start over the span's length)")
    listed = len(W) <= MAX_LISTED_POSES

    def norms(residual: NDArray) -> dict:
        return {"force_N": np.linalg.norm(residual[:, :3], axis=1).tolist() if listed else None,
                "torque_Nm": np.linalg.norm(residual[:, 3:], axis=1).tolist() if listed else None,
                "rms": residual_rms_of(residual).tolist()}

    return {"format": "ftcal-tool-identification", "format_version": 1, "n_poses": int(len(W)),
            "drift_model": "constant" if d is None else d.description, "axis": axis,
            "values": values.tolist() if listed else None,
            "span": None if d is None else list(d.covered), "drift_rate": rate, "selection": selection,
            "residual": {"constant_bias": norms(residual_constant), "with_drift": norms(residual_drift)},
            "note": "residual = the identification poses' wrench minus the fitted gravity wrench and bias (in-sample); "
                    "the held-out errors that chose the drift are in 'selection'"}
