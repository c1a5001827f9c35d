"""Two revisions of ftcal timed in the same run, interleaved: the time of a workload after a change over before it.

Usage::

    python benchmarks/before_after.py [--before d600b34] [--after HEAD] [--repeats 5]
        [--workloads network auto] [--epochs 20] [--rows 4000] [--out benchmarks/results/before_after.json]

Each revision is checked out as a detached ``git worktree`` in a temporary folder (removed at the end). Each
workload then runs alternately under the two revisions (before, after, before, after, ...: ``--repeats`` pairs),
each run a fresh ``python`` subprocess with ``PYTHONPATH=<worktree>`` (it checks that ``ftcal`` comes from there),
one thread for torch and BLAS. A subprocess imports everything first and times only the fit. On a shared, loaded
machine absolute seconds mean little; the ratio after/before of runs taken side by side is the figure: the ratio of
the medians, each pair's ratio (min-max) and a bootstrap interval of the median pair ratio (resampling the pairs).

Workloads (only names that both revisions export at the top level or in a package both have):

* ``network``: the "fit" figure of ``benchmarks/network_speed.py``: ``ftcal.DirectionalCalibrator`` with
  ``phase1_epochs=--epochs`` (``max_epochs`` before the redesign, the same schedule: phase 1 only), ``alpha=50``, seed 0, on its ``--rows`` x 6 data (4000 x 6, 20 epochs
  there), net (64, 64, 64), batch 32;
* ``auto``: ``ftcal.AutoCalibrator(candidates=..., baselines=False, n_jobs=1, random_state=0)`` on the first 400
  rows of ``make_soft_sensor_dataset`` (the small case of ``benchmarks/auto_speed.py``), the candidates being the
  list ``auto`` tried before the redesign (linear, four polynomials, axis_nonlinear, gaussian_process,
  directional, comparative on the short schedule), built with ``ftcal.make_calibrator`` in each revision; the
  stack is on (both revisions have it). ``n_jobs=1`` (``auto_speed.py`` uses 2 workers): no worker start-up in
  the timed fit.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import random
import shutil
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

WORKLOADS = ("network", "auto")

_PRELUDE = """
import json, sys, time, warnings
warnings.simplefilter("ignore")
import numpy as np
import torch
import skorch, sklearn.gaussian_process
from threadpoolctl import threadpool_limits
import ftcal
torch.set_num_threads(1)
assert ftcal.__file__.startswith(sys.argv[1]), (ftcal.__file__, sys.argv[1])
"""

_NETWORK = _PRELUDE + """
epochs, rows = int(sys.argv[2]), int(sys.argv[3])

def data(n, seed):  # benchmarks/network_speed.py's data
    rng = np.random.default_rng(seed)
    w = rng.normal(size=(n, 6)) * np.array([100.0] * 3 + [2.0] * 3)
    seen = w + 2e-5 * w * np.abs(w)
    return seen @ np.random.default_rng(99).normal(size=(6, 6)) * 0.01, w

raw, w = data(rows, 0)
# phase 1's length: phase1_epochs after the redesign, max_epochs before (the same schedule with no plateau phase)
length = "phase1_epochs" if "phase1_epochs" in ftcal.DirectionalCalibrator().get_params() else "max_epochs"
model = ftcal.DirectionalCalibrator(**{length: epochs}, plateau_epochs=0, max_recover_epochs=0, alpha=50.0,
                                    random_state=0)
with threadpool_limits(1):
    start = time.perf_counter()
    model.fit(raw, w)
    seconds = time.perf_counter() - start
print(json.dumps({"seconds": seconds, "ftcal": ftcal.__file__}))
"""

_AUTO = _PRELUDE + """
try:  # its home after the redesign (the top-level name is gone there)
    from ftcal.simulation import make_soft_sensor_dataset
except ImportError:  # before: a top-level name only
    from ftcal import make_soft_sensor_dataset

def candidates():  # auto's candidates before the redesign, in their order
    make = ftcal.make_calibrator
    out = [("linear", make("linear"))]
    for degree in (2, 3):
        for ridge in (1e-2, 1e-4):
            out.append((f"polynomial(degree={degree}, ridge={ridge:g})", make("polynomial", degree=degree, ridge=ridge)))
    out.append(("axis_nonlinear", make("axis_nonlinear")))
    out.append(("gaussian_process", make("gaussian_process", random_state=0)))
    for name in ("directional", "comparative"):
        out.append((name, make(name, schedule="short", random_state=0)))
    return out

soft = make_soft_sensor_dataset()
X, y = soft.raw[:400], soft.wrench[:400]
auto = ftcal.AutoCalibrator(candidates=candidates(), baselines=False, n_jobs=1, random_state=0)
with threadpool_limits(1):
    start = time.perf_counter()
    auto.fit(X, y)
    seconds = time.perf_counter() - start
print(json.dumps({"seconds": seconds, "ftcal": ftcal.__file__, "choice": auto.best_name_}))
"""


def parse_args(argv=None) -> argparse.Namespace:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])

    def positive(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
        if not 1 <= value <= 1000:
            raise argparse.ArgumentTypeError(f"{text} is not in 1..1000")
        return value

    parser.add_argument("--before", default="d600b34", help="the revision before (default: d600b34)")
    parser.add_argument("--after", default="HEAD", help="the revision after (default: HEAD)")
    parser.add_argument("--repeats", type=positive, default=5, help="before/after pairs per workload")
    parser.add_argument("--workloads", nargs="+", choices=WORKLOADS, default=list(WORKLOADS))
    parser.add_argument("--epochs", type=positive, default=20, help="the network workload's epochs")
    parser.add_argument("--rows", type=positive, default=4000, help="the network workload's rows")
    parser.add_argument("--repo", default=".", help="the git repository the revisions come from")
    parser.add_argument("--out", default="benchmarks/results/before_after.json")
    parser.add_argument("--force", action="store_true", help="replace an --out file this script did not write")
    args = parser.parse_args(argv)
    if args.rows < 100:
        parser.error(f"--rows {args.rows}: the network workload needs at least 100 rows")
    return args


def summarize(before: list[float], after: list[float], *, resamples: int = 2000, seed: int = 0) -> dict:
    """The medians of paired times (seconds), their ratio after/before, each pair's ratio (min-max) and a 90 %
    bootstrap interval of the median pair ratio, resampling the pairs.

    Examples
    --------
    >>> s = summarize([10.0, 12.0, 11.0], [11.0, 12.0, 11.0])
    >>> s["median_before_s"], s["median_after_s"], round(s["ratio_of_medians"], 3)
    (11.0, 11.0, 1.0)
    >>> s["pair_ratio_min"], s["pair_ratio_max"]
    (1.0, 1.1)
    """
    if len(before) != len(after) or not before:
        raise ValueError(f"before and after need as many times, at least one: {len(before)} and {len(after)}")
    if min(before) <= 0 or min(after) <= 0:
        raise ValueError(f"times must be positive seconds: before {before}, after {after}")
    ratios = [a / b for a, b in zip(after, before)]
    rng = random.Random(seed)
    medians = sorted(statistics.median(rng.choices(ratios, k=len(ratios))) for _ in range(resamples))
    return {
        "before_s": list(before), "after_s": list(after),
        "median_before_s": statistics.median(before), "median_after_s": statistics.median(after),
        "ratio_of_medians": statistics.median(after) / statistics.median(before),
        "pair_ratios": ratios, "median_pair_ratio": statistics.median(ratios),
        "pair_ratio_min": min(ratios), "pair_ratio_max": max(ratios),
        "bootstrap_90": [medians[int(0.05 * (resamples - 1))], medians[int(0.95 * (resamples - 1))]],
    }


def _run(workload: str, tree: Path, args: argparse.Namespace, scratch: Path) -> dict:
    code = {"network": _NETWORK, "auto": _AUTO}[workload]
    env = dict(os.environ, PYTHONPATH=str(tree), OMP_NUM_THREADS="1", MKL_NUM_THREADS="1",
               OPENBLAS_NUM_THREADS="1", PYTHONWARNINGS="ignore")
    done = subprocess.run([sys.executable, "-c", code, str(tree), str(args.epochs), str(args.rows)], env=env,
                          cwd=scratch, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"the {workload} workload failed under {tree}:\n{done.stderr[-3000:]}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None) -> int:
    args = parse_args(argv)
    repo = Path(args.repo).resolve()
    sys.path.insert(0, str(Path(__file__).resolve().parent))
    from _output import single_output  # the script's one output file, checked before any work

    out = single_output(argparse.ArgumentParser(prog="before_after.py"), args.out, args.force)
    revs = {}
    for key in ("before", "after"):
        revs[key] = subprocess.run(["git", "-C", str(repo), "rev-parse", "--verify", getattr(args, key) + "^{commit}"],
                                   capture_output=True, text=True, check=True).stdout.strip()
    result: dict = {
        "command": " ".join(["python", "benchmarks/before_after.py", *(argv if argv is not None else sys.argv[1:])]),
        "revisions": revs, "repeats": args.repeats, "epochs": args.epochs, "rows": args.rows,
        "load_average_start": os.getloadavg(),
        "machine": {"platform": platform.platform(), "cpus": os.cpu_count(), "python": platform.python_version()},
        "workloads": {},
    }
    folder = Path(tempfile.mkdtemp(prefix="ftcal-before-after-"))
    trees = {key: folder / key for key in revs}
    scratch = folder / "scratch"
    scratch.mkdir()
    try:
        for key, rev in revs.items():
            subprocess.run(["git", "-C", str(repo), "worktree", "add", "--detach", str(trees[key]), rev],
                           capture_output=True, text=True, check=True)
        for workload in args.workloads:
            times: dict = {"before": [], "after": []}
            extra: dict = {"before": set(), "after": set()}
            for pair in range(args.repeats):
                for key in ("before", "after"):
                    run = _run(workload, trees[key], args, scratch)
                    times[key].append(run["seconds"])
                    if "choice" in run:
                        extra[key].add(run["choice"])
                    print(f"{workload} pair {pair + 1}/{args.repeats} {key}: {run['seconds']:.2f} s", flush=True)
            summary = summarize(times["before"], times["after"])
            summary.update({f"choice_{k}": sorted(v) for k, v in extra.items() if v})
            result["workloads"][workload] = summary
            print(f"{workload}: before {summary['median_before_s']:.2f} s, after {summary['median_after_s']:.2f} s, "
                  f"after/before {summary['ratio_of_medians']:.3f} (pairs {summary['pair_ratio_min']:.3f}-"
                  f"{summary['pair_ratio_max']:.3f}, bootstrap 90 % {summary['bootstrap_90'][0]:.3f}-"
                  f"{summary['bootstrap_90'][1]:.3f})", flush=True)
    finally:
        for tree in trees.values():
            subprocess.run(["git", "-C", str(repo), "worktree", "remove", "--force", str(tree)], capture_output=True)
        shutil.rmtree(folder, ignore_errors=True)
        subprocess.run(["git", "-C", str(repo), "worktree", "prune"], capture_output=True)
    result["load_average_end"] = os.getloadavg()
    out.write_text(json.dumps(result, indent=1))
    print(json.dumps({k: v for k, v in result.items() if k != "workloads"}))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
