"""Speed of the calibrators: fit time, one-sample predict latency, throughput.

On ``--n-samples`` (default 5000) samples of a 6-channel affine sensor with
thesis-like loads (forces O(100 N), torques O(2 N·m)):

* fit time of each calibrator with the ``short`` schedule (median of
  ``--repeats`` runs) and with the ``thesis`` schedule (ONE run each: it takes
  minutes per model; skip it with ``--skip-thesis``);
* ``predict`` latency for one sample (median of ``--latency-calls`` calls);
* ``predict`` throughput on 10 000 samples (median of 5 calls);

each also as a ratio to the LinearCalibrator measured in the same process.
The figures are written to ``benchmarks/RESULTS.md`` under ``## Speed (issue 2)``
(other sections are kept); the short/predict figures are written before the
thesis runs start and completed afterwards.

Then the network figures (``benchmarks/network_speed.py``: the
lean loop against plain skorch, stacked ensembles against one member,
one-sample and bulk ``predict`` against the numpy forward pass).

Run: ``python benchmarks/speed.py`` (about 10-40 min on 2 cores, mostly the
thesis schedule); ``python benchmarks/speed.py --skip-thesis`` takes about two minutes.
"""

from __future__ import annotations

import argparse
import os
import platform
import re
import shlex
import statistics
import sys
import time
from pathlib import Path

import numpy as np
import torch

from ftcal.compose import CALIBRATOR_NAMES
from ftcal import make_calibrator

RESULTS = Path(__file__).with_name("RESULTS.md")
SECTION = "## Speed (issue 2)"
MODELS = ("linear", "comparative", "directional")


def sensor_data(n: int, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(seed)
    calibration = rng.normal(size=(6, 6)) * np.array([100.0] * 3 + [2.0] * 3)[:, None]
    raw = rng.normal(size=(n, 6))
    return raw, raw @ calibration.T


def fit_seconds(name: str, schedule: str, raw, wrench, repeats: int) -> tuple[float, object, list[float]]:
    times, model = [], None
    for i in range(repeats):
        model = make_calibrator(name, schedule=schedule, random_state=i)
        start = time.perf_counter()
        model.fit(raw, wrench)
        times.append(time.perf_counter() - start)
    return statistics.median(times), model, times


def predict_figures(model, raw, latency_calls: int) -> tuple[float, float]:
    one = raw[:1]
    model.predict(one)  # warm-up
    latency = []
    for _ in range(latency_calls):
        start = time.perf_counter()
        model.predict(one)
        latency.append(time.perf_counter() - start)
    big = np.resize(raw, (10_000, raw.shape[1]))
    through = []
    for _ in range(5):
        start = time.perf_counter()
        model.predict(big)
        through.append(time.perf_counter() - start)
    return statistics.median(latency), 10_000 / statistics.median(through)


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    return (
        f"{cpu}, {os.cpu_count()} logical cores, Python {platform.python_version()}, torch {torch.__version__} "
        f"(the calibrators run torch single-threaded in fit and predict); "
        f"other jobs were sharing the cores"
    )


def render(args, short: dict, thesis: dict, predict: dict) -> str:
    lin_fit = short["linear"][0]
    lin_lat, lin_thr = predict["linear"]
    lines = [
        SECTION,
        "",
        f"Command: `{' '.join(shlex.quote(a) for a in ['python', *sys.argv])}`  ",
        f"Machine: {machine()}  ",
        f"Data: {args.n_samples} samples, 6 channels; validation split 0.2; ratios are against "
        f"LinearCalibrator measured in the same process.",
        "",
        f"| model | fit, short schedule [s] (median of {args.repeats}) | ratio to LTM | epochs | "
        "fit, thesis schedule [s] (1 run) | epochs | predict 1 sample [ms] (median) | ratio to LTM | "
        "throughput on 10 000 [samples/s] | ratio to LTM |",
        "|---|---|---|---|---|---|---|---|---|---|",
    ]
    for name in MODELS:
        fit, epochs = short[name]
        t_fit, t_epochs = thesis.get(name, (None, None))
        lat, thr = predict[name]
        thesis_cell = "not run" if t_fit is None else f"{t_fit:.1f}"
        lines.append(
            f"| {name} | {fit:.3f} | {fit / lin_fit:.0f}x | {epochs} | {thesis_cell} | {t_epochs or '-'} | "
            f"{lat * 1e3:.3f} | {lat / lin_lat:.1f}x | {thr:,.0f} | {thr / lin_thr:.3f}x |"
        )
    lines += [
        "",
        "Schedules: `short` = 150 (directional) / 250 (comparative) phase-1 epochs + 30 plateau + up to 50 "
        "recover; `thesis` = 1700 / 3000 + 100 + up to 500 (see `ftcal.compose.training_schedule`). "
        "The thesis schedule was fitted once per model (minutes each), so its figure is one sample, not a median. "
        "Epochs = epochs actually run (phase 3 ends early by the 5 % rule).",
        "",
    ]
    return "\n".join(lines)


def write_section(text: str) -> None:
    old = RESULTS.read_text() if RESULTS.exists() else "# Benchmark results\n"
    pattern = re.compile(rf"^{re.escape(SECTION)}\n.*?(?=^## |\Z)", re.S | re.M)
    new = pattern.sub(lambda _: text, old) if pattern.search(old) else old.rstrip("\n") + "\n\n" + text
    RESULTS.write_text(new)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n-samples", type=int, default=5000)
    parser.add_argument("--repeats", type=int, default=3, help="runs of the short-schedule fit (median)")
    parser.add_argument("--latency-calls", type=int, default=1000)
    parser.add_argument("--skip-thesis", action="store_true", help="do not run the (slow) thesis schedule")
    parser.add_argument("--skip-networks", action="store_true",
                        help="do not run the issue-13 network figures (benchmarks/network_speed.py)")
    args = parser.parse_args(argv)
    assert set(MODELS) <= set(CALIBRATOR_NAMES)
    raw, wrench = sensor_data(args.n_samples)
    short, predict, thesis = {}, {}, {}
    for name in MODELS:
        seconds, model, times = fit_seconds(name, "short", raw, wrench, args.repeats)
        short[name] = (seconds, getattr(model, "n_epochs_", "-"))
        predict[name] = predict_figures(model, raw, args.latency_calls)
        print(f"{name}: short fit {times} s; predict {predict[name]}", flush=True)
    write_section(render(args, short, thesis, predict))
    if not args.skip_thesis:
        for name in MODELS:
            seconds, model, _ = fit_seconds(name, "thesis", raw, wrench, 1)
            thesis[name] = (seconds, getattr(model, "n_epochs_", "-"))
            print(f"{name}: thesis fit {seconds:.1f} s, {thesis[name][1]} epochs", flush=True)
            write_section(render(args, short, thesis, predict))
    print(f"wrote {RESULTS}")
    if not args.skip_networks:  # lean loop, stacked nets, inference, as ratios in this process
        import network_speed

        network_speed.main([])


if __name__ == "__main__":
    main()
