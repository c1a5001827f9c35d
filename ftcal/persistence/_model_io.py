"""Model files: one ``.npz`` holding JSON metadata and the weight arrays, no pickle.

Layout (a zip of ``.npy`` members, as ``numpy.savez`` writes; read member by
member without pickle, so loading never executes code from the file):

* ``__metadata__``: a 0-d unicode array holding a JSON object with
  ``format`` (``"ftcal-model"``), ``format_version`` (``2``), ``model_type``
  (the class name), ``ftcal_version``, ``params`` (constructor parameters),
  ``fitted`` (JSON-able fitted attributes: ``alpha_``, ``n_features_in_``,
  ``feature_names_in_`` as ``{"strings": [...]}``, ...) and, for networks, a
  compact ``history`` (epoch, phase, lr, losses);
* ``fitted/<name>``: fitted arrays (``zero_reading_``, ``calibration_matrix_``,
  ...);
* ``module/<name>``: what a class encodes itself (its ``_encoded_state``): a network calibrator's
  ``_state_to_arrays`` gives its torch ``state_dict`` (float32) and its history, ``_array_shapes`` the names and
  shapes a file must hold (checked before reading), ``_state_from_arrays`` rebuilds the net;
* ``children/<i>/...``: fitted sub-models (the members of an
  :class:`~ftcal.EnsembleCalibrator`, the inner calibrator of a wrapper), each
  in this same layout, their metadata in the JSON's ``children`` list with the
  attribute they belong to.

**What is stored is declared once, next to each class**: ``_fitted_state``, a
tuple of fitted attribute names (collected over the class' bases, so every
calibrator stores :class:`~ftcal.calibrators._base.BaseCalibrator`'s
``alpha_``, ``zero_reading_``, ``feature_names_in_``, ...). Each value is
stored by what it is: a numeric array as a member, a number, string, flag or
plain dict as JSON, a fitted calibrator (or a list of them) as children, and
what the class lists in ``_encoded_state`` by the class' own hooks (a network: its weights and history; this
module knows no network internals). Which classes a file may name is
the registry's list (:func:`ftcal.compose._registry.model_classes`): adding a
calibrator is one module and one registry line. **Each fitted value is bounded**: ``_fitted_constraints``
beside ``_fitted_state`` (scikit-learn's constraint vocabulary, :func:`fitted_constraints`) gives the allowed
values of a field, checked at load (a tampered ``tau_rows_ = 0.5`` is refused naming the field, the value and
the range); every numeric array must be finite and every JSON value non-null and not NaN.

Reading is bounded: only the members the model type needs are read (others
are never decompressed), each member's declared size and the shape in its
``.npy`` header are checked against ftcal's memory limit
(:func:`~ftcal.core.check_allocation`) and against each other before anything
is allocated, and at most the declared bytes are decompressed. A file that is
missing, not a zip archive, truncated, not an ftcal model, of another format
version, of an unknown model type, or inconsistent raises
:class:`~ftcal.core.ModelFileError` saying which. Files of format version 1 (ftcal
before the declarations) are read too. Files are written to a temporary file
next to the target and then renamed, so an interrupted save never leaves half
a file, and an existing file is only replaced with ``overwrite=True``.
"""

from __future__ import annotations

import json
import os
import stat
import warnings
import zipfile
from numbers import Integral
from pathlib import Path

import numpy as np
from sklearn.base import BaseEstimator
from sklearn.utils.validation import check_is_fitted

from .. import __version__
from ..calibrators._base import BaseCalibrator
from ..compose._registry import model_class, model_classes
from ..core._exceptions import ModelFileError
from ..core._files import atomic_output, describe_file_start
from ..core._memory import MemoryLimitError, check_allocation, format_bytes, read_npy_member

__all__ = ["save_model", "load_model", "model_data", "fitted_state_names", "fitted_constraints", "FORMAT_VERSION",
           "is_model_file"]

FORMAT = "ftcal-model"
#: Version of the model-file layout written by :func:`save_model` (1: before the per-class declarations).
FORMAT_VERSION = 2
_READABLE_VERSIONS = (1, 2)
_META_KEY = "__metadata__"
#: Largest metadata member read [bytes]: an ftcal model's JSON is a few kB (a long training history: ~1 MB).
_MAX_METADATA_BYTES = 64 * 2**20
#: Version-1 files name no attribute for their sub-models; these were the only meta-estimators then.
_V1_CHILDREN = {"EnsembleCalibrator": "estimators_", "TemperatureCompensatedCalibrator": "estimator_",
                "AutoCalibrator": "best_estimator_"}


def fitted_state_names(cls: type) -> tuple[str, ...]:
    """The fitted attributes a model file stores for ``cls``: every ``_fitted_state`` along its bases.

    Examples
    --------
    >>> from ftcal import LinearCalibrator
    >>> names = fitted_state_names(LinearCalibrator)
    >>> "calibration_matrix_" in names and "zero_reading_" in names and "feature_names_in_" in names
    True
    """
    # each name once, where it is first declared (the base classes' first)
    return tuple(dict.fromkeys(name for klass in reversed(cls.__mro__)
                               for name in vars(klass).get("_fitted_state", ())))


def fitted_constraints(cls: type) -> dict[str, list]:
    """The allowed values of the fitted attributes of ``cls``: every ``_fitted_constraints`` along its bases.

    Declared next to ``_fitted_state``, in scikit-learn's ``_parameter_constraints`` vocabulary
    (``Interval``, ``StrOptions``, ``"boolean"``); an array's every entry must satisfy them. A model file whose
    value breaks them is refused at load, naming the attribute, the value and the allowed range.

    Examples
    --------
    >>> from ftcal import GaussianProcessCalibrator
    >>> str(fitted_constraints(GaussianProcessCalibrator)["std_scale_"][0])
    'a float in the range [1.0, inf)'
    """
    # a subclass' declaration replaces its base's
    return {k: v for klass in reversed(cls.__mro__) for k, v in vars(klass).get("_fitted_constraints", {}).items()}


def _check_fitted_constraints(estimator) -> None:
    """Refuse a fitted value outside its declared constraints (:func:`fitted_constraints`), naming it."""
    from sklearn.utils._param_validation import Interval, make_constraint

    name = type(estimator).__name__
    for key, declared in fitted_constraints(type(estimator)).items():
        value = estimator.__dict__.get(key)
        if value is None:
            continue
        constraints = [make_constraint(c) for c in declared]
        values = np.asarray(value).ravel() if isinstance(value, np.ndarray) else [value]
        if isinstance(value, np.ndarray) and value.dtype.kind in "biuf" and len(constraints) == 1 \
                and isinstance(constraints[0], Interval):  # every entry at once: arrays may be large
            c = constraints[0]
            low = -np.inf if c.left is None else c.left
            high = np.inf if c.right is None else c.right
            below = values < low if c.closed in ("left", "both") else values <= low
            above = values > high if c.closed in ("right", "both") else values >= high
            wrong_kind = (values != np.floor(values)) if c.type is Integral and value.dtype.kind == "f" else False
            values = [values[i].item() for i in np.flatnonzero(below | above | wrong_kind)[:1]]  # the first bad one
        for offending in values:
            if not any(c.is_satisfied_by(offending) for c in constraints):
                where = " (an entry of it)" if isinstance(value, np.ndarray) else ""
                raise ModelFileError(
                    f"the {name}'s stored {key}{where} is {offending!r:.80}, outside its allowed values: "
                    f"{' or '.join(str(c) for c in constraints)}. The file is damaged or was edited; fit and save "
                    "the model again.")


def _is_known(estimator) -> bool:
    return model_class(type(estimator).__name__) is type(estimator)


def _encode(value):
    """JSON form of a parameter value (tuples and arrays tagged so they come back as such)."""
    if isinstance(value, tuple):
        return {"tuple": [_encode(v) for v in value]}
    if isinstance(value, np.ndarray):
        return {"array": value.tolist()}
    if isinstance(value, (np.integer, np.floating, np.bool_)):
        return value.item()
    if isinstance(value, list):
        return [_encode(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _encode(v) for k, v in value.items()}
    if isinstance(value, (str, int, float, bool)) or value is None:
        return value
    if isinstance(value, BaseCalibrator) and _is_known(value):
        return {"estimator": {"model_type": type(value).__name__, "params": _stored_params(value)}}
    return None  # e.g. a RandomState instance: not reproducible from a file; stored as None


def _stored_params(estimator) -> dict:
    """JSON form of the constructor parameters; transient ones (e.g. ``callbacks``) are stored as None."""
    transient = getattr(estimator, "_transient_params", ())
    return {k: None if k in transient else _encode(v) for k, v in estimator.get_params(deep=False).items()}


def _known_params(cls: type, params: dict) -> dict:
    """``params`` less those the class has removed since the file was written (its ``_removed_params``).

    A parameter that is neither accepted nor listed as removed is kept, so that ``cls(**params)`` reports it.
    """
    removed = getattr(cls, "_removed_params", ())
    return {k: v for k, v in params.items() if k not in removed}


def _decode(value):
    if isinstance(value, dict) and set(value) == {"tuple"}:
        return tuple(_decode(v) for v in value["tuple"])
    if isinstance(value, dict) and set(value) == {"array"}:
        return np.asarray(value["array"], dtype=float)
    if isinstance(value, dict) and set(value) == {"estimator"}:
        name = value["estimator"]["model_type"]
        cls = model_class(name)
        if cls is None:
            raise ModelFileError(f"a parameter names an unknown model type {name!r}.")
        return cls(**_known_params(cls, {k: _decode(v) for k, v in value["estimator"]["params"].items()}))
    if isinstance(value, list):
        return [_decode(v) for v in value]
    return value


def is_model_file(path: str | Path) -> bool:
    """Whether ``path`` is an ftcal model file (a zip holding the model's metadata), without reading the model.

    Examples
    --------
    >>> is_model_file("no-such-file.npz")
    False
    """
    try:
        with zipfile.ZipFile(path) as archive:
            return f"{_META_KEY}.npy" in archive.namelist()
    except (OSError, zipfile.BadZipFile):
        return False

def save_model(estimator, path: str | os.PathLike, *, overwrite: bool = False, data: dict | None = None) -> Path:
    """Write a fitted calibrator to one ``.npz`` model file; returns the path.

    Parameters
    ----------
    estimator : fitted calibrator
        Any calibrator of the registry (:data:`~ftcal.compose.CALIBRATOR_NAMES`), an
        :class:`~ftcal.EnsembleCalibrator` or a
        :class:`~ftcal.TemperatureCompensatedCalibrator`, fitted on targets of
        any width.
    path : str or path-like
        Target file; written exactly there (no suffix is added).
    overwrite : bool, default=False
        Replace an existing file; otherwise an existing file raises
        ``ModelFileError`` and is left untouched.
    data : dict, optional
        How the training data were read (plain JSON: the column mapping, units and wrench axes the CLI fitted
        with), kept in the metadata and returned by :func:`model_data`, so that the model reads its data alike.

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
    _refuse_non_finite(type(estimator).__name__, meta, arrays)
    meta = {"format": FORMAT, "format_version": FORMAT_VERSION, **meta, "ftcal_version": __version__,
            **({} if data is None else {"data": data})}
    arrays[_META_KEY] = np.array(json.dumps(meta))
    if not isinstance(path, (str, os.PathLike)) or isinstance(os.fspath(path), bytes):
        raise ModelFileError(f"path must be a str or a pathlib.Path naming the model file; got {path!r:.80}.")
    path = Path(path)
    if path.is_dir():
        raise ModelFileError(f"{path} is a folder; name the model file to write (e.g. {path / 'model.model.npz'}).")
    if not path.parent.is_dir():
        raise ModelFileError(f"cannot write {path}: the folder {path.parent} does not exist. Fix: create it first.")
    if path.exists() and not overwrite:
        raise ModelFileError(f"{path} already exists.", parameter="path", value=str(path), fix="pass {overwrite} to replace it, or choose another path", settings={"overwrite": True})
    with atomic_output(path, overwrite=overwrite, error=ModelFileError) as tmp, open(tmp, "wb") as f:
        np.savez(f, **arrays)
    return path


def _refuse_non_finite(name: str, meta: dict, arrays: dict[str, np.ndarray]) -> None:
    """A model whose fitted values hold NaN or inf is damaged (``load_model`` would refuse its file): refuse to
    write it, naming the value."""
    def scalars(m: dict, where: str):
        for key, value in (m.get("fitted") or {}).items():
            yield f"{where}{key}", value
        for i, child in enumerate(m.get("children") or []):
            yield from scalars(child, f"{where}{child.get('attribute', 'child')}[{i}].")

    def refused(key: str, value) -> bool:  # what load_model's _check_scalar refuses (inf is a valid ridge_)
        rule = _SCALAR_RULES.get(key.rsplit(".", 1)[-1])
        return not rule(value) if rule is not None else isinstance(value, float) and np.isnan(value)

    bad = next((k for k, v in scalars(meta, "") if refused(k, v)), None) or next(
        (k.replace("fitted/", "") for k, a in arrays.items() if a.dtype.kind == "f" and not np.isfinite(a).all()), None)
    if bad is not None:
        raise ModelFileError(
            f"cannot save the {name}: its fitted {bad} holds NaN or inf (the model diverged or was changed after "
            "fitting), and a model file must predict finite wrenches. Fix: fit the model again.")


def _state(estimator) -> tuple[dict, dict[str, np.ndarray]]:
    """Metadata (model type, parameters, fitted values) and arrays of one fitted model, from its declarations."""
    name = type(estimator).__name__
    if not _is_known(estimator):
        raise ModelFileError(
            f"cannot save a {name}: model files hold the registry's calibrator classes ({sorted(model_classes())}); "
            "register the class with ftcal.register_calibrator to save it.")
    check_is_fitted(estimator)
    # "state": what is stored, so that a reader can tell a missing entry from an absent attribute
    meta: dict = {"model_type": name, "params": _stored_params(estimator), "fitted": {}, "state": []}
    arrays: dict[str, np.ndarray] = {}
    children: list[tuple[str, bool, object]] = []
    encoded = getattr(type(estimator), "_encoded_state", ())  # stored by the class' own _state_to_arrays
    for key in fitted_state_names(type(estimator)):
        value = estimator.__dict__.get(key)
        if value is None:
            continue
        meta["state"].append(key)
        if key in encoded:
            continue
        if isinstance(value, BaseCalibrator):
            children.append((key, True, value))
        elif isinstance(value, list) and value and all(isinstance(v, BaseCalibrator) for v in value):
            children.extend((key, False, v) for v in value)
        elif isinstance(value, np.ndarray) and value.dtype.kind in "biuf":
            arrays[f"fitted/{key}"] = value
        elif isinstance(value, np.ndarray) and all(isinstance(v, str) for v in value.ravel()):
            meta["fitted"][key] = {"strings": [str(v) for v in value.ravel()]}
        elif isinstance(value, BaseEstimator):  # the fitted model itself: a file would load as another model
            raise ModelFileError(
                f"cannot save a {name} that holds a {type(value).__name__} of the user's ({key}): a model file "
                "holds ftcal's registered calibrators and plain values only, never code to run. Keep this model "
                "in Python, or build it from names (e.g. StockCalibrator(baseline='sk_poly2')) to save it.")
        else:  # a typed result (a Comparison, a FoldPlan) stores its own JSON-able state, read back by its class
            typed = key in getattr(type(estimator), "_typed_state", {})
            meta["fitted"][key] = value.to_state() if typed else _encode(value)
    if any(key in encoded for key in meta["state"]):
        own_arrays, own_meta = estimator._state_to_arrays()
        arrays.update({f"module/{k}": v for k, v in own_arrays.items()})
        meta.update(own_meta)
    if children:
        meta["children"] = []
        for i, (key, single, child) in enumerate(children):
            child_meta, child_arrays = _state(child)
            meta["children"].append({**child_meta, "attribute": key, "single": single})
            arrays.update({f"children/{i}/{k}": v for k, v in child_arrays.items()})
    return meta, arrays


class _Archive:
    """A model file opened as a zip of ``.npy`` members, read one checked member at a time."""

    def __init__(self, path: Path) -> None:
        self.path = path
        _check_is_regular_file(path)
        try:
            self.zip = zipfile.ZipFile(path)
        except zipfile.BadZipFile:
            raise ModelFileError(f"{path} is not a readable ftcal model file (truncated or not an .npz archive: "
                                 f"{describe_file_start(path)}). Save the model again with ftcal.save_model.") from None
        except OSError as exc:
            raise ModelFileError(f"{path} cannot be read ({exc.strerror or exc}).") from None
        self.members = {info.filename[:-4]: info for info in self.zip.infolist() if info.filename.endswith(".npy")}

    def __enter__(self):
        return self

    def __exit__(self, *exc) -> None:
        self.zip.close()

    def has(self, key: str) -> bool:
        return key in self.members

    def keys(self, prefix: str) -> list[str]:
        return [k for k in self.members if k.startswith(prefix)]

    def read(self, key: str, *, limit: float | None = None) -> np.ndarray:
        """The array of member ``key``: sizes checked before decompressing, at most the declared bytes read."""
        info = self.members[key]
        what = f"{self.path}: member {key!r}"
        fix = ("the file is damaged (cut short or changed since it was written) or was not written by ftcal: copy it "
               "again from where it was saved, or fit and save the model again with ftcal.save_model")
        check_allocation(float(info.file_size), f"{what} (declared {format_bytes(info.file_size)} uncompressed)", fix)
        if limit is not None and info.file_size > limit:
            raise ModelFileError(f"{what} declares {format_bytes(info.file_size)}, more than an ftcal model's "
                                 f"{format_bytes(limit)}; {fix}.")
        return read_npy_member(self.zip, info.filename, what, ModelFileError, fix, fix, max_empty_dim=_MAX_EMPTY_DIM)


#: Longest dimension of an empty model array (shape (n, 0)); any longer one is a damaged or crafted header.
_MAX_EMPTY_DIM = 1 << 20


def _check_is_regular_file(path: Path) -> None:
    try:
        mode = path.stat().st_mode
    except FileNotFoundError:
        raise ModelFileError(f"model file {path} does not exist (or is not a file).") from None
    except OSError as exc:
        raise ModelFileError(f"model file {path} cannot be read ({exc.strerror or exc}).") from None
    if stat.S_ISDIR(mode):
        raise ModelFileError(f"{path} is a directory, not a model file; give the .model.npz file inside it.")
    if not stat.S_ISREG(mode):
        raise ModelFileError(f"{path} is not a regular file (a device, pipe or socket); give a .model.npz file.")


def _read_metadata(archive: _Archive) -> dict:
    path = archive.path
    if not archive.has(_META_KEY):
        raise ModelFileError(f"{path} is an .npz file but not an ftcal model file (no {_META_KEY!r} entry).")
    try:
        raw = archive.read(_META_KEY, limit=_MAX_METADATA_BYTES)
    except MemoryLimitError as exc:
        raise ModelFileError(str(exc)) from None
    if raw.dtype.kind != "U" or raw.ndim != 0:
        raise ModelFileError(f"{path} is not an ftcal model file ({_META_KEY!r} is not a text entry).")
    try:
        meta = json.loads(str(raw))
    except (json.JSONDecodeError, RecursionError) as exc:
        raise ModelFileError(f"{path}: the model metadata is not valid JSON ({str(exc)[:80]}).") from None
    if not isinstance(meta, dict) or meta.get("format") != FORMAT:
        raise ModelFileError(
            f"{path} is not an ftcal model file (format {meta.get('format') if isinstance(meta, dict) else meta!r}).")
    return meta


def model_data(path: str | os.PathLike) -> dict:
    """How the data of the model file ``path`` were read at fit time (``save_model(..., data=...)``), or ``{}``.

    Only the metadata is read (bounded like :func:`load_model`).
    """
    with _Archive(Path(path)) as archive:
        meta = _read_metadata(archive)
    data = meta.get("data", {})
    if not isinstance(data, dict):
        raise ModelFileError(f"{path}: the stored data description is not a JSON object; fit the model again.")
    return data


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
    if not isinstance(path, (str, os.PathLike)) or isinstance(os.fspath(path), bytes):
        raise ModelFileError(f"path must be a str or a pathlib.Path naming the model file; got {path!r:.80}.")
    path = Path(path)
    with _Archive(path) as archive:
        meta = _read_metadata(archive)
        version = meta.get("format_version")
        if version not in _READABLE_VERSIONS:
            raise ModelFileError(
                f"{path} has model-file format version {version!r}; this ftcal (version {__version__}) "
                f"reads versions {', '.join(map(str, _READABLE_VERSIONS))}. Re-fit and save the model with this "
                "ftcal version.")
        name = meta.get("model_type")
        expected = model_type.__name__ if isinstance(model_type, type) else model_type
        if expected is not None and name != expected:
            raise ModelFileError(f"{path} holds a {name}, not the expected {expected}.")
        if not isinstance(name, str) or model_class(name) is None:
            raise ModelFileError(
                f"{path} holds an unknown model type {name!r}; this ftcal reads {sorted(model_classes())}.")
        try:
            estimator = _from_state(meta, archive, "")
        except MemoryLimitError as exc:
            raise ModelFileError(str(exc)) from None
        except ModelFileError as exc:
            message = str(exc)
            raise ModelFileError(message if message.startswith(str(path)) else f"{path}: {message}") from None
        except (KeyError, TypeError, ValueError, RuntimeError, AttributeError, RecursionError, IndexError) as exc:
            raise ModelFileError(
                f"{path}: the {name} model file is incomplete or inconsistent ({exc!r}).") from None
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
    expected = (1,) if getattr(estimator, "y_1d_", False) else (1, int(getattr(estimator, "n_outputs_", 6)))
    if out.shape != expected:
        raise ModelFileError(f"{path}: the model gives output of shape {out.shape[1:]} instead of "
                             f"{expected[1:]}; the file is damaged.")


def _is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _is_number(value) -> bool:
    return isinstance(value, (int, float)) and not isinstance(value, bool) and not np.isnan(value)


#: Checks of the fitted values every calibrator has (others: any JSON value but NaN and null).
_SCALAR_RULES = {
    "alpha_": lambda v: _is_number(v) and 0 < v < np.inf,
    "n_features_in_": lambda v: _is_int(v) and v >= 1,
    "n_outputs_": lambda v: _is_int(v) and 1 <= v <= 10_000,
    "y_1d_": lambda v: isinstance(v, bool),
    "feature_names_in_": lambda v: isinstance(v, dict) and isinstance(v.get("strings"), list)
    and all(isinstance(s, str) for s in v["strings"]),
    # the wrench axes named at fit: distinct names among Fx..Tz
    "axes_": lambda v: isinstance(v, dict) and isinstance(v.get("strings"), list) and 0 < len(v["strings"]) <= 6
    and len(set(v["strings"])) == len(v["strings"]) and set(v["strings"]) <= {"Fx", "Fy", "Fz", "Tx", "Ty", "Tz"},
}


def _check_scalar(name: str, key: str, value) -> None:
    rule = _SCALAR_RULES.get(key)
    ok = rule(value) if rule is not None else (
        value is not None and not (isinstance(value, float) and np.isnan(value)))
    if not ok:
        raise ModelFileError(f"the {name}'s stored {key} is {value!r:.80}, which is not a valid value; the file is "
                             "damaged.")


def _from_state(meta: dict, archive: _Archive, prefix: str):
    """The fitted model of :func:`_state`'s output, reading only the members its declarations name."""
    name = meta["model_type"]
    cls = model_class(name)
    if cls is None:
        raise ModelFileError(f"a sub-model has an unknown model type {name!r}.")
    params = {k: _decode(v) for k, v in meta["params"].items()}
    if params.get("device") not in (None, "cpu"):
        from ..networks._base import device_available

        if not device_available(params["device"]):
            warnings.warn(
                f"the model was saved with device={params['device']!r}, which this machine does not have; "
                "it runs on the CPU instead.", UserWarning, stacklevel=4,
            )
            params["device"] = "cpu"
    estimator = cls(**_known_params(cls, params))
    declared = fitted_state_names(cls)
    renamed = getattr(cls, "_renamed_state", {})  # names earlier versions stored some attributes under
    fitted = {renamed.get(k, k): v for k, v in meta.get("fitted", {}).items()}
    for key in declared:
        if key in fitted:
            value = fitted[key]
            _check_scalar(name, key, value)
            if isinstance(value, dict) and set(value) == {"strings"}:
                value = np.asarray(value["strings"], dtype=object)
            reader = getattr(cls, "_typed_state", {}).get(key)
            if reader is not None:  # the class' typed result (also from an earlier file's plain dict)
                try:
                    setattr(estimator, key, reader(value))
                except (KeyError, TypeError, ValueError) as exc:
                    raise ModelFileError(f"the {name}'s stored {key} cannot be read ({exc}); the file is damaged or "
                                         "was edited. Fit and save the model again.") from None
                continue
            setattr(estimator, key, _decode(value))
        elif archive.has(f"{prefix}fitted/{key}"):
            array = archive.read(f"{prefix}fitted/{key}")
            if array.dtype.kind not in "biuf" or (array.dtype.kind == "f" and not np.isfinite(array).all()):
                raise ModelFileError(f"array 'fitted/{key}' holds NaN, inf or non-numeric values; the file is "
                                     "damaged. Fit and save the model again.")
            setattr(estimator, key, array)
    if meta.get("history") is not None or archive.keys(f"{prefix}module/"):
        _restore_encoded(estimator, meta, archive, prefix)
    children = meta.get("children") or []
    if meta.get("format_version", FORMAT_VERSION) == 1 and children:  # version 1: one attribute, named nowhere
        attribute = _V1_CHILDREN[name]
        children = [{**c, "attribute": attribute, "single": bool(meta.get("single_child"))} for c in children]
    for i, child_meta in enumerate(children):
        key = child_meta["attribute"]
        if key not in declared:
            raise ModelFileError(f"a sub-model is stored as {key!r}, which a {name} does not have.")
        child = _from_state({"format_version": meta.get("format_version"), **child_meta}, archive,
                            f"{prefix}children/{i}/")
        if child_meta.get("single"):
            setattr(estimator, key, child)
        else:  # a list of sub-models, in the stored order
            vars(estimator).setdefault(key, []).append(child)
    _check_fitted_constraints(estimator)
    required = [renamed.get(k, k) for k in meta.get("state") or []] or \
        [k for k in ("alpha_", "n_features_in_", "zero_reading_") if k in declared]
    missing = [k for k in required if k not in estimator.__dict__]
    if missing:
        raise ModelFileError(f"the {name} model file is incomplete or inconsistent: its fitted {missing[0]!r} is "
                             "missing; the file is damaged or was edited. Fit and save the model again.")
    return estimator


def _restore_encoded(estimator, meta: dict, archive: _Archive, prefix: str) -> None:
    """The state a class encodes itself (a network's weights and history): its ``module/`` arrays, names and shapes
    checked against the class' :meth:`_array_shapes` before any is read, then its ``_state_from_arrays``."""
    name = meta["model_type"]
    if not getattr(type(estimator), "_encoded_state", ()):
        raise ModelFileError(f"the file holds network weights ('module/' arrays or a history), which a {name} "
                             "does not have; the file is damaged or was edited.")
    _check_scalar(name, "n_features_in_", meta["fitted"].get("n_features_in_"))
    expected = estimator._array_shapes()
    got_names = {k[len(prefix) + len("module/"):]: k for k in archive.keys(f"{prefix}module/")}
    arrays = {short: archive.read(got_names[short]) for short in expected if short in got_names}
    got = {k: tuple(v.shape) for k, v in arrays.items()}
    extra = sorted(set(got_names) - set(expected))
    if got != expected or extra:
        k = (extra or sorted(set(expected) ^ set(got)) or [k for k in expected if expected[k] != got[k]])[0]
        raise ModelFileError(
            f"the network weights do not match the declared layers (hidden_layer_sizes="
            f"{estimator.hidden_layer_sizes}, {meta['fitted']['n_features_in_']} inputs): {k} is "
            f"{got.get(k, 'missing')}, expected {expected.get(k, 'absent')}; the file is damaged or was edited.")
    bad = [k for k, v in arrays.items() if v.dtype.kind != "f" or not np.isfinite(v).all()]
    if bad:
        raise ModelFileError(f"array 'module/{bad[0]}' holds NaN, inf or non-numeric values; the file is damaged.")
    estimator._state_from_arrays(arrays, {"history": meta.get("history") or []})
