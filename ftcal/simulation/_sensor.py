"""Sensor profiles: operating range, calibration matrix and units of a force/torque sensor.

A calibration matrix ``C`` (6 x N) maps the N raw channels of a sensor to the
wrench, ``w = C @ raw`` with forces in [N] and torques in [N·m]. The
artificial data of the thesis (section IV-A-d) go the other way: an
(erroneous) wrench is turned into raw readings with the inverse of ``C``
(the Moore-Penrose pseudo-inverse when N != 6).

The default sensor
------------------
The thesis uses a Nordbo NRS-6200 (Fmax = 2000 N, Tmax = 40 N·m, so
``alpha = 50`` m⁻¹) whose internal matrix is not public. :meth:`SensorProfile.default`
ships a representative matrix built from first principles instead, for the
classic *3-beam / 6-bridge* layout of ATI Nano/Mini/Gamma-style and
hexagonal industrial sensors (compare the published ATI Gamma/Nano17
matrices, whose rows show the same sign and sparsity pattern):

* three radial beams at 0°, 120°, 240° join the hub to the outer ring at
  radius ``r = 0.02 m`` (chosen so that ``Tmax / r = Fmax``, i.e. ``alpha = 1 / r``);
* each beam carries a *vertical* bending bridge (sees the beam's vertical
  shear ``Fz / 3 + 2 / (3 r) (Tx sin θ - Ty cos θ)``) and a *horizontal*
  bending bridge (sees the tangential shear
  ``2 / 3 (-Fx sin θ + Fy cos θ) + Tz / (3 r)``); channels are ordered
  ``[V0, H0, V1, H1, V2, H2]`` like ATI's SG0...SG5;
* manufacturing imperfections: fixed bridge gains
  ``[1.012, 0.987, 1.021, 0.994, 1.006, 0.979]`` and a gauge misalignment of
  about 1° (each vertical bridge picks up 1.5 % of its beam's horizontal
  shear, each horizontal bridge -1.0 % of the vertical one), so that the
  matrix is full like a real one, not block-diagonal;
* bridges give 5 V at the largest beam shear of a single-axis full-scale
  load (1154.7 N), the raw unit is [V].

The compliance matrix ``G`` (raw = G w) built this way is inverted to give
``C = G⁻¹``. Its force rows are in [N/V] and its torque rows in [N·m/V].
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core._exceptions import CalibrationInputError
from ..core._wrench import WRENCH_LABELS

__all__ = ["SensorProfile", "default_calibration_matrix"]

#: Beam angles of the 3-beam layout [rad].
_BEAM_ANGLES = np.deg2rad([0.0, 120.0, 240.0])
#: Fixed bridge gain deviations of the default sensor (channel order V0, H0, V1, H1, V2, H2).
_BRIDGE_GAINS = np.array([1.012, 0.987, 1.021, 0.994, 1.006, 0.979])
#: Share of the horizontal shear a vertical bridge picks up (gauge misalignment), and vice versa.
_V_FROM_H, _H_FROM_V = 0.015, -0.010
#: Bridge output at the largest single-axis full-scale beam shear [V].
_FULL_SCALE_VOLTS = 5.0


def _beam_shear_matrix(radius: float) -> NDArray[np.float64]:
    """Rows: vertical then horizontal shear of each beam [N] per wrench component (3-beam statics)."""
    vert = np.array([[0, 0, 1 / 3, 2 * np.sin(t) / (3 * radius), -2 * np.cos(t) / (3 * radius), 0] for t in _BEAM_ANGLES])
    horiz = np.array([[-2 * np.sin(t) / 3, 2 * np.cos(t) / 3, 0, 0, 0, 1 / (3 * radius)] for t in _BEAM_ANGLES])
    return np.vstack([vert, horiz])


def default_calibration_matrix(fmax: float = 2000.0, tmax: float = 40.0) -> NDArray[np.float64]:
    """The representative 6 x 6 calibration matrix of the default sensor (see the module notes).

    Parameters
    ----------
    fmax : float, default=2000.0
        Force range [N]; the beam radius is ``tmax / fmax`` [m].
    tmax : float, default=40.0
        Torque range [N·m].

    Returns
    -------
    ndarray of shape (6, 6)
        ``C`` with ``wrench = C @ raw``; force rows [N/V], torque rows [N·m/V].

    Examples
    --------
    >>> C = default_calibration_matrix()
    >>> C.shape
    (6, 6)
    >>> C_scaled = C * np.array([1, 1, 1, 50, 50, 50])[:, None]  # torque rows times alpha
    >>> bool(np.linalg.cond(C_scaled) < 5)
    True
    """
    radius = tmax / fmax
    shear = _beam_shear_matrix(radius)  # (6 rows: V0 V1 V2 H0 H1 H2, 6 wrench components)
    vert, horiz = shear[:3], shear[3:]
    compliance = np.empty((6, 6))
    compliance[0::2] = vert + _V_FROM_H * horiz
    compliance[1::2] = horiz + _H_FROM_V * vert
    full_scale = np.array([fmax] * 3 + [tmax] * 3)
    largest_shear = np.max(np.abs(shear * full_scale))
    compliance *= (_FULL_SCALE_VOLTS / largest_shear) * _BRIDGE_GAINS[:, None]
    return np.linalg.inv(compliance)


@dataclass
class SensorProfile:
    """What is known about a force/torque sensor before calibration.

    Parameters
    ----------
    calibration_matrix : ndarray of shape (6, n_channels)
        ``wrench = calibration_matrix @ raw``; n_channels >= 6 and rank 6.
    fmax : float
        Force range [N] (largest rated force component).
    tmax : float
        Torque range [N·m] (largest rated torque component).
    name : str
        Free text (model, serial number, ...).
    axis_max : tuple of 6 floats, optional
        Rated range per axis ``Fx ... Tz`` in [N] / [N·m] (ATI files list one
        per axis); defaults to ``fmax`` for the forces and ``tmax`` for the torques.
    raw_unit : str
        Unit of the raw channels (``"V"``, ``"counts"``, ...).
    meta : dict
        Anything else read from a vendor file (serial, calibration date,
        original units, ...).

    Examples
    --------
    >>> p = SensorProfile.default()
    >>> p.fmax, p.tmax, p.alpha, p.n_channels
    (2000.0, 40.0, 50.0, 6)
    >>> w = np.array([[100.0, 0, -50, 1, 0, 2]])
    >>> np.allclose(p.wrench_from_reading(p.reading_from_wrench(w)), w)
    True
    """

    calibration_matrix: NDArray[np.float64]
    fmax: float
    tmax: float
    name: str = ""
    axis_max: tuple | None = None
    raw_unit: str = "V"
    meta: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        c = np.asarray(self.calibration_matrix, dtype=float)
        if c.ndim != 2 or c.shape[0] != 6:
            raise CalibrationInputError(
                f"calibration_matrix must have shape (6, n_channels) (rows Fx..Tz, one column per raw channel); "
                f"got shape {c.shape}. Transpose it if your matrix is (n_channels, 6)."
            )
        if not np.all(np.isfinite(c)):
            raise CalibrationInputError("calibration_matrix contains NaN or inf.")
        rank = int(np.linalg.matrix_rank(c))
        if rank < 6:
            raise CalibrationInputError(
                f"calibration_matrix (shape {c.shape}) has rank {rank} < 6: it cannot resolve all six wrench "
                "components, and wrenches cannot be mapped back into raw readings. A 6-axis sensor needs at "
                "least 6 independent channels."
            )
        self.calibration_matrix = c
        self.fmax, self.tmax = float(self.fmax), float(self.tmax)
        for label, value in (("fmax", self.fmax), ("tmax", self.tmax)):
            if not (np.isfinite(value) and value > 0):
                raise CalibrationInputError(f"{label} must be a positive range; got {value}.")
        if self.axis_max is not None:
            am = tuple(float(v) for v in self.axis_max)
            if len(am) != 6 or not all(np.isfinite(v) and v > 0 for v in am):
                raise CalibrationInputError(f"axis_max must hold 6 positive ranges Fx..Tz; got {self.axis_max}.")
            self.axis_max = am

    @classmethod
    def default(cls) -> "SensorProfile":
        """The thesis' sensor: 2000 N, 40 N·m, with the representative 3-beam matrix."""
        return cls(calibration_matrix=default_calibration_matrix(2000.0, 40.0), fmax=2000.0, tmax=40.0,
                   name="representative 3-beam/6-bridge sensor, 2000 N / 40 N·m (thesis NRS-6200 range)")

    @property
    def n_channels(self) -> int:
        """Number of raw channels N."""
        return int(self.calibration_matrix.shape[1])

    @property
    def alpha(self) -> float:
        """Torque scale ``fmax / tmax`` [m⁻¹] (eq. 5)."""
        return self.fmax / self.tmax

    @property
    def full_scale(self) -> NDArray[np.float64]:
        """Rated range per axis, shape (6,), [N] x3 then [N·m] x3."""
        return np.array(self.axis_max if self.axis_max is not None else [self.fmax] * 3 + [self.tmax] * 3)

    def wrench_from_reading(self, raw: ArrayLike) -> NDArray[np.float64]:
        """Wrench [N, N·m] of raw readings (n, N) through the calibration matrix."""
        r = np.asarray(raw, dtype=float)
        if r.ndim != 2 or r.shape[1] != self.n_channels:
            raise CalibrationInputError(f"raw must have shape (n_samples, {self.n_channels}); got shape {r.shape}.")
        return r @ self.calibration_matrix.T

    def reading_from_wrench(self, wrench: ArrayLike) -> NDArray[np.float64]:
        """Raw readings (n, N) that the calibration matrix maps to ``wrench`` (pseudo-inverse, IV-A-d)."""
        w = np.asarray(wrench, dtype=float)
        if w.ndim != 2 or w.shape[1] != 6:
            raise CalibrationInputError(
                f"wrench must have shape (n_samples, 6) {list(WRENCH_LABELS)}; got shape {w.shape}."
            )
        return w @ np.linalg.pinv(self.calibration_matrix).T

    def to_dict(self) -> dict:
        """Plain-JSON form (matrix as nested lists)."""
        return {
            "name": self.name,
            "fmax": self.fmax,
            "tmax": self.tmax,
            "axis_max": None if self.axis_max is None else list(self.axis_max),
            "raw_unit": self.raw_unit,
            "calibration_matrix": self.calibration_matrix.tolist(),
            "meta": self.meta,
        }
