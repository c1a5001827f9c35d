"""Writes the version-1 model files of tests/data/model_files_v1 with ftcal before the one training engine (main at bf1836f)."""
import sys
import numpy as np
import ftcal
from ftcal import (LinearCalibrator, DirectionalCalibrator, EnsembleCalibrator, AutoCalibrator, PolynomialCalibrator,
                   TemperatureCompensatedCalibrator, AxisNonlinearCalibrator, save_model)
if __name__ == "__main__":  # python make_files.py OUT_DIR (not run when pytest collects doctests)
    out = sys.argv[1]
    rng = np.random.default_rng(7)
    w = rng.normal(size=(80, 6)) * [50, 50, 50, 1, 1, 1]
    raw = w @ rng.normal(size=(6, 6)) / 50 + 0.3
    T = rng.uniform(15, 35, size=80)
    tiny = dict(hidden_layer_sizes=(8,), max_epochs=3, plateau_epochs=1, max_recover_epochs=1, batch_size=16)
    models = {
        "linear": (LinearCalibrator().fit(raw, w), raw),
        "axis_nonlinear": (AxisNonlinearCalibrator().fit(raw, w), raw),
        "directional": (DirectionalCalibrator(random_state=0, **tiny).fit(raw, w), raw),
        "ensemble": (EnsembleCalibrator(LinearCalibrator(), n_members=2, random_state=0).fit(raw, w), raw),
        "auto": (AutoCalibrator(candidates=[("linear", LinearCalibrator()), ("poly", PolynomialCalibrator(degree=2))],
                                cv=3).fit(raw, w), raw),
        "temperature": (TemperatureCompensatedCalibrator(LinearCalibrator()).fit(np.column_stack([raw, T]), w),
                        np.column_stack([raw, T])),
    }
    for name, (model, X) in models.items():
        save_model(model, f"{out}/{name}.model.npz", overwrite=True)
        np.save(f"{out}/{name}.expected.npy", model.predict(X[:5]))
    np.save(f"{out}/readings.npy", np.column_stack([raw, T])[:5])
    print(ftcal.__file__)
