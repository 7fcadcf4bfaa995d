"""Chunking many small, independent computations into Dask tasks so that task overhead stays a
small share of the run (``robocal fleet study``).

A task costs a fixed overhead ``o`` (scheduling, serialisation, a round trip) besides its work. A
chunk of ``k`` items of ``t`` seconds each spends the share ``o / (o + k t)`` on overhead; keeping
that under ``s`` needs ``k >= o (1 - s) / (s t)``. Fewer, larger chunks than workers would leave
workers idle, so ``k`` is also capped at ``ceil(n / workers)``; the share that results is reported.
"""

from __future__ import annotations

import math
import time

__all__ = ["MAX_OVERHEAD_SHARE", "chunk_size", "overhead_share", "measure_task_overhead", "chunks"]

#: Largest share of a task's wall time that may go to overhead (issue 19: under 5 %).
MAX_OVERHEAD_SHARE = 0.05


def overhead_share(overhead_s: float, item_s: float, k: int) -> float:
    """Share of a chunk's wall time spent on task overhead: o / (o + k t)."""
    return overhead_s / (overhead_s + k * item_s)


def chunk_size(n: int, item_s: float, overhead_s: float, workers: int, *, max_share: float = MAX_OVERHEAD_SHARE) -> int:
    """Items per task (see the module docstring): the smallest ``k`` with overhead share below
    ``max_share``, at most ``ceil(n / workers)``, at least 1. item_s, overhead_s: seconds."""
    if n < 1:
        return 1
    need = math.ceil(overhead_s * (1.0 - max_share) / (max_share * max(item_s, 1e-9)))
    return int(max(1, min(need, math.ceil(n / max(1, workers)))))


def _noop(x):
    return x


def measure_task_overhead(client, n_tasks: int = 200) -> float:
    """Seconds of one worker's time per empty task on ``client``: the wall time of ``n_tasks``
    no-op tasks times the number of worker threads, over ``n_tasks`` (after a warm-up batch)."""
    from .cluster import import_distributed

    wait = import_distributed().wait
    threads = sum(w.get("nthreads", 1) for w in client.scheduler_info()["workers"].values()) or 1
    wait(client.map(_noop, range(min(20, n_tasks)), pure=False))
    t0 = time.perf_counter()
    wait(client.map(_noop, range(n_tasks), pure=False))
    return (time.perf_counter() - t0) * threads / n_tasks


def chunks(n: int, k: int) -> list:
    """[(start, stop), ...] covering range(n) in pieces of ``k``."""
    return [(i, min(n, i + k)) for i in range(0, n, k)]
