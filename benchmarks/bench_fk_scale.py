"""Batched FK at scale (issue 12): poses/s at N = 1e4, 1e5, 1e6 on one thread and on every core,
with a fresh result array and with ``out=``; and single-pose ``fk(q)`` against ``fk_single``.

Rows of a size are timed interleaved (one repeat of each in turn); medians of ``--repeat``.
The thread count is switched through ``NUMBA_NUM_THREADS``, which caps robocal's FK threads.
Usage: ``python benchmarks/bench_fk_scale.py [--repeat 7]``. A script, not a test.
"""

from __future__ import annotations

import argparse
import os

# Kernel speed is measured: the compiled kernels from the first call (not numpy until the work pays).
os.environ.setdefault("ROBOCAL_KERNELS", "compiled")
import statistics
import timeit

import numpy as np

from robocal.robots import load_robot


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    args = ap.parse_args()
    m = load_robot("ur10")
    rng = np.random.default_rng(0)
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    print(f"UR10, poses/s (median of {args.repeat}); {cores} CPUs; load avg {os.getloadavg()[0]:.2f} at start")
    print(f"{'N':>9}  {'1 thread':>10}  {'1 thr out=':>10}  {f'{cores} threads':>10}  {f'{cores} thr out=':>11}")
    for n in (10_000, 100_000, 1_000_000):
        q = rng.uniform(-3, 3, (n, 6))
        out = np.empty((n, 4, 4))
        m.fk(q[:10])
        rows = [("1", None), ("1", out), (str(cores), None), (str(cores), out)]
        times = {k: [] for k in range(len(rows))}
        number = max(1, 300_000 // n)
        for _ in range(args.repeat):
            for k, (threads, o) in enumerate(rows):
                os.environ["NUMBA_NUM_THREADS"] = threads
                times[k].append(timeit.timeit(lambda o=o, q=q: m.fk(q, out=o), number=number) / number)
        rates = [n / statistics.median(times[k]) / 1e6 for k in range(len(rows))]
        print(f"{n:>9}  " + "  ".join(f"{r:>8.2f} M" for r in rates))
    q1 = rng.uniform(-3, 3, 6)
    buf = np.empty((4, 4))
    calls = {"fk_single(q)": lambda: m.fk_single(q1), "fk_single(q, out)": lambda: m.fk_single(q1, buf),
             "fk(q)": lambda: m.fk(q1)}
    times = {k: [] for k in calls}
    for _ in range(args.repeat):
        for k, f in calls.items():
            times[k].append(timeit.timeit(f, number=20_000) / 20_000)
    base = statistics.median(times["fk_single(q)"])
    print(f"\n{'single pose':<20}{'median us':>10}{'x fk_single(q)':>16}")
    for k in calls:
        med = statistics.median(times[k])
        print(f"{k:<20}{med * 1e6:10.2f}{med / base:16.2f}")


if __name__ == "__main__":
    main()
