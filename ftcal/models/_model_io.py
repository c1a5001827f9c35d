"""Model files: one ``.npz`` holding JSON metadata and the weight arrays, no pickle.

Layout (``numpy.savez``; read back with ``allow_pickle=False``, so loading
never executes code from the file):

* ``__metadata__``: a 0-d unicode array holding a JSON object with
  ``format`` (``"ftcal-model"``), ``format_version`` (``1``), ``model_type``
  (the class name), ``ftcal_version``, ``params`` (constructor parameters),
  ``fitted`` (scalar fitted attributes: ``alpha_``, ``n_features_in_``, ...)
  and, for networks, a compact ``history`` (epoch, phase, lr, losses);
* ``fitted/<name>``: fitted arrays (``zero_reading_``, ``calibration_matrix_``,
  scaling arrays, ...);
* ``module/<name>``: the torch ``state_dict`` of a network (float32);
* ``children/<i>/...``: the sub-models of a meta-estimator (e.g. the members
  of an :class:`~ftcal.EnsembleCalibrator`), each in this same layout, their
  metadata in the JSON's ``children`` list.

A file that is missing, truncated, not an ftcal model, of another format
version or of an unexpected model type raises :class:`~ftcal.ModelFileError`
saying which. Files are written to a temporary file next to the target and
then renamed, so an interrupted save never leaves half a file, and an
existing file is only replaced with ``overwrite=True``.
"""

from __future__ import annotations

import io
import json
import os
import warnings
import zipfile
from pathlib import Path

import numpy as np
import torch
from sklearn.utils.validation import check_is_fitted
from skorch.history import History

from ._auto import AutoCalibrator, StackedCalibrator
from ..neural_network._comparative import ComparativeCalibrator
from ..neural_network._directional import DirectionalCalibrator
from ._ensemble import EnsembleCalibrator
from ..core._exceptions import ModelFileError
from ..core._files import atomic_output
from ..calibrators._gaussian_process import GaussianProcessCalibrator
from ..calibrators._axis_nonlinear import AxisNonlinearCalibrator
from ..calibrators._linear import LinearCalibrator
from ..neural_network._base import NetworkCalibrator, device_available
from ..calibrators._polynomial import PolynomialCalibrator
from ..calibrators._temperature_compensation import TemperatureCompensatedCalibrator

__all__ = ["save_model", "load_model", "register_model_type", "FORMAT_VERSION"]

FORMAT = "ftcal-model"
#: Version of the model-file layout written by :func:`save_model`.
FORMAT_VERSION = 1
_META_KEY = "__metadata__"
_HISTORY_KEYS = ("epoch", "phase", "lr", "train_loss", "valid_loss", "stop_reason")

#: Fitted attributes stored per model type: (scalars, arrays).
_MODEL_TYPES: dict[str, tuple[type, tuple[str, ...], tuple[str, ...]]] = {}
#: Fitted arrays every calibrator may have (files written before they existed lack them).
_OPTIONAL_ARRAYS = ("reading_noise_", "tare_reading_", "calibrated_range_")
#: Fitted scalars of every calibrator that older files lack (then: a wrench, 6 outputs, 2-D).
_OPTIONAL_SCALARS = ("n_outputs_", "y_1d_")
#: Meta-estimators: the fitted attribute holding their list of fitted sub-models.
_CHILDREN: dict[str, str] = {}


def register_model_type(
    cls: type, scalars: tuple[str, ...], arrays: tuple[str, ...], *, children: str | None = None
) -> None:
    """Allow :func:`save_model` / :func:`load_model` for ``cls`` (by class name).

    ``scalars`` are JSON-able fitted attributes, ``arrays`` ndarray ones.
    Subclasses of the network base get their ``net_`` weights stored as well.
    ``children`` names the fitted attribute of a meta-estimator that holds a
    list of fitted sub-models, or one (registered types themselves); each is stored
    whole (metadata under ``children``, arrays under ``children/<i>/``).
    A parameter whose value is an estimator of a registered type (e.g. an
    ensemble's ``estimator``) is stored by type and parameters.
    """
    _MODEL_TYPES[cls.__name__] = (cls, tuple(scalars), tuple(arrays))
    if children is not None:
        _CHILDREN[cls.__name__] = children


_NET_SCALARS = ("alpha_", "n_features_in_", "n_epochs_", "best_epoch_", "stop_reason_")
register_model_type(LinearCalibrator, ("alpha_", "n_features_in_"), ("zero_reading_", "calibration_matrix_", "offset_"))
register_model_type(
    DirectionalCalibrator, _NET_SCALARS + ("scale_reference_", "n_dropped_zero_load_"), ("zero_reading_",)
)
register_model_type(
    ComparativeCalibrator,
    _NET_SCALARS,
    ("zero_reading_", "input_mean_", "input_scale_", "target_mean_", "target_scale_"),
)


register_model_type(
    PolynomialCalibrator, ("alpha_", "n_features_in_"), ("zero_reading_", "input_scale_", "coef_", "intercept_")
)
register_model_type(
    AxisNonlinearCalibrator,
    ("alpha_", "n_features_in_", "ridge_"),
    ("zero_reading_", "base_matrix_", "base_offset_", "axis_scale_", "coefs_", "intercepts_"),
)
register_model_type(
    EnsembleCalibrator, ("alpha_", "n_features_in_"), ("zero_reading_", "member_seeds_"), children="estimators_"
)
register_model_type(
    GaussianProcessCalibrator,
    ("alpha_", "n_features_in_", "mean_", "kernel_", "per_output_"),
    ("zero_reading_", "linear_matrix_", "linear_offset_", "input_mean_", "input_scale_", "train_inputs_", "theta_",
     "dual_coef_", "cholesky_", "target_mean_", "target_scale_"),
)

register_model_type(
    TemperatureCompensatedCalibrator, ("alpha_", "n_features_in_"),
    ("zero_reading_", "offset_per_deg_", "gain_per_deg_"), children="estimator_",
)

register_model_type(StackedCalibrator, ("alpha_", "n_features_in_"), ("zero_reading_", "weights_"),
                    children="estimators_")
register_model_type(
    AutoCalibrator, ("alpha_", "n_features_in_", "best_name_", "cv_results_"), ("zero_reading_",),
    children="best_estimator_",
)


def _encode(value):
    """JSON form of a parameter value (tuples and arrays tagged so they come back as such)."""
    if isinstance(value, tuple):
        return {"tuple": [_encode(v) for v in value]}
    if isinstance(value, np.ndarray):
        return {"array": value.tolist()}
    if isinstance(value, (np.integer, np.floating)):
        return value.item()
    if isinstance(value, list):
        return [_encode(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _encode(v) for k, v in value.items()}
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    if type(value).__name__ in _MODEL_TYPES and type(value) is _MODEL_TYPES[type(value).__name__][0]:
        return {"estimator": {"model_type": type(value).__name__,
                              "params": _stored_params(value)}}
    return None  # e.g. a RandomState instance: not reproducible from a file; stored as None


def _stored_params(estimator) -> dict:
    """JSON form of the constructor parameters; transient ones (e.g. ``callbacks``) are stored as None."""
    transient = getattr(estimator, "_transient_params", ())
    return {k: None if k in transient else _encode(v) for k, v in estimator.get_params(deep=False).items()}


def _decode(value):
    if isinstance(value, dict) and set(value) == {"tuple"}:
        return tuple(_decode(v) for v in value["tuple"])
    if isinstance(value, dict) and set(value) == {"array"}:
        return np.asarray(value["array"], dtype=float)
    if isinstance(value, dict) and set(value) == {"estimator"}:
        cls = _MODEL_TYPES[value["estimator"]["model_type"]][0]
        return cls(**{k: _decode(v) for k, v in value["estimator"]["params"].items()})
    if isinstance(value, list):
        return [_decode(v) for v in value]
    return value


def _history_rows(net) -> list[dict]:
    return [{k: row[k] for k in _HISTORY_KEYS if k in row} for row in net.history]


def save_model(estimator, path: str | os.PathLike, *, overwrite: bool = False) -> Path:
    """Write a fitted calibrator to one ``.npz`` model file; returns the path.

    Parameters
    ----------
    estimator : LinearCalibrator, ComparativeCalibrator or DirectionalCalibrator
        A fitted calibrator (or another registered model type).
    path : str or path-like
        Target file; written exactly there (no suffix is added).
    overwrite : bool, default=False
        Replace an existing file; otherwise an existing file raises
        ``ModelFileError`` and is left untouched.

    Examples
    --------
    >>> import numpy as np, tempfile, os
    >>> from ftcal import LinearCalibrator, save_model, load_model
    >>> raw = np.random.default_rng(0).normal(size=(20, 6))
    >>> model = LinearCalibrator().fit(raw, raw * 2.0)
    >>> path = save_model(model, os.path.join(tempfile.mkdtemp(), "ltm.npz"))
    >>> bool(np.array_equal(load_model(path).predict(raw), model.predict(raw)))
    True
    """
    meta, arrays = _state(estimator)
    meta = {"format": FORMAT, "format_version": FORMAT_VERSION, **meta, "ftcal_version": _ftcal_version()}
    arrays[_META_KEY] = np.array(json.dumps(meta))
    path = Path(path)
    if path.exists() and not overwrite:
        raise ModelFileError(f"{path} already exists; pass overwrite=True to replace it, or choose another path.")
    with atomic_output(path, overwrite=overwrite, error=ModelFileError) as tmp, open(tmp, "wb") as f:
        np.savez(f, **arrays)
    return path


def _state(estimator) -> tuple[dict, dict[str, np.ndarray]]:
    """Metadata (model type, parameters, fitted scalars) and arrays of one fitted model."""
    name = type(estimator).__name__
    if name not in _MODEL_TYPES or type(estimator) is not _MODEL_TYPES[name][0]:
        raise ModelFileError(f"cannot save a {name}: model files support {sorted(_MODEL_TYPES)}.")
    check_is_fitted(estimator)
    _, scalar_names, array_names = _MODEL_TYPES[name]
    meta = {
        "model_type": name,
        "params": _stored_params(estimator),
        "fitted": {k: _encode(getattr(estimator, k)) for k in scalar_names + tuple(
            k for k in _OPTIONAL_SCALARS if k in estimator.__dict__ and k not in scalar_names)},
    }
    arrays = {f"fitted/{k}": np.asarray(getattr(estimator, k)) for k in array_names}
    arrays.update({f"fitted/{k}": np.asarray(getattr(estimator, k)) for k in _OPTIONAL_ARRAYS if hasattr(estimator, k)})
    if isinstance(estimator, NetworkCalibrator):
        meta["history"] = _history_rows(estimator.net_)
        state = estimator.net_.module_.state_dict()
        arrays.update({f"module/{k}": v.detach().cpu().numpy() for k, v in state.items()})
    if name in _CHILDREN:
        meta["children"] = []
        kids = getattr(estimator, _CHILDREN[name])
        meta["single_child"] = not isinstance(kids, list)
        for i, child in enumerate([kids] if meta["single_child"] else kids):
            child_meta, child_arrays = _state(child)
            meta["children"].append(child_meta)
            arrays.update({f"children/{i}/{k}": v for k, v in child_arrays.items()})
    return meta, arrays


def _ftcal_version() -> str:
    from .. import __version__

    return __version__


def _read(path: Path) -> tuple[dict, dict[str, np.ndarray]]:
    if not path.is_file():
        raise ModelFileError(f"model file {path} does not exist (or is not a file).")
    try:
        with np.load(path, allow_pickle=False) as data:
            arrays = {k: data[k] for k in data.files}
    except (zipfile.BadZipFile, EOFError, OSError, ValueError, KeyError) as exc:
        raise ModelFileError(
            f"{path} is not a readable ftcal model file (truncated or not an .npz archive: {exc}). "
            f"Save the model again with ftcal.save_model."
        ) from None
    if _META_KEY not in arrays:
        raise ModelFileError(f"{path} is an .npz file but not an ftcal model file (no {_META_KEY!r} entry).")
    try:
        meta = json.loads(str(arrays.pop(_META_KEY)))
    except (json.JSONDecodeError, RecursionError) as exc:
        raise ModelFileError(f"{path}: the model metadata is not valid JSON ({str(exc)[:80]}).") from None
    bad = [k for k, v in arrays.items() if v.dtype.kind not in "biuf" or (v.dtype.kind == "f" and not np.isfinite(v).all())]
    if bad:
        raise ModelFileError(
            f"{path}: array {bad[0]!r} holds NaN, inf or non-numeric values; the file is damaged. "
            "Fit and save the model again."
        )
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise ModelFileError(f"{path} is not an ftcal model file (format {meta.get('format') if isinstance(meta, dict) else meta!r}).")
    return meta, arrays


def load_model(path: str | os.PathLike, *, model_type: str | type | None = None):
    """Read a calibrator written by :func:`save_model`; no code from the file is executed.

    Parameters
    ----------
    path : str or path-like
        The model file.
    model_type : str, class or None
        When given, the file must hold this model type (class or class
        name), otherwise ``ModelFileError``.

    Returns
    -------
    estimator
        The fitted calibrator, predicting exactly like the saved one.
    """
    path = Path(path)
    meta, arrays = _read(path)
    version = meta.get("format_version")
    if version != FORMAT_VERSION:
        raise ModelFileError(
            f"{path} has model-file format version {version!r}; this ftcal (version {_ftcal_version()}) "
            f"reads version {FORMAT_VERSION}. Re-fit and save the model with this ftcal version."
        )
    name = meta.get("model_type")
    expected = model_type.__name__ if isinstance(model_type, type) else model_type
    if expected is not None and name != expected:
        raise ModelFileError(f"{path} holds a {name}, not the expected {expected}.")
    if name not in _MODEL_TYPES:
        raise ModelFileError(f"{path} holds an unknown model type {name!r}; this ftcal reads {sorted(_MODEL_TYPES)}.")
    try:
        estimator = _from_state(meta, arrays)
    except ModelFileError as exc:
        raise ModelFileError(f"{path}: {exc}") from None
    except (KeyError, TypeError, ValueError, RuntimeError, AttributeError, RecursionError) as exc:
        raise ModelFileError(f"{path}: the {name} model file is incomplete or inconsistent ({exc!r}).") from None
    _check_consistent(estimator, path)
    return estimator


def _check_consistent(estimator, path: Path) -> None:
    """Predict one tare reading; a model whose stored arrays do not fit together fails here, not at the user's predict."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            out = estimator.predict(np.asarray(estimator.zero_reading_, dtype=float)[None, :])
    except Exception as exc:  # any failure means the stored arrays are inconsistent
        raise ModelFileError(
            f"{path}: the stored arrays do not fit together ({type(exc).__name__}: {str(exc)[:120]}); "
            "the file is damaged or was edited. Fit and save the model again."
        ) from None
    if out.shape != (1, 6):
        raise ModelFileError(f"{path}: the model gives output of shape {out.shape[1:]} instead of (6,); the file is damaged.")


def _check_fitted_scalars(name: str, fitted: dict) -> None:
    """Types and ranges of the stored scalars (a ``null`` or a string would fail later, at predict)."""
    for key, value in fitted.items():
        if key in ("stop_reason_", "best_name_"):
            ok = isinstance(value, str)
        elif key == "cv_results_":
            ok = isinstance(value, dict)
        elif key in ("mean_", "kernel_"):  # the GP's choices
            ok = value in ("none", "linear", "rbf", "matern52", "rbf+linear", "matern52+linear")
        elif key == "per_output_":
            ok = isinstance(value, bool)
        elif key in ("n_features_in_", "n_epochs_", "best_epoch_", "n_dropped_zero_load_"):
            ok = isinstance(value, int) and not isinstance(value, bool) and value >= 0
        elif key == "ridge_":  # inf is the LTM fallback of the hybrid
            ok = isinstance(value, (int, float)) and not isinstance(value, bool) and value >= 0
        else:
            ok = isinstance(value, (int, float)) and not isinstance(value, bool) and np.isfinite(value)
        if key in ("alpha_", "scale_reference_") and ok:
            ok = value > 0
        if key == "n_features_in_" and ok:
            ok = value >= 1
        if not ok:
            raise ModelFileError(f"the {name}'s stored {key} is {value!r}, which is not a valid value; the file is damaged.")


def _from_state(meta: dict, arrays: dict[str, np.ndarray]):
    """The fitted model of :func:`_state`'s output (``KeyError`` etc. when incomplete)."""
    name = meta["model_type"]
    cls, scalar_names, array_names = _MODEL_TYPES[name]
    params = {k: _decode(v) for k, v in meta["params"].items()}
    if params.get("device") not in (None, "cpu") and not device_available(params["device"]):
        warnings.warn(
            f"the model was saved with device={params['device']!r}, which this machine does not have; "
            "it runs on the CPU instead.", UserWarning, stacklevel=3,
        )
        params["device"] = "cpu"
    estimator = cls(**params)
    _check_fitted_scalars(name, {k: meta["fitted"][k] for k in scalar_names})
    for k in scalar_names:
        setattr(estimator, k, meta["fitted"][k])
    for k in _OPTIONAL_SCALARS:
        if k in meta["fitted"] and k not in scalar_names:
            setattr(estimator, k, _optional_scalar(name, k, meta["fitted"][k]))
    for k in array_names + tuple(k for k in _OPTIONAL_ARRAYS if f"fitted/{k}" in arrays):
        setattr(estimator, k, arrays[f"fitted/{k}"])
    if isinstance(estimator, NetworkCalibrator):
        _restore_net(estimator, meta, arrays)
    if name in _CHILDREN:
        children = []
        for i, child_meta in enumerate(meta["children"]):
            prefix = f"children/{i}/"
            child_arrays = {k[len(prefix):]: v for k, v in arrays.items() if k.startswith(prefix)}
            children.append(_from_state(child_meta, child_arrays))
        setattr(estimator, _CHILDREN[name], children[0] if meta.get("single_child") else children)
    return estimator


def _optional_scalar(name: str, key: str, value):
    """``n_outputs_`` (a positive int) or ``y_1d_`` (a bool) read from a file, checked."""
    ok = isinstance(value, bool) if key == "y_1d_" else (
        isinstance(value, int) and not isinstance(value, bool) and 1 <= value <= 10_000)
    if not ok:
        raise ModelFileError(f"{name} model file: fitted {key} is {value!r}, not a valid value; the file is damaged.")
    return value


def _expected_module_shapes(estimator: NetworkCalibrator, n_inputs: int) -> dict[str, tuple[int, ...]]:
    """Shapes of the state_dict the declared ``hidden_layer_sizes`` would build (checked before building it)."""
    sizes = estimator.hidden_layer_sizes
    if not isinstance(sizes, (tuple, list)) or not all(isinstance(w, int) and w >= 1 for w in sizes):
        raise ModelFileError(f"hidden_layer_sizes {sizes!r} is not a tuple of positive widths; the file is damaged.")
    widths = [n_inputs, *sizes, estimator._network_outputs()]
    shapes = {}
    for i in range(len(widths) - 1):
        shapes[f"layers.{2 * i}.weight"] = (widths[i + 1], widths[i])
        shapes[f"layers.{2 * i}.bias"] = (widths[i + 1],)
    return shapes


def _restore_net(estimator: NetworkCalibrator, meta: dict, arrays: dict[str, np.ndarray]) -> None:
    stored = {k[len("module/"):]: v for k, v in arrays.items() if k.startswith("module/")}
    n_inputs = int(meta["fitted"]["n_features_in_"])
    expected = _expected_module_shapes(estimator, n_inputs)
    got = {k: tuple(v.shape) for k, v in stored.items()}
    if got != expected:
        diff = sorted(set(expected) ^ set(got)) or [k for k in expected if expected[k] != got[k]]
        k = diff[0]
        raise ModelFileError(
            f"the network weights do not match the declared layers (hidden_layer_sizes="
            f"{estimator.hidden_layer_sizes}, {n_inputs} inputs): {k} is {got.get(k, 'missing')}, expected "
            f"{expected.get(k, 'absent')}; the file is damaged or was edited."
        )
    state = {k: torch.from_numpy(v.astype(np.float32)) for k, v in stored.items()}
    net = estimator._build_net(n_inputs, seed=0)
    net.initialize()
    net.module_.load_state_dict(state)
    net.history = History(meta.get("history", []))
    estimator.net_ = net
    estimator._cache_numpy_layers()
