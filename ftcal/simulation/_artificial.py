"""Artificial calibration data (thesis section IV-A): a virtual sensor and the 30-dataset generator.

The pipeline per dataset: sample true wrenches (:mod:`ftcal.simulation._sampling`), draw
the dataset's error parameters from a preset (:mod:`ftcal.simulation._presets`), apply
them (:mod:`ftcal.simulation._error_models`), map the erroneous wrench to raw readings
through the inverse (pseudo-inverse) calibration matrix (IV-A-d), add the
optional zero-load offset. The calibrators then learn ``raw -> true wrench``.

The noise floor
---------------
The RMSE (eq. 18, torque-scaled, [N]) that a *perfect* calibrator, one that
knows and inverts every deterministic error exactly, would still make on the
test set because of the simulated noise: the RMSE between the noisy and the
noise-free erroneous wrenches of the actual test set. (A perfect calibrator
maps a noisy reading back through the inverse error map, whose Jacobian
differs from identity by a few per cent, so this is the floor to within that.)
With eq. 12 and the default radial test set (torque-scaled norm uniform in
``[0, 2000]`` N, so ``rms(|w_scaled|) = 2000 / sqrt(3) ≈ 1155`` N) it is about
``σ rms(|w_scaled|) / sqrt(6)``: 1 % of 471 N ≈ 4.7 N.
"""

from __future__ import annotations


from numbers import Integral

import numpy as np
from numpy.typing import ArrayLike, NDArray
from sklearn.utils._param_validation import Interval

from ..io._dataset import CalibrationDataset
from ._error_models import ErrorModel, SampledErrors
from ..core._exceptions import CalibrationInputError
from ..core._metrics import wrench_rmse
from ..core._validation import check_arguments
from ._presets import default_test_distribution, error_preset
from ._sampling import SPHERE_FRACTIONS, check_dataset_arguments, check_points, continuous_wrenches, sphere_wrenches
from ._sensor import SensorProfile

__all__ = ["VirtualSensor", "make_artificial_dataset", "noise_floor"]

#: Largest zero-load offset as a multiple of the sensor's raw full scale: float64 (16 digits) then still resolves
#: the load signal to ~1e-10 of its span; a larger offset leaves too few digits for the load (a unit error).
ZERO_OFFSET_LIMIT = 1e6


def zero_offset_bound(profile: SensorProfile) -> tuple[float, float]:
    """The largest ``|zero_offset|`` a virtual sensor accepts [raw unit], and the raw full scale it derives from.

    The raw full scale is the largest raw value over the rated wrench box
    (``max_i sum_j |pinv(C)_ij| full_scale_j``); the bound is
    :data:`ZERO_OFFSET_LIMIT` times it.

    Examples
    --------
    >>> bound, full_scale = zero_offset_bound(SensorProfile.default())
    >>> bool(bound == 1e6 * full_scale), bool(1 < full_scale < 100)
    (True, True)
    """
    full_scale = float((np.abs(np.linalg.pinv(profile.calibration_matrix)) @ profile.full_scale).max())
    return ZERO_OFFSET_LIMIT * full_scale, full_scale


def noise_floor(wrench_noise_free: ArrayLike, wrench_noisy: ArrayLike, alpha: float) -> float:
    """RMSE [N] between noise-free and noisy erroneous wrenches, torque-scaled (see the module notes).

    Examples
    --------
    >>> noise_floor([[100.0, 0, 0, 0, 0, 0]], [[101.0, 0, 0, 0, 0, 0]], alpha=50.0)
    0.408...
    """
    return wrench_rmse(wrench_noise_free, wrench_noisy, alpha)


class VirtualSensor:
    """A simulated force/torque sensor: wrench in, erroneous raw readings out.

    Parameters
    ----------
    calibration_matrix : ndarray of shape (6, N) or SensorProfile, optional
        The sensor's calibration matrix (``wrench = C @ raw``) or a whole
        profile; ``None`` -> :meth:`SensorProfile.default`. A bare matrix
        takes ``fmax`` / ``tmax`` for its ranges.
    errors : str, ErrorModel or SampledErrors, default="thesis"
        A preset name, a nominal model (its parameters are drawn once, here,
        from ``random_state``) or concrete parameters.
    zero_offset : array-like of shape (N,), optional
        Raw reading at zero load, added to every reading [raw unit].
    random_state : int or numpy.random.Generator, optional
        Seeds the error parameters and the noise.
    fmax, tmax : float
        Ranges [N] / [N·m] when ``calibration_matrix`` is a bare matrix.

    Attributes
    ----------
    profile : SensorProfile
    errors_ : SampledErrors
        The concrete error parameters in use.

    Examples
    --------
    >>> s = VirtualSensor(errors="thesis", zero_offset=np.full(6, 0.1), random_state=0)
    >>> raw = s.read(np.array([[100.0, 0, 0, 0, 0, 1.0]]))
    >>> raw.shape
    (1, 6)
    >>> clean = VirtualSensor(errors="none").read(np.array([[100.0, 0, 0, 0, 0, 1.0]]))
    >>> np.allclose(clean @ VirtualSensor().profile.calibration_matrix.T, [[100.0, 0, 0, 0, 0, 1.0]])
    True
    """

    def __init__(
        self,
        calibration_matrix: ArrayLike | SensorProfile | None = None,
        *,
        errors: str | ErrorModel | SampledErrors = "thesis",
        zero_offset: ArrayLike | None = None,
        random_state: int | np.random.Generator | None = None,
        fmax: float = 2000.0,
        tmax: float = 40.0,
    ) -> None:
        if calibration_matrix is None:
            self.profile = SensorProfile.default()
        elif isinstance(calibration_matrix, SensorProfile):
            self.profile = calibration_matrix
        else:
            self.profile = SensorProfile(calibration_matrix=calibration_matrix, fmax=fmax, tmax=tmax, name="user matrix")
        self._rng = np.random.default_rng(random_state)
        self.errors_ = errors if isinstance(errors, SampledErrors) else \
            error_preset(errors).sample(self.profile.full_scale, self.profile.alpha, self._rng)
        n = self.profile.n_channels
        if zero_offset is None:
            self.zero_offset = np.zeros(n)
        else:
            try:
                self.zero_offset = np.asarray(zero_offset, dtype=float)
            except (TypeError, ValueError):
                raise CalibrationInputError(f"zero_offset must be {n} numbers, one raw value per channel; got "
                                            f"{zero_offset!r:.80}.") from None
            if self.zero_offset.shape != (n,) or not np.all(np.isfinite(self.zero_offset)):
                raise CalibrationInputError(
                    f"zero_offset must be a finite array of shape ({n},), one raw value per channel; "
                    f"got shape {self.zero_offset.shape}."
                )
            bound, full_scale = zero_offset_bound(self.profile)
            if np.abs(self.zero_offset).max(initial=0.0) > bound:
                channel = int(np.argmax(np.abs(self.zero_offset)))
                raise CalibrationInputError(
                    f"zero_offset holds {self.zero_offset[channel]:.6g} (channel {channel}); the accepted range is "
                    f"|zero_offset| <= {bound:.3g} {self.profile.raw_unit} ({ZERO_OFFSET_LIMIT:g} x the sensor's raw "
                    f"full scale, {full_scale:.3g} {self.profile.raw_unit}): beyond it float64 keeps too few digits "
                    "of the load signal."
                )
        self._pinv = np.linalg.pinv(self.profile.calibration_matrix)

    def erroneous_wrench(self, wrench: ArrayLike, noise: bool = True) -> NDArray[np.float64]:
        """The wrench the gauges 'see' [N, N·m]: the errors applied, with or without noise."""
        w = self.errors_.apply_deterministic(wrench)
        return self.errors_.apply_noise(w, self._rng) if noise else w

    def raw_from_erroneous(self, erroneous: ArrayLike) -> NDArray[np.float64]:
        """Raw readings (n, N) of an already erroneous wrench: inverse calibration matrix plus offset."""
        return np.asarray(erroneous, dtype=float) @ self._pinv.T + self.zero_offset

    def read(self, wrench: ArrayLike, noise: bool = True) -> NDArray[np.float64]:
        """Raw readings (n, N) under true wrenches (n, 6) [N, N·m]; each call draws fresh noise."""
        return self.raw_from_erroneous(self.erroneous_wrench(wrench, noise=noise))

    def __repr__(self) -> str:
        return f"VirtualSensor(profile={self.profile.name!r}, n_channels={self.profile.n_channels})"


def _sample_split(sensor: VirtualSensor, wrench: NDArray[np.float64]) -> tuple[NDArray, float]:
    clean = sensor.erroneous_wrench(wrench, noise=False)
    noisy = sensor.errors_.apply_noise(clean, sensor._rng)
    return sensor.raw_from_erroneous(noisy), noise_floor(clean, noisy, sensor.profile.alpha)


def make_artificial_dataset(
    preset: str | ErrorModel = "thesis",
    random_state: int | np.random.Generator | None = None,
    *,
    profile: SensorProfile | None = None,
    n_per_sphere: int = 1250,
    n_test: int = 1250,
    test_distribution: str | None = None,
    zero_offset: ArrayLike | None = None,
    n_spheres: int = 4,
) -> tuple[CalibrationDataset, CalibrationDataset, dict]:
    """One artificial dataset of the thesis (IV-A): four-sphere train set, continuous test set.

    Parameters
    ----------
    preset : str or ErrorModel, default="thesis"
        Error preset (``"thesis"``, ``"asymmetric"``, ``"stress"``, ``"reconstructed"``,
        ``"none"``) or a model.
    random_state : int or numpy.random.Generator, optional
        Seed; the same seed gives the same data.
    profile : SensorProfile, optional
        Sensor; default :meth:`SensorProfile.default`. The sphere radii are
        0.2, 0.4, 0.6, 0.8 of its ``fmax`` in the torque-scaled space
        (400 ... 1600 N for the thesis sensor).
    n_per_sphere : int, default=1250
        Training points per sphere (5000 in all, IV-A-a).
    n_test : int, default=1250
        Test points (IV-A-b).
    test_distribution : {"radial", "box", "ball"}, optional
        See :mod:`ftcal.simulation._sampling`. Default: the preset's
        (:func:`~ftcal.simulation._presets.default_test_distribution`:
        ``"ball"`` for ``"reconstructed"``, else ``"radial"``).
    zero_offset : array-like of shape (N,), optional
        Raw zero-load offset added to every reading.
    n_spheres : int, default=4
        Training spheres, 1-4: the *outermost* ones (1: 0.8 Fmax only; 2:
        0.6 and 0.8 Fmax, ...), so that fewer spheres mean less calibration
        data over the same range, not a smaller range.

    Returns
    -------
    train, test : CalibrationDataset
        ``train.group`` is the sphere index (0 .. n_spheres-1, innermost first); ``test.group`` is None.
    info : dict
        ``preset``, ``errors`` (the sampled parameters), ``noise_floor``
        (on the test set, [N]), ``noise_floor_train``, ``alpha``, ``profile``
        name, sizes.

    Examples
    --------
    >>> train, test, info = make_artificial_dataset(random_state=0, n_per_sphere=5, n_test=4)
    >>> train.raw.shape, test.raw.shape, sorted(set(train.group.tolist()))
    ((20, 6), (4, 6), [0, 1, 2, 3])
    """
    check_points("make_artificial_dataset", n_per_sphere=n_per_sphere, n_test=n_test)  # here None is no count
    check_dataset_arguments("make_artificial_dataset", test_distribution=test_distribution, n_spheres=n_spheres)
    check_arguments("make_artificial_dataset", {
        "random_state": [Interval(Integral, 0, None, closed="left"), np.random.Generator, None],
        "profile": [SensorProfile, None],
    }, random_state=random_state, profile=profile)
    model = error_preset(preset)
    rng = np.random.default_rng(random_state)
    test_distribution = test_distribution or default_test_distribution(preset)  # None: the preset's
    profile = SensorProfile.default() if profile is None else profile
    sensor = VirtualSensor(profile, errors=model, zero_offset=zero_offset, random_state=rng)
    radii = np.array(SPHERE_FRACTIONS[len(SPHERE_FRACTIONS) - int(n_spheres):]) * profile.fmax
    train_wrench, sphere = sphere_wrenches(radii, n_per_sphere, profile.alpha, rng)
    test_wrench = continuous_wrenches(n_test, profile.fmax, profile.tmax, rng, test_distribution)
    train_raw, floor_train = _sample_split(sensor, train_wrench)
    test_raw, floor_test = _sample_split(sensor, test_wrench)
    info = {
        "preset": preset if isinstance(preset, str) else "custom",
        "error_model": model.to_dict(),
        "errors": sensor.errors_.to_dict(),
        "noise_floor": floor_test,
        "noise_floor_train": floor_train,
        "alpha": profile.alpha,
        "profile": profile.name,
        "sphere_radii": radii.tolist(),
        "n_train": int(train_wrench.shape[0]),
        "n_test": int(n_test),
        "test_distribution": test_distribution,
        "zero_offset": sensor.zero_offset.tolist(),
    }
    meta = {k: info[k] for k in ("preset", "alpha", "profile", "noise_floor")}
    train = CalibrationDataset(raw=train_raw, wrench=train_wrench, group=sphere, meta={**meta, "split": "train"})
    test = CalibrationDataset(raw=test_raw, wrench=test_wrench, group=None, meta={**meta, "split": "test"})
    return train, test, info
