"""Robot models and forward kinematics of the sensor frame, with Pinocchio.

A :class:`RobotModel` is a Pinocchio model of the joints that move a named
sensor frame, plus what the calibration experiment needs to know about it
(joint limits, a home posture, the frame whose position pose planning keeps
fixed). Load one with :func:`load_robot`:

* a built-in name: ``"kuka_iiwa14"`` (the thesis' KUKA LBR iiwa 14 R820 with
  the sensor mount of Fig. 4, shipped with ftcal; see ``robots/README.md``),
  or ``"panda"``, ``"ur3"``, ``"ur5"``, ``"ur10"`` (the URDFs of the installed
  ``example-robot-data`` package, sensor frame at the tool flange);
* any URDF path, with ``sensor_frame`` naming the frame at the sensing origin.

Frames: the *base* frame is Pinocchio's world frame of the URDF (the robot's
base); the *sensor* frame is the named frame. Poses are homogeneous
``(4, 4)`` matrices with translations in [m]; joint values are in [rad] for
revolute and [m] for prismatic joints.
"""

from __future__ import annotations

import contextlib
import importlib.metadata
import sysconfig
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pinocchio as pin
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import KinematicsError, Placeholder

__all__ = [
    "sensor_mounting_transform",
    "MOUNTED_SENSOR_FRAME",
    "RobotModel",
    "BUILTIN_ROBOTS",
    "load_robot",
    "example_robot_data_dir",
    "sensor_pose_in_base",
    "frame_pose_in_base",
]

def _robots_dir() -> Path:
    """The repository's ``robots/`` folder, shipped in the wheel as the data package ``ftcal.robots``."""
    from importlib.resources import files

    return Path(str(files("ftcal.robots")))
_ERD_SUBDIR = Path("cmeel.prefix") / "share" / "example-robot-data" / "robots"


@dataclass(frozen=True)
class _BuiltinRobot:
    urdf: str  # "ftcal:<file>" for robots/ (package ftcal.robots), "erd:<relative path>" for example-robot-data
    sensor_frame: str
    home_deg: tuple[float, ...]
    anchor_frame: str | None = None


#: Built-in robots: name -> URDF source, default sensor frame, home posture [deg]
#: and the frame whose position pose planning holds fixed (None: the sensor frame).
BUILTIN_ROBOTS: dict[str, _BuiltinRobot] = {
    # Home: wrist centre 0.61 m in front of A1, 0.72 m above the base, flange pointing down.
    "kuka_iiwa14": _BuiltinRobot(
        "ftcal:kuka_iiwa14_ft.urdf", "ft_sensor", (0.0, 30.0, 0.0, -60.0, 0.0, 90.0, 0.0), "iiwa_link_6"
    ),
    "panda": _BuiltinRobot(
        "erd:panda_description/urdf/panda.urdf", "panda_link8", (0.0, -45.0, 0.0, -135.0, 0.0, 90.0, 45.0)
    ),
    "ur3": _BuiltinRobot("erd:ur_description/urdf/ur3_robot.urdf", "tool0", (0.0, -90.0, 90.0, -90.0, -90.0, 0.0)),
    "ur5": _BuiltinRobot("erd:ur_description/urdf/ur5_robot.urdf", "tool0", (0.0, -90.0, 90.0, -90.0, -90.0, 0.0)),
    "ur10": _BuiltinRobot("erd:ur_description/urdf/ur10_robot.urdf", "tool0", (0.0, -90.0, 90.0, -90.0, -90.0, 0.0)),
}


@dataclass
class RobotModel:
    """A kinematic chain from the robot base to a sensor frame.

    Attributes
    ----------
    name : str
        Built-in name or the URDF file's stem.
    model : pinocchio.Model
        The arm's joints only: joints that do not move the sensor frame
        (grippers, fingers) are locked at their neutral value.
    sensor_frame : str
        Name of the frame at the sensor's sensing origin.
    urdf_path : pathlib.Path
        The URDF the model was built from.
    home_configuration : ndarray of shape (n_joints,)
        A comfortable posture inside the limits [rad]; the seed of pose planning.
    anchor_frame : str
        The frame whose position pose planning keeps fixed (a wrist centre where
        the arm has one, else the sensor frame).
    """

    name: str
    model: pin.Model
    sensor_frame: str
    urdf_path: Path
    home_configuration: NDArray[np.float64]
    anchor_frame: str
    data: pin.Data = field(init=False, repr=False)  # scratch of the FK/IK calls: not thread-safe
    sensor_frame_id: int = field(init=False, repr=False)
    anchor_frame_id: int = field(init=False, repr=False)

    def __post_init__(self) -> None:
        self.data = self.model.createData()
        self.sensor_frame_id = self.frame_id(self.sensor_frame)
        self.anchor_frame_id = self.frame_id(self.anchor_frame)

    @property
    def n_joints(self) -> int:
        """Length of a joint vector ``q``."""
        return int(self.model.nq)

    @property
    def joint_names(self) -> tuple[str, ...]:
        """Names of the joints, in the order of ``q``."""
        return tuple(self.model.names[1:])

    @property
    def lower_limits(self) -> NDArray[np.float64]:
        """Lower joint position limits [rad] (or [m])."""
        return np.array(self.model.lowerPositionLimit, dtype=float)

    @property
    def upper_limits(self) -> NDArray[np.float64]:
        """Upper joint position limits [rad] (or [m])."""
        return np.array(self.model.upperPositionLimit, dtype=float)

    @property
    def velocity_limits(self) -> NDArray[np.float64]:
        """Joint velocity limits [rad/s] (or [m/s]) as the URDF gives them."""
        return np.array(self.model.velocityLimit, dtype=float)

    def frame_id(self, frame: str) -> int:
        """Pinocchio index of ``frame``; :class:`KinematicsError` listing the frames if unknown."""
        if not self.model.existFrame(frame):
            names = ", ".join(f.name for f in self.model.frames)
            raise KinematicsError(f"robot {self.name!r} has no frame {frame!r}; its frames are: {names}.")
        return int(self.model.getFrameId(frame))

    def check_joints(self, q: ArrayLike, name: str = "q") -> NDArray[np.float64]:
        """``q`` as a float array of shape (n, n_joints), checked for shape and finiteness."""
        arr = np.asarray(q, dtype=float)
        if arr.ndim == 1:
            arr = arr[None, :]
        if arr.ndim != 2 or arr.shape[1] != self.n_joints:
            raise KinematicsError(
                f"{name} must have shape ({self.n_joints},) or (n, {self.n_joints}) for robot {self.name!r} "
                f"(joints {', '.join(self.joint_names)}); got shape {np.shape(q)}."
            )
        if not np.all(np.isfinite(arr)):
            row = int(np.argwhere(~np.isfinite(arr))[0, 0])
            raise KinematicsError(f"{name} holds NaN or inf (first at row {row}); joint values must be finite.")
        return arr

    def within_limits(self, q: ArrayLike, tolerance: float = 1e-9) -> NDArray[np.bool_]:
        """Whether each row of ``q`` (n, n_joints) lies inside the position limits, shape (n,)."""
        arr = self.check_joints(q)
        return np.all((arr >= self.lower_limits - tolerance) & (arr <= self.upper_limits + tolerance), axis=1)


def example_robot_data_dir() -> Path:
    """Folder of the URDFs shipped by the ``example-robot-data`` package.

    Looks the package up through its installed metadata, then through the
    interpreter's site-packages folders.

    Raises
    ------
    KinematicsError
        When ``example-robot-data`` is not installed.
    """
    candidates = [Path(sysconfig.get_paths()[key]) / _ERD_SUBDIR for key in ("purelib", "platlib")]
    with contextlib.suppress(importlib.metadata.PackageNotFoundError):
        candidates.insert(0, Path(importlib.metadata.distribution("example-robot-data").locate_file(_ERD_SUBDIR)))
    found = next((path for path in candidates if path.is_dir()), None)
    if found is not None:
        return found
    raise KinematicsError(
        "example-robot-data is not installed (looked in "
        + ", ".join(map(str, candidates))
        + "); install it with `pip install example-robot-data` or pass a URDF path."
    )


def _arm_model(full: pin.Model, sensor_frame: str, urdf: Path) -> pin.Model:
    """``full`` with every joint that does not move ``sensor_frame`` locked at neutral."""
    if not full.existFrame(sensor_frame):
        names = ", ".join(f.name for f in full.frames)
        raise KinematicsError(f"{urdf}: no frame named {sensor_frame!r}; its frames are: {names}.")
    parent = full.frames[full.getFrameId(sensor_frame)].parentJoint
    supporting = set(full.supports[parent])
    locked = [j for j in range(1, full.njoints) if j not in supporting]
    if not locked:
        return full
    return pin.buildReducedModel(full, locked, pin.neutral(full))


#: Name of the frame :func:`load_robot` adds for a ``sensor_mounting``.
MOUNTED_SENSOR_FRAME = "ftcal_mounted_sensor"


def sensor_mounting_transform(mounting) -> pin.SE3:
    """A sensor mounting as ``pin.SE3``: from ``pin.SE3``, a 4x4 matrix, or 6 numbers
    ``(rx, ry, rz, x, y, z)`` = a rotation vector [deg] (axis times angle, about the frame's own axes) and an
    offset [m], both expressed in the URDF's sensor frame.

    Examples
    --------
    >>> M = sensor_mounting_transform([0, 0, 90, 0, 0, 0.02])   # turned 90 deg about z, 2 cm further out
    >>> M.rotation.round(6) + 0.0
    array([[ 0., -1.,  0.],
           [ 1.,  0.,  0.],
           [ 0.,  0.,  1.]])
    """
    if isinstance(mounting, pin.SE3):
        return mounting
    a = np.asarray(mounting, dtype=float)
    if a.shape == (4, 4):
        R, p = a[:3, :3], a[:3, 3]
        if not np.allclose(R @ R.T, np.eye(3), atol=1e-9) or not np.isclose(np.linalg.det(R), 1.0, atol=1e-9) \
                or not np.allclose(a[3], [0, 0, 0, 1]):
            raise KinematicsError("sensor_mounting: a 4x4 mounting must be a rigid transform (rotation, offset).")
        return pin.SE3(R, p)
    if a.shape != (6,) or not np.all(np.isfinite(a)):
        raise KinematicsError(f"sensor_mounting must be rx,ry,rz [deg],x,y,z [m] (6 finite numbers), a 4x4 transform "
                              f"or a pin.SE3; got {np.asarray(mounting).tolist()!r}.")
    if np.abs(a[3:]).max() > 2.0 or np.linalg.norm(a[3:]) > 2.0:  # the max first: no overflowing norm
        length = np.abs(a[3:]).max() if np.abs(a[3:]).max() > 1e150 else np.linalg.norm(a[3:])
        raise KinematicsError(f"sensor_mounting offset {a[3:].tolist()} is {length:.3g} m long; give "
                              "it in metres.")
    if np.abs(a[:3]).max() > 360.0:
        raise KinematicsError(f"sensor_mounting rotation {a[:3].tolist()} [deg] turns more than 360 deg about an "
                              "axis; give the rotation vector (axis times angle) in degrees, at most 360.")
    return pin.SE3(pin.exp3(np.deg2rad(a[:3])), a[3:])


def _mount_sensor(model: pin.Model, frame: str, mounting) -> str:
    """Add the mounted sensor frame (``frame`` composed with ``mounting``) to ``model``; return its name."""
    fid = model.getFrameId(frame)
    parent = model.frames[fid]
    model.addFrame(pin.Frame(MOUNTED_SENSOR_FRAME, parent.parentJoint, fid,
                             parent.placement * sensor_mounting_transform(mounting), pin.FrameType.OP_FRAME))
    return MOUNTED_SENSOR_FRAME


def check_urdf_xml(path: str | Path) -> None:
    """Refuse a URDF file that is not well-formed XML, naming the line and column of the syntax error.

    Pinocchio's own parser (urdfdom) only says that parsing failed; this names where.

    Raises
    ------
    KinematicsError
        The file is empty or not valid XML (its line and column, 1-based); or it cannot be read.

    Examples
    --------
    >>> import os, tempfile
    >>> path = os.path.join(tempfile.mkdtemp(), "broken.urdf")
    >>> _ = open(path, "w").write('<robot name="r">\\n  <link name="a">\\n</robot>\\n')
    >>> check_urdf_xml(path)
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.KinematicsError: .../broken.urdf: line 3, column 3: not valid XML (mismatched tag); a URDF is an XML file.
    """
    import xml.etree.ElementTree as ET

    path = Path(path)
    try:
        ET.parse(path)
    except ET.ParseError as exc:
        line, column = getattr(exc, "position", (None, None))
        reason = str(exc).split(":")[0]
        if path.stat().st_size == 0:
            raise KinematicsError(f"{path}: the URDF file is empty.") from None
        raise KinematicsError(f"{path}: line {line}, column {column + 1 if column is not None else '?'}: not "
                              f"valid XML ({reason}); a URDF is an XML file.") from None
    except OSError as exc:
        raise KinematicsError(f"{path}: {exc.strerror or exc}.") from None


def load_robot(name_or_urdf_path: str | Path = "kuka_iiwa14", sensor_frame: str | None = None, *,
               sensor_mounting=None) -> RobotModel:
    """Load a built-in robot or a URDF file as a :class:`RobotModel`.

    Parameters
    ----------
    name_or_urdf_path : str or path, default="kuka_iiwa14"
        A key of :data:`BUILTIN_ROBOTS` or the path of a ``.urdf`` file. Meshes
        are not needed (only kinematics are loaded).
    sensor_frame : str, optional
        Frame at the sensing origin. Defaults to the built-in's sensor frame;
        required for a URDF path.
    sensor_mounting : pin.SE3, 4x4 array or 6 numbers, optional
        How the sensor actually sits relative to ``sensor_frame`` (rotated on
        the flange, offset by an adapter), without editing the URDF: see
        :func:`sensor_mounting_transform`. The model's sensor frame becomes
        ``sensor_frame`` composed with it (frame ``ftcal_mounted_sensor``).

    Returns
    -------
    RobotModel

    Raises
    ------
    KinematicsError
        Unknown name, missing or unparsable file, unknown frame, or a model
        with unbounded joints.

    Examples
    --------
    >>> robot = load_robot("kuka_iiwa14")
    >>> robot.n_joints, robot.sensor_frame
    (7, 'ft_sensor')
    >>> sensor_pose_in_base(robot, [0.0] * 7)[:3, 3].round(3)  # arm upright [m]
    array([0.   , 0.   , 1.376])
    """
    key = str(name_or_urdf_path)
    spec = BUILTIN_ROBOTS.get(key)
    if spec is not None:
        source, _, rel = spec.urdf.partition(":")
        urdf = _robots_dir() / rel if source == "ftcal" else example_robot_data_dir() / rel
        frame, name = sensor_frame or spec.sensor_frame, key
    else:
        urdf = Path(name_or_urdf_path)
        if urdf.suffix.lower() != ".urdf":
            raise KinematicsError(
                f"{key!r} is neither a built-in robot ({', '.join(BUILTIN_ROBOTS)}) nor a .urdf path."
            )
        if sensor_frame is None:
            raise KinematicsError(f"{urdf}: a URDF path needs the sensor frame.", parameter="sensor_frame",
                                  fix="pass {sensor_frame}",
                                  settings={"sensor_frame": Placeholder("<frame at the sensing origin>")})
        frame, name = sensor_frame, urdf.stem
    if not urdf.is_file():
        raise KinematicsError(f"{urdf}: no such URDF file.")
    if spec is None:
        check_urdf_xml(urdf)
    try:
        full = pin.buildModelFromUrdf(str(urdf))
    except Exception as exc:  # Pinocchio raises ValueError/RuntimeError on malformed XML
        raise KinematicsError(f"{urdf}: Pinocchio cannot parse this URDF ({exc}).") from exc
    model = _arm_model(full, frame, urdf)
    lower, upper = np.array(model.lowerPositionLimit), np.array(model.upperPositionLimit)
    if not (np.all(np.isfinite(lower)) and np.all(np.isfinite(upper))) or model.nq != model.nv:
        raise KinematicsError(
            f"{urdf}: every arm joint must be revolute or prismatic with finite limits "
            f"(got lower {lower}, upper {upper}); continuous joints are not supported."
        )
    if spec is not None and len(spec.home_deg) == model.nq:
        home = np.deg2rad(np.array(spec.home_deg, dtype=float))
    else:
        home = np.clip(np.zeros(model.nq), lower, upper)
    anchor = spec.anchor_frame if spec is not None and spec.anchor_frame and frame == spec.sensor_frame else frame
    if sensor_mounting is not None:
        frame = _mount_sensor(model, frame, sensor_mounting)  # the anchor (a wrist centre) stays where it is
    return RobotModel(name=name, model=model, sensor_frame=frame, urdf_path=urdf,
                      home_configuration=home, anchor_frame=anchor)


def frame_pose_in_base(robot: RobotModel, q: ArrayLike, frame: str) -> NDArray[np.float64]:
    """Pose of ``frame`` in the base frame for each joint vector.

    Parameters
    ----------
    robot : RobotModel
    q : array-like of shape (n_joints,) or (n, n_joints)
        Joint values [rad].
    frame : str
        A frame of ``robot.model``.

    Returns
    -------
    ndarray of shape (4, 4) or (n, 4, 4)
        Homogeneous transforms base <- frame, translations in [m]; 2-D input
        gives a stack, 1-D input a single matrix.
    """
    fid = robot.frame_id(frame)
    arr = robot.check_joints(q)
    out = np.empty((arr.shape[0], 4, 4))
    for i, qi in enumerate(arr):
        pin.framesForwardKinematics(robot.model, robot.data, qi)
        out[i] = robot.data.oMf[fid].homogeneous
    return out[0] if np.ndim(q) == 1 else out


def sensor_pose_in_base(robot: RobotModel, q: ArrayLike) -> NDArray[np.float64]:
    """Pose of the sensor frame in the base frame, ``P = [[R, p], [0, 1]]``.

    ``R`` maps vectors from the sensor frame to the base frame (``R_sensor`` of
    eq. 15) and ``p`` is the sensing origin in the base frame [m].

    Parameters
    ----------
    robot : RobotModel
    q : array-like of shape (n_joints,) or (n, n_joints)
        Joint values [rad].

    Returns
    -------
    ndarray of shape (4, 4) or (n, 4, 4)

    Examples
    --------
    >>> import numpy as np
    >>> robot = load_robot()
    >>> P = sensor_pose_in_base(robot, np.zeros((3, 7)))
    >>> P.shape
    (3, 4, 4)
    """
    return frame_pose_in_base(robot, q, robot.sensor_frame)
