"""What ftcal's thread policy costs its fits, beside the threads a program may have alive.

Usage::

    python benchmarks/thread_limits.py [--repeats 5] [--json out.json]

ftcal runs BLAS on one thread inside each fit, unconditionally and scoped (:mod:`ftcal.core._threads`, as
scikit-learn's ``KMeans``); an earlier policy limited BLAS only when every other live thread was one it knew idle
(joblib's pool threads, tqdm's monitor, its progress timer) and left it alone beside any other thread. This script
times, in one process and interleaved (so a slow spell of a shared machine hits all alike), each fit **alone**,
**beside a joblib process pool's threads** (alive after any ``Parallel(n_jobs=2)``: what ``auto`` and the report
leave behind, and the command's progress timer is another such thread) and **beside a thread of the program's**
(an idle one, as a notebook has), and prints the medians. Run it under two revisions (``PYTHONPATH``) to compare
policies; it uses public names only.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import threading
import time
import warnings

import numpy as np
from threadpoolctl import threadpool_info

import ftcal


def cases():
    rng = np.random.default_rng(0)
    X = rng.normal(size=(5000, 8))
    Y = X[:, :6] @ rng.normal(size=(6, 6)) + 0.05 * X[:, 6:7] ** 2
    soft = ftcal.simulation.make_soft_sensor_dataset(random_state=0)
    yield "LinearCalibrator, 5000 x 8", lambda: ftcal.LinearCalibrator().fit(X, Y)
    yield "PolynomialCalibrator(degree=2), 5000 x 8", lambda: ftcal.PolynomialCalibrator(degree=2).fit(X, Y)
    yield "GaussianProcessCalibrator (rbf, shared), 200 x 8", lambda: ftcal.GaussianProcessCalibrator(
        mean="none", kernel="rbf", per_output=False, random_state=0).fit(soft.raw[:200], soft.wrench[:200])


def _beside_user_thread(fit):
    release = threading.Event()
    other = threading.Thread(target=release.wait, name="the-program-s-thread")
    other.start()
    try:
        start = time.perf_counter()
        fit()
        return time.perf_counter() - start
    finally:
        release.set()
        other.join()


def _timed(fit):
    start = time.perf_counter()
    fit()
    return time.perf_counter() - start


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--json", help="also write the medians here")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    import scipy.linalg  # noqa: F401  (both OpenBLAS libraries loaded, as in any fit)

    pools = ", ".join(f"{i['internal_api']} {i['num_threads']}" for i in threadpool_info())
    print(f"ftcal from {ftcal.__file__}; thread pools: {pools}; load average before: {os.getloadavg()[0]:.2f}")
    from joblib import Parallel, delayed

    situations = {"alone": _timed, "beside joblib's pool threads": _timed, "beside a thread of the program's":
                  _beside_user_thread}
    results = {}
    print("\n| fit | " + " | ".join(f"{s} [s]" for s in situations) + " |\n|---|" + "---|" * len(situations))
    for name, fit in cases():
        fit()  # warm-up (imports, caches)
        times: dict = {s: [] for s in situations}
        for _ in range(args.repeats):
            for situation, run in situations.items():
                if situation == "beside joblib's pool threads":  # the pool's manager thread stays alive after it
                    Parallel(n_jobs=2)(delayed(np.sum)(np.ones(3)) for _ in range(2))
                    assert any("ExecutorManager" in type(t).__name__ for t in threading.enumerate())
                times[situation].append(run(fit))
        results[name] = {s: statistics.median(v) for s, v in times.items()}
        print(f"| {name} | " + " | ".join(f"{results[name][s]:.3f}" for s in situations) + " |", flush=True)
    print(f"\nload average after: {os.getloadavg()[0]:.2f}")
    if args.json:
        with open(args.json, "w") as out:
            json.dump({"ftcal": ftcal.__file__, "medians": results, "load": os.getloadavg()}, out, indent=1)
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
