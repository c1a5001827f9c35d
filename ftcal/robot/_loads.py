"""Load configurations (thesis IV-B-b, Table I) and reference wrenches (eq. 15-16).

A load configuration is the position of the external load's centre of mass in
the sensor frame [m]. The thesis uses a centre at ``[186, 0, 79]`` mm from the
sensing origin and six translations of it (Table I), so that all three torque
axes are excited.

Table I, transcribed as printed (translations in mm, added to the centre)::

    axis   positive            negative
    x      ( 161, 93,  0)      (-161, 93,   0)
    y      (   0, 29,  0)      (   0, -42,  0)
    z      (   0,  0, 15)      (   0,  0, -48)

The x row carries y = 93 mm in both directions; it is kept as printed (the
holder's x positions are offset sideways). The load mass is not given in the
thesis; it is a parameter everywhere here.

Reference wrench
----------------
``F = R^T (m g)`` (eq. 15) and ``tau = r x F`` (eq. 16), with ``R`` the sensor's
rotation in the base (gravitational) frame, ``g`` gravity in the base frame
[m/s²], ``m`` the load mass [kg] and ``r`` the load's centre of mass in the
sensor frame [m]. ``F`` is the force the load exerts on the sensor [N].
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import KinematicsError
from ._robot import RobotModel, sensor_pose_in_base

__all__ = [
    "STANDARD_GRAVITY",
    "GRAVITY_IN_BASE",
    "THESIS_LOAD_CENTER_MM",
    "TABLE_I_TRANSLATIONS_MM",
    "LoadConfiguration",
    "thesis_load_configurations",
    "THESIS_FIXTURE",
    "read_load_configurations",
    "load_fixture",
    "reference_wrench",
    "reference_wrench_at_joints",
]

#: Standard gravity [m/s²].
STANDARD_GRAVITY: float = 9.80665
#: Gravity in the base frame of a robot on a flat table [m/s²].
GRAVITY_IN_BASE: tuple[float, float, float] = (0.0, 0.0, -STANDARD_GRAVITY)
#: Centre load position in the sensor frame [mm] (thesis IV-B-b).
THESIS_LOAD_CENTER_MM: tuple[float, float, float] = (186.0, 0.0, 79.0)
#: Table I: translations from the centre [mm], keyed by principal axis and sign.
TABLE_I_TRANSLATIONS_MM: dict[str, tuple[float, float, float]] = {
    "+x": (161.0, 93.0, 0.0),
    "-x": (-161.0, 93.0, 0.0),
    "+y": (0.0, 29.0, 0.0),
    "-y": (0.0, -42.0, 0.0),
    "+z": (0.0, 0.0, 15.0),
    "-z": (0.0, 0.0, -48.0),
}


@dataclass(frozen=True)
class LoadConfiguration:
    """Where the external load's centre of mass sits in the sensor frame.

    Attributes
    ----------
    config_id : int
        Label used in logs and as the dataset's group.
    name : str
        Human-readable name (``"centre"``, ``"+x"``, ...).
    position_in_sensor : tuple of 3 floats
        Centre of mass in the sensor frame [m].
    mass_kg : float or None
        The load's mass [kg] when the fixture says it (else the logs' or the caller's mass).
    inertia_kg_m2 : tuple of 6 floats or None
        ``Ixx, Iyy, Izz, Ixy, Ixz, Iyz`` about the centre of mass [kg·m²], if known. Recorded only: a static
        calibration pose loads the sensor with the weight alone.
    """

    config_id: int
    name: str
    position_in_sensor: tuple[float, float, float]
    mass_kg: float | None = None
    inertia_kg_m2: tuple[float, ...] | None = None


def thesis_load_configurations() -> tuple[LoadConfiguration, ...]:
    """The seven load configurations of the thesis: id 0 the centre, ids 1-6 Table I.

    Examples
    --------
    >>> cfgs = thesis_load_configurations()
    >>> [(c.config_id, c.name) for c in cfgs][:3]
    [(0, 'centre'), (1, '+x'), (2, '-x')]
    >>> cfgs[1].position_in_sensor  # [m]
    (0.347, 0.093, 0.079)
    """
    centre = np.array(THESIS_LOAD_CENTER_MM)
    shifts = {"centre": (0.0, 0.0, 0.0), **TABLE_I_TRANSLATIONS_MM}
    return tuple(LoadConfiguration(i, name, tuple(float(v) for v in np.round((centre + np.array(shift)) / 1000.0, 9)))
                 for i, (name, shift) in enumerate(shifts.items()))


def _vector3(v: ArrayLike, name: str, n: int | None = None) -> NDArray[np.float64]:
    a = np.asarray(v, dtype=float)
    if a.shape != (3,) and not (a.ndim == 2 and a.shape[1] == 3 and (n is None or a.shape[0] == n)):
        want = "(3,)" if n is None else f"(3,) or ({n}, 3)"
        raise KinematicsError(f"{name} must have shape {want}; got shape {a.shape}.")
    if not np.all(np.isfinite(a)):
        raise KinematicsError(f"{name} holds NaN or inf; got {a.tolist()!r}.")
    return a


def reference_wrench(
    sensor_rotation_in_base: ArrayLike,
    load_mass: float,
    load_position_in_sensor: ArrayLike,
    gravity_in_base: ArrayLike = GRAVITY_IN_BASE,
) -> NDArray[np.float64]:
    """Wrench of a point load on the sensor, in the sensor frame (eq. 15-16).

    Parameters
    ----------
    sensor_rotation_in_base : array-like of shape (3, 3) or (n, 3, 3)
        ``R_sensor``: maps sensor-frame vectors to the base frame.
    load_mass : float
        Mass of the load [kg], >= 0.
    load_position_in_sensor : array-like of shape (3,) or (n, 3)
        The load's centre of mass in the sensor frame [m].
    gravity_in_base : array-like of shape (3,), default=(0, 0, -9.80665)
        Gravitational acceleration in the base frame [m/s²].

    Returns
    -------
    ndarray of shape (n, 6)
        ``[Fx, Fy, Fz, Tx, Ty, Tz]`` in [N] and [N·m].

    Examples
    --------
    Sensor upright (R = I), 1 kg at 0.1 m along x: the load pulls with
    ``Fz = -9.81 N`` and, 0.1 m out along x, gives ``Ty = -x Fz = +0.98 N·m``:

    >>> import numpy as np
    >>> reference_wrench(np.eye(3), 1.0, [0.1, 0, 0]).round(4) + 0.0
    array([[ 0.    ,  0.    , -9.8066,  0.    ,  0.9807,  0.    ]])
    """
    R = np.asarray(sensor_rotation_in_base, dtype=float)
    if R.shape == (3, 3):
        R = R[None]
    if R.ndim != 3 or R.shape[1:] != (3, 3) or not np.all(np.isfinite(R)):
        raise KinematicsError(f"sensor_rotation_in_base must be finite with shape (3, 3) or (n, 3, 3); got {R.shape}.")
    if not np.isfinite(load_mass) or load_mass < 0:
        raise KinematicsError(f"load_mass must be a finite mass >= 0 [kg]; got {load_mass!r}.")
    g = _vector3(gravity_in_base, "gravity_in_base")
    r = _vector3(load_position_in_sensor, "load_position_in_sensor", R.shape[0])
    force = load_mass * np.einsum("nji,j->ni", R, g)
    torque = np.cross(np.broadcast_to(r, force.shape), force)
    return np.hstack([force, torque])


def reference_wrench_at_joints(
    robot: RobotModel,
    q: ArrayLike,
    load_mass: float,
    load_position_in_sensor: ArrayLike,
    gravity_in_base: ArrayLike = GRAVITY_IN_BASE,
) -> NDArray[np.float64]:
    """:func:`reference_wrench` with the sensor rotation from forward kinematics of ``q`` (n, n_joints) [rad].

    Examples
    --------
    >>> from ftcal.robot import load_robot
    >>> w = reference_wrench_at_joints(load_robot(), [0.0] * 7, 2.0, [0, 0, 0.1])
    >>> w.round(3) + 0.0  # arm upright: load straight down the sensor z axis
    array([[ 0.   ,  0.   , -19.613,  0.   ,  0.   ,  0.   ]])
    """
    P = np.asarray(sensor_pose_in_base(robot, robot.check_joints(q)))
    return reference_wrench(P[:, :3, :3], load_mass, load_position_in_sensor, gravity_in_base)


#: Name of the default fixture: the thesis' seven load configurations (ids 0-6).
THESIS_FIXTURE = "thesis"
_FIXTURE_CSV = "id,name,mass_kg,com_x_m,com_y_m,com_z_m[,ixx,iyy,izz,ixy,ixz,iyz]"


def _configuration(entry: dict, where: str) -> LoadConfiguration:
    from ..core._exceptions import CalibrationInputError

    try:
        cid = entry["id"]
        com = [float(v) for v in entry["center_of_mass_m"]]
        mass, inertia = entry.get("mass_kg"), entry.get("inertia_kg_m2")
        mass = None if mass is None else float(mass)
        inertia = None if inertia is None else tuple(float(v) for v in np.ravel(inertia))
    except (KeyError, TypeError, ValueError) as exc:
        raise CalibrationInputError(f"{where}: each configuration needs 'id' and 'center_of_mass_m' (3 numbers, m), "
                                    f"optional 'mass_kg', 'name', 'inertia_kg_m2' ({exc!r}).") from None
    if isinstance(cid, bool) or not isinstance(cid, (int, np.integer)) and not (isinstance(cid, float) and cid.is_integer()):
        raise CalibrationInputError(f"{where}: id {cid!r} must be an integer (the logs' config column).")
    if len(com) != 3 or not np.all(np.isfinite(com)):
        raise CalibrationInputError(f"{where}: center_of_mass_m must be 3 finite numbers [m]; got {com}.")
    if np.linalg.norm(com) > 5.0:
        raise CalibrationInputError(f"{where}: center_of_mass_m {com} is {np.linalg.norm(com):.3g} m from the sensor; "
                                    "give it in metres (not mm).")
    if mass is not None and not (np.isfinite(mass) and mass > 0):
        raise CalibrationInputError(f"{where}: mass_kg must be a positive mass in kg; got {mass!r}.")
    if inertia is not None:
        if len(inertia) == 9:  # a 3x3 matrix: its diagonal, then xy, xz, yz
            inertia = tuple(np.reshape(inertia, (3, 3))[[0, 1, 2, 0, 0, 1], [0, 1, 2, 1, 2, 2]])
        if len(inertia) != 6 or not np.all(np.isfinite(inertia)) or min(inertia[:3]) < 0:
            raise CalibrationInputError(f"{where}: inertia_kg_m2 must be Ixx,Iyy,Izz (>= 0),Ixy,Ixz,Iyz [kg·m²] or a "
                                        f"3x3 matrix; got {list(inertia)}.")
    return LoadConfiguration(int(cid), str(entry.get("name", f"config{int(cid)}")), tuple(com), mass, inertia)


def read_load_configurations(path) -> tuple[LoadConfiguration, ...]:
    """Your fixture's load configurations from a small file (JSON or CSV).

    JSON: ``{"name": "...", "configurations": [{"id": 0, "name": "centre", "mass_kg": 2.0,
    "center_of_mass_m": [0.186, 0, 0.079], "inertia_kg_m2": [Ixx, Iyy, Izz, Ixy, Ixz, Iyz]}, ...]}`` (or the
    list alone). CSV: a header ``id,name,mass_kg,com_x_m,com_y_m,com_z_m[,ixx,iyy,izz,ixy,ixz,iyz]``, one row
    per configuration (``mass_kg`` may be empty: then the logs' mass). Centres of mass in the sensor frame [m].

    Examples
    --------
    >>> import json, tempfile, pathlib
    >>> p = pathlib.Path(tempfile.mkdtemp()) / "fixture.json"
    >>> _ = p.write_text(json.dumps([{"id": 0, "mass_kg": 1.5, "center_of_mass_m": [0, 0, 0.1]}]))
    >>> read_load_configurations(p)[0].mass_kg
    1.5
    """
    import csv
    import json
    from pathlib import Path

    from ..core._exceptions import CalibrationInputError

    path = Path(path)
    if not path.is_file():
        raise CalibrationInputError(f"{path}: no such fixture file (JSON or CSV, or the name '{THESIS_FIXTURE}').")
    try:
        text = path.read_text(encoding="utf-8-sig")
    except UnicodeDecodeError:
        raise CalibrationInputError(f"{path}: not a UTF-8 text file.") from None
    entries: list[tuple[dict, str]] = []
    if path.suffix.lower() == ".json":
        try:
            doc = json.loads(text)
        except (json.JSONDecodeError, RecursionError) as exc:
            raise CalibrationInputError(f"{path}: bad JSON ({str(exc)[:80]}).") from None
        items = doc.get("configurations") if isinstance(doc, dict) else doc
        if not isinstance(items, list) or not all(isinstance(e, dict) for e in items):
            raise CalibrationInputError(f"{path}: expected a list of configurations (objects) or "
                                        "{\"configurations\": [...]}.")
        entries = [(e, f"{path}: configuration {i + 1}") for i, e in enumerate(items)]
    elif path.suffix.lower() == ".csv":
        rows = list(csv.reader(line for line in text.splitlines() if line.strip() and not line.startswith("#")))
        if not rows:
            raise CalibrationInputError(f"{path}: empty fixture file; expected a header {_FIXTURE_CSV}.")
        head = [h.strip() for h in rows[0]]
        needed = ["id", "com_x_m", "com_y_m", "com_z_m"]
        if any(n not in head for n in needed):
            raise CalibrationInputError(f"{path}: line 1: the header lacks {[n for n in needed if n not in head]}; "
                                        f"expected {_FIXTURE_CSV}.")
        inertia_cols = ["ixx", "iyy", "izz", "ixy", "ixz", "iyz"]
        for k, row in enumerate(rows[1:], start=2):
            if len(row) != len(head):
                raise CalibrationInputError(f"{path}: line {k}: {len(row)} values for {len(head)} columns.")
            d = dict(zip(head, (v.strip() for v in row)))
            try:
                entry = {"id": float(d["id"]), "name": d.get("name") or f"config{d['id']}",
                         "center_of_mass_m": [float(d[c]) for c in needed[1:]],
                         "mass_kg": float(d["mass_kg"]) if d.get("mass_kg") else None}
                if all(d.get(c) for c in inertia_cols):
                    entry["inertia_kg_m2"] = [float(d[c]) for c in inertia_cols]
            except ValueError as exc:
                raise CalibrationInputError(f"{path}: line {k}: {exc}.") from None
            entries.append((entry, f"{path}: line {k}"))
    else:
        raise CalibrationInputError(f"{path}: a fixture file is .json or .csv; got {path.suffix!r}.")
    if not entries:
        raise CalibrationInputError(f"{path}: the fixture lists no load configuration.")
    configs = tuple(_configuration(e, where) for e, where in entries)
    ids = [c.config_id for c in configs]
    dup = sorted({i for i in ids if ids.count(i) > 1})
    if dup:
        raise CalibrationInputError(f"{path}: configuration id {dup[0]} appears {ids.count(dup[0])} times.")
    return configs


def load_fixture(spec: str | None) -> tuple[str, tuple[LoadConfiguration, ...]]:
    """``(description, configurations)`` of ``--fixture``: the thesis' default, or a fixture file."""
    if spec is None or spec == THESIS_FIXTURE:
        configs = thesis_load_configurations()
        return (f"the thesis' fixture ({len(configs)} load configurations, ids 0-{len(configs) - 1}: centre and "
                "Table I)", configs)
    configs = read_load_configurations(spec)
    return f"{spec} ({len(configs)} load configurations, ids {', '.join(str(c.config_id) for c in configs)})", configs
