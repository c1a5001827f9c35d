"""What ftcal's fits lose by not limiting BLAS threads process-wide (and by limiting torch's in the fitting thread only).

Usage::

    python benchmarks/thread_limits.py [--repeats 5] [--auto]

OpenBLAS has one thread count per process: a ``threadpool_limits(1, user_api="blas")`` inside ``fit`` (what ftcal
did before) slows every other thread of the user's program while the fit runs. ftcal's fits now limit torch's
OpenMP threads in the fitting thread only, and BLAS only when the fitting thread is the process' only thread
(:mod:`ftcal.core._threads`). This script times, in one process and interleaved (so a slow spell of a shared
machine hits all alike), each fit **as before** (inside a process-wide ``threadpool_limits(1)``: BLAS and OpenMP,
as the old ``fit`` set them), **as now** in a single-threaded program (the CLI, a script, a worker process) and
**as now with another thread alive** (an idle thread: BLAS is then left alone, the price of not touching that
thread), and prints the medians and the ratios to "before" (<= 1.10 is the target for the single-threaded case).
``--auto`` adds an ``AutoCalibrator(n_jobs=1)`` fit on 400 soft-sensor rows (minutes).
"""

from __future__ import annotations

import argparse
import os
import threading
import statistics
import time
import warnings

import numpy as np
from threadpoolctl import threadpool_info, threadpool_limits

import ftcal


def cases(auto: bool):
    rng = np.random.default_rng(0)
    X = rng.normal(size=(5000, 8))
    Y = X[:, :6] @ rng.normal(size=(6, 6)) + 0.05 * X[:, 6:7] ** 2
    soft = ftcal.simulation.make_soft_sensor_dataset(random_state=0)
    yield "LinearCalibrator, 5000 x 8", lambda: ftcal.LinearCalibrator().fit(X, Y)
    yield "PolynomialCalibrator(degree=2), 5000 x 8", lambda: ftcal.PolynomialCalibrator(degree=2).fit(X, Y)
    yield "GaussianProcessCalibrator (rbf, shared), 418 x 8", lambda: ftcal.GaussianProcessCalibrator(
        mean="none", kernel="rbf", per_output=False, random_state=0).fit(soft.raw, soft.wrench)
    yield "DirectionalCalibrator, 20 epochs, 2000 x 8", lambda: ftcal.DirectionalCalibrator(
        phase1_epochs=20, plateau_epochs=0, max_recover_epochs=0, random_state=0).fit(X[:2000], Y[:2000])
    if auto:
        yield "AutoCalibrator(n_jobs=1), 400 x 8", lambda: ftcal.AutoCalibrator(n_jobs=1, random_state=0).fit(
            soft.raw[:400], soft.wrench[:400])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--auto", action="store_true")
    args = parser.parse_args(argv)
    warnings.simplefilter("ignore")
    pools = ", ".join(f"{i['internal_api']} {i['num_threads']}" for i in threadpool_info())
    print(f"thread pools: {pools}; load average before: {os.getloadavg()[0]:.2f}")
    print("\n| fit | before: process-wide limit [s] | now, one thread [s] | ratio | now, another thread alive [s] "
          "| ratio |\n|---|---|---|---|---|---|")
    for name, fit in cases(args.auto):
        fit()  # warm-up (imports, caches)
        times: dict = {"before": [], "now": [], "other": []}
        for _ in range(args.repeats):
            for how in times:
                start = time.perf_counter()
                if how == "before":
                    with threadpool_limits(1):
                        fit()
                elif how == "now":
                    fit()
                else:
                    release = threading.Event()
                    idle = threading.Thread(target=release.wait)
                    idle.start()
                    start = time.perf_counter()
                    fit()
                    release.set()
                    idle.join()
                times[how].append(time.perf_counter() - start)
        before, now, other = (statistics.median(times[k]) for k in ("before", "now", "other"))
        print(f"| {name} | {before:.3f} | {now:.3f} | {now / before:.3f} | {other:.3f} | {other / before:.3f} |",
              flush=True)
    print(f"\nload average after: {os.getloadavg()[0]:.2f}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
