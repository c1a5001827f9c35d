"""Every bounded fitted field of every registered calibrator: a model file carrying a value outside its declared
range is refused at load, naming the field, the value and the allowed range (never loaded silently)."""

from __future__ import annotations

import json
from numbers import Integral

import numpy as np
import pytest
from sklearn.utils._param_validation import Interval, StrOptions, make_constraint

from ftcal.core import ModelFileError
from ftcal import load_model, save_model
from ftcal.simulation import make_soft_sensor_dataset
from ftcal.persistence._model_io import fitted_constraints
from ftcal.compose._registry import model_classes

from conftest import CALIBRATOR_KINDS, WRAPPER_KINDS, affine_sensor_data, tiny_calibrators

_FILES: dict = {}


def _data(kind: str):
    if kind == "history":  # rows in time order with a load history, so that the history term is chosen
        d = make_soft_sensor_dataset(n_samples=160, n_zero=10, n_presses=12, hysteresis=1.0, random_state=0)
        return d.raw, d.wrench
    raw, wrench, _, _ = affine_sensor_data(n_samples=60, seed=2)
    if kind == "temperature_compensated":
        raw = np.column_stack([raw, np.linspace(15.0, 35.0, len(raw))])
    return raw, wrench


def _saved(kind: str, tmp_path_factory):
    if kind not in _FILES:
        model = dict(zip(CALIBRATOR_KINDS + WRAPPER_KINDS, tiny_calibrators()))[kind]
        if kind == "history":
            model.set_params(taus=(2.0, 4.0))
        model.fit(*_data(kind))
        _FILES[kind] = save_model(model, tmp_path_factory.mktemp(kind) / "model.npz")
    return _FILES[kind]


def _cases():
    classes = {kind: type(m) for kind, m in zip(CALIBRATOR_KINDS + WRAPPER_KINDS, tiny_calibrators())}
    return [(kind, field) for kind, cls in classes.items() for field in fitted_constraints(cls)]


def _outside(constraint, like):
    """Values that break ``constraint`` (of the kind of ``like``): just outside each finite bound, far outside."""
    c = make_constraint(constraint)
    if isinstance(c, StrOptions):
        return ["tampered"]
    if not isinstance(c, Interval):  # "boolean"
        return ["yes", 2]
    values = []
    if c.left is not None:
        values += [c.left - 0.5 * max(1.0, abs(c.left)), -5.0 if c.left > -5 else c.left - 1e6]
        if c.left > 0:
            values.append(1e-300)
        if c.closed in ("neither", "right"):
            values.append(float(c.left))
    if c.right is not None:
        values += [c.right + max(1.0, abs(c.right))]
    if c.type is Integral:
        low = 0 if c.left is None else c.left
        values.append(low + 0.5)
    values = [v for v in values if not c.is_satisfied_by(v)]
    return [int(v) if c.type is Integral and float(v).is_integer() else v for v in values]


def _tampered(path, tmp_path, field, value):
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    meta = json.loads(str(arrays["__metadata__"]))
    if f"fitted/{field}" in arrays:
        array = arrays[f"fitted/{field}"].astype(float if isinstance(value, float) else arrays[f"fitted/{field}"].dtype)
        array.flat[-1] = value
        arrays[f"fitted/{field}"] = array
    else:
        assert field in meta["fitted"], f"{field} is declared bounded but the file does not hold it"
        meta["fitted"][field] = value
    arrays["__metadata__"] = np.array(json.dumps(meta))
    out = tmp_path / f"tampered_{field}.npz"
    np.savez(out, **arrays)
    return out


def test_every_registered_class_is_covered():
    covered = {type(m) for m in tiny_calibrators()}
    assert set(model_classes().values()) <= covered | {c for c in model_classes().values() if not fitted_constraints(c)}


@pytest.mark.parametrize("kind, field", _cases())
def test_a_tampered_bounded_field_is_refused_naming_field_value_and_range(kind, field, tmp_path_factory, tmp_path):
    path = _saved(kind, tmp_path_factory)
    model = load_model(path)  # the untouched file loads
    with np.load(path, allow_pickle=False) as data:
        stored = field in json.loads(str(data["__metadata__"]))["state"]
    if not stored:  # a field this model does not have (a wrapper's inner model holds it): nothing to tamper
        assert field not in model.__dict__
        return
    constraints = fitted_constraints(type(model))[field]
    for value in _outside(constraints[0], None):
        tampered = _tampered(path, tmp_path, field, value)
        with pytest.raises(ModelFileError) as info:
            load_model(tampered)
        message = str(info.value)
        assert field in message and repr(value)[:12] in message, message
        assert str(make_constraint(constraints[0])) in message, message


def test_the_history_time_constant_of_the_field_report_is_refused(tmp_path_factory, tmp_path):
    """tau_rows_ 0.5, -5 and 1e-300 (each loaded silently before) are refused."""
    path = _saved("history", tmp_path_factory)
    assert load_model(path).tau_rows_ is not None
    for value in (0.5, -5.0, 1e-300):
        with pytest.raises(ModelFileError, match=rf"tau_rows_ is {value!r}, outside its allowed values: a float in "
                                                 r"the range \[1(\.0)?, inf\)"):
            load_model(_tampered(path, tmp_path, "tau_rows_", value))


@pytest.mark.filterwarnings("ignore::sklearn.exceptions.ConvergenceWarning")  # 40 noise-free rows
@pytest.mark.parametrize("field, value", [("amplitude_", -1.0), ("length_scale_", 0.0), ("target_scale_", -2.0),
                                          ("input_scale_", 0.0)])
def test_a_tampered_stock_kernel_baseline_is_refused_naming_the_field(field, value, tmp_path):
    """A stock GP baseline's file (auto may choose and save one) keeps its kernel's scales bounded too: a zero
    length scale or a negative amplitude was loaded and predicted before."""
    from ftcal.calibrators._baselines import StockCalibrator

    raw, wrench, _, _ = affine_sensor_data(n_samples=40, seed=3)
    path = save_model(StockCalibrator(baseline="sk_gp").fit(raw, wrench), tmp_path / "gp.npz")
    assert load_model(path).amplitude_ > 0
    with pytest.raises(ModelFileError, match=rf"stored {field} .*is {value!r}, outside its allowed values: a float in "
                                             r"the range \(0(\.0)?, inf\)"):
        load_model(_tampered(path, tmp_path, field, value))
