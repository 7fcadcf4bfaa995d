"""The Dask worker plugin of robocal's local cluster (imported only where dask.distributed is)."""

from __future__ import annotations

from distributed import WorkerPlugin

__all__ = ["TunedAllocator"]


class TunedAllocator(WorkerPlugin):
    """:func:`robocal._allocator.tune_allocator` in each worker process of the local cluster, those
    restarted by their nanny too (~12 % of a 100-pose calibration's time; benchmarks/README.md)."""

    def setup(self, worker):
        from ..._allocator import tune_allocator

        tune_allocator()
