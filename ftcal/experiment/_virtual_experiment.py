"""The thesis' real-world experiment, simulated: load / no-load runs written as run logs.

What is simulated (thesis IV-B):

* the planned sphere of poses (:func:`ftcal.robot.plan_calibration_poses`), run once
  without and once with the external load for every load configuration;
* the **mounting device** (Fig. 4, item 2), a rigid mass on the sensor in both
  runs. Its mass and centre of mass are not in the thesis; the defaults
  (0.9 kg at ``[90, 0, 45]`` mm) are assumptions for a holder that carries a
  load 186 mm off-axis;
* **pose differences between the runs** (IV-B-e, "tenths of a degree"): the
  load run reaches each pose with a Gaussian error of ``load_pose_jitter_deg``
  (default 0.1 deg) per joint, truncated at 3 standard deviations (a robot's
  repeatability is bounded), recorded in its log. The rotation between the
  two poses of a pair is then at most ``3 * n_joints * load_pose_jitter_deg``
  (the angle of a product of joint rotations is at most the sum of the joint
  angles): 2.1 deg for the defaults on a 7-joint arm, within
  :func:`ftcal.experiment.prepare_dataset`'s pairing limit of 3 deg;
* **robot accuracy** (IV-B-f): the true joint angles differ from the logged
  ones by a uniform error of at most ``joint_error_max / n_joints`` per joint
  (0.0055 / 7 = 0.00079 rad, the thesis' per-link estimate), so that the
  accumulated error stays below 0.0055 rad. Fresh per pose and run;
* the **sensor**: a :class:`ftcal.simulation.VirtualSensor` (calibration matrix, the
  error models of the artificial benchmark, a zero offset), read at the true
  pose under the true wrench of mounting device plus load.

The logs go through :func:`ftcal.experiment.prepare_dataset` exactly as real ones would.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Callable, Sequence

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..simulation._artificial import VirtualSensor
from ..core._exceptions import LogFormatError
from ..robot._loads import GRAVITY_IN_BASE, LoadConfiguration, reference_wrench, thesis_load_configurations
from ..core._temperature import ThermalDrift
from ..io._logs import write_run_log
from ..robot._pose_planning import THESIS_EXCLUDED_CAP_DEG, THESIS_SUBDIVISIONS, CalibrationPlan, plan_calibration_poses
from ..robot._robot import RobotModel, load_robot, sensor_pose_in_base

__all__ = ["MountingDevice", "simulate_experiment", "THESIS_JOINT_ERROR_RAD", "DEFAULT_LOAD_MASS_KG"]

#: The per-joint pose jitter between the load and no-load runs is truncated at this many standard deviations.
JITTER_TRUNCATION = 3.0

#: Accumulated joint-angle error of the iiwa estimated in the thesis (IV-B-f) [rad].
THESIS_JOINT_ERROR_RAD: float = 0.0055
#: Default external load [kg]. ASSUMED: the thesis does not state the mass; a few
#: kg give forces of the size its Table IV errors suggest.
DEFAULT_LOAD_MASS_KG: float = 2.0
_POSE_PERIOD_S = 4.0  # time per pose (move + settle + record) [s]
_SAMPLE_PERIOD_S = 0.01  # 100 Hz sampling within a pose [s]


@dataclass(frozen=True)
class MountingDevice:
    """The load holder bolted to the sensor (present in load and no-load runs).

    Attributes
    ----------
    mass : float
        [kg]. Default 0.9 (ASSUMED).
    center_of_mass_in_sensor : tuple of 3 floats
        [m]. Default ``(0.09, 0.0, 0.045)`` (ASSUMED).
    """

    mass: float = 0.9
    center_of_mass_in_sensor: tuple[float, float, float] = (0.09, 0.0, 0.045)


def simulate_experiment(
    out_dir: str | Path, *, robot: RobotModel | str | Path = "kuka_iiwa14", load_mass: float = DEFAULT_LOAD_MASS_KG,
    load_configurations: Sequence[LoadConfiguration] | None = None, sensor: VirtualSensor | None = None,
    errors: str = "thesis", mounting: MountingDevice = MountingDevice(), plan: CalibrationPlan | None = None,
    subdivisions: int = THESIS_SUBDIVISIONS, excluded_cap_deg: float = THESIS_EXCLUDED_CAP_DEG,
    joint_error_max: float = THESIS_JOINT_ERROR_RAD, load_pose_jitter_deg: float = 0.1, samples_per_pose: int = 1,
    gravity_in_base: ArrayLike = GRAVITY_IN_BASE, random_state: int | None = None, overwrite: bool = False,
    thermal_drift: ThermalDrift | str | None = None, temperature_range_deg: tuple[float, float] = (20.0, 30.0),
    temperature_profile: Callable[[NDArray[np.float64]], ArrayLike] | None = None,
    bias_drift: Callable[[NDArray[np.float64]], ArrayLike] | None = None,
) -> list[Path]:
    """Simulate the load / no-load runs and write one log per run into ``out_dir``.

    Parameters
    ----------
    out_dir : str or path
        Folder for ``config<c>_no-load.csv``, ``config<c>_load.csv`` and a
        ``virtual_experiment.json`` with the simulated truths (created if needed).
    robot : RobotModel, name or URDF path, default="kuka_iiwa14"
    load_mass : float, default=2.0
        External load [kg].
    load_configurations : sequence of LoadConfiguration, optional
        Default the thesis' seven.
    sensor : VirtualSensor, optional
        Default ``VirtualSensor(errors=errors, zero_offset=<0.5 % FS tare>)``
        seeded from ``random_state``.
    errors : str, default="thesis"
        Error preset of the default sensor.
    mounting : MountingDevice
        The holder's mass and centre of mass.
    plan : CalibrationPlan, optional
        Poses to run; default ``plan_calibration_poses(robot, subdivisions=...,
        excluded_cap_deg=...)`` (155 poses for the defaults).
    joint_error_max : float, default=0.0055
        Largest accumulated joint-angle error [rad]; 0 disables it.
    load_pose_jitter_deg : float, default=0.1
        Std of the per-joint difference between load and no-load poses [deg],
        truncated at 3 std (see the module docstring for the bound it implies).
    samples_per_pose : int, default=1
        Rows recorded per pose (each with fresh sensor noise).
    gravity_in_base : array-like of shape (3,)
        [m/s²].
    thermal_drift : ThermalDrift, "typical" or None
        Simulate the sensor's thermal zero and span drift (``"typical"``: data-sheet
        magnitudes for this sensor, :meth:`ThermalDrift.typical` of its full-scale readings): each run's
        temperature ramps linearly between two random values in
        ``temperature_range_deg`` [deg C] (a slow drift over the run), the
        readings drift accordingly and the logs carry a ``temperature`` column.
    temperature_range_deg : (float, float), default=(20, 30)
        Range of the simulated temperatures [deg C].
    temperature_profile : callable, optional
        ``temperature_profile(time_s) -> (n,)`` [deg C] at each sample's log time [s], instead of the
        per-run ramp (with ``thermal_drift``): e.g. a room warming and cooling over the whole experiment.
    bias_drift : callable, optional
        ``bias_drift(time_s) -> (n, 6)`` [N, N·m]: a wrench added to every sample at its log time [s] (the
        sensor's zero moving while it warms up or creeps), read through the sensor like any load.
    random_state : int, optional
    overwrite : bool, default=False
        Replace existing logs; otherwise an existing file is an error and
        nothing is written.

    Returns
    -------
    list of pathlib.Path
        The log files, no-load before load for each configuration.

    Examples
    --------
    >>> import tempfile
    >>> from ftcal.robot import load_robot, plan_calibration_poses
    >>> from ftcal.experiment import prepare_dataset
    >>> robot = load_robot()
    >>> plan = plan_calibration_poses(robot, subdivisions=0, excluded_cap_deg=0)
    >>> paths = simulate_experiment(tempfile.mkdtemp(), robot=robot, plan=plan, random_state=0)
    >>> len(paths)
    14
    >>> ds = prepare_dataset(paths, robot)
    >>> ds.raw.shape, ds.wrench.shape, sorted(set(ds.group.tolist()))
    ((84, 6), (84, 6), [0, 1, 2, 3, 4, 5, 6])
    """
    if isinstance(robot, (str, Path)):
        robot = load_robot(robot)
    _check_arguments(load_mass, samples_per_pose, joint_error_max, load_pose_jitter_deg, thermal_drift)
    configs = tuple(load_configurations) if load_configurations is not None else thesis_load_configurations()
    out = Path(out_dir)
    paths = [out / f"config{c.config_id}_{kind}.csv" for c in configs for kind in ("no-load", "load")]
    existing = [str(p) for p in paths + [out / "virtual_experiment.json"] if p.exists()]
    if existing and not overwrite:
        raise LogFormatError(f"{existing[0]} exists ({len(existing)} of the logs do).", parameter="out_dir",
                             value=str(out), fix="pass {overwrite}, or choose an empty out_dir",
                             settings={"overwrite": True})
    rng = np.random.default_rng(random_state)
    if sensor is None:
        sensor = VirtualSensor(errors=errors, random_state=rng)
        tare = rng.normal(0.0, 0.005, 6) * np.array([sensor.profile.fmax] * 3 + [sensor.profile.tmax] * 3)
        sensor.zero_offset = sensor.profile.reading_from_wrench(tare[None])[0]  # a tare of 0.5 % of the full scale
    if plan is None:
        plan = plan_calibration_poses(robot, subdivisions=subdivisions, excluded_cap_deg=excluded_cap_deg,
                                      gravity_in_base=gravity_in_base)
    g = np.asarray(gravity_in_base, dtype=float)
    reps, n, clock = int(samples_per_pose), plan.n_poses, 0.0
    for (c, kind), path in zip([(c, kind) for c in configs for kind in ("no-load", "load")], paths):
        mass = (load_mass if c.mass_kg is None else c.mass_kg) if kind == "load" else None
        q_logged, t, rows_w = _run_wrenches(rng, robot, plan.q, mounting, g, c.position_in_sensor, mass,
                                            joint_error_max / robot.n_joints, load_pose_jitter_deg, reps, clock)
        if bias_drift is not None:
            rows_w = rows_w + _drift_values("bias_drift", bias_drift, t, (len(t), 6))
        raw = sensor.read(rows_w)
        temperature = None
        if isinstance(thermal_drift, str):  # "typical": drawn here, after the first run's readings
            full_scale = np.abs(sensor.profile.reading_from_wrench(np.diag(sensor.profile.full_scale))).sum(axis=0)
            thermal_drift = ThermalDrift.typical(full_scale, random_state=rng)
        if thermal_drift is not None:
            start, end = rng.uniform(*temperature_range_deg, size=2)
            temperature = (np.linspace(start, end, len(raw)) if temperature_profile is None
                           else _drift_values("temperature_profile", temperature_profile, t, (len(t),)))
            raw = thermal_drift.apply(raw, temperature)
        clock = float(t[-1]) + _POSE_PERIOD_S
        write_run_log(path, timestamp=t, run_kind=[kind] * (n * reps), config=[c.config_id] * (n * reps),
                      pose=np.repeat(np.arange(n), reps), q=np.repeat(q_logged, reps, axis=0), raw=raw,
                      raw_unit=sensor.profile.raw_unit, load_mass=mass, robot=robot.name,
                      sensor_frame=robot.sensor_frame, meta={"simulated": True, "load_configuration": c.name},
                      overwrite=overwrite, temperature=temperature)
    truth = {
        "robot": robot.name, "load_mass_kg": load_mass, "mounting_device": asdict(mounting),
        "load_configurations": [asdict(c) for c in configs], "n_poses": n, "samples_per_pose": reps,
        "joint_error_max_rad": joint_error_max, "load_pose_jitter_deg": load_pose_jitter_deg,
        "sensor_errors": sensor.errors_.to_dict() if hasattr(sensor.errors_, "to_dict") else repr(sensor.errors_),
        "zero_offset": np.asarray(sensor.zero_offset).tolist(), "random_state": random_state,
        "thermal_drift": None if thermal_drift is None else {
            "offset_per_deg": thermal_drift.offset_per_deg.tolist(),
            "gain_per_deg": thermal_drift.gain_per_deg.tolist(),
            "reference_temperature": thermal_drift.reference_temperature,
            "temperature_range_deg": list(temperature_range_deg)}, "plan": plan.settings,
    }
    (out / "virtual_experiment.json").write_text(json.dumps(truth, indent=2, default=str), encoding="utf-8")
    return paths


def _check_arguments(load_mass: float, samples_per_pose: int, joint_error_max: float, load_pose_jitter_deg: float,
                     thermal_drift) -> None:
    """Refuse a load mass <= 0, a fractional or zero sample count, negative errors and an unknown drift name."""
    if not np.isfinite(load_mass) or load_mass <= 0:
        raise LogFormatError(f"load_mass must be a positive mass in kg; got {load_mass!r}.")
    if int(samples_per_pose) != samples_per_pose or samples_per_pose < 1:
        raise LogFormatError(f"samples_per_pose must be a positive integer; got {samples_per_pose!r}.")
    if not (np.isfinite(joint_error_max) and joint_error_max >= 0 and np.isfinite(load_pose_jitter_deg)
            and load_pose_jitter_deg >= 0):
        raise LogFormatError(f"joint_error_max ({joint_error_max!r} rad) and load_pose_jitter_deg "
                             f"({load_pose_jitter_deg!r} deg) must be finite and >= 0.")
    if isinstance(thermal_drift, str) and thermal_drift != "typical":
        raise LogFormatError(f"thermal_drift must be a ThermalDrift, 'typical' or None; got {thermal_drift!r}.")


def _run_wrenches(rng: np.random.Generator, robot: RobotModel, q_planned: NDArray, mounting: MountingDevice,
                  g: NDArray, load_position: ArrayLike, load_mass: float | None, per_joint: float, jitter_deg: float,
                  reps: int, clock: float) -> tuple[NDArray, NDArray, NDArray]:
    """One run's logged joints (n, n_joints) [rad], sample times (n * reps,) [s] from ``clock`` and true wrenches
    (n * reps, 6) [N, N·m]: the mounting device's weight, and the load's (``load_mass`` [kg]; ``None`` for a
    no-load run, which also reaches the planned poses without jitter)."""
    q_logged = q_planned.copy()
    if load_mass is not None:
        sigma = np.deg2rad(jitter_deg)
        jitter = np.clip(rng.normal(0, sigma, q_logged.shape), -JITTER_TRUNCATION * sigma, JITTER_TRUNCATION * sigma)
        q_logged = np.clip(q_logged + jitter, robot.lower_limits, robot.upper_limits)
    q_true = q_logged + rng.uniform(-per_joint, per_joint, q_logged.shape)
    R_true = sensor_pose_in_base(robot, q_true)[:, :3, :3]
    wrench = reference_wrench(R_true, mounting.mass, mounting.center_of_mass_in_sensor, g)
    if load_mass is not None:
        wrench += reference_wrench(R_true, load_mass, load_position, g)
    n = len(q_logged)
    t = clock + np.repeat(np.arange(n) * _POSE_PERIOD_S, reps) + np.tile(np.arange(reps) * _SAMPLE_PERIOD_S, n)
    return q_logged, t, np.repeat(wrench, reps, axis=0)


def _drift_values(name: str, function: Callable, t: NDArray[np.float64], shape: tuple[int, ...]) -> NDArray:
    """``function(t)`` checked: finite, of ``shape``."""
    values = np.asarray(function(t), dtype=float)
    if values.shape != shape or not np.isfinite(values).all():
        raise LogFormatError(f"{name}(time_s) must return finite values of shape {shape}; got shape {values.shape}.")
    return values
