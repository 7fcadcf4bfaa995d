"""Batched FK at scale (issues 12, 34): poses/s at N = 1e4, 1e5, 1e6 on one thread and on every core,
with a fresh result array and with ``out=``; and single-pose ``fk(q)`` against ``fk_single``.

Rows of a size are timed interleaved (one repeat of each in turn); medians of ``--repeat``.
The thread count is switched through ``NUMBA_NUM_THREADS``, which caps robocal's FK threads.

* wall-clock poses/s: what a caller gets on this machine now (on a shared VM, a share of it);
* ``cpu``: the one-thread rows timed by the thread's CPU time (page faults of a fresh array
  included): the kernel's own speed, independent of other processes on the cores;
* ``--against REV``: the batch kernel ``fk_fused_into`` of git revision REV (its ``_kernels.py``,
  compiled here, no cache) timed interleaved with today's, same threads, same arrays: the ratio
  new / old of the same run, which a loaded machine leaves meaningful when absolute figures are not.

Usage: ``python benchmarks/bench_fk_scale.py [--repeat 7] [--against 080bb7b]``. A script, not a test.
"""

from __future__ import annotations

import argparse
import importlib.util
import os

# Kernel speed is measured: the compiled kernels from the first call (not numpy until the work pays).
os.environ.setdefault("ROBOCAL_KERNELS", "compiled")
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from robocal.kinematics._threads import run_ranges
from robocal.robots import load_robot

sys.path.insert(0, str(Path(__file__).resolve().parent))
from _machine import machine_info  # noqa: E402


def kernels_at(rev: str):
    """The ``_kernels`` module of git revision ``rev``, imported from a temporary file (no numba cache)."""
    root = Path(__file__).resolve().parents[1]
    text = subprocess.run(["git", "show", f"{rev}:src/robocal/kinematics/_kernels.py"], cwd=root,
                          check=True, capture_output=True, text=True).stdout
    text = text.replace("_CACHE = True", "_CACHE = False").replace("from .links import", "from robocal.kinematics.links import")
    path = Path(tempfile.mkdtemp(prefix="fk-kernels-")) / f"kernels_{rev}.py"
    path.write_text(text)
    spec = importlib.util.spec_from_file_location(path.stem, path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def fk_with(kernel, m, q, out=None):
    """``m.fk(q, out=out)`` through a given batch kernel: the same joint check, the same threads."""
    q, _ = m._as_joints(q)
    if out is None:
        out = np.empty((len(q), 4, 4))
    run_ranges(kernel, len(q), q, m._fused_ints, m._fused_floats, 0, out, m._no_links)
    return out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=7)
    ap.add_argument("--against", metavar="REV", help="also time fk_fused_into of this git revision")
    args = ap.parse_args()
    m = load_robot("ur10")
    rng = np.random.default_rng(0)
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    for line in machine_info([f"fk          UR10, poses/s, median of {args.repeat}"]):
        print(line)
    from robocal.kinematics import _kernels

    kernels = {"now": _kernels.fk_fused_into}
    if args.against:
        kernels[args.against] = kernels_at(args.against).fk_fused_into
    q0 = rng.uniform(-3, 3, (10, 6))
    for k in kernels.values():
        fk_with(k, m, q0)  # compile / load
    cols = [("1", False), ("1", True), (str(cores), False), (str(cores), True)]
    head = ["1 thread", "1 thr out=", f"{cores} threads", f"{cores} thr out=", "1 thr cpu", "1 thr out= cpu"]
    print(f"\n{'N':>9}  {'kernel':<8}" + "".join(f"{h:>15}" for h in head))
    for n in (10_000, 100_000, 1_000_000):
        q = rng.uniform(-3, 3, (n, 6))
        out = np.empty((n, 4, 4))
        number = max(1, 300_000 // n)
        wall = {(k, c): [] for k in kernels for c in range(len(cols))}
        cpu = {(k, c): [] for k in kernels for c in (0, 1)}
        for _ in range(args.repeat):
            for name, kern in kernels.items():
                for c, (threads, use_out) in enumerate(cols):
                    os.environ["NUMBA_NUM_THREADS"] = threads
                    o = out if use_out else None
                    t0, c0 = time.perf_counter(), time.thread_time()
                    for _ in range(number):
                        fk_with(kern, m, q, o)
                    wall[name, c].append((time.perf_counter() - t0) / number)
                    if threads == "1":
                        cpu[name, c].append((time.thread_time() - c0) / number)
        rates = {}
        for name in kernels:
            rates[name] = [n / statistics.median(wall[name, c]) / 1e6 for c in range(len(cols))]
            rates[name] += [n / statistics.median(cpu[name, c]) / 1e6 for c in (0, 1)]
            print(f"{n:>9}  {name:<8}" + "".join(f"{r:>13.2f} M" for r in rates[name]))
        if args.against:
            ratio = [a / b for a, b in zip(rates["now"], rates[args.against])]
            print(f"{'':>9}  {'ratio':<8}" + "".join(f"{r:>14.2f}x" for r in ratio))
    print(f"load avg at end {os.getloadavg()[0]:.2f}")
    q1 = rng.uniform(-3, 3, 6)
    buf = np.empty((4, 4))
    calls = {"fk_single(q)": lambda: m.fk_single(q1), "fk_single(q, out)": lambda: m.fk_single(q1, buf),
             "fk(q)": lambda: m.fk(q1)}
    times = {k: [] for k in calls}
    for _ in range(args.repeat):
        for k, f in calls.items():
            t0 = time.perf_counter()
            for _ in range(20_000):
                f()
            times[k].append((time.perf_counter() - t0) / 20_000)
    base = statistics.median(times["fk_single(q)"])
    print(f"\n{'single pose':<20}{'median us':>10}{'x fk_single(q)':>16}")
    for k in calls:
        med = statistics.median(times[k])
        print(f"{k:<20}{med * 1e6:10.2f}{med / base:16.2f}")


if __name__ == "__main__":
    main()
