"""Simulated sensors like the real ones ftcal is judged on: soft, robot-held at scale, and dead-weight few-row data.

The thesis' presets are rigid strain-gauge sensors where the LTM is close to
optimal. Real sensors outside the repository showed three other regimes, each
simulated here so that the gaps can be seen and closed on data anyone can run:

* :func:`make_soft_sensor_dataset`: a soft/compliant fingertip sensor: 8
  channels, a few hundred rows (some at zero load), a smooth strong
  saturation of every channel, cross-coupling between channels, and a
  hysteresis-like dependence on the load history (an exponentially lagged
  copy of the load). A stock Gaussian process beats the LTM by a factor ~1.7 here
  (5-fold, ``benchmarks/gp_vs_stock_soft.py``); the lag is what no memoryless model can learn.
* :func:`make_robot_held_dataset`: a rigid 8-channel sensor on a robot arm,
  tens of thousands of rows in 40-50 poses (the ``group``); each pose holds a
  tool's gravity wrench plus loads applied by hand, and carries its own small
  offset (mounting and thermal state), which no model can learn from the
  other poses: the LTM is near the floor and flexible models must not be worse.
* :func:`make_dead_weight_dataset`: 15-50 dead-weight rows within a
  calibrated range, and a validation set with loads up to ``range_factor``
  times larger (extrapolation).

Every dataset's ``meta["noise_floor_rmse"]`` is the RMSE (eq. 18, torque
scaled with the dataset's ``alpha``) of the reference noise alone, i.e. what a
perfect model would score.
"""

from __future__ import annotations

from numbers import Integral, Real

import numpy as np
from scipy.spatial.transform import Rotation
from sklearn.utils._param_validation import Interval, Options

from ..core._exceptions import CalibrationInputError
from ..core._memory import check_allocation
from ..core._validation import check_arguments
from ..core._wrench import MIN_CHANNELS, alpha_from_wrenches, scale_torques
from ..io._dataset import CalibrationDataset

__all__ = ["make_soft_sensor_dataset", "make_robot_held_dataset", "make_dead_weight_dataset"]


#: A seed of numpy's generators: an int >= 0.
_SEED = [Interval(Integral, 0, None, closed="left")]


def _check_rows(caller: str, name: str, n_rows: int, floats_per_row: int) -> None:
    """Refuse, before allocating, a row count ``name`` whose arrays would exceed ftcal's memory limit."""
    check_allocation(8.0 * floats_per_row * n_rows, f"{caller}'s arrays for {name}={n_rows} rows", f"lower {name}")


def _with_floor(raw, wrench, noise, group, meta) -> CalibrationDataset:
    """The dataset with reference ``noise`` added and its RMSE floor (eq. 18) in ``meta``."""
    alpha = alpha_from_wrenches(wrench)
    meta = dict(meta, alpha=alpha, noise_floor_rmse=float(np.sqrt(np.mean(scale_torques(noise, alpha) ** 2))))
    return CalibrationDataset(raw=raw, wrench=wrench + noise, group=group, meta=meta)


def make_soft_sensor_dataset(n_samples: int = 418, *, n_zero: int = 48, n_presses: int = 37,
                             hysteresis: float = 0.25, random_state: int = 0) -> CalibrationDataset:
    """A soft fingertip-like sensor: 8 channels, saturating, coupled, with load-history dependence.

    The loads come as ``n_presses`` presses (the ``group``), each a smooth
    sequence of contact wrenches (``Fz`` 0..10 N pressing, ``Fx``, ``Fy``
    ±3 N, torques ±0.05 N·m) followed by rows at zero load (``n_zero`` in all).
    The channels see ``s = A w`` (normalised load, random 8 x 6 ``A``) through
    ``tanh`` saturation with products of channel pairs (coupling), plus
    ``hysteresis`` times a lagged copy of the load (time constant ~3 rows), so
    the same load read on the way up and down differs.

    No static calibration can undo that history dependence, so the error
    floor of this sensor is above the reference noise (``meta
    ["noise_floor_rmse"]``). The sensor (``A`` and the coupling pairs) depends
    only on ``random_state``: a larger ``n_samples`` and ``n_presses`` with the
    same seed records more of the *same* sensor, which is how
    ``benchmarks/auto_vs_stock.py`` estimates the floor a static map can reach.

    Parameters
    ----------
    n_samples : int, default=418
    n_zero : int, default=48
        Rows at zero load (after presses; they still show the lag).
    n_presses : int, default=37
    hysteresis : float, default=0.25
        Weight of the lagged load in the readings, 0 to 10 (1: as strong as the saturating response).
    random_state : int, default=0

    Returns
    -------
    CalibrationDataset
        ``raw`` (n, 8), ``wrench`` (n, 6) [N, N·m], ``group`` (press index).

    Examples
    --------
    >>> d = make_soft_sensor_dataset(random_state=1)
    >>> d.raw.shape, d.wrench.shape, int((abs(d.wrench[:, 2]) < 0.2).sum()) >= 48
    ((418, 8), (418, 6), True)
    """
    check_arguments("make_soft_sensor_dataset", {
        "n_samples": [Interval(Integral, 1, None, closed="left")],
        "n_zero": [Interval(Integral, 0, None, closed="left")],
        "n_presses": [Interval(Integral, 1, None, closed="left")],
        "hysteresis": [Interval(Real, 0, 10, closed="both")],
        "random_state": _SEED,
    }, **locals())  # every argument, in the signature's order
    if n_zero > max(n_samples - 5, 0):
        raise CalibrationInputError(
            f"make_soft_sensor_dataset: n_zero={n_zero} rows at zero load do not fit in n_samples={n_samples} (the "
            f"first 5 rows are loaded): n_zero must be at most {max(n_samples - 5, 0)}.")
    if n_presses > n_samples:
        raise CalibrationInputError(
            f"make_soft_sensor_dataset: n_presses={n_presses} presses need at least as many rows; n_samples is "
            f"{n_samples}. Fix: n_presses <= n_samples.")
    _check_rows("make_soft_sensor_dataset", "n_samples", n_samples, 80)
    rng = np.random.default_rng(random_state)
    # the sensor from its own stream: more rows (n_samples, n_presses) of the same random_state are the same sensor
    sensor = np.random.default_rng([random_state, 1])
    a = sensor.normal(size=(8, 6)) / np.sqrt(6)
    pairs = sensor.permutation(8)
    span = np.array([3.0, 3.0, 10.0, 0.05, 0.05, 0.05])
    zero_rows = set(np.sort(rng.choice(np.arange(5, n_samples), size=n_zero, replace=False)).tolist())
    press_of_row = np.sort(rng.integers(0, n_presses, size=n_samples))
    z = np.zeros((n_samples, 6))
    target = rng.uniform(-1, 1, size=6)
    for i in range(n_samples):
        if i in zero_rows:
            continue
        if i == 0 or press_of_row[i] != press_of_row[i - 1] or rng.random() < 0.3:
            target = rng.uniform(-1, 1, size=6)
            target[2] = rng.uniform(0, 1)  # pressing only
        z[i] = z[i - 1] + 0.6 * (target - z[i - 1]) + 0.05 * rng.normal(size=6)  # z[-1]: still zero at i = 0
        z[i, 2] = abs(z[i, 2])
    lag = np.zeros_like(z)
    for i in range(1, n_samples):
        lag[i] = lag[i - 1] + (z[i - 1] - lag[i - 1]) / 3.0
    s = 1.5 * z @ a.T
    raw = np.tanh(s + 0.3 * s * s[:, pairs]) + hysteresis * np.tanh(lag @ a.T) + 0.003 * rng.normal(size=(n_samples, 8))
    raw = 2000.0 + 800.0 * raw  # ADC-like counts around a non-zero tare
    wrench = z * span
    noise = rng.normal(size=wrench.shape) * 0.01 * span
    return _with_floor(raw, wrench, noise, press_of_row, {"preset": "soft_sensor", "random_state": random_state})


def make_robot_held_dataset(n_samples: int = 90_000, *, n_poses: int = 47, tool_mass_kg: float = 1.5,
                            pose_offset: float = 0.002, random_state: int = 0) -> CalibrationDataset:
    """A rigid 8-channel sensor held by a robot in ``n_poses`` poses, with tens of thousands of rows.

    In each pose (the ``group``) the sensor carries a tool (``tool_mass_kg``,
    centre of mass 0.08 m along z) whose gravity wrench depends on the pose's
    orientation, plus loads applied by hand (forces up to ~20 N at lever arms
    up to 0.1 m) as smooth time series. The readings are the LTM's inverse with
    a mild quadratic coupling (1 % of span), a per-pose offset
    (``pose_offset`` of each channel's span: mounting and thermal state, the
    same for every row of a pose, unlearnable across poses), and noise.

    Parameters
    ----------
    n_samples : int, default=90000
        Rows, at least 2 and at least ``n_poses``.
    n_poses : int, default=47
    tool_mass_kg : float, default=1.5
        Tool mass [kg], 0 to 1000.
    pose_offset : float, default=0.002
        Per-pose offset as a fraction of each channel's span, 0 to 1.
    random_state : int, default=0

    Returns
    -------
    CalibrationDataset
        ``raw`` (n, 8), ``wrench`` (n, 6) [N, N·m], ``group`` (pose index).

    Examples
    --------
    >>> d = make_robot_held_dataset(2000, n_poses=40, random_state=0)
    >>> d.raw.shape, len(set(d.group.tolist()))
    ((2000, 8), 40)
    """
    check_arguments("make_robot_held_dataset", {
        "n_samples": [Interval(Integral, 2, None, closed="left")],
        "n_poses": [Interval(Integral, 1, None, closed="left")],
        "tool_mass_kg": [Interval(Real, 0, 1000, closed="both")],
        "pose_offset": [Interval(Real, 0, 1, closed="both")],
        "random_state": _SEED,
    }, **locals())  # every argument, in the signature's order
    if n_poses > n_samples:
        raise CalibrationInputError(
            f"make_robot_held_dataset: n_poses={n_poses} poses need at least one row each; n_samples is {n_samples}. "
            "Fix: n_poses <= n_samples.")
    _check_rows("make_robot_held_dataset", "n_samples", n_samples, 120)
    rng = np.random.default_rng(random_state)
    pose = np.sort(np.concatenate([np.arange(n_poses), rng.integers(0, n_poses, size=n_samples - n_poses)]))
    rotations = Rotation.random(n_poses, random_state=int(rng.integers(2**31))).as_matrix()
    com = np.array([0.0, 0.0, 0.08])
    gravity_in_sensor = np.einsum("pji,j->pi", rotations, np.array([0.0, 0.0, -9.81 * tool_mass_kg]))
    tool = np.hstack([gravity_in_sensor, np.cross(com, gravity_in_sensor)])[pose]
    # hand loads: a smooth random walk per pose (AR(1) with a ~50-row time constant)
    push, lever = np.zeros((2, n_samples, 3))
    shock = rng.normal(size=(n_samples, 6))
    for i in range(1, n_samples):
        keep = 0.0 if pose[i] != pose[i - 1] else 0.98
        push[i] = keep * push[i - 1] + np.sqrt(1 - keep**2) * 8.0 * shock[i, :3]
        lever[i] = keep * lever[i - 1] + np.sqrt(1 - keep**2) * 0.04 * shock[i, 3:]
    wrench = tool + np.hstack([push, np.cross(lever, push)])
    span = np.abs(wrench).max(axis=0)
    z = wrench / span
    a = rng.normal(size=(8, 6)) / np.sqrt(6)
    s = z @ a.T
    raw = s + 0.01 * s * s[:, rng.permutation(8)] + pose_offset * rng.normal(size=(n_poses, 8))[pose] \
        + 0.0005 * rng.normal(size=(n_samples, 8))
    raw = 32768.0 + 20000.0 * raw
    noise = rng.normal(size=wrench.shape) * np.array([0.1, 0.1, 0.1, 0.005, 0.005, 0.005])
    return _with_floor(raw, wrench, noise, pose, {"preset": "robot_held", "random_state": random_state})


def make_dead_weight_dataset(n_samples: int = 15, *, n_validation: int = 200, range_factor: float = 2.0,
                             n_channels: int = 6, nonlinearity: float = 0.01, loaded_axes: int | None = None,
                             random_state: int = 0) -> tuple[CalibrationDataset, CalibrationDataset]:
    """Few dead-weight calibration rows in a range, and a validation set at loads up to ``range_factor`` x it.

    The calibration loads are uniform within ±(10 N, 10 N, 10 N, 0.5 N·m x 3);
    the validation loads within ``range_factor`` times that. The channels are
    linear in the load with a cubic term (``nonlinearity`` of the span at the
    calibrated range's edge) and noise of 0.1 % of span; the references carry
    0.02 N / 0.001 N·m noise.

    Parameters
    ----------
    n_samples : int, default=15
        Calibration rows (>= 1).
    n_validation : int, default=200
        Validation rows (>= 1).
    range_factor : float, default=2.0
        Validation loads' range over the calibrated one, 1 to 1000.
    n_channels : int, default=6
        Raw channels, at least 3.
    nonlinearity : float, default=0.01
        Cubic term at the calibrated range's edge, as a fraction of span, -1 to 1.
    loaded_axes : {3, 6} or None, default=None
        ``None``: every calibration row loads all six axes at once. 3 (a 3-axis load cell: Fx, Fy, Fz) or 6:
        each calibration row loads one of the first ``loaded_axes`` axes only, in turn, and its ``group`` is
        that axis (one group per loaded axis, as a dead-weight session records them); the validation rows load
        those axes together (the others stay zero).
    random_state : int, default=0

    Returns
    -------
    calibration, validation : CalibrationDataset

    Examples
    --------
    >>> cal, val = make_dead_weight_dataset(15)
    >>> cal.raw.shape, val.raw.shape, bool(abs(val.wrench[:, 0]).max() > abs(cal.wrench[:, 0]).max())
    ((15, 6), (200, 6), True)
    """
    check_arguments("make_dead_weight_dataset", {
        "n_samples": [Interval(Integral, 1, None, closed="left")],
        "n_validation": [Interval(Integral, 1, None, closed="left")],
        "range_factor": [Interval(Real, 1, 1000, closed="both")],
        "n_channels": [Interval(Integral, MIN_CHANNELS, None, closed="left")],
        "nonlinearity": [Interval(Real, -1, 1, closed="both")],
        "loaded_axes": [Options(int, {3, 6}), None],
        "random_state": _SEED,
    }, **locals())  # every argument, in the signature's order
    for name, rows in (("n_samples", n_samples), ("n_validation", n_validation)):
        _check_rows("make_dead_weight_dataset", name, rows, 8 * n_channels + 40)
    rng = np.random.default_rng(random_state)
    span = np.array([10.0, 10.0, 10.0, 0.5, 0.5, 0.5])
    a = np.eye(6)[:n_channels] if n_channels <= 6 else np.vstack([np.eye(6), rng.normal(size=(n_channels - 6, 6))])
    a = a + 0.2 * rng.normal(size=a.shape)
    offset = rng.normal(size=n_channels)

    def make(n, factor, name, one_axis=False):
        w = rng.uniform(-factor, factor, size=(n, 6)) * span
        group = None
        if loaded_axes is not None:
            w[:, loaded_axes:] = 0.0
            if one_axis:  # each row loads one axis, in turn: its group
                group = np.arange(n) % loaded_axes
                w *= np.eye(6)[group]
        s = (w / span) @ a.T
        raw = offset + s + nonlinearity * s**3 + 0.001 * rng.normal(size=s.shape)
        noise = rng.normal(size=w.shape) * span * 0.002
        if loaded_axes is not None:
            noise[:, loaded_axes:] = 0.0
        return _with_floor(raw, w, noise, group, {"preset": name, "random_state": random_state})

    return (make(n_samples, 1.0, "dead_weight", one_axis=True),
            make(n_validation, range_factor, "dead_weight_validation"))
