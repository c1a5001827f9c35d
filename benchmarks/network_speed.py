"""Figures of the one training engine (skorch's loop) and the numpy inference path, as ratios in one process.

Usage::

    python benchmarks/network_speed.py [--repeats 3] [--epochs 20] [--latency-calls 3000]

Timed runs of the fits are interleaved (plain, ftcal, floor; ensemble, one member), so that a slow spell of a
shared or virtual machine hits a measurement and its baseline alike.

* fit: ``DirectionalCalibrator`` with a fixed number of epochs (phase 1 only) against a plain
  ``skorch.NeuralNetRegressor`` with the same net (64, 64, 64), data (4000 x 6), batch size (32), epochs,
  Adam lr and 20 % validation split; medians of ``--repeats`` runs; also the final held-out RMSE of both;
* stacked training: a 5-member ``EnsembleCalibrator`` of that directional model (members trained together
  as one stacked module) against one member's fit, and ``ftcal.networks.fit_stacked`` of ``--stack`` nets (one per
  seed) against one fit, per net;
* the floor of the fit: the same net, split, batches, epochs, fused Adam and per-epoch validation loss in a
  bare torch loop (autograd, no skorch): what an engine that calls a user's skorch callbacks per batch cannot beat;
* predict: one-sample ``predict`` latency against the numpy forward pass of the same fitted net (median of
  ``--latency-calls`` calls), and 100 000-row ``predict`` throughput against the numpy forward's.

Everything runs single-threaded (torch and BLAS): the script sets it for the plain skorch baseline too;
ftcal's networks limit themselves to ``n_threads=1`` (a threadpoolctl context) by default.
"""

from __future__ import annotations

import argparse
import os
import platform
import statistics
import time

import numpy as np
import torch
from skorch import NeuralNetRegressor
from skorch.dataset import ValidSplit
from sklearn.base import clone
from threadpoolctl import threadpool_limits

import ftcal
from ftcal.networks import DirectionalNet, WeightedSquaredError


def data(n: int, seed: int):
    rng = np.random.default_rng(seed)
    w = rng.normal(size=(n, 6)) * np.array([100.0] * 3 + [2.0] * 3)
    seen = w + 2e-5 * w * np.abs(w)  # mildly nonlinear gauges (up to ~1 % at 300 N)
    return seen @ np.random.default_rng(99).normal(size=(6, 6)) * 0.01, w  # one sensor for every seed


def median_time(fn, repeats: int) -> tuple[float, object]:
    times, out = [], None
    for _ in range(repeats):
        start = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - start)
    return statistics.median(times), out


def _ratio(times: dict, a: str, b: str) -> float:
    """Median of ``times[a]`` over median of ``times[b]``."""
    return statistics.median(times[a]) / statistics.median(times[b])


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--epochs", type=int, default=20)
    parser.add_argument("--latency-calls", type=int, default=3000)
    parser.add_argument("--stack", type=int, default=30, help="nets in the fit_stacked measurement")
    args = parser.parse_args(argv)
    load_before = os.getloadavg()[0]
    raw, w = data(4000, 0)
    test_raw, test_w = data(2000, 1)
    torch.set_num_threads(1)

    def ftcal_fit():
        return ftcal.DirectionalCalibrator(phase1_epochs=args.epochs, plateau_epochs=0, max_recover_epochs=0,
                                           alpha=50.0, random_state=0).fit(raw, w)

    model = ftcal_fit()  # warm-up; also provides the directional inputs/targets for the plain net
    # the same network inputs and targets as the calibrator's (thesis eq. 3-8, scale normalised as documented)
    inputs = model.network_inputs(raw)
    scaled = ftcal.core.scale_torques(w, model.alpha_)
    magnitude = np.linalg.norm(scaled, axis=1, keepdims=True)
    v_in = np.linalg.norm(raw - model.zero_reading_, axis=1, keepdims=True)
    targets = np.hstack([scaled / magnitude, magnitude / v_in / model.scale_reference_])

    def plain_fit():
        torch.manual_seed(0)
        net = NeuralNetRegressor(
            DirectionalNet, criterion=WeightedSquaredError, criterion__weights=(1.0,) * 7,
            module__n_inputs=6, module__hidden_layer_sizes=(64, 64, 64), optimizer=torch.optim.Adam, lr=1e-3,
            batch_size=32, max_epochs=args.epochs, train_split=ValidSplit(0.2, random_state=0),
            iterator_train__shuffle=True, verbose=0,
        )
        return net.fit(inputs.astype(np.float32), targets.astype(np.float32))

    def bare_loop():
        """The floor of any engine that keeps skorch's per-batch contract with autograd: the same net, data split,
        batches, epochs and fused Adam as ftcal's fit, in a bare torch loop (no skorch, no callbacks, no history)."""
        torch.manual_seed(0)
        net = DirectionalNet(6, (64, 64, 64), 7)
        optimizer = torch.optim.Adam(net.parameters(), lr=1e-3, fused=True)
        n_train = len(inputs) - int(np.ceil(0.2 * len(inputs)))
        X_t = torch.from_numpy(inputs[:n_train].astype(np.float32))
        y_t = torch.from_numpy(targets[:n_train].astype(np.float32))
        X_v = torch.from_numpy(inputs[n_train:].astype(np.float32))
        y_v = torch.from_numpy(targets[n_train:].astype(np.float32))
        for _ in range(args.epochs):
            order = torch.randperm(n_train)
            X_e, y_e = X_t[order], y_t[order]
            for start in range(0, n_train, 32):
                for p in net.parameters():
                    p.grad = None
                loss = ((net(X_e[start:start + 32]) - y_e[start:start + 32]) ** 2).sum(dim=-1).mean()
                loss.backward()
                optimizer.step()
            with torch.no_grad():  # the epoch's validation loss, as every fit computes it
                float(((net(X_v) - y_v) ** 2).sum(dim=-1).mean())
        return net

    with threadpool_limits(1):  # interleaved, so that a slow spell of a shared machine hits all three alike
        times: dict = {"plain": [], "ftcal": [], "bare": []}
        cpu: dict = {"plain": [], "ftcal": [], "bare": [], "ensemble": [], "single": []}  # process CPU time [s]
        for _ in range(args.repeats):
            for name, fn in (("plain", plain_fit), ("ftcal", ftcal_fit), ("bare", bare_loop)):
                start, start_cpu = time.perf_counter(), time.process_time()
                out = fn()
                times[name].append(time.perf_counter() - start)
                cpu[name].append(time.process_time() - start_cpu)
                model = out if name == "ftcal" else model
        t_plain, t_ftcal, t_bare = (statistics.median(times[k]) for k in ("plain", "ftcal", "bare"))
    member = ftcal.DirectionalCalibrator(phase1_epochs=args.epochs, plateau_epochs=0, max_recover_epochs=0, alpha=50.0)
    with threadpool_limits(1):  # the ensemble interleaved with one member's fit, its baseline
        ensemble_times, single_times = [], []
        for _ in range(args.repeats):
            start, start_cpu = time.perf_counter(), time.process_time()
            ensemble = ftcal.EnsembleCalibrator(member, n_members=5, random_state=0).fit(raw, w)
            ensemble_times.append(time.perf_counter() - start)
            cpu["ensemble"].append(time.process_time() - start_cpu)
            start, start_cpu = time.perf_counter(), time.process_time()
            ftcal_fit()
            single_times.append(time.perf_counter() - start)
            cpu["single"].append(time.process_time() - start_cpu)
        t_ensemble, t_single = statistics.median(ensemble_times), statistics.median(single_times)
        t_stack, _ = median_time(
            lambda: ftcal.networks.fit_stacked([clone(member).set_params(random_state=s) for s in range(args.stack)], raw, w),
            1)
    rmse = ftcal.core.wrench_rmse(test_w, model.predict(test_raw), alpha=50.0)
    rmse_ensemble = ftcal.core.wrench_rmse(test_w, ensemble.predict(test_raw), alpha=50.0)
    ltm = ftcal.core.wrench_rmse(test_w, ftcal.LinearCalibrator(alpha=50.0).fit(raw, w).predict(test_raw), alpha=50.0)

    one = test_raw[:1].copy()
    layers = [(w.astype(np.float32), b.astype(np.float32), a) for w, b, a in model.fitted_layers()]  # the float32 floor

    def numpy_forward(x):
        h = x.astype(np.float32)
        for weight, bias, activation in layers:
            h = h @ weight + bias
            if activation == "relu":
                np.maximum(h, 0.0, out=h)
            elif activation == "tanh":
                np.tanh(h, out=h)
        return h

    unit_one = model.network_inputs(one)
    lat_numpy, _ = median_time(lambda: numpy_forward(unit_one), args.latency_calls)
    lat_predict, _ = median_time(lambda: model.predict(one), args.latency_calls)
    big = np.repeat(test_raw, 50, axis=0)
    unit_big = model.network_inputs(big)
    with threadpool_limits(1):
        thr_numpy, _ = median_time(lambda: numpy_forward(unit_big), 5)
        thr_predict, _ = median_time(lambda: model.predict(big), 5)
    lines = [
        f"machine: {platform.machine()}, {torch.get_num_threads()} torch thread, Python {platform.python_version()}, "
        f"torch {torch.__version__}; ftcal from {ftcal.__file__}",
        "",
        "| measure | ftcal | baseline (same process) | ratio | target |",
        "|---|---|---|---|---|",
        f"| fit, {args.epochs} epochs, 4000 x 6, batch 32, (64, 64, 64) | {t_ftcal:.2f} s | plain skorch "
        f"NeuralNetRegressor {t_plain:.2f} s | {t_ftcal / t_plain:.3f} | <= 0.33 |",
        f"| floor: a bare torch loop (autograd, fused Adam, no skorch), same net, batches, epochs | {t_bare:.2f} s | "
        f"plain skorch {t_plain:.2f} s | {t_bare / t_plain:.3f} | |",
        f"| 5-member directional ensemble fit, {args.epochs} epochs (members stacked) | {t_ensemble:.2f} s | "
        f"one member's fit {t_single:.2f} s | {t_ensemble / t_single:.3f} | <= 1.5 |",
        f"| fit_stacked of {args.stack} nets, per net | {t_stack / args.stack:.3f} s | one fit {t_ftcal:.2f} s | "
        f"{t_stack / args.stack / t_ftcal:.3f} | |",
        f"| fit_stacked of {args.stack} nets, per net, vs plain skorch | {t_stack / args.stack:.3f} s | plain skorch "
        f"{t_plain:.2f} s | {t_stack / args.stack / t_plain:.3f} | |",
        f"| one-sample predict (directional) | {lat_predict * 1e6:.1f} us | numpy forward {lat_numpy * 1e6:.1f} us "
        f"| {lat_predict / lat_numpy:.2f} | <= 5 |",
        f"| 100 000-row predict throughput | {len(big) / thr_predict:,.0f} rows/s | numpy forward "
        f"{len(big) / thr_numpy:,.0f} rows/s | {thr_numpy / thr_predict:.2f} of numpy's | >= 0.5 |",
        "",
        "the same ratios in process CPU time (less moved by other processes' time slices on a shared machine): "
        f"fit / plain skorch {_ratio(cpu, 'ftcal', 'plain'):.3f}, bare loop / plain skorch "
        f"{_ratio(cpu, 'bare', 'plain'):.3f}, ensemble / one member {_ratio(cpu, 'ensemble', 'single'):.3f}; "
        f"load average {load_before:.1f} before, {os.getloadavg()[0]:.1f} after",
        "",
        f"held-out RMSE after {args.epochs} epochs: directional {rmse:.3f} N, its 5-member ensemble "
        f"{rmse_ensemble:.3f} N (LTM {ltm:.3f} N)",
    ]
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
