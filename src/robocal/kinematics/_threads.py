"""Sharing a large batch between the cores: a kernel that releases the GIL, run on disjoint ranges.

Small batches stay on the calling thread (a thread hand-off costs ~10-50 µs); from
:data:`PARALLEL_MIN` poses on, the range is cut into one contiguous piece per thread. The number
of threads is the number of usable CPUs, capped by ``NUMBA_NUM_THREADS`` when that is set (the
benchmarks set it to 1 for one-thread figures).
"""

from __future__ import annotations

import os

#: Poses from which a batch is shared between the cores. On the idle 2-core VM (UR10, 2026-11-24)
#: two threads beat one from ~2,000 poses (10.4 vs 7.4 M poses/s; 13.5 vs 7.5 M at 10,000); below a
#: few thousand the thread hand-off (~10-50 us) and a busy second core make it a gamble.
PARALLEL_MIN = 4_000

_pool = None


def n_threads() -> int:
    """Threads a large batch is shared between (>= 1)."""
    try:
        usable = len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        usable = os.cpu_count() or 1
    cap = os.environ.get("NUMBA_NUM_THREADS")
    if cap and cap.isdigit() and int(cap) > 0:
        usable = min(usable, int(cap))
    return max(1, usable)


def run_ranges(kernel, n: int, *args) -> None:
    """Call ``kernel(*args, start, stop)`` over ``range(n)``: in one call below :data:`PARALLEL_MIN`,
    else in one contiguous piece per thread (the kernel must release the GIL and write only its
    own range)."""
    threads = n_threads() if n >= PARALLEL_MIN else 1
    if threads == 1:
        kernel(*args, 0, n)
        return
    global _pool
    if _pool is None or _pool._max_workers != threads:
        from concurrent.futures import ThreadPoolExecutor

        _pool = ThreadPoolExecutor(max_workers=threads, thread_name_prefix="robocal-fk")
    bounds = [n * k // threads for k in range(threads + 1)]
    futures = [_pool.submit(kernel, *args, bounds[k], bounds[k + 1]) for k in range(1, threads)]
    kernel(*args, bounds[0], bounds[1])  # the calling thread takes the first piece
    for f in futures:
        f.result()
