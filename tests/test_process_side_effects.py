"""A fit or a model load changes nothing of the process beyond the estimator: other threads keep their BLAS and
OpenMP threads while a fit runs, and torch's global random generator is left as it was."""

import threading
from pathlib import Path

import numpy as np
import pytest
import torch
from threadpoolctl import threadpool_info, threadpool_limits

from ftcal import (DirectionalCalibrator, GaussianProcessCalibrator, LinearCalibrator,
                   PolynomialCalibrator, load_model, save_model)

V2 = Path(__file__).parent / "data" / "model_files_v2"
#: These tests look at what a fit does beside threads of the user's: the process is not claimed for ftcal here
#: (conftest.py declares it ftcal's for every other test: the test runner's threads never compute).
pytestmark = pytest.mark.user_threads


def _pools() -> dict:
    return {pool["filepath"]: pool["num_threads"] for pool in threadpool_info()}


class _Pause:
    """Holds a fit at one point (``wait``, called from inside it) until the test has looked and releases it."""

    def __init__(self):
        self.inside, self.release = threading.Event(), threading.Event()

    def wait(self):
        if not self.inside.is_set():
            self.inside.set()
            assert self.release.wait(60), "the test never released the fit"


class _PausingReadings:
    """Readings that hold the fit at its first look at them (inside ``fit``, where the BLAS limit applies)."""

    def __init__(self, values, pause):
        self.values, self.pause = values, pause

    def __array__(self, dtype=None, copy=None):
        self.pause.wait()
        return np.asarray(self.values, dtype=dtype)

    def __len__(self):
        return len(self.values)

    @property
    def shape(self):
        return self.values.shape


def _pausing_in_training(pause):
    """A skorch callback that holds a network's fit at its first epoch: inside training, where the network's
    torch / OpenMP limit applies (entered after the data are validated)."""
    from skorch.callbacks import Callback

    class PauseInTraining(Callback):
        def on_epoch_begin(self, net, **kwargs):
            pause.wait()

    return PauseInTraining()


@pytest.mark.parametrize("make, in_training", [
    (lambda pause: LinearCalibrator(), False),
    (lambda pause: PolynomialCalibrator(degree=2), False),
    (lambda pause: GaussianProcessCalibrator(mean="none", kernel="rbf", per_output=False, random_state=0), False),
    (lambda pause: DirectionalCalibrator(hidden_layer_sizes=(8,), phase1_epochs=2, plateau_epochs=0,
                                         max_recover_epochs=0, random_state=0, n_threads=1,  # a limit in force
                                         callbacks=[_pausing_in_training(pause)]), True),
], ids=["linear", "polynomial", "gaussian_process", "directional"])
def test_a_thread_outside_fit_keeps_its_blas_and_openmp_threads_while_a_fit_runs(make, in_training):
    rng = np.random.default_rng(0)
    wrench = rng.normal(size=(60, 6))
    raw = wrench @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(60, 6))
    pause = _Pause()
    readings = raw if in_training else _PausingReadings(raw, pause)
    # the process' own thread counts (a threadpool_limits around the test would hide a limit set in another thread:
    # OpenBLAS then ignores the other thread's setting)
    before, torch_threads = _pools(), torch.get_num_threads()
    if min(before.values()) < 2:
        pytest.skip(f"the thread pools run one thread already ({before}): a limit to one could not show")
    errors = []

    def fit():
        try:
            make(pause).fit(readings, wrench)
        except BaseException as exc:  # reported by the main thread
            errors.append(exc)
            pause.inside.set()

    worker = threading.Thread(target=fit)
    worker.start()
    assert pause.inside.wait(60)
    during, torch_during = _pools(), torch.get_num_threads()
    pause.release.set()
    worker.join(120)
    assert not errors, errors
    assert during == before
    assert torch_during == torch_threads


def _in_a_fresh_process(script: str, *args: str) -> dict:
    """The JSON that ``script`` prints last, run with ``args`` in a new Python process: a check of the process'
    thread counts that no thread of another test may change meanwhile."""
    import json
    import subprocess
    import sys

    done = subprocess.run([sys.executable, "-c", script, *args], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


_LIMIT_IN_ANOTHER_THREAD = r"""
import json, threading
import scipy.linalg  # both OpenBLAS libraries loaded: numpy's and scipy's
from threadpoolctl import threadpool_info, threadpool_limits

def pools():
    return {p["filepath"]: p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"}

inside, release = threading.Event(), threading.Event()

def limit_everything():
    limits = threadpool_limits(limits=1, user_api="blas")
    inside.set()
    release.wait(60)  # held while the other thread looks, as a fit is
    limits.restore_original_limits()

before = pools()
worker = threading.Thread(target=limit_everything)
worker.start()
inside.wait(60)
during = pools()
release.set()
worker.join(60)
print(json.dumps({"before": before, "during": during}))
"""


def test_a_limit_set_for_the_whole_process_in_another_thread_would_show():
    """The check above can fail: a process-wide BLAS limit to one thread, set in another thread that is still
    inside its work (as a paused fit is), is seen here. In a fresh process: no thread of another test may change
    the process' count meanwhile."""
    facts = _in_a_fresh_process(_LIMIT_IN_ANOTHER_THREAD)
    if min(facts["before"].values()) < 2:
        pytest.skip(f"the thread pools run one thread already ({facts['before']}): a limit to one could not show")
    assert facts["during"] != facts["before"] and min(facts["during"].values()) == 1


_BESIDE_IDLE_THREADS = r"""
import json, sys, threading
import numpy as np
from joblib import Parallel, delayed
from threadpoolctl import threadpool_info
from ftcal import LinearCalibrator
from ftcal.cli import main

def blas():
    return sorted({p["num_threads"] for p in threadpool_info() if p["user_api"] == "blas"})

Parallel(n_jobs=2)(delayed(np.sum)(np.ones(3)) for _ in range(2))  # joblib's pool threads stay alive after it
seen, original = [], LinearCalibrator._fit
def recording_fit(self, *args, **kwargs):
    seen.append({"threads": sorted(t.name for t in threading.enumerate()), "blas": blas()})
    return original(self, *args, **kwargs)
LinearCalibrator._fit = recording_fit
before = blas()
code = main(["fit", sys.argv[1], "--model", "linear", "--out", sys.argv[2]])  # not -q: its progress timer runs
print(json.dumps({"code": code, "before": before, "seen": seen, "after": blas()}))
"""


def test_fits_run_blas_on_one_thread_beside_threads_known_idle(tmp_path):
    """A script that used a joblib process pool keeps its pool's threads; the command shows a fit's progress from
    a timer thread: neither computes, so the fit still runs BLAS on one thread (with the process' BLAS threads
    these fits took 4.8-17x longer), and the process' count is restored after it. In a fresh process: the test
    runner's own threads are not among those ftcal knows idle."""
    from ftcal import CalibrationDataset

    rng = np.random.default_rng(0)
    wrench = rng.normal(size=(60, 6))
    path = CalibrationDataset(raw=wrench @ rng.normal(size=(6, 6)), wrench=wrench).save(tmp_path / "d.csv")
    facts = _in_a_fresh_process(_BESIDE_IDLE_THREADS, str(path), str(tmp_path / "m"))
    if facts["before"] == [1]:
        pytest.skip(f"BLAS runs one thread in a fresh process here ({facts['before']}): a limit could not show")
    assert facts["code"] == 0 and facts["seen"]
    assert any("ftcal-idle-progress" in fit["threads"] for fit in facts["seen"])  # the timer beside the fit
    assert all("ExecutorManagerThread" in fit["threads"] for fit in facts["seen"])  # and joblib's pool threads
    assert all(fit["blas"] == [1] for fit in facts["seen"]), facts["seen"]
    assert facts["after"] == facts["before"]


_OVERLAPPING_FITS = r"""
import json, threading
import scipy.linalg  # both OpenBLAS libraries loaded: numpy's and scipy's
from threadpoolctl import threadpool_info
from ftcal.core._threads import limit_threads_here, whole_process_is_ftcal

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
with whole_process_is_ftcal():
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
    """Two fits in two threads of a process declared ftcal's: the first leaves while the second runs, which keeps
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


class _PausingLinear(LinearCalibrator):
    """An LTM whose first fit while ``armed`` waits (inside the report's fold) until the test releases it."""

    armed, inside, release = False, threading.Event(), threading.Event()

    def fit(self, X, y, **kwargs):
        cls = type(self)
        if cls.armed and not cls.inside.is_set():
            cls.inside.set()
            assert cls.release.wait(60), "the test never released the fit"
        return super().fit(X, y, **kwargs)


def test_a_thread_outside_the_calibration_report_keeps_its_blas_threads_while_its_folds_are_fitted():
    from ftcal import CalibrationDataset, calibration_certificate

    rng = np.random.default_rng(1)
    wrench = rng.normal(size=(60, 6))
    data = CalibrationDataset(raw=wrench @ rng.normal(size=(6, 6)) + 0.01 * rng.normal(size=(60, 6)), wrench=wrench)
    model = _PausingLinear().fit(data.raw, data.wrench)
    before = _pools()
    if min(before.values()) < 2:
        pytest.skip(f"the thread pools run one thread already ({before}): a limit to one could not show")
    errors = []

    def report():
        try:
            calibration_certificate(model, data, cv=3, baselines=False, figures=False)
        except BaseException as exc:  # reported by the main thread
            errors.append(exc)
            _PausingLinear.inside.set()

    _PausingLinear.armed = True
    try:
        worker = threading.Thread(target=report)
        worker.start()
        assert _PausingLinear.inside.wait(60)
        during = _pools()
        _PausingLinear.release.set()
        worker.join(120)
    finally:
        _PausingLinear.armed = False
    assert not errors, errors
    assert during == before
