"""Test-session settings.

One BLAS thread: the suite's linear algebra is on small matrices (tens of columns), where OpenBLAS's
thread pool costs more than it gains, and on the shared 2-core CI machine it can turn a 10 ms QR
into ~1 s under load (measured in the hand-eye tests: 68 s wall against 11 s). Set before numpy
is imported by any test module (pytest loads this file first); a user's explicit setting is kept.
numba's own threads (NUMBA_NUM_THREADS) are left alone.
"""

import os

for _var in ("OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")
