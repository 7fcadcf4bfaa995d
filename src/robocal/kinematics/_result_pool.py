"""Fresh result arrays of a large batch on reused memory: the memory of a dropped result serves again.

numpy takes a result of tens of MB from the operating system (glibc maps every block above 32 MiB
on its own and unmaps it on ``free``), so every new result pays the kernel's page faults and the
zeroing of its pages: on the 2-core VM of the benchmarks (2026-11-27) ~54 ms per GB with
transparent huge pages (numpy asks for them), ~290 ms per GB with 4 KiB pages, against ~230 ms per
GB for the FK that fills it on both cores (``benchmarks/README.md``). :func:`empty` keeps the
memory of the last large result the caller dropped and hands it out again to the next request of
the same size, so ``T = model.fk(q)`` in a loop runs at the speed of ``fk(q, out=T)``.

Safety: the memory is never shared by two live results. Each array handed out is a view of its
block through a lease made for that call alone (a ``ctypes`` array over the block); every view,
slice or ``memoryview`` of the result keeps the lease alive (numpy's base chain and the buffer
protocol hold it), and only the lease's collection puts the block back. One block at most is kept,
so the memory held beyond the caller's arrays is at most the size of the last large result dropped,
and a request of another size lets it go before it asks for new memory; :func:`clear` lets it go.
"""

from __future__ import annotations

import ctypes
import threading
import weakref

import numpy as np

#: Results from this many bytes up come from the pool; smaller ones from ``np.empty`` (glibc reuses
#: freed blocks up to 32 MiB from its heap: no new pages, nothing to win).
MIN_BYTES = 32 << 20

_lock = threading.RLock()
_kept: np.ndarray | None = None  # the block of the last dropped result, free for the next request


def _give_back(block: np.ndarray) -> None:
    """A lease was collected: its block is free for the next request of its size (the only one kept)."""
    global _kept
    with _lock:
        _kept = block


def empty(shape: tuple[int, ...]) -> np.ndarray:
    """An uninitialised C-contiguous float64 array of ``shape`` that no other live array shares.

    From :data:`MIN_BYTES` on, it lives in the memory of the last dropped result of the same byte
    size when there is one (no page faults), else in new memory; below, it is ``np.empty(shape)``.
    The array does not own its data (``flags.owndata`` is False): it cannot be ``resize``-d in place.
    """
    global _kept
    nbytes = 8 * int(np.prod(shape, dtype=np.int64))
    if nbytes < MIN_BYTES:
        return np.empty(shape)
    with _lock:  # the kept block is taken, or let go before new memory is asked for (no two held)
        block, _kept = _kept, None
    if block is not None and block.nbytes != nbytes:
        block = None
    if block is None:
        block = np.empty(nbytes, dtype=np.uint8)
    lease = (ctypes.c_char * nbytes).from_buffer(block)
    weakref.finalize(lease, _give_back, block).atexit = False
    return np.frombuffer(lease, dtype=np.float64).reshape(shape)


def clear() -> None:
    """Let the kept block go (its memory returns to the system once no result uses it)."""
    global _kept
    with _lock:
        _kept = None
