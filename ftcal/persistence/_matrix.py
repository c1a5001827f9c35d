"""A linear calibration as a plain k x N matrix and offset, for a vendor driver or a fieldbus device.

``wrench = matrix @ raw + offset``: ``matrix`` (k, N) maps the raw channels to the sensor's k wrench axes
(``Fx, Fy, Fz`` [N] and ``Tx, Ty, Tz`` [N·m] for a 6-axis sensor, ``Fx, Fy, Fz`` for a 3-axis load cell),
``offset`` (k,) holds the tare. Any fitted calibrator whose prediction is affine in
the raw readings has one (the LTM, a degree-1 polynomial, ``auto`` when it chose one, after a re-tare);
it is read off the model's own ``predict`` and checked on probe readings, so the numbers a driver gets
are exactly what ``predict`` computes. A nonlinear model has no such matrix and is refused.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from ..compose._history import reads_history
from ..core._exceptions import NO_SETTING, ExportError
from ..core._wrench import axis_unit, default_axes

__all__ = ["linear_calibration_matrix", "matrix_export_dict"]


def linear_calibration_matrix(model: Any) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """``(matrix (k, N), offset (k,))`` with ``model.predict(X) == X @ matrix.T + offset`` (k wrench axes).

    Raises
    ------
    ExportError
        When the model's prediction is not affine in the readings (a network, a GP, a polynomial,
        temperature compensation).

    Examples
    --------
    >>> import numpy as np
    >>> from ftcal import LinearCalibrator
    >>> rng = np.random.default_rng(0)
    >>> raw = rng.normal(size=(50, 6)); w = raw @ rng.normal(size=(6, 6)) + 2.0
    >>> C, b = linear_calibration_matrix(LinearCalibrator().fit(raw, w))
    >>> bool(np.allclose(raw @ C.T + b, w))
    True
    """
    n = int(getattr(model, "n_features_in_", 0))
    if n < 1:
        raise ExportError(f"{type(model).__name__} is not a fitted calibrator (no n_features_in_); fit it first.")
    if reads_history(model) and getattr(model, "tau_rows_", None) is not None:
        raise ExportError(f"{type(model).__name__} has a load-history term (tau = {model.tau_rows_:g} rows): its "
                          "wrench depends on the readings before each one, which no matrix can hold.",
                          parameter="model", fix="export a model fitted without {HistoryCalibrator} (no "
                          "load-history term) for a matrix", settings={"HistoryCalibrator": NO_SETTING})
    center = np.asarray(getattr(model, "zero_reading_", np.zeros(n)), dtype=float).ravel()
    if center.shape != (n,):
        center = np.zeros(n)
    scale = max(1.0, float(np.max(np.abs(center), initial=0.0)))
    points = np.vstack([center, center + scale * np.eye(n)])
    probes = center + scale * np.random.default_rng(0).normal(size=(4 * n + 4, n))
    try:
        out = np.asarray(model.predict(np.vstack([points, probes])), dtype=float)
    except Exception as exc:
        raise ExportError(f"{type(model).__name__} could not be evaluated for a matrix export "
                          f"({type(exc).__name__}: {exc}).") from None
    if out.ndim != 2 or not 1 <= out.shape[1] <= 6:
        raise ExportError(f"{type(model).__name__} does not predict 1 to 6 wrench components; got shape {out.shape}.")
    matrix = ((out[1:n + 1] - out[0]) / scale).T  # out[0]: the prediction at the centre
    offset = out[0] - matrix @ center
    got = out[n + 1:]
    gap = float(np.max(np.abs(got - (probes @ matrix.T + offset))))
    if not gap <= 1e-7 * (1.0 + float(np.max(np.abs(got)))):
        from ..calibrators._base import calibration_tags

        if calibration_tags(model).temperature_column:  # a temperature-compensated model, linear or not
            raise ExportError(
                f"{type(model).__name__} is temperature-compensated: its wrench depends on the temperature (its last "
                f"input) beyond a 6x{n} matrix (by {gap:.3g} on probe readings), so it has no calibration matrix.",
                parameter="model", fix="export it to ONNX ({export_onnx}), which keeps the compensation, or fit "
                "without {TemperatureCompensatedCalibrator} for a matrix",
                settings={"export_onnx": NO_SETTING, "TemperatureCompensatedCalibrator": NO_SETTING})
        raise ExportError(
            f"{type(model).__name__} is not a linear calibration (its prediction departs from the best {out.shape[1]}x{n} matrix "
            f"by {gap:.3g} on probe readings), so it has no calibration matrix.", parameter="model",
            fix="fit a linear model ({model}) for a matrix, or export this model to ONNX ({export_onnx})",
            settings={"model": "linear", "export_onnx": NO_SETTING})
    return matrix, offset


def matrix_export_dict(model: Any, axes=None, inputs=None) -> dict:
    """The matrix export as a JSON-able dict (what ``ftcal export --format matrix`` writes to ``.json``).

    ``axes`` names the outputs (the model file's wrench axes; default Fx..Tz for six, else the first of them),
    ``inputs`` the raw channels (the columns the model was fitted on; default s0..s{N-1}).
    """
    matrix, offset = linear_calibration_matrix(model)
    axes = list(axes) if axes is not None else list(default_axes(matrix.shape[0]))
    if len(axes) != matrix.shape[0]:
        raise ExportError(f"the model predicts {matrix.shape[0]} axes but {len(axes)} are named ({', '.join(axes)}).")
    names = list(inputs) if inputs is not None and len(inputs) == matrix.shape[1] else \
        [f"s{i}" for i in range(matrix.shape[1])]
    return {
        "format": "ftcal-calibration-matrix", "format_version": 1,
        "equation": "wrench = matrix @ raw + offset",
        "inputs": names, "outputs": axes,
        "units": {"raw": "the sensor's own unit (as in the calibration data)",
                  "wrench": "; ".join(f"{a} in {axis_unit(a)}" for a in axes) + ", sensor frame"},
        "matrix": matrix.tolist(), "offset": offset.tolist(),
    }
