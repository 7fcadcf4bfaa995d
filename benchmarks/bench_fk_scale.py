"""Batched FK at scale (issues 12, 34): poses/s at N = 1e4, 1e5, 1e6 on one thread and on every core,
``fk(q, out=)`` and a fresh result side by side with their ratio; the cost of new pages; single-pose
``fk(q)`` against ``fk_single``.

Rows of a size are timed interleaved (one repeat of each in turn); medians of ``--repeat``.
The thread count is switched through ``NUMBA_NUM_THREADS``, which caps robocal's FK threads.

* ``out=``: ``model.fk(q, out=T)`` into an array written before (no page faults);
* ``fresh``: ``T = model.fk(q)`` with the result dropped after each call, as a loop does: from
  32 MiB on the result reuses the memory of the last one dropped (``kinematics/_result_pool.py``);
* ``new mem``: ``model.fk(q)`` on memory never used before (the pool emptied before each call: the
  first call of a process, or results all kept): the kernel's page faults and zeroing included;
* ``cpu``: the one-thread rows timed by the thread's CPU time: the kernel's own speed, independent of
  other processes on the cores;
* the page table: what a new page costs here, ms per GiB of float64 result (``np.empty`` + one
  write per 4 KiB page = fault + the kernel's zeroing), with numpy's huge-page advice on and off,
  against writing all of memory already mapped, 1 and 2 threads;
* ``--against REV``: the batch kernel ``fk_fused_into`` of git revision REV (its ``_kernels.py``,
  compiled here, no cache) timed interleaved with today's, same threads, same arrays (``np.empty``
  results): the ratio new / old of the same run, which a loaded machine leaves meaningful when
  absolute figures are not.

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

from robocal.kinematics import _result_pool
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


def _threads(count: str) -> None:
    os.environ["NUMBA_NUM_THREADS"] = count


def interleaved(calls: dict, repeat: int, number: int) -> tuple[dict, dict]:
    """Seconds per call of each of ``calls``, one repeat of each in turn: wall and thread CPU lists."""
    wall = {k: [] for k in calls}
    cpu = {k: [] for k in calls}
    for _ in range(repeat):
        for k, f in calls.items():
            t0, c0 = time.perf_counter(), time.thread_time()
            for _ in range(number):
                f()
            wall[k].append((time.perf_counter() - t0) / number)
            cpu[k].append((time.thread_time() - c0) / number)
    return wall, cpu


def paired(ref: list, other: list) -> float:
    """Median over the repeats of ``ref / other`` (their times): the rate of ``other`` over that of
    ``ref``, each repeat's two calls timed side by side."""
    return statistics.median(x / y for x, y in zip(ref, other))


def api_table(m, sizes, cores: int, repeat: int, rng) -> None:
    """``fk(q, out=)``, ``fk(q)`` fresh and ``fk(q)`` on new memory, per size and thread count."""
    print("\nfk(q, out=) and a fresh result, M poses/s (ratios: medians of the repeats' paired ratios)")
    print(f"{'N':>9} {'threads':>8}{'out=':>11}{'fresh':>11}{'fresh/out=':>12}{'new mem':>11}{'new/out=':>10}")
    thread_counts = ["1", str(cores)] if cores > 1 else ["1"]
    for n in sizes:
        q = rng.uniform(-3, 3, (n, 6))
        out = np.empty((n, 4, 4))
        m.fk(q, out=out)
        pooled = 8 * out.size >= _result_pool.MIN_BYTES
        calls = {}
        for t in thread_counts:
            calls[t, "out="] = lambda t=t, q=q, out=out: (_threads(t), m.fk(q, out=out))
            calls[t, "fresh"] = lambda t=t, q=q: (_threads(t), m.fk(q))
            if pooled:
                calls[t, "new"] = lambda t=t, q=q: (_threads(t), _result_pool.clear(), m.fk(q))
        wall, cpu = interleaved(calls, repeat, max(1, 300_000 // n))
        for t in thread_counts:
            rate = {k: n / statistics.median(wall[t, k]) / 1e6 for k in ("out=", "fresh", "new") if (t, k) in wall}
            new = (f"{rate['new']:9.2f} M{paired(wall[t, 'out='], wall[t, 'new']):9.2f}x" if pooled
                   else f"{'-':>11}{'-':>10}")
            print(f"{n:>9} {t:>8}{rate['out=']:9.2f} M{rate['fresh']:9.2f} M"
                  f"{paired(wall[t, 'out='], wall[t, 'fresh']):11.2f}x{new}")
            if t == "1":
                rate = {k: n / statistics.median(cpu[t, k]) / 1e6 for k in ("out=", "fresh", "new") if (t, k) in cpu}
                new = (f"{rate['new']:9.2f} M{paired(cpu[t, 'out='], cpu[t, 'new']):9.2f}x" if pooled
                       else f"{'-':>11}{'-':>10}")
                print(f"{'':>9} {'1 (cpu)':>8}{rate['out=']:9.2f} M{rate['fresh']:9.2f} M"
                      f"{paired(cpu[t, 'out='], cpu[t, 'fresh']):11.2f}x{new}")


def kernel_table(m, kernels: dict, sizes, cores: int, repeat: int, rng) -> None:
    """Today's batch kernel against another revision's, same threads, same arrays (``np.empty`` results)."""
    cols = [("1", False), ("1", True), (str(cores), False), (str(cores), True)]
    head = ["1 thread", "1 thr out=", f"{cores} threads", f"{cores} thr out=", "1 thr cpu", "1 thr out= cpu"]
    print(f"\nbatch kernel against {list(kernels)[1]}, M poses/s")
    print(f"{'N':>9}  {'kernel':<8}" + "".join(f"{h:>15}" for h in head))
    for n in sizes:
        q = rng.uniform(-3, 3, (n, 6))
        out = np.empty((n, 4, 4))
        out.fill(0.0)  # mapped before: the out= columns pay no page faults
        calls = {(name, c): (lambda kern=kern, t=t, q=q, o=(out if use_out else None): (_threads(t), fk_with(kern, m, q, o)))
                 for name, kern in kernels.items() for c, (t, use_out) in enumerate(cols)}
        wall, cpu = interleaved(calls, repeat, max(1, 300_000 // n))
        rates = {}
        for name in kernels:
            rates[name] = [n / statistics.median(wall[name, c]) / 1e6 for c in range(len(cols))]
            rates[name] += [n / statistics.median(cpu[name, c]) / 1e6 for c in (0, 1)]
            print(f"{n:>9}  {name:<8}" + "".join(f"{r:>13.2f} M" for r in rates[name]))
        ratio = [a / b for a, b in zip(*rates.values())]
        print(f"{'':>9}  {'ratio':<8}" + "".join(f"{r:>14.2f}x" for r in ratio))


def page_table(n: int, repeat: int) -> None:
    """What new pages cost on this machine against writing memory mapped before, ms per GiB."""
    from concurrent.futures import ThreadPoolExecutor

    from numpy._core.multiarray import _get_madvise_hugepage, _set_madvise_hugepage

    thp = Path("/sys/kernel/mm/transparent_hugepage")
    state = {f: (thp / f).read_text().strip() if (thp / f).exists() else "n/a" for f in ("enabled", "defrag")}
    advice = _get_madvise_hugepage()
    shape = (n, 4, 4)
    mapped = np.empty(shape)
    mapped.fill(0.0)
    pool = ThreadPoolExecutor(1)

    def write2(a):  # half each on two threads (np.copyto releases the GIL)
        flat = a.reshape(-1)
        half = len(flat) // 2
        other = pool.submit(np.copyto, flat[half:], 0.0)
        np.copyto(flat[:half], 0.0)
        other.result()

    def advised(on, f):
        def call():
            _set_madvise_hugepage(on)
            f()
        return call

    calls = {
        "new pages, one write per 4 KiB page, huge-page advice": advised(True, lambda: np.empty(shape).reshape(-1)[::512].fill(0.0)),
        "new pages, one write per 4 KiB page, no advice (4 KiB pages)": advised(False, lambda: np.empty(shape).reshape(-1)[::512].fill(0.0)),
        "write all, memory mapped before, 1 thread": lambda: mapped.fill(0.0),
        "write all, new memory (advice), 1 thread": advised(True, lambda: np.empty(shape).fill(0.0)),
        "write all, memory mapped before, 2 threads": lambda: write2(mapped),
        "write all, new memory (advice), 2 threads": advised(True, lambda: write2(np.empty(shape))),
    }
    try:
        wall, cpu = interleaved(calls, repeat, 1)
    finally:
        _set_madvise_hugepage(advice)
        pool.shutdown()
    gib = 8 * mapped.size / 2**30
    print(f"\nnew pages against memory mapped before, {8 * mapped.size / 1e6:.0f} MB arrays, ms per GiB "
          f"(transparent huge pages: enabled {state['enabled']}, defrag {state['defrag']}; numpy's advice {advice})")
    print(f"  {'':<64}{'wall':>9}{'cpu':>9}")
    for k, w in wall.items():
        c = f"{statistics.median(cpu[k]) / gib * 1e3:9.1f}" if "1 thread" in k or "per 4 KiB" in k else f"{'-':>9}"
        print(f"  {k:<64}{statistics.median(w) / gib * 1e3:9.1f}{c}")


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

    sizes = (10_000, 100_000, 1_000_000)
    m.fk(rng.uniform(-3, 3, (10, 6)))  # compile / load
    api_table(m, sizes, cores, args.repeat, rng)
    if args.against:
        kernels = {"now": _kernels.fk_fused_into, args.against: kernels_at(args.against).fk_fused_into}
        for k in kernels.values():
            fk_with(k, m, rng.uniform(-3, 3, (10, 6)))  # compile / load
        kernel_table(m, kernels, sizes, cores, args.repeat, rng)
    page_table(sizes[-1], args.repeat)
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
