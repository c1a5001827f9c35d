"""Model files: round trips, and truncated / foreign / other-version / other-type files."""

from __future__ import annotations

import io
import json
import warnings
import zipfile
from pathlib import Path

import numpy as np
import pytest

from ftcal.core import ModelFileError
from ftcal import load_model, save_model
from ftcal.persistence._model_io import FORMAT_VERSION

from conftest import affine_sensor_data


@pytest.fixture
def fitted(tiny_calibrator):
    raw, wrench, _, _ = affine_sensor_data(n_samples=60, seed=31)
    return tiny_calibrator.fit(raw, wrench), raw


def test_round_trip_gives_identical_predictions(fitted, tmp_path):
    model, raw = fitted
    path = save_model(model, tmp_path / "model.npz")
    loaded = load_model(path)
    assert type(loaded) is type(model)
    assert repr(loaded) == repr(model)  # same constructor parameters (tuples stay tuples)
    np.testing.assert_array_equal(loaded.predict(raw), model.predict(raw))
    assert loaded.alpha_ == model.alpha_ and loaded.n_features_in_ == model.n_features_in_
    np.testing.assert_array_equal(loaded.zero_reading_, model.zero_reading_)
    if hasattr(model, "net_"):
        assert loaded.net_.history[:, "phase"] == model.net_.history[:, "phase"]
        assert loaded.stop_reason_ == model.stop_reason_


def test_file_is_plain_npz_with_json_metadata(fitted, tmp_path):
    model, _ = fitted
    path = save_model(model, tmp_path / "model.npz")
    with np.load(path, allow_pickle=False) as data:  # readable without pickle
        meta = json.loads(str(data["__metadata__"]))
        assert all(data[k].dtype != object for k in data.files)
    assert meta["format"] == "ftcal-model" and meta["format_version"] == FORMAT_VERSION
    assert meta["model_type"] == type(model).__name__
    assert meta["fitted"]["alpha_"] == model.alpha_


def test_existing_file_is_not_overwritten_unless_asked(fitted, tmp_path):
    model, _ = fitted
    path = tmp_path / "mine.npz"
    path.write_bytes(b"user data")
    with pytest.raises(ModelFileError, match="already exists. Fix: pass overwrite=True"):
        save_model(model, path)
    assert path.read_bytes() == b"user data"
    save_model(model, path, overwrite=True)
    assert load_model(path).n_features_in_ == 6
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine.npz"]  # no temporary files left


def test_truncated_file(fitted, tmp_path):
    model, _ = fitted
    path = save_model(model, tmp_path / "model.npz")
    content = path.read_bytes()
    path.write_bytes(content[: len(content) // 2])
    with pytest.raises(ModelFileError, match="truncated or not an .npz archive"):
        load_model(path)
    path.write_bytes(content[:-200])  # the end of the last member cut off, the directory gone
    with pytest.raises(ModelFileError, match="truncated or not an .npz archive"):
        load_model(path)


def rewrite_metadata(path, **changes):
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    meta = json.loads(str(arrays["__metadata__"]))
    meta.update(changes)
    arrays["__metadata__"] = np.array(json.dumps(meta))
    with open(path, "wb") as f:
        np.savez(f, **arrays)


def test_other_format_version(fitted, tmp_path):
    path = save_model(fitted[0], tmp_path / "model.npz")
    rewrite_metadata(path, format_version=FORMAT_VERSION + 1)
    with pytest.raises(ModelFileError, match=f"format version {FORMAT_VERSION + 1}; this ftcal .* reads version"):
        load_model(path)


def test_other_or_unknown_model_type(fitted, tmp_path):
    model, _ = fitted
    path = save_model(model, tmp_path / "model.npz")
    other = "LinearCalibrator" if type(model).__name__ != "LinearCalibrator" else "DirectionalCalibrator"
    with pytest.raises(ModelFileError, match=f"holds a {type(model).__name__}, not the expected {other}"):
        load_model(path, model_type=other)
    rewrite_metadata(path, model_type="os.system")
    with pytest.raises(ModelFileError, match="unknown model type 'os.system'"):
        load_model(path)


def test_foreign_files(tmp_path):
    text = tmp_path / "notes.npz"
    text.write_text("not a model")
    with pytest.raises(ModelFileError, match="not a readable ftcal model file"):
        load_model(text)
    plain = tmp_path / "arrays.npz"
    np.savez(plain, a=np.arange(3))
    with pytest.raises(ModelFileError, match="not an ftcal model file"):
        load_model(plain)
    with pytest.raises(ModelFileError, match="does not exist"):
        load_model(tmp_path / "missing.npz")


def test_pickled_object_array_is_refused(tmp_path):
    path = tmp_path / "evil.npz"
    with zipfile.ZipFile(path, "w") as zf, zf.open("__metadata__.npy", "w") as f:
        np.lib.format.write_array(f, np.array([object()], dtype=object), allow_pickle=True)
    with pytest.raises(ModelFileError):
        load_model(path)


def test_missing_weights_are_reported(fitted, tmp_path):
    model, _ = fitted
    path = save_model(model, tmp_path / "model.npz")
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files if k != "fitted/zero_reading_"}
    with open(path, "wb") as f:
        np.savez(f, **arrays)
    with pytest.raises(ModelFileError, match="incomplete or inconsistent"):
        load_model(path)


def test_unfitted_model_cannot_be_saved(tiny_calibrator, tmp_path):
    from sklearn.exceptions import NotFittedError

    with pytest.raises(NotFittedError):
        save_model(tiny_calibrator, tmp_path / "model.npz")
    assert not (tmp_path / "model.npz").exists()


# --- any target width, every calibrator -------------------------------------------------------------------------
def _fit_on(model, width, seed=5):
    """Fit ``model`` on an affine sensor with targets of ``width`` columns (``None``: a 1-D target)."""
    from ftcal import TemperatureCompensatedCalibrator

    raw, wrench, _, _ = affine_sensor_data(n_samples=70, seed=seed)
    y = wrench[:, 0] if width is None else wrench[:, :width]
    X = raw
    if isinstance(model, TemperatureCompensatedCalibrator):
        X = np.column_stack([raw, np.random.default_rng(seed).uniform(15, 35, len(raw))])
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)
        return model.fit(X, y), X


def _every_calibrator():
    from conftest import tiny_calibrators

    return tiny_calibrators()  # the wrappers (stack, temperature compensation) included


@pytest.mark.parametrize("width", [None, 3, 6], ids=["1-D", "3", "6"])
@pytest.mark.parametrize("index", range(len(_every_calibrator())),
                         ids=[type(m).__name__ for m in _every_calibrator()])
def test_every_calibrator_round_trips_at_every_target_width(index, width, tmp_path):
    model, X = _fit_on(_every_calibrator()[index], width)
    loaded = load_model(save_model(model, tmp_path / "m.npz"))
    expected = model.predict(X)
    assert expected.shape == ((len(X),) if width is None else (len(X), width))
    np.testing.assert_array_equal(loaded.predict(X), expected)
    assert loaded.n_outputs_ == model.n_outputs_ and loaded.y_1d_ == model.y_1d_


def test_saved_state_is_what_the_class_declares(tmp_path):
    """No second list: the file holds exactly the declared fitted attributes the model has."""
    from ftcal import LinearCalibrator
    from ftcal.persistence._model_io import fitted_state_names

    model, _ = _fit_on(LinearCalibrator(), 6)
    path = save_model(model, tmp_path / "m.npz")
    with np.load(path, allow_pickle=False) as data:
        meta = json.loads(str(data["__metadata__"]))
        arrays = {k.split("/", 1)[1] for k in data.files if k.startswith("fitted/")}
    stored = arrays | set(meta["fitted"])
    assert stored == {k for k in fitted_state_names(LinearCalibrator) if k in model.__dict__}
    assert {"calibration_matrix_", "offset_", "zero_reading_", "alpha_"} <= stored


@pytest.mark.parametrize("name", ["linear", "axis_nonlinear", "directional", "ensemble", "auto", "temperature"])
def test_files_written_by_format_version_1_still_load(name):
    """Files of the previous ftcal (written by tests/data/model_files_v1/make_files.py at main bf1836f)."""
    folder = Path(__file__).parent / "data" / "model_files_v1"
    with np.load(folder / f"{name}.model.npz", allow_pickle=False) as data:
        assert json.loads(str(data["__metadata__"]))["format_version"] == 1
    model = load_model(folder / f"{name}.model.npz")
    X = np.load(folder / "readings.npy")
    X = X if name == "temperature" else X[:, :6]
    np.testing.assert_array_equal(model.predict(X), np.load(folder / f"{name}.expected.npy"))


# --- column names ----------------------------------------------------------------------------------------------------
def test_column_names_survive_save_and_load_and_reordered_frames_are_refused(tmp_path):
    import pickle

    import pandas as pd  # in the test extra: never skipped
    from ftcal import LinearCalibrator

    raw, wrench, _, _ = affine_sensor_data(n_samples=60, seed=3)
    frame = pd.DataFrame(raw, columns=[f"s{i}" for i in range(6)])
    model = LinearCalibrator().fit(frame, wrench)
    loaded = load_model(save_model(model, tmp_path / "m.npz"))
    assert list(loaded.feature_names_in_) == list(model.feature_names_in_)
    np.testing.assert_array_equal(loaded.predict(frame), model.predict(frame))
    reordered = frame[frame.columns[::-1]]
    unpickled = pickle.loads(pickle.dumps(model))
    for m in (unpickled, loaded):  # the loaded model refuses what scikit-learn's pickled copy refuses
        with pytest.raises(ValueError, match="feature names"):
            m.predict(reordered)


# --- files that are not what they claim ------------------------------------------------------------------------------
@pytest.mark.parametrize("content, what", [
    (b"Fx,Fy,Fz\n1,2,3\n", "text file"),
    (b"\x80\x04\x95\x05\x00\x00\x00\x00\x00\x00\x00K\x01.", "pickle"),
    (b"", "empty"),
    (b"\x93NUMPY\x01\x00", "single .npy array"),
])
def test_non_zip_files_are_named_for_what_they_are(tmp_path, content, what):
    path = tmp_path / "model.npz"
    path.write_bytes(content)
    with pytest.raises(ModelFileError) as info:
        load_model(path)
    assert str(path) in str(info.value) and what in str(info.value)
    assert "pickle.load" not in str(info.value)


def test_directory_and_fifo_are_not_reported_missing(tmp_path):
    import os

    with pytest.raises(ModelFileError, match="is a directory"):
        load_model(tmp_path)
    fifo = tmp_path / "pipe.npz"
    os.mkfifo(fifo)
    with pytest.raises(ModelFileError, match="not a regular file"):
        load_model(fifo)  # never opened: opening a FIFO without a writer would block


def _zero_stream_member(zf, name, n_bytes, chunk=4 * 2**20):
    """A deflated member of ``n_bytes`` zeros (an .npy header first), written in chunks: a few kB on disk."""
    header = io.BytesIO()
    np.lib.format.write_array_header_1_0(header, {"descr": "<f8", "fortran_order": False,
                                                  "shape": (n_bytes // 8,)})
    info = zipfile.ZipInfo(name)
    info.compress_type = zipfile.ZIP_DEFLATED
    with zf.open(info, "w", force_zip64=True) as f:
        f.write(header.getvalue())
        zeros = bytes(chunk)
        for _ in range(n_bytes // chunk):
            f.write(zeros)


def _rewrite_with(path, extra):
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files}
    with zipfile.ZipFile(path, "w", zipfile.ZIP_DEFLATED) as zf:
        for key, value in arrays.items():
            with zf.open(f"{key}.npy", "w") as f:
                np.lib.format.write_array(f, value, allow_pickle=False)
        extra(zf)


def test_an_unused_huge_member_is_never_decompressed(tmp_path):
    """A small file carrying a 256 MiB deflate bomb the model does not use loads without touching it."""
    import tracemalloc

    from ftcal import LinearCalibrator

    model, X = _fit_on(LinearCalibrator(), 6)
    path = save_model(model, tmp_path / "m.npz")
    _rewrite_with(path, lambda zf: _zero_stream_member(zf, "junk/bomb.npy", 256 * 2**20))
    assert path.stat().st_size < 2 * 2**20
    tracemalloc.start()
    try:
        loaded = load_model(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    np.testing.assert_array_equal(loaded.predict(X), model.predict(X))
    assert peak < 32 * 2**20  # the bomb would be 256 MiB



def replace_member(path, member, write, compression=zipfile.ZIP_STORED):
    """Rewrite the model file ``path`` without its array ``member``, then let ``write(zipfile)`` add what replaces it."""
    with np.load(path, allow_pickle=False) as data:
        arrays = {k: data[k] for k in data.files if k != member}
    with zipfile.ZipFile(path, "w", compression) as zf:
        for key, value in arrays.items():
            with zf.open(f"{key}.npy", "w") as f:
                np.lib.format.write_array(f, value, allow_pickle=False)
        write(zf)

def test_a_used_member_declaring_more_than_the_memory_limit_is_refused_before_decompressing(tmp_path, monkeypatch):
    from ftcal import LinearCalibrator

    model, _ = _fit_on(LinearCalibrator(), 6)
    path = save_model(model, tmp_path / "m.npz")

    def bomb(zf):  # the model's own offset_, replaced by 64 MiB of zeros
        _zero_stream_member(zf, "fitted/offset_.npy", 64 * 2**20)

    replace_member(path, "fitted/offset_", bomb, zipfile.ZIP_DEFLATED)
    monkeypatch.setenv("FTCAL_MEMORY_LIMIT_GB", "0.01")  # 10 MiB
    with pytest.raises(ModelFileError, match=r"fitted/offset_.*64.00 MiB.*memory limit"):
        load_model(path)


def test_a_header_declaring_a_huge_shape_is_refused_before_allocating(tmp_path):
    from ftcal import LinearCalibrator

    model, _ = _fit_on(LinearCalibrator(), 6)
    path = save_model(model, tmp_path / "m.npz")
    def huge(zf):
        with zf.open("fitted/offset_.npy", "w") as f:  # shape (1e10,) = 80 GB declared, 48 bytes held
            np.lib.format.write_array_header_1_0(f, {"descr": "<f8", "fortran_order": False, "shape": (10**10,)})
            f.write(np.zeros(6).tobytes())

    replace_member(path, "fitted/offset_", huge)
    assert path.stat().st_size < 8000
    with pytest.raises(ModelFileError, match=r"shape \(10000000000,\)") as info:
        load_model(path)
    assert "this is a bug" not in str(info.value) and "declares shape" in str(info.value)


def test_a_model_with_nan_or_inf_fitted_values_is_not_saved(tmp_path):
    # load_model refuses such a file as damaged: save_model refuses to write it, and nothing is left on disk
    from ftcal import LinearCalibrator

    raw, wrench, _, _ = affine_sensor_data(n_samples=40, seed=3)
    model = LinearCalibrator().fit(raw, wrench)
    model.calibration_matrix_[0, 0] = np.nan
    with pytest.raises(ModelFileError, match=r"cannot save the LinearCalibrator: its fitted calibration_matrix_ holds "
                                             r"NaN or inf.*fit the model again"):
        save_model(model, tmp_path / "m.model.npz")
    model = LinearCalibrator().fit(raw, wrench)
    model.alpha_ = float("inf")
    with pytest.raises(ModelFileError, match=r"its fitted alpha_ holds NaN or inf"):
        save_model(model, tmp_path / "m.model.npz")
    assert list(tmp_path.iterdir()) == []


def test_save_and_load_name_a_bad_path_not_an_internal_file(tmp_path):
    from ftcal import LinearCalibrator

    raw, wrench, _, _ = affine_sensor_data(n_samples=40, seed=3)
    model = LinearCalibrator().fit(raw, wrench)
    with pytest.raises(ModelFileError, match=rf"cannot write {tmp_path / 'missing' / 'm.npz'}: the folder .* does not "
                                             r"exist"):
        save_model(model, tmp_path / "missing" / "m.npz")
    with pytest.raises(ModelFileError, match=rf"{tmp_path} is a folder; name the model file"):
        save_model(model, tmp_path, overwrite=True)
    for bad in (None, b"m.npz", 3):
        with pytest.raises(ModelFileError, match=r"path must be a str or a pathlib.Path"):
            load_model(bad)
        with pytest.raises(ModelFileError, match=r"path must be a str or a pathlib.Path"):
            save_model(model, bad)
    assert not any(p.name.startswith(".") for p in tmp_path.rglob("*"))
