"""Wrench conventions and the torque scaling of the thesis (eq. 5-6).

A wrench is a row ``[Fx, Fy, Fz, Tx, Ty, Tz]`` with forces in [N] and torques
in [N·m]. The *torque-scaled* wrench multiplies the torques by
``alpha = Fmax / Tmax`` [m⁻¹] so that forces and torques weigh alike in losses
and metrics (thesis section III-A-a).
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ._exceptions import CalibrationInputError

__all__ = ["WRENCH_LABELS", "FORCE", "TORQUE", "alpha_from_wrenches", "check_alpha", "ALPHA_RANGE_PER_M",
           "MAX_LOAD_MASS_KG", "scale_torques", "unscale_torques", "force_columns", "torque_columns", "axis_unit",
           "default_axes", "target_axes", "torque_slice", "named_targets"]

#: Column names of a wrench, in order.
WRENCH_LABELS: tuple[str, ...] = ("Fx", "Fy", "Fz", "Tx", "Ty", "Tz")
#: Column slice of the forces [N] in a wrench.
FORCE = slice(0, 3)
#: Column slice of the torques [N·m] in a wrench.
TORQUE = slice(3, 6)


def force_columns(axes) -> list[int]:
    """Positions of the force axes (``Fx``, ``Fy``, ``Fz``) among ``axes`` (a wrench of any number of axes).

    Examples
    --------
    >>> force_columns(("Fx", "Fy", "Fz")), force_columns(("Fz", "Tx", "Ty"))
    ([0, 1, 2], [0])
    """
    return [k for k, a in enumerate(axes) if str(a).startswith("F")]


def torque_columns(axes) -> list[int]:
    """Positions of the torque axes (``Tx``, ``Ty``, ``Tz``) among ``axes``.

    Examples
    --------
    >>> torque_columns(("Fx", "Fy", "Fz")), torque_columns(WRENCH_LABELS)
    ([], [3, 4, 5])
    """
    return [k for k, a in enumerate(axes) if str(a).startswith("T")]


def axis_unit(axis: str) -> str:
    """The unit of an axis: ``N`` for a force, ``N·m`` for a torque.

    Examples
    --------
    >>> axis_unit("Fz"), axis_unit("Tx")
    ('N', 'N·m')
    """
    return "N·m" if str(axis).startswith("T") else "N"


def default_axes(width: int) -> tuple[str, ...]:
    """The axes of a wrench of ``width`` columns when nothing names them: Fx..Tz for six, else the first ``width``
    of Fx, Fy, Fz, Tx, Ty, Tz (the calibrators and metrics of a target of another width).

    Examples
    --------
    >>> default_axes(3)
    ('Fx', 'Fy', 'Fz')
    """
    return WRENCH_LABELS[:width] if 0 < width <= len(WRENCH_LABELS) else tuple(f"y{k}" for k in range(width))


#: Fewest raw channels of a 6-axis calibration (enforced where calibration data enter:
#: :class:`~ftcal.CalibrationDataset` and the CLI).
MIN_CHANNELS = 3


#: The torque scales [1/m] a calibrator accepts as its ``alpha`` parameter: ``alpha = Fmax / Tmax`` is the
#: inverse of the loads' largest lever arm, and lever arms from 1 µm to 1 km cover every sensor; a value outside
#: is a unit or typing error (no computation needs it, and 1e200 would overflow the scaled squares).
ALPHA_RANGE_PER_M = (1e-3, 1e6)

#: The largest mass [kg] of a load or tool on a force/torque sensor (the heaviest robots carry ~2 t); a larger
#: value in a log or a tool file is a unit or typing error.
MAX_LOAD_MASS_KG = 1e4


def check_alpha(alpha, name: str = "alpha") -> float:
    """``alpha`` as a float when it is a finite torque scale > 0 [1/m], else :class:`~ftcal.core.CalibrationInputError`.

    Examples
    --------
    >>> check_alpha(50)
    50.0
    >>> check_alpha(float("nan"))
    Traceback (most recent call last):
    ...
    ftcal.core._exceptions.CalibrationInputError: alpha must be a finite torque scale > 0 [1/m] (Fmax / Tmax, e.g. 2000 N / 40 N·m = 50); got nan.
    """
    try:
        value = None if isinstance(alpha, (bool, str, bytes)) else float(alpha)
    except (TypeError, ValueError):
        value = None
    if value is None or not (math.isfinite(value) and value > 0):
        raise CalibrationInputError(
            f"{name} must be a finite torque scale > 0 [1/m] (Fmax / Tmax, e.g. 2000 N / 40 N·m = 50); got {alpha!r}."
        )
    return value


def alpha_from_wrenches(wrench: ArrayLike, axes=None) -> float:
    """Torque scale ``alpha = Fmax / Tmax`` [m⁻¹] estimated from wrenches (eq. 5).

    ``Fmax`` is the largest absolute force component and ``Tmax`` the largest
    absolute torque component among the rows. This is how the calibrators
    derive ``alpha`` when none is given; pass the sensor's rated ranges
    (e.g. ``2000 / 40 = 50``) for the thesis' definition.

    Parameters
    ----------
    wrench : array-like of shape (n_samples, n_axes)
        Wrenches in [N] and [N·m].
    axes : sequence of str, optional
        The axes of the columns (``Fx``...``Tz``); default Fx..Tz (six columns). A wrench without forces or
        without torques (a 3-axis load cell) has no torque scale: 1.

    Returns
    -------
    float
        ``alpha``; ``1.0`` when the data hold no force or no torque at all, and clipped to
        :data:`ALPHA_RANGE_PER_M` (a lever arm below 1 µm or above 1 km means torques or forces that are noise).

    Examples
    --------
    >>> alpha_from_wrenches([[100.0, 0, 0, 0, 0, 2.0], [-50.0, 0, 0, 0, 1.0, 0]])
    50.0
    """
    w = np.asarray(wrench, dtype=float)
    axes = WRENCH_LABELS if axes is None else tuple(axes)
    if w.ndim != 2 or w.shape[1] != len(axes):
        raise CalibrationInputError(
            f"wrench must have shape (n_samples, {len(axes)}) [{', '.join(axes)}]; got shape {w.shape}."
        )
    fmax = float(np.max(np.abs(w[:, force_columns(axes)]), initial=0.0))
    tmax = float(np.max(np.abs(w[:, torque_columns(axes)]), initial=0.0))
    if fmax == 0.0 or tmax == 0.0 or not np.isfinite(fmax / tmax):
        return 1.0
    low, high = ALPHA_RANGE_PER_M  # beyond, the data hold (almost) no torque or no force: the scale would weigh noise
    return float(min(max(fmax / tmax, low), high))


def target_axes(y) -> tuple[str, ...] | None:
    """The wrench axes a calibrator's target ``y`` names, when they are not the default ones of its width.

    ``y`` as a table whose columns are wrench axes (a ``pandas.DataFrame`` with columns among Fx..Tz, each once)
    names its axes, as ``X``'s columns name the features (``feature_names_in_``); any other ``y`` (an array,
    other column names) has :func:`default_axes`: Fx..Tz for six columns, else forces only. ``None`` when the axes
    are the default ones (nothing to remember).

    Examples
    --------
    >>> import pandas as pd
    >>> target_axes(pd.DataFrame([[1.0, 0.1, 0.2]], columns=["Fz", "Tx", "Ty"]))
    ('Fz', 'Tx', 'Ty')
    >>> target_axes(pd.DataFrame([[1.0, 2.0, 3.0]], columns=["Fx", "Fy", "Fz"])), target_axes([[1.0, 2.0]])
    (None, None)
    """
    columns = getattr(y, "columns", None)
    if columns is None or getattr(y, "ndim", 2) != 2:
        return None
    names = tuple(str(c) for c in columns)
    if not names or len(set(names)) != len(names) or not set(names) <= set(WRENCH_LABELS):
        return None
    return None if names == default_axes(len(names)) else names


def named_targets(y, axes):
    """``y`` (n, k) as a table whose columns name its wrench ``axes`` (a ``pandas.DataFrame``), so that a calibrator
    fitted on it knows which columns are torques (:func:`target_axes`); ``y`` itself when ``axes`` is None.

    Examples
    --------
    >>> named_targets([[1.0, 0.1, 0.2]], ("Fz", "Tx", "Ty")).columns.tolist()
    ['Fz', 'Tx', 'Ty']
    """
    if axes is None:
        return y
    import pandas as pd

    return pd.DataFrame(np.asarray(y, dtype=float).reshape(len(y), -1), columns=[str(a) for a in axes])


def scale_torques(wrench: ArrayLike, alpha: float, axes=None) -> NDArray[np.float64]:
    """Return a copy of ``wrench`` with the torque columns multiplied by ``alpha`` (eq. 6).

    ``axes`` names the columns (e.g. ``("Fz", "Tx", "Ty")`` for a plate: its torques are scaled); without it
    only a 6-column wrench has torques, and targets of another width (a force-only cell, a calibrator fitted on
    other outputs by scikit-learn's generic checks) are returned unchanged.

    Examples
    --------
    >>> scale_torques([[1.0, 2, 3, 0.1, 0.2, 0.3]], 10.0)
    array([[1., 2., 3., 1., 2., 3.]])
    """
    return _scaled(wrench, check_alpha(alpha), multiply=True, axes=axes)


def unscale_torques(scaled: ArrayLike, alpha: float, axes=None) -> NDArray[np.float64]:
    """Inverse of :func:`scale_torques`: divide the torque columns by ``alpha``.

    Examples
    --------
    >>> unscale_torques([[1.0, 2, 3, 1, 2, 3]], 10.0)
    array([[1. , 2. , 3. , 0.1, 0.2, 0.3]])
    """
    return _scaled(scaled, check_alpha(alpha), multiply=False, axes=axes)


def torque_slice(width: int, axes=None):
    """The torque columns of a target of ``width`` columns named ``axes`` (default: those of a 6-column wrench, no
    other width has torques): a slice or a list of positions, empty when there is none.

    Examples
    --------
    >>> torque_slice(6), torque_slice(3), torque_slice(3, ("Fz", "Tx", "Ty"))
    (slice(3, 6, None), [], [1, 2])
    """
    if axes is None:
        return TORQUE if width == 6 else []
    axes = tuple(axes)
    if len(axes) != width:
        raise CalibrationInputError(f"axes {axes} name {len(axes)} axes but the wrenches have {width} columns.")
    columns = torque_columns(axes)
    return TORQUE if columns == [3, 4, 5] else columns


def _scaled(wrench: ArrayLike, alpha: float, *, multiply: bool, axes=None) -> NDArray[np.float64]:
    """A float copy of ``wrench`` with the torque columns (:func:`torque_slice`) multiplied or divided by
    ``alpha``; an overflow is an error naming alpha, not an inf in the result."""
    w = np.array(wrench, dtype=float, copy=True)
    columns = torque_slice(w.shape[-1], axes)
    if isinstance(columns, list) and not columns:
        return w
    with np.errstate(over="ignore", divide="ignore", invalid="ignore"):  # 0 * (1 / 5e-324) is NaN: refused below
        # times 1 / alpha, not divided by alpha: the bits every dataset and cached result were made with
        torque = w[..., columns] * (alpha if multiply else 1.0 / alpha)
    if not np.isfinite(torque).all() and np.isfinite(w[..., columns]).all():
        big = float(np.abs(w[..., columns]).max())
        raise CalibrationInputError(
            f"{'multiplying' if multiply else 'dividing'} the torques (largest |value| {big:.3g}) by alpha = "
            f"{alpha:.3g} 1/m overflows float64. Fix: check alpha (Fmax / Tmax of the sensor, usually 1-1000 1/m) "
            "and the torques' unit."
        )
    w[..., columns] = torque
    return w
