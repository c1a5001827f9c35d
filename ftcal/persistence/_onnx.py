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

import os
from pathlib import Path

import numpy as np
from sklearn.utils.validation import check_is_fitted

from .. import __version__
from ..calibrators._base import calibration_tags, retare_shift
from ..compose._history import reads_history
from ..core._exceptions import NO_SETTING, ExportError, ExportExistsError
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

    # the building blocks the calibrators' ``_emit_onnx`` share ------------------------------------------------------
    def affine(self, x: str, matrix_t, offset=None) -> str:
        """``x @ matrix_t (+ offset)`` in float64."""
        y = self.op("MatMul", x, self.const(matrix_t))
        return y if offset is None else self.op("Add", y, self.const(offset))

    def unscale_torques(self, y: str, alpha: float, n_outputs: int, axes=None) -> str:
        from ..core._wrench import torque_slice

        scale = np.ones(n_outputs)
        scale[torque_slice(n_outputs, axes)] = alpha  # the torque columns, as ftcal.core._wrench.unscale_torques
        return y if (scale == 1.0).all() else self.op("Div", y, self.const(scale))

    def columns(self, x: str, start: int, end: int) -> str:
        return self.op("Slice", x, self.const([start], np.int64), self.const([end], np.int64),
                       self.const([1], np.int64))

    def mlp(self, x: str, layers) -> str:
        """The network of :meth:`NetworkCalibrator._numpy_layers` in float32, like ftcal's forward pass."""
        h = self.op("Cast", x, to=self.onnx.TensorProto.FLOAT)
        for weight_t, bias, activation in layers:
            h = self.op("Gemm", h, self.const(weight_t, np.float32), self.const(bias, np.float32))
            if activation in ("relu", "tanh"):  # the ONNX ops Relu and Tanh
                h = self.op(activation.title(), h)
        return self.op("Cast", h, to=self.onnx.TensorProto.DOUBLE)


# ------------------------------------------------------------------------------------ the calibrators
    def calibration(self, model, x: str) -> str:
        """The graph of ``model.predict`` (after validation) on the float64 node ``x``: re-tare, then the model.

        The model's own part is the ``_emit_onnx(graph, x)`` its class declares next to itself; a wrapper's
        calls this again for its inner calibrators.
        """
        # the _emit_onnx of its class (its own or inherited) when its tags say it is exportable: a subclass of an
        # exportable calibrator keeps its parent's graph unless it declares onnx=False
        emit = getattr(type(model), "_emit_onnx", None)
        emit = emit if callable(emit) and calibration_tags(model).onnx else None
        static = None
        if reads_history(model):
            if getattr(model, "tau_rows_", None) is not None or getattr(model, "estimator_", None) is None:
                raise ExportError(f"{type(model).__name__} cannot be exported to ONNX: its load-history term depends "
                                  "on the readings before each one, a state an ONNX graph does not keep.",
                                  parameter="model", fix="call predict (or stream()) from Python, or export a model "
                                  "fitted without {HistoryCalibrator} (no load-history term)",
                                  settings={"HistoryCalibrator": NO_SETTING})
            # its cross-validation chose no history term: the model is its static calibrator (after its own tare)
            static = model.estimator_
        if emit is None and static is None:
            names = ", ".join(t.__name__ for t in exportable_types())
            raise ExportError(
                f"{type(model).__name__} cannot be exported to ONNX: ftcal knows how to write the graphs of {names} "
                "and of their subclasses whose tags keep onnx=True (a custom calibrator may compute something "
                "else). Export one of those, or call predict from Python."
            )
        check_is_fitted(model)
        if getattr(model, "tare_reading_", None) is not None:
            x = self.op("Sub", x, self.const(retare_shift(model)))
        return self.calibration(static, x) if static is not None else emit(model, self, x)


def exportable_types() -> tuple[type, ...]:
    """The registry's calibrator classes :func:`export_onnx` knows (and their subclasses that keep the tag)."""
    from ..compose._registry import model_classes

    return tuple(cls for cls in model_classes().values() if callable(getattr(cls, "_emit_onnx", None)))


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
        The model's type cannot be exported, or the ``onnx`` package is missing; ``ExportExistsError`` (an
        ``ExportError`` and a ``FileExistsError``): ``path`` exists and ``overwrite`` is False.

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
        raise ExportExistsError(f"{path} exists.", parameter="path", value=str(path), fix="pass {overwrite} to replace it, or choose another path", settings={"overwrite": True})
    g = _Graph(onnx)
    wrench = g.calibration(model, "readings")
    g.nodes.append(onnx.helper.make_node("Identity", [wrench], ["wrench"]))
    n_inputs = int(model.n_features_in_)
    double = onnx.TensorProto.DOUBLE
    graph = onnx.helper.make_graph(
        g.nodes, f"ftcal_{type(model).__name__}",
        [onnx.helper.make_tensor_value_info("readings", double, ["n", n_inputs])],
        # 6 outputs for a model file written before n_outputs_ existed
        [onnx.helper.make_tensor_value_info("wrench", double, ["n", int(getattr(model, "n_outputs_", 6))])],
        initializer=g.initializers,
        doc_string=("readings: raw channels (n, N) in the training order"
                    + (", temperature [deg C] last" if calibration_tags(model).temperature_column else "")
                    + "; wrench: Fx, Fy, Fz [N], Tx, Ty, Tz [N m]"),
    )
    onnx_model = onnx.helper.make_model(
        graph, producer_name="ftcal", producer_version=__version__,
        opset_imports=[onnx.helper.make_opsetid("", OPSET)],
    )
    onnx_model.ir_version = 8  # what onnxruntime >= 1.14 reads
    onnx.helper.set_model_props(onnx_model, {"ftcal_model": type(model).__name__,
                                             "wrench_units": "N, N, N, N m, N m, N m"})
    onnx.checker.check_model(onnx_model, full_check=True)
    with atomic_output(path, overwrite=overwrite, error=ExportExistsError) as tmp:
        tmp.write_bytes(onnx_model.SerializeToString())
    return path
