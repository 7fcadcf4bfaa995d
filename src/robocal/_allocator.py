"""The C memory allocator's settings in robocal's own processes (Linux with glibc).

A calibration makes many short-lived arrays of tens of KiB to a few MiB. Under glibc's default,
dynamic thresholds the heap's free top is returned to the system and arrays above the mmap
threshold are mapped afresh, so the same memory is faulted in again and again: ~2,600 page faults
per 100-pose calibration, ~13 % of its time (50 calibrations, 2026-11-27: 1.67 s with 132,000
faults and 0.26 s of system time, 1.45 s with ~30 faults and 0.06 s; peak memory unchanged,
181 MiB). :func:`tune_allocator` fixes the thresholds instead: blocks up to
:data:`MMAP_THRESHOLD_BYTES` come from the heap, and the heap keeps up to
:data:`TRIM_THRESHOLD_BYTES` of free memory at its top. Larger arrays (a 100,000-pose campaign's)
are still mapped and returned as before, so peak memory does not grow.

The command line (every ``robocal`` command) and the fleet's worker tasks call it once per
process. A program using the library gets the same from the environment, the way glibc documents
it: ``MALLOC_MMAP_THRESHOLD_=4194304 MALLOC_TRIM_THRESHOLD_=16777216``. It does nothing on other
systems, when the user set any ``MALLOC_*_`` variable or glibc malloc tunable (the user's choice
wins; Dask's workers set ``MALLOC_TRIM_THRESHOLD_`` unless told not to), or when
``ROBOCAL_MALLOC=system``.
"""

from __future__ import annotations

import os
import sys

__all__ = ["MMAP_THRESHOLD_BYTES", "TRIM_THRESHOLD_BYTES", "tune_allocator"]

#: Blocks at least this large are mapped from the system (glibc's ``M_MMAP_THRESHOLD``) [bytes].
MMAP_THRESHOLD_BYTES = 4 << 20
#: Free memory at the heap's top above this is returned to the system (``M_TRIM_THRESHOLD``) [bytes].
TRIM_THRESHOLD_BYTES = 16 << 20

# mallopt parameter numbers (glibc malloc.h)
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
_USER_SETTINGS = ("MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_", "MALLOC_TOP_PAD_", "MALLOC_MMAP_MAX_",
                  "MALLOC_ARENA_MAX")
_applied: bool | None = None


def tune_allocator() -> bool:
    """Set glibc's mmap and trim thresholds for this process (see the module docstring), once.

    Returns
    -------
    bool
        True when the thresholds are set (now or by an earlier call), False when left alone (not
        glibc, the user's own ``MALLOC_*`` settings, ``ROBOCAL_MALLOC=system``).
    """
    global _applied
    if _applied is None:
        _applied = _apply()
    return _applied


def _apply() -> bool:
    if not sys.platform.startswith("linux"):
        return False
    if os.environ.get("ROBOCAL_MALLOC", "").strip().lower() in ("system", "default", "off", "0"):
        return False
    if any(os.environ.get(k) for k in _USER_SETTINGS) or "glibc.malloc." in os.environ.get("GLIBC_TUNABLES", ""):
        return False
    try:
        import ctypes

        libc = ctypes.CDLL(None)
        libc.gnu_get_libc_version  # noqa: B018 - glibc only (musl's mallopt does nothing)
        mallopt = libc.mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    mallopt.restype = ctypes.c_int
    return bool(mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD_BYTES)) and bool(mallopt(_M_TRIM_THRESHOLD,
                                                                                   TRIM_THRESHOLD_BYTES))
