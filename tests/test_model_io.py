"""Model files: round trips, and truncated / foreign / other-version / other-type files."""

from __future__ import annotations

import json
import zipfile

import numpy as np
import pytest

from ftcal import ModelFileError, load_model, save_model
from ftcal.models._model_io import FORMAT_VERSION

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
    with pytest.raises(ModelFileError, match="already exists; pass overwrite=True"):
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
