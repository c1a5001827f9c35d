"""Writes the wrapper model files of tests/data/model_files_v3 with ftcal before the wrappers shared one composition
(main at c026f98): each re-tared, so the file holds the tare, torque scale and range: python make_files.py OUT_DIR."""
import sys
import numpy as np
import ftcal
from ftcal import (EnsembleCalibrator, HistoryCalibrator, LinearCalibrator, PolynomialCalibrator,
                   TemperatureCompensatedCalibrator, save_model)
from ftcal.calibrators import StockCalibrator
if __name__ == "__main__":  # not run when pytest collects doctests
    out = sys.argv[1]
    rng = np.random.default_rng(12)
    w = rng.normal(size=(120, 6)) * [50, 50, 50, 1, 1, 1]
    raw = w @ rng.normal(size=(6, 6)) / 50 + 0.3 + 0.001 * rng.normal(size=(120, 6))
    temperature = rng.uniform(15, 35, size=(120, 1))
    shift = np.full((8, 6), 0.31) + 0.001 * rng.normal(size=(8, 6))  # a zero that moved by +0.01
    models = {
        "ensemble": (EnsembleCalibrator(LinearCalibrator(), n_members=2, random_state=0).fit(raw, w), raw),
        "history": (HistoryCalibrator(LinearCalibrator(), taus=(2.0,), cv=3).fit(raw, w), raw),
        "stock": (StockCalibrator(baseline="sk_poly2").fit(raw, w), raw),
        "temperature": (TemperatureCompensatedCalibrator(PolynomialCalibrator(degree=2)).fit(
            np.hstack([raw, temperature]), w), np.hstack([raw, temperature])),
    }
    for name, (model, X) in models.items():
        model.retare(shift if X.shape[1] == 6 else np.hstack([shift, np.full((8, 1), 25.0)]))
        save_model(model, f"{out}/{name}.model.npz", overwrite=True)
        np.save(f"{out}/{name}.expected.npy", model.predict(X[:5]))
        np.save(f"{out}/{name}.readings.npy", X[:5])
    print(ftcal.__file__)
