"""Cholesky solves of the small normal matrices (n x n, n ~ 10-60) inside the solvers, through
LAPACK directly (``dpotrf`` / ``dpotrs`` / ``dpotri``).

``scipy.linalg.cho_factor`` / ``cho_solve`` give the same numbers but wrap every call in argument
checks and array-API dispatch that cost ~10-20 us each; a 4-iteration solve makes ~10 of them,
which was a measurable part of a ~2 ms identification (benchmarks/bench_calibration.py).
"""

from __future__ import annotations

import numpy as np
from scipy.linalg.lapack import dpotrf, dpotri, dpotrs

__all__ = ["cholesky_factor", "cholesky_solve", "cholesky_inverse"]


def cholesky_factor(A, overwrite: bool = False) -> np.ndarray:
    """Upper Cholesky factor U (n, n) with ``U.T @ U = A`` of a symmetric positive definite A (n, n)
    (only its upper triangle is read; the strict lower triangle of U is garbage). Raises
    ``numpy.linalg.LinAlgError`` when A is not positive definite."""
    U, info = dpotrf(A, lower=0, clean=0, overwrite_a=int(overwrite))
    if info != 0:
        raise np.linalg.LinAlgError(f"matrix not positive definite (LAPACK dpotrf info {info})")
    return U


def cholesky_solve(U, b) -> np.ndarray:
    """``A^-1 b`` for b (n,) or (n, k) from the factor of :func:`cholesky_factor`."""
    x, info = dpotrs(U, b, lower=0)
    if info != 0:  # pragma: no cover - only for malformed arguments
        raise ValueError(f"LAPACK dpotrs failed (info {info})")
    return x


def cholesky_inverse(A) -> np.ndarray:
    """``A^-1`` (n, n, symmetric) of a symmetric positive definite A (n, n); LinAlgError if not."""
    U = cholesky_factor(A)
    inv, info = dpotri(U, lower=0)
    if info != 0:
        raise np.linalg.LinAlgError(f"matrix is singular (LAPACK dpotri info {info})")
    upper = np.triu(inv)
    return upper + np.triu(inv, 1).T
