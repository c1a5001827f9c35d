"""Export of a fitted calibrator to ONNX: the whole calibration, raw readings in, wrench out.

The graph holds everything ``predict`` does after validation: the re-tare
shift, the zero-load reading, the unit vector and magnitude of the
directional model, the standardisation of the comparative one, the
networks (float32, as in ftcal), the torque scaling, and the members of an
ensemble, the model an :class:`~ftcal.AutoCalibrator` chose, the thermal
compensation of a :class:`~ftcal.TemperatureCompensatedCalibrator`. A C++,
C# or embedded program runs it with onnxruntime and gets what ``predict``
returns (within 1e-5 relative; ``tests/test_onnx.py``).

The graph has one input ``readings`` (float64, ``(n, N)``: the raw channels
in the order of the training data, plus the temperature [deg C] last for a
temperature-compensated model) and one output ``wrench`` (float64,
``(n, 6)``: Fx, Fy, Fz [N], Tx, Ty, Tz [N·m]). ``predict``'s input checks
(channel count, NaN) are the caller's job in the deployed program.

Only ``onnx`` is needed to export (``pip install "ftcal[onnx]"`` also brings
onnxruntime, to run it). The graph is built node by node with
``onnx.helper`` from the fitted arrays, so nothing goes through torch's
exporter.
"""

from __future__ import annotations

import functools
import os
from collections.abc import Callable
from pathlib import Path

import numpy as np
from sklearn.utils.validation import check_is_fitted

from ..core._exceptions import ExportError
from ..core._files import atomic_output

__all__ = ["export_onnx", "exportable_types", "OPSET"]

#: ONNX operator set of the exported graphs (onnxruntime >= 1.14 runs it).
OPSET = 17


class _Graph:
    """A growing ONNX graph: constants become initializers, every op gets a fresh output name."""

    def __init__(self, onnx) -> None:
        self.onnx = onnx
        self.nodes: list = []
        self.initializers: list = []
        self._count = 0

    def _name(self, stem: str) -> str:
        self._count += 1
        return f"{stem}_{self._count}"

    def const(self, value, dtype=np.float64) -> str:
        name = self._name("c")
        array = np.ascontiguousarray(np.asarray(value, dtype=dtype))
        self.initializers.append(self.onnx.numpy_helper.from_array(array, name))
        return name

    def op(self, op_type: str, *inputs: str, **attributes) -> str:
        out = self._name(op_type.lower())
        self.nodes.append(self.onnx.helper.make_node(op_type, list(inputs), [out], **attributes))
        return out

    # the building blocks the calibrators share ------------------------------------------------------
    def affine(self, x: str, matrix_t, offset=None) -> str:
        """``x @ matrix_t (+ offset)`` in float64."""
        y = self.op("MatMul", x, self.const(matrix_t))
        return y if offset is None else self.op("Add", y, self.const(offset))

    def unscale_torques(self, y: str, alpha: float, n_outputs: int) -> str:
        if n_outputs != 6:  # only a wrench has torques (as in ftcal.core._wrench.unscale_torques)
            return y
        return self.op("Div", y, self.const([1.0, 1.0, 1.0, alpha, alpha, alpha]))

    def columns(self, x: str, start: int, end: int) -> str:
        return self.op("Slice", x, self.const([start], np.int64), self.const([end], np.int64),
                       self.const([1], np.int64))

    def mlp(self, x: str, layers) -> str:
        """The network of :meth:`NetworkCalibrator._numpy_layers` in float32, like ftcal's forward pass."""
        h = self.op("Cast", x, to=self.onnx.TensorProto.FLOAT)
        for weight_t, bias, activation in layers:
            h = self.op("Gemm", h, self.const(weight_t, np.float32), self.const(bias, np.float32))
            if activation == "relu":
                h = self.op("Relu", h)
            elif activation == "tanh":
                h = self.op("Tanh", h)
        return self.op("Cast", h, to=self.onnx.TensorProto.DOUBLE)


# ------------------------------------------------------------------------------------ the calibrators
def _n_outputs(model) -> int:
    """Output width: 6 for a wrench calibrator (and for model files written before ``n_outputs_`` existed)."""
    return int(getattr(model, "n_outputs_", 6))


def _linear(model, g: _Graph, x: str) -> str:
    return g.affine(x, model.calibration_matrix_.T, model.offset_)


def _polynomial(model, g: _Graph, x: str) -> str:
    u = g.op("Div", g.op("Sub", x, g.const(model.zero_reading_)), g.const(model.input_scale_))
    powers = model._monomials().powers_.astype(np.float64)  # (n_monomials, N)
    expanded = g.op("Unsqueeze", u, g.const([1], np.int64))  # (n, 1, N)
    monomials = g.op("ReduceProd", g.op("Pow", expanded, g.const(powers)), axes=[2], keepdims=0)
    return g.affine(monomials, model.coef_, model.intercept_)


def _axis_nonlinear(model, g: _Graph, x: str) -> str:
    z = g.affine(g.op("Sub", x, g.const(model.zero_reading_)), model.base_matrix_.T, model.base_offset_)
    u = g.op("Div", z, g.const(model.axis_scale_))
    u_width = len(model.axis_scale_)
    parts = [u]
    for power in model.powers:  # signed_power_features, term by term
        a = g.op("Abs", u)
        inside = g.op("Pow", g.op("Min", a, g.const(1.0)), g.const(power + 1.0))
        beyond = g.op("Mul", g.const(power + 1.0), g.op("Max", g.op("Sub", a, g.const(1.0)), g.const(0.0)))
        parts.append(g.op("Mul", g.op("Sign", u), g.op("Add", inside, beyond)))
    block = g.op("Concat", *parts, axis=1)
    width = len(parts) * u_width
    previous = z
    for coefs, intercepts in zip(model.coefs_, model.intercepts_):
        coefs = np.asarray(coefs)  # (k, 2 * width + 1): [block, gate, gate * block] per output
        gate = g.op("Cast", g.op("Greater", previous, g.const(0.0)), to=g.onnx.TensorProto.DOUBLE)
        plain = g.affine(block, coefs[:, :width].T)
        gated = g.op("Add", g.affine(block, coefs[:, width + 1:].T), g.const(coefs[:, width]))
        previous = g.op("Add", g.op("Add", plain, g.op("Mul", gate, gated)), g.const(intercepts))
    return g.unscale_torques(previous, model.alpha_, _n_outputs(model))


def _gaussian_process(model, g: _Graph, x: str) -> str:
    xc = g.op("Sub", x, g.const(model.zero_reading_))
    scaled = g.op("Div", xc, g.const(model.input_scale_ * model.length_scale_))
    train = model.train_inputs_ / model.length_scale_
    cross = g.op("MatMul", scaled, g.const(train.T))
    squared = g.op("Add", g.op("ReduceSumSquare", scaled, axes=[1], keepdims=1), g.const((train * train).sum(axis=1)))
    distances = g.op("Max", g.op("Sub", squared, g.op("Mul", g.const(2.0), cross)), g.const(0.0))
    kernel = g.op("Mul", g.const(model.constant_), g.op("Exp", g.op("Mul", g.const(-0.5), distances)))
    residual = g.op("Add", g.op("Mul", g.op("MatMul", kernel, g.const(model.dual_coef_)), g.const(model.residual_scale_)),
                    g.const(model.residual_mean_))
    mean = g.op("Add", g.affine(xc, model.linear_matrix_.T, model.linear_offset_), residual)
    return g.unscale_torques(mean, model.alpha_, _n_outputs(model))


def _directional(model, g: _Graph, x: str) -> str:
    xc = g.op("Sub", x, g.const(model.zero_reading_))
    v_in = g.op("ReduceL2", xc, axes=[1], keepdims=1)
    unit = g.op("Where", g.op("Greater", v_in, g.const(0.0)), g.op("Div", xc, v_in), g.const(0.0))
    out = g.mlp(unit, model._numpy_layers())
    k = _n_outputs(model)
    magnitude = g.op("Mul", g.op("Mul", g.columns(out, k, k + 1), g.const(model.scale_reference_)), v_in)
    return g.unscale_torques(g.op("Mul", g.columns(out, 0, k), magnitude), model.alpha_, k)


def _comparative(model, g: _Graph, x: str) -> str:
    inputs = g.op("Div", g.op("Sub", x, g.const(model.input_mean_)), g.const(model.input_scale_))
    out = g.mlp(inputs, model._numpy_layers())
    return g.op("Add", g.op("Mul", out, g.const(model.target_scale_)), g.const(model.target_mean_))


def _ensemble(model, g: _Graph, x: str) -> str:
    members = [_calibration(member, g, x) for member in model.estimators_]
    total = members[0] if len(members) == 1 else g.op("Sum", *members)
    return g.op("Div", total, g.const(float(len(members))))


def _auto(model, g: _Graph, x: str) -> str:
    return _calibration(model.best_estimator_, g, x)


def _temperature_compensated(model, g: _Graph, x: str) -> str:
    n = int(model.n_features_in_)
    raw, temperature = g.columns(x, 0, n - 1), g.columns(x, n - 1, n)
    dt = g.op("Sub", temperature, g.const(float(model.reference_temperature)))
    shifted = g.op("Sub", raw, g.op("Mul", dt, g.const(model.offset_per_deg_)))
    compensated = g.op("Div", shifted, g.op("Add", g.const(1.0), g.op("Mul", dt, g.const(model.gain_per_deg_))))
    return _calibration(model.estimator_, g, compensated)


@functools.cache
def _emitters() -> dict[type, Callable]:
    from ._auto import AutoCalibrator
    from ..neural_network._comparative import ComparativeCalibrator
    from ..neural_network._directional import DirectionalCalibrator
    from ._ensemble import EnsembleCalibrator
    from ..calibrators._gaussian_process import GaussianProcessCalibrator
    from ..calibrators._axis_nonlinear import AxisNonlinearCalibrator
    from ..calibrators._linear import LinearCalibrator
    from ..calibrators._polynomial import PolynomialCalibrator
    from ..calibrators._temperature_compensation import TemperatureCompensatedCalibrator

    return {
        LinearCalibrator: _linear, PolynomialCalibrator: _polynomial, AxisNonlinearCalibrator: _axis_nonlinear,
        GaussianProcessCalibrator: _gaussian_process, DirectionalCalibrator: _directional,
        ComparativeCalibrator: _comparative, EnsembleCalibrator: _ensemble, AutoCalibrator: _auto,
        TemperatureCompensatedCalibrator: _temperature_compensated,
    }


def exportable_types() -> tuple[type, ...]:
    """The calibrator classes :func:`export_onnx` knows (exactly these, not their subclasses)."""
    return tuple(_emitters())


def _calibration(model, g: _Graph, x: str) -> str:
    """The graph of ``model.predict`` (after validation) on the float64 node ``x``: re-tare, then the model."""
    emit = _emitters().get(type(model))
    if emit is None:
        names = ", ".join(t.__name__ for t in exportable_types())
        raise ExportError(
            f"{type(model).__name__} cannot be exported to ONNX: ftcal knows how to write the graphs of {names} "
            "(a subclass or a registered custom calibrator may compute something else). Export one of those, "
            "or call predict from Python."
        )
    check_is_fitted(model)
    tare = getattr(model, "tare_reading_", None)
    if tare is not None:
        x = g.op("Sub", x, g.const(tare - model.zero_reading_))
    return emit(model, g, x)


def export_onnx(model, path: str | os.PathLike, *, overwrite: bool = False) -> Path:
    """Write a fitted calibrator as an ONNX model that maps raw readings to the wrench.

    Parameters
    ----------
    model : fitted calibrator
        Any of :func:`exportable_types`, fitted (and possibly re-tared).
    path : path-like
        The ``.onnx`` file to write.
    overwrite : bool, default=False
        Replace an existing file; without it an existing ``path`` is an
        error and stays as it is.

    Returns
    -------
    Path
        ``path``.

    Raises
    ------
    ExportError
        The model's type cannot be exported, or the ``onnx`` package is missing.
    FileExistsError
        ``path`` exists and ``overwrite`` is False.

    Examples
    --------
    >>> import numpy as np, tempfile, pathlib
    >>> from ftcal import LinearCalibrator, export_onnx
    >>> rng = np.random.default_rng(0)
    >>> w = rng.normal(size=(50, 6)); raw = w @ rng.normal(size=(6, 6))
    >>> model = LinearCalibrator().fit(raw, w)
    >>> path = export_onnx(model, pathlib.Path(tempfile.mkdtemp()) / "sensor.onnx")
    >>> import onnxruntime
    >>> session = onnxruntime.InferenceSession(str(path))
    >>> wrench = session.run(["wrench"], {"readings": raw[:3]})[0]
    >>> bool(np.allclose(wrench, model.predict(raw[:3])))
    True
    """
    try:
        import onnx
    except ImportError:
        raise ExportError(
            "exporting to ONNX needs the 'onnx' package: pip install \"ftcal[onnx]\" (also installs onnxruntime)."
        ) from None
    path = Path(path)
    if path.exists() and not overwrite:
        raise FileExistsError(f"{path} exists; pass overwrite=True (CLI: --force) to replace it.")
    g = _Graph(onnx)
    wrench = _calibration(model, g, "readings")
    g.nodes.append(onnx.helper.make_node("Identity", [wrench], ["wrench"]))
    n_inputs = int(model.n_features_in_)
    double = onnx.TensorProto.DOUBLE
    graph = onnx.helper.make_graph(
        g.nodes, f"ftcal_{type(model).__name__}",
        [onnx.helper.make_tensor_value_info("readings", double, ["n", n_inputs])],
        [onnx.helper.make_tensor_value_info("wrench", double, ["n", _n_outputs(model)])],
        initializer=g.initializers,
        doc_string=("readings: raw channels (n, N) in the training order"
                    + (", temperature [deg C] last" if type(model).__name__ == "TemperatureCompensatedCalibrator"
                       else "")
                    + "; wrench: Fx, Fy, Fz [N], Tx, Ty, Tz [N m]"),
    )
    from .. import __version__

    onnx_model = onnx.helper.make_model(
        graph, producer_name="ftcal", producer_version=__version__,
        opset_imports=[onnx.helper.make_opsetid("", OPSET)],
    )
    onnx_model.ir_version = 8  # what onnxruntime >= 1.14 reads
    onnx.helper.set_model_props(onnx_model, {"ftcal_model": type(model).__name__,
                                             "wrench_units": "N, N, N, N m, N m, N m"})
    onnx.checker.check_model(onnx_model, full_check=True)
    with atomic_output(path, overwrite=overwrite, error=FileExistsError) as tmp:
        tmp.write_bytes(onnx_model.SerializeToString())
    return path
