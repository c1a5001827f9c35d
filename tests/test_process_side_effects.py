"""A fit or a model load changes nothing of the process beyond the estimator, but for one documented, scoped
limit: while a fit runs, the process' BLAS runs one thread (as in scikit-learn's KMeans), whatever other threads
are alive, and the count is back after it; another thread keeps its OpenMP (torch) threads; torch's global random
generator is left as it was."""

import os
import threading
from pathlib import Path

import numpy as np
import pytest
import torch
from threadpoolctl import threadpool_info, threadpool_limits

from ftcal import (DirectionalCalibrator, GaussianProcessCalibrator, LinearCalibrator,
                   PolynomialCalibrator, load_model, save_model)

V2 = Path(__file__).parent / "data" / "model_files_v2"

@pytest.fixture(autouse=True)
def _torch_on_its_default_threads():
    """These tests look at a limit to one thread, which cannot show on a pool at one already: an xdist worker runs
    torch on one thread (the root conftest), so here torch gets its default back, a thread a core."""
    before = torch.get_num_threads()
    torch.set_num_threads(max(before, os.cpu_count() or 1))
    yield
    torch.set_num_threads(before)


def _pools() -> dict:
    return {pool["filepath"]: pool["num_threads"] for pool in threadpool_info()}


def _blas_pools() -> dict:
    return {pool["filepath"]: pool["num_threads"] for pool in threadpool_info() if pool["user_api"] == "blas"}


class _Look:
    """Records, from inside a fit (``wait``, called at its first look at the data or its first epoch), the process'
    thread pools as the fitting thread sees them, and the torch thread count of another live thread (the user's,
    which waits for the request and answers it)."""

    def __init__(self):
        self.asked, self.answered, self.done = threading.Event(), threading.Event(), threading.Event()
        self.seen: dict = {}

    def wait(self):
        if "fit" not in self.seen:
            self.seen["fit"] = _pools()
            self.asked.set()
            assert self.answered.wait(60), "the other thread never answered"

    def other_thread(self):
        while not self.done.is_set():
            if self.asked.wait(0.05):
                self.seen["other torch threads"] = torch.get_num_threads()
                self.answered.set()
                return


class _LookingReadings:
    """Readings that look at the threads at the fit's first look at them (inside ``fit``, where the limit applies)."""

    def __init__(self, values, look):
        self.values, self.look = values, look

    def __array__(self, dtype=None, copy=None):
        self.look.wait()
        return np.asarray(self.values, dtype=dtype)

    def __len__(self):
        return len(self.values)

    @property
    def shape(self):
        return self.values.shape


def _looking_in_training(look):
    """A skorch callback that looks at the threads at a network's first epoch: inside training, where the
    network's torch / OpenMP limit applies (entered after the data are validated)."""
    from skorch.callbacks import Callback

    class LookInTraining(Callback):
        def on_epoch_begin(self, net, **kwargs):
            look.wait()

    return LookInTraining()


@pytest.mark.parametrize("make, in_training", [
    (lambda look: LinearCalibrator(), False),
    (lambda look: PolynomialCalibrator(degree=2), False),
    (lambda look: GaussianProcessCalibrator(mean="none", kernel="rbf", per_output=False, random_state=0), False),
    (lambda look: DirectionalCalibrator(hidden_layer_sizes=(8,), phase1_epochs=2, plateau_epochs=0,
                                        max_recover_epochs=0, random_state=0, n_threads=1,  # a limit in force
                                        callbacks=[_looking_in_training(look)]), True),
], ids=["linear", "polynomial", "gaussian_process", "directional"])
def test_a_fit_runs_blas_on_one_thread_and_leaves_other_threads_openmp_alone(make, in_training):
    """Beside a live thread of the program's, the fit limits the process' BLAS to one thread (it never looks at
    other threads; OpenBLAS has one count per process), the other thread keeps its OpenMP (torch) count, and every
    count is as before after the fit. (The fit runs in the test's thread: OpenBLAS ignores a count set from another
    thread once one thread has set it.)"""
    rng = np.random.default_rng(0)
    wrench = rng.normal(size=(60, 6))
    raw = wrench @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(60, 6))
    look = _Look()
    readings = raw if in_training else _LookingReadings(raw, look)
    before = _pools()
    if min(before.values()) < 2:
        pytest.skip(f"the thread pools run one thread already ({before}): a limit to one could not show")
    with threadpool_limits(2, user_api="openmp"):  # the other thread starts with 2 torch threads
        user = threading.Thread(target=look.other_thread)
        user.start()
        try:
            make(look).fit(readings, wrench)
        finally:
            look.done.set()
            user.join(60)
    blas = set(_blas_pools())
    assert {path: n for path, n in look.seen["fit"].items() if path in blas} == dict.fromkeys(blas, 1)
    assert look.seen["other torch threads"] == 2
    if in_training:  # the network's n_threads: the fitting thread's OpenMP
        assert {n for path, n in look.seen["fit"].items() if path not in blas} == {1}
    assert _pools() == before


def _in_a_fresh_process(script: str, *args: str) -> dict:
    """The JSON that ``script`` prints last, run with ``args`` in a new Python process: a check of the process'
    thread counts that no thread of another test may change meanwhile."""
    import json
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", script, *args], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


_THE_COMMAND_S_POLICY = r"""
import json, sys, threading
import numpy as np
from joblib import Parallel, delayed
from threadpoolctl import threadpool_info
from ftcal import LinearCalibrator
from ftcal.cli import main

def blas():
    return sorted({p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"})

Parallel(n_jobs=2)(delayed(np.sum)(np.ones(3)) for _ in range(2))  # joblib's pool threads stay alive after it
done = threading.Event()
user = threading.Thread(target=done.wait, name="the-user-s-thread")  # a thread of the program's own
user.start()
seen, fit, predict = {"fit": [], "predict": []}, LinearCalibrator._fit, LinearCalibrator.predict
def recording_fit(self, *args, **kwargs):
    seen["fit"].append(blas())
    return fit(self, *args, **kwargs)
def recording_predict(self, *args, **kwargs):  # outside any fit: the command's own policy
    seen["predict"].append(blas())
    return predict(self, *args, **kwargs)
LinearCalibrator._fit, LinearCalibrator.predict = recording_fit, recording_predict
before = blas()
code = main(["fit", sys.argv[1], "--model", "linear", "--out", sys.argv[2]])  # not -q: its progress timer runs
after = blas()
done.set()
user.join()
print(json.dumps({"code": code, "before": before, "seen": seen, "after": after}))
"""


def test_the_command_runs_blas_on_one_thread_whatever_threads_are_alive_and_restores_it(tmp_path):
    """The command sets its process' policy once (one BLAS thread, for the fits and everything between them),
    beside a joblib pool's threads, its progress timer and a thread of the calling program's; after it returns,
    the program's count is back. In a fresh process: no thread of another test may change the count meanwhile."""
    from ftcal import CalibrationDataset

    rng = np.random.default_rng(0)
    wrench = rng.normal(size=(60, 6))
    path = CalibrationDataset(raw=wrench @ rng.normal(size=(6, 6)), wrench=wrench).save(tmp_path / "d.csv")
    facts = _in_a_fresh_process(_THE_COMMAND_S_POLICY, str(path), str(tmp_path / "m"))
    if facts["before"] == [1]:
        pytest.skip(f"BLAS runs one thread in a fresh process here ({facts['before']}): a limit could not show")
    assert facts["code"] == 0 and facts["seen"]["fit"] and facts["seen"]["predict"]
    assert all(seen == [1] for seen in facts["seen"]["fit"] + facts["seen"]["predict"]), facts["seen"]
    assert facts["after"] == facts["before"]


_OVERLAPPING_FITS = r"""
import json, threading
import scipy.linalg  # both OpenBLAS libraries loaded: numpy's and scipy's
from threadpoolctl import threadpool_info
from ftcal.core._threads import limit_threads_here

def blas():
    return sorted({p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"})

first_in, second_in, first_out, release_second = (threading.Event() for _ in range(4))
seen = {}

def first():
    with limit_threads_here(1):
        first_in.set()
        second_in.wait(60)
    first_out.set()

def second():
    first_in.wait(60)
    with limit_threads_here(1):
        second_in.set()
        first_out.wait(60)
        seen["second, after the first left"] = blas()
        release_second.wait(60)

before = blas()
threads = [threading.Thread(target=first), threading.Thread(target=second)]
for t in threads:
    t.start()
first_out.wait(60)
seen["main, after the first left"] = blas()
release_second.set()
for t in threads:
    t.join(60)
print(json.dumps({"before": before, "seen": seen, "after": blas()}))
"""


def test_fits_that_overlap_share_the_blas_limit_and_the_last_restores_it():
    """Two fits in two threads: the first leaves while the second runs, which keeps
    BLAS on one thread; the last to leave restores the process' count (restoring in entry order left it at 1). In
    a fresh process: no thread of another test may change the process' count meanwhile."""
    facts = _in_a_fresh_process(_OVERLAPPING_FITS)
    if facts["before"] == [1]:
        pytest.skip(f"BLAS runs one thread in a fresh process here ({facts['before']}): a limit could not show")
    assert facts["seen"] == {"second, after the first left": [1], "main, after the first left": [1]}
    assert facts["after"] == facts["before"]


def test_the_networks_thread_limit_holds_in_the_fitting_thread():
    """n_threads limits torch in the thread that fits (OpenMP keeps a count per thread)."""
    seen = []

    from skorch.callbacks import Callback

    class Record(Callback):
        def on_epoch_end(self, net, **kwargs):
            seen.append(torch.get_num_threads())

    rng = np.random.default_rng(1)
    wrench = rng.normal(size=(40, 6))
    raw = wrench @ rng.normal(size=(6, 6))
    with threadpool_limits(2, user_api="openmp"):
        DirectionalCalibrator(hidden_layer_sizes=(8,), phase1_epochs=2, plateau_epochs=0, max_recover_epochs=0,
                              n_threads=1, callbacks=[Record()], random_state=0).fit(raw, wrench)
        assert torch.get_num_threads() == 2
    assert seen and set(seen) == {1}


@pytest.mark.parametrize("name", ["directional", "comparative", "ensemble"])
def test_load_model_leaves_torchs_global_generator_as_it_was(name):
    torch.manual_seed(123)
    torch.rand(2)  # the generator in some state past its seed
    state = torch.random.get_rng_state()
    expected_next = torch.rand(3)
    torch.random.set_rng_state(state)
    load_model(V2 / f"{name}.model.npz")
    assert torch.initial_seed() == 123
    assert torch.equal(torch.rand(3), expected_next)


@pytest.mark.parametrize("name", ["directional", "comparative", "ensemble"])
def test_network_files_written_before_the_networks_encoded_their_own_weights_still_load(name, tmp_path):
    """Files of format version 2 written by tests/data/model_files_v2/make_files.py (before the weight hooks)
    predict exactly as when they were saved, and save again to the same arrays."""
    model = load_model(V2 / f"{name}.model.npz")
    readings = np.load(V2 / "readings.npy")
    np.testing.assert_array_equal(model.predict(readings), np.load(V2 / f"{name}.expected.npy"))
    again = save_model(model, tmp_path / "again.model.npz")
    with np.load(V2 / f"{name}.model.npz") as old, np.load(again) as new:
        weights = sorted(k for k in old.files if "module/" in k)
        assert weights and weights == sorted(k for k in new.files if "module/" in k)
        for k in weights:
            np.testing.assert_array_equal(old[k], new[k])


class _RecordingLinear(LinearCalibrator):
    """An LTM that records the process' BLAS counts at each fit while ``armed`` (inside the report's folds)."""

    armed, seen = False, []

    def fit(self, X, y, **kwargs):
        if type(self).armed:
            type(self).seen.append(set(_blas_pools().values()))
        return super().fit(X, y, **kwargs)


def test_the_calibration_report_runs_its_fold_loop_with_one_blas_thread_and_restores_the_count():
    """The report's fold loop (ftcal's own small fits) is one scoped limit: BLAS on one thread while it runs, and
    the count as before after it."""
    from ftcal import CalibrationDataset, calibration_certificate

    rng = np.random.default_rng(1)
    wrench = rng.normal(size=(60, 6))
    data = CalibrationDataset(raw=wrench @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(60, 6)), wrench=wrench)
    model = _RecordingLinear().fit(data.raw, data.wrench)
    before = _pools()
    if min(before.values()) < 2:
        pytest.skip(f"the thread pools run one thread already ({before}): a limit to one could not show")
    _RecordingLinear.armed, _RecordingLinear.seen = True, []
    try:
        calibration_certificate(model, data, cv=3, baselines=False, figures=False)
    finally:
        _RecordingLinear.armed = False
    assert _RecordingLinear.seen and all(seen == {1} for seen in _RecordingLinear.seen), _RecordingLinear.seen
    assert _pools() == before
