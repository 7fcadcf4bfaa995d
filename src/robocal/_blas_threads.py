"""One BLAS thread for robocal's processes, set before numpy loads its BLAS.

robocal's dense linear algebra is small (normal matrices of tens to a few hundred unknowns, Jacobians
of a few thousand rows); its large batches run in its own compiled kernels, which share the cores
themselves. On such sizes OpenBLAS's threads gain little on an idle machine and lose badly on a busy
one: measured on the shared 2-core VM at load ~3, a 214 x 214 Cholesky factor took 220-280 ms with
OpenBLAS's default two threads against 0.4-0.8 ms with one, and elastic-full on DLR Justin 114 s
against 13.7 s (benchmarks/README.md). The command line and the documentation scripts call
:func:`single_thread_blas` first; a variable the user set is left as it is.
"""

from __future__ import annotations

import os
import sys

#: the thread-count variables of the BLAS builds numpy and scipy ship with (OpenBLAS) or may use
VARIABLES = ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS", "VECLIB_MAXIMUM_THREADS", "BLIS_NUM_THREADS")


def single_thread_blas() -> bool:
    """Ask for one BLAS thread unless the user chose a number; True if it takes effect (numpy not
    imported yet: the BLAS reads the variables when it loads)."""
    for var in VARIABLES:
        os.environ.setdefault(var, "1")
    return "numpy" not in sys.modules
