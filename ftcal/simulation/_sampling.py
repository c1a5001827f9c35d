"""Load sampling for the artificial datasets (thesis section IV-A-a and IV-A-b).

Both samplers work in the **torque-scaled** 6-D wrench space (torques times
``alpha = Fmax / Tmax``, eq. 6), where a force of ``r`` [N] and a torque of
``r / alpha`` [N·m] have the same length, and return ordinary wrenches
([N] and [N·m]).

Interpretations of the thesis text
----------------------------------
Train set (IV-A-a)
    "four concentric spheres, radius steps of 400 N (force) and 8 Nm
    (torque)": spheres of radius 400, 800, 1200 and 1600 in the torque-scaled
    space (8 N·m times alpha = 50 is 400), 1250 points on each, uniformly
    distributed on the 5-sphere (normalised Gaussian vectors). Every point is
    a combined load with all six components non-zero.
Test set (IV-A-b)
    "randomly sampled from the sensor's operational range to capture
    continuous variations": by default (``"radial"``) a uniform direction
    on the 5-sphere times a radius uniform in ``[0, Fmax]``, so load
    magnitudes are spread evenly from zero to full scale, every component
    stays inside its rated range (``|F_i| <= Fmax``, ``|T_i| <= Tmax``), most
    points lie between the training spheres and 20 % lie beyond the outer one
    (1600 < r <= 2000), testing mild extrapolation. ``"box"`` samples every
    component independently and uniformly in its rated range instead; its
    loads reach ``sqrt(6) Fmax`` in norm, far outside the training spheres.
    ``"ball"`` draws the force uniformly in the 3-D ball of radius ``Fmax``
    and, independently, the torque uniformly in the 3-D ball of radius
    ``Tmax``: every load is one a sensor rated ``|F| <= Fmax``, ``|T| <= Tmax``
    can carry, and the torque-scaled norm reaches ``sqrt(2) Fmax``
    (rms ``sqrt(6/5) Fmax``, about twice the radial set's ``Fmax / sqrt(3)``),
    so a sizeable share lies beyond the outer training sphere. It is the
    reading of the thesis' "operational range" that reproduces its RMSE-to-
    relative-error ratio (see the ``reconstructed`` preset).
"""

from __future__ import annotations

from numbers import Integral

import numpy as np
from numpy.typing import NDArray

from ..core._exceptions import CalibrationInputError
from ..core._wrench import unscale_torques

__all__ = ["sphere_wrenches", "continuous_wrenches", "check_points", "check_dataset_arguments", "TEST_DISTRIBUTIONS",
           "MAX_POINTS", "SPHERE_FRACTIONS", "N_SPHERES"]

#: Names accepted by :func:`continuous_wrenches`.
TEST_DISTRIBUTIONS = ("radial", "box", "ball")
#: Most points one sampler call draws (per sphere, or test points): the artificial datasets' size limit.
MAX_POINTS = 1_000_000
#: Training-sphere radii as fractions of Fmax: 400, 800, 1200, 1600 N for 2000 N (IV-A-a).
SPHERE_FRACTIONS = (0.2, 0.4, 0.6, 0.8)
#: Training spheres of the thesis' artificial datasets (IV-A-a).
N_SPHERES = len(SPHERE_FRACTIONS)


def _unit_directions(n: int, rng: np.random.Generator, dim: int = 6) -> NDArray[np.float64]:
    """``n`` directions uniform on the unit sphere of ``dim`` dimensions (the 5-sphere by default), shape (n, dim)."""
    v = rng.standard_normal((n, dim))
    return v / np.linalg.norm(v, axis=1, keepdims=True)


def _uniform_ball_3d(n: int, radius: float, rng: np.random.Generator) -> NDArray[np.float64]:
    """``n`` points uniform in the 3-D ball of ``radius``: uniform direction, radius ``R u^(1/3)``."""
    return _unit_directions(n, rng, 3) * (radius * np.cbrt(rng.uniform(0.0, 1.0, size=(n, 1))))


def check_points(caller: str, **counts) -> None:
    """Refuse a point count that is not an integer from 1 to :data:`MAX_POINTS` (a bool or ``2.5`` included).

    Examples
    --------
    >>> check_points("make_artificial_dataset", n_test=2.5)
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.CalibrationInputError: The 'n_test' parameter of make_artificial_dataset must be an int in the range [1, 1000000]. Got 2.5 instead.
    """
    from sklearn.utils._param_validation import Interval  # scikit-learn only when a dataset is made (not for --help)

    from ..core._validation import check_arguments

    check_arguments(caller, {name: [Interval(Integral, 1, MAX_POINTS, closed="both")] for name in counts}, **counts)


def check_dataset_arguments(caller: str, *, n_per_sphere=None, n_test=None, test_distribution=None,
                            n_spheres=N_SPHERES) -> None:
    """The arguments of an artificial dataset, checked alike by every caller (a count of None: the default)."""
    from sklearn.utils._param_validation import Interval

    from ..core._validation import check_arguments

    # a test_distribution that is neither one of TEST_DISTRIBUTIONS nor None (the default)
    if test_distribution is not None and not (isinstance(test_distribution, str)
                                              and test_distribution in TEST_DISTRIBUTIONS):
        raise CalibrationInputError(f"The 'test_distribution' parameter of {caller} must be one of "
                                    f"{', '.join(map(repr, TEST_DISTRIBUTIONS))} or None. "
                                    f"Got {test_distribution!r:.80} instead.")
    points = [Interval(Integral, 1, MAX_POINTS, closed="both"), None]
    check_arguments(caller, {"n_per_sphere": points, "n_test": points,
                             "n_spheres": [Interval(Integral, 1, N_SPHERES, closed="both")]},
                    n_per_sphere=n_per_sphere, n_test=n_test, n_spheres=n_spheres)


def sphere_wrenches(
    radii: NDArray[np.float64] | list[float],
    n_per_sphere: int,
    alpha: float,
    rng: np.random.Generator,
) -> tuple[NDArray[np.float64], NDArray[np.int64]]:
    """Wrenches uniformly spread on concentric spheres of the torque-scaled space.

    Parameters
    ----------
    radii : sequence of float
        Sphere radii in the torque-scaled space [N].
    n_per_sphere : int
        Points on each sphere.
    alpha : float
        Torque scale [m⁻¹].
    rng : numpy.random.Generator
        Random source.

    Returns
    -------
    wrench : ndarray of shape (len(radii) * n_per_sphere, 6)
        Wrenches in [N] and [N·m].
    sphere : ndarray of shape (len(radii) * n_per_sphere,)
        Index of the sphere of each row.

    Examples
    --------
    >>> from ftcal.core._wrench import scale_torques
    >>> w, g = sphere_wrenches([400.0, 800.0], 3, 50.0, np.random.default_rng(0))
    >>> np.linalg.norm(scale_torques(w, 50.0), axis=1).round(6)
    array([400., 400., 400., 800., 800., 800.])
    """
    radii = np.asarray(radii, dtype=float)
    if radii.ndim != 1 or radii.size == 0 or not np.all(radii > 0):
        raise CalibrationInputError(f"radii must be a non-empty list of positive radii; got {radii!r}.")
    check_points("sphere_wrenches", n_per_sphere=n_per_sphere)
    n = int(n_per_sphere)
    scaled = np.vstack([r * _unit_directions(n, rng) for r in radii])
    sphere = np.repeat(np.arange(radii.size, dtype=np.int64), n)
    return unscale_torques(scaled, alpha), sphere


def continuous_wrenches(
    n: int,
    fmax: float,
    tmax: float,
    rng: np.random.Generator,
    distribution: str = "radial",
) -> NDArray[np.float64]:
    """Wrenches sampled continuously over the operating range (see the module notes).

    Parameters
    ----------
    n : int
        Number of wrenches.
    fmax, tmax : float
        Force range [N] and torque range [N·m].
    rng : numpy.random.Generator
        Random source.
    distribution : {"radial", "box", "ball"}, default="radial"
        ``"radial"``: uniform direction, torque-scaled norm uniform in
        ``[0, fmax]``. ``"box"``: each component uniform in ``[-fmax, fmax]``
        (forces) or ``[-tmax, tmax]`` (torques). ``"ball"``: force uniform in
        the ball ``|F| <= fmax``, torque independently uniform in ``|T| <= tmax``.

    Returns
    -------
    ndarray of shape (n, 6)
        Wrenches in [N] and [N·m].

    Examples
    --------
    >>> w = continuous_wrenches(100, 2000.0, 40.0, np.random.default_rng(0))
    >>> bool(np.all(np.abs(w[:, :3]) <= 2000) and np.all(np.abs(w[:, 3:]) <= 40))
    True
    >>> b = continuous_wrenches(100, 2000.0, 40.0, np.random.default_rng(0), "ball")
    >>> bool(np.all(np.linalg.norm(b[:, :3], axis=1) <= 2000) and np.all(np.linalg.norm(b[:, 3:], axis=1) <= 40))
    True
    """
    check_points("continuous_wrenches", n=n)
    alpha = fmax / tmax
    if distribution == "radial":
        scaled = _unit_directions(int(n), rng) * rng.uniform(0.0, fmax, size=(int(n), 1))
        return unscale_torques(scaled, alpha)
    if distribution == "box":
        ranges = np.array([fmax] * 3 + [tmax] * 3)
        return rng.uniform(-1.0, 1.0, size=(int(n), 6)) * ranges
    if distribution == "ball":
        return np.hstack([_uniform_ball_3d(int(n), fmax, rng), _uniform_ball_3d(int(n), tmax, rng)])
    raise CalibrationInputError(f"The 'distribution' parameter of continuous_wrenches must be one of "
                                f"{', '.join(map(repr, TEST_DISTRIBUTIONS))}. Got {distribution!r:.80} instead.")
