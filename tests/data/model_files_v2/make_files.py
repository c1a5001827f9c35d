"""Writes the network model files of tests/data/model_files_v2 with ftcal before the networks encoded their own
weights (format version 2, main at 26ef161): python make_files.py OUT_DIR."""
import sys
import numpy as np
import ftcal
from ftcal import ComparativeCalibrator, DirectionalCalibrator, EnsembleCalibrator, save_model
if __name__ == "__main__":  # not run when pytest collects doctests
    out = sys.argv[1]
    rng = np.random.default_rng(11)
    w = rng.normal(size=(80, 6)) * [50, 50, 50, 1, 1, 1]
    raw = w @ rng.normal(size=(6, 6)) / 50 + 0.3
    tiny = dict(hidden_layer_sizes=(8, 5), max_epochs=3, plateau_epochs=1, max_recover_epochs=1, batch_size=16)
    models = {
        "directional": DirectionalCalibrator(random_state=0, **tiny).fit(raw, w),
        "comparative": ComparativeCalibrator(random_state=1, **tiny).fit(raw, w),
        "ensemble": EnsembleCalibrator(DirectionalCalibrator(**tiny), n_members=2, random_state=0).fit(raw, w),
    }
    for name, model in models.items():
        save_model(model, f"{out}/{name}.model.npz", overwrite=True)
        np.save(f"{out}/{name}.expected.npy", model.predict(raw[:5]))
    np.save(f"{out}/readings.npy", raw[:5])
    print(ftcal.__file__)
