"""Reading ROS bags: memory that stays bounded as the bag grows, and the reading rate, per storage.

For each storage (rosbag2 sqlite3, rosbag2 MCAP, ROS 1) and each message count, a bag of a 1 kHz
``geometry_msgs/WrenchStamped`` topic and 100 Hz ``sensor_msgs/JointState`` (7 joints) is written with
``ftcal.io.write_bag``, then read with ``ftcal.io.read_bag(max_samples=2000)``:

* ``peak MiB``: the peak of Python's traced allocations while reading (``tracemalloc``; numpy's arrays
  included), against ``whole MiB``: the same for the baseline that keeps every decoded message of the two topics
  in a list (what a reader that loads the bag whole holds);
* ``msgs/s``: messages read per second (median of ``--repeats`` reads, without tracemalloc). This one depends
  on the machine and its load; the memory figures do not.

Command: ``python benchmarks/bag_reading.py [--counts 20000,200000] [--repeats 3]``
"""

from __future__ import annotations

import argparse
import statistics
import tempfile
import time
import tracemalloc
from pathlib import Path

import numpy as np

from ftcal.io import read_bag, write_bag

STORAGES = ("sqlite3", "mcap", "ros1")


def make_bag(path: Path, storage: str, n: int) -> Path:
    t = 1.7e9 + np.arange(n) * 1e-3
    rng = np.random.default_rng(0)
    return write_bag(path, storage, sensor_time=t, reading=rng.normal(size=(n, 6)), pose_time=t[::10],
                     joints=rng.normal(size=(len(t[::10]), 7)), joint_names=[f"j{k}" for k in range(7)])


def whole_bag(path: Path) -> list:
    """The baseline: every message of the bag decoded and kept (rosbags' own reader)."""
    from rosbags.highlevel import AnyReader

    with AnyReader([path]) as reader:
        return [reader.deserialize(data, conn.msgtype) for conn, _, data in reader.messages()]


def peak_mib(fn) -> float:
    tracemalloc.start()
    try:
        fn()
        return tracemalloc.get_traced_memory()[1] / 2**20
    finally:
        tracemalloc.stop()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--counts", default="20000,200000", help="sensor messages per bag, comma-separated")
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    counts = [int(c) for c in args.counts.split(",")]
    print("| storage | sensor msgs | bag MiB | peak MiB (ftcal) | whole MiB (baseline) | msgs/s (ftcal) |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as tmp:
        for storage in STORAGES:
            for n in counts:
                bag = make_bag(Path(tmp) / f"{storage}_{n}{'.bag' if storage == 'ros1' else ''}", storage, n)
                size = sum(p.stat().st_size for p in ([bag] if bag.is_file() else bag.rglob("*"))) / 2**20
                peak = peak_mib(lambda: read_bag(bag, max_samples=2000))
                whole = peak_mib(lambda: whole_bag(bag))
                times = []
                for _ in range(args.repeats):
                    start = time.perf_counter()
                    read_bag(bag, max_samples=2000)
                    times.append(time.perf_counter() - start)
                rate = 1.1 * n / statistics.median(times)  # sensor + joint messages
                print(f"| {storage} | {n} | {size:.1f} | {peak:.2f} | {whole:.1f} | {rate:,.0f} |", flush=True)


if __name__ == "__main__":
    main()
