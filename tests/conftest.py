"""Shared fixtures of the calibrator tests: small data sets and tiny training schedules."""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
import ftcal
import pytest

from ftcal import (
    AutoCalibrator,
    AxisNonlinearCalibrator,
    ComparativeCalibrator,
    DirectionalCalibrator,
    EnsembleCalibrator,
    GaussianProcessCalibrator,
    LinearCalibrator,
    PolynomialCalibrator,
    HistoryCalibrator,
    TemperatureCompensatedCalibrator,
)
from ftcal.compose._auto import StackedCalibrator
from ftcal.calibrators._baselines import StockCalibrator

#: ``tests/data`` holds the scripts that wrote the stored model files (each folder's ``make_files.py``): data, not
#: tests, and two modules of one name, which ``--doctest-modules`` would otherwise import as one.
collect_ignore_glob = ["data/*"]

# the benchmark scripts import their shared helpers (benchmarks/_output.py) as when run from their folder
BENCHMARKS = Path(__file__).resolve().parents[1] / "benchmarks"
if str(BENCHMARKS) not in sys.path:
    sys.path.append(str(BENCHMARKS))

#: A schedule of a handful of epochs: enough to exercise all three phases in well under a second.
TINY_SCHEDULE = dict(
    hidden_layer_sizes=(16, 16),
    phase1_epochs=6,
    plateau_epochs=3,
    plateau_patience=1,
    max_recover_epochs=3,
    batch_size=32,
)


#: ``ftcal fit`` options for a network small enough for a test and trained enough to beat the mean wrench on the
#: simulated datasets (``ftcal fit`` refuses to save a network that does not: its degenerate-calibration check).
SMALL_NET_CLI = ["--schedule", "short", "--param", "phase1_epochs=20", "--param", "plateau_epochs=1",
                 "--param", "max_recover_epochs=1", "--param", "hidden_layer_sizes=[16]"]


#: Names of the first instances of :func:`tiny_calibrators`, in order: every public calibrator of ftcal (each run
#: by the ``tiny_calibrator`` fixture through the shared tests on affine data).
#: Registry names the instances below stand for; every other registered calibrator joins the list, built with its
#: defaults by the registry (so a calibrator added in one module and one registry line is in the common checks).
_COVERED = {"linear", "comparative", "directional", "polynomial", "axis_nonlinear", "directional_ensemble",
            "comparative_ensemble", "gaussian_process", "auto", "stock"}
_REGISTERED = tuple(name for name in ftcal.compose.CALIBRATOR_NAMES if name not in _COVERED)
CALIBRATOR_KINDS = ("linear", "comparative", "directional", "polynomial", "axis_nonlinear", "ensemble",
                    "gaussian_process", "auto", "stock") + _REGISTERED
#: Names of its last instances: the wrappers, in the common checks too, but whose data are not the shared affine
#: data (a temperature column; fitted members; rows in time order), tested in test_sklearn_compat.py::test_wrappers_*.
WRAPPER_KINDS = ("stacked", "temperature_compensated", "history")


def tiny_calibrators(random_state: int = 0) -> list:
    """One instance of every public calibrator, the networks with :data:`TINY_SCHEDULE`, then the wrappers.

    Names in :data:`CALIBRATOR_KINDS` then :data:`WRAPPER_KINDS`.
    """
    return [
        LinearCalibrator(),
        ComparativeCalibrator(**TINY_SCHEDULE, random_state=random_state),
        DirectionalCalibrator(**TINY_SCHEDULE, random_state=random_state),
        PolynomialCalibrator(degree=2),
        AxisNonlinearCalibrator(),
        EnsembleCalibrator(DirectionalCalibrator(**TINY_SCHEDULE), n_members=2, random_state=random_state),
        GaussianProcessCalibrator(max_samples=100, mean="linear", kernel="rbf", per_output=False,
                                  random_state=random_state),
        AutoCalibrator(candidates=[("linear", LinearCalibrator()), ("polynomial", PolynomialCalibrator(degree=2))],
                       cv=3, baselines=False),
        StockCalibrator(baseline="sk_poly2"),  # a stock baseline as auto's candidate (saved as its arrays)
        *(ftcal.make_calibrator(name, random_state=random_state) for name in _REGISTERED),
        StackedCalibrator(estimators=[LinearCalibrator(), PolynomialCalibrator(degree=2)], weights=[0.5, 0.5]),
        TemperatureCompensatedCalibrator(LinearCalibrator()),
        HistoryCalibrator(LinearCalibrator(), taus=(1.0, 4.0), cv=3),
    ]


def affine_sensor_data(n_samples: int = 120, n_channels: int = 6, seed: int = 0):
    """Noise-free affine sensor: raw readings ``S``, wrenches ``W = C S + b``, and ``C``, ``b``.

    Forces are O(100 N), torques O(2 N·m), like a mid-range F/T sensor.
    """
    rng = np.random.default_rng(seed)
    calibration = rng.normal(size=(6, n_channels)) * np.array([100.0] * 3 + [2.0] * 3)[:, None]
    offset = rng.normal(size=6) * np.array([5.0] * 3 + [0.1] * 3)
    raw = rng.normal(size=(n_samples, n_channels))
    wrench = raw @ calibration.T + offset
    return raw, wrench, calibration, offset


@pytest.fixture
def affine_data():
    return affine_sensor_data()


@pytest.fixture(params=CALIBRATOR_KINDS)
def tiny_calibrator(request):
    """Each public calibrator in turn, networks with the tiny schedule."""
    return dict(zip(CALIBRATOR_KINDS, tiny_calibrators()))[request.param]
