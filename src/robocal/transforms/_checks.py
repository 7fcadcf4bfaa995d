"""Input checks of the transform functions: shapes, finiteness, proper rotations.

Each check returns its input as a float array or raises ``ValueError`` naming the argument, the
shape that arrived and the shape expected.
"""

from __future__ import annotations

import numpy as np

__all__ = ["check_rotations", "check_transforms"]


def check_transforms(T, name: str = "T") -> np.ndarray:
    """Return ``T`` as a float array shaped ``(..., 4, 4)`` or raise ``ValueError`` naming it."""
    T = np.asarray(T, dtype=float)
    if T.ndim < 2 or T.shape[-2:] != (4, 4):
        raise ValueError(f"{name}: expected shape (..., 4, 4), got {T.shape}")
    if not np.all(np.isfinite(T)):
        raise ValueError(f"{name}: contains NaN or infinite values")
    if not np.allclose(T[..., 3, :], [0.0, 0.0, 0.0, 1.0], atol=1e-9):
        raise ValueError(f"{name}: last row must be [0, 0, 0, 1]")
    check_rotations(T[..., :3, :3], name=f"{name}[..., :3, :3]")
    return T


def check_rotations(R, name: str = "R", tol: float = 1e-6) -> np.ndarray:
    """Return ``R`` as ``(..., 3, 3)`` floats; raise ``ValueError`` if not proper rotations."""
    R = np.asarray(R, dtype=float)
    if R.ndim < 2 or R.shape[-2:] != (3, 3):
        raise ValueError(f"{name}: expected shape (..., 3, 3), got {R.shape}")
    err = np.abs(np.swapaxes(R, -1, -2) @ R - np.eye(3)).max(initial=0.0)
    if err > tol:
        raise ValueError(f"{name}: not orthonormal (max |R^T R - I| = {err:.2e} > {tol:.0e})")
    if np.any(np.linalg.det(R) < 0):
        raise ValueError(f"{name}: determinant is negative (a reflection, not a rotation)")
    return R


def as_vectors(x, n: int, name: str) -> np.ndarray:
    """Return ``x`` as finite floats shaped ``(..., n)`` or raise ``ValueError`` naming it."""
    x = np.asarray(x, dtype=float)
    if x.ndim < 1 or x.shape[-1] != n:
        raise ValueError(f"{name}: expected shape (..., {n}), got {x.shape}")
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{name}: contains NaN or infinite values")
    return x


def as_matrices(R, name: str) -> np.ndarray:
    """Return ``R`` as finite floats shaped ``(..., 3, 3)`` (not checked for orthonormality)."""
    R = np.asarray(R, dtype=float)
    if R.ndim < 2 or R.shape[-2:] != (3, 3):
        raise ValueError(f"{name}: expected shape (..., 3, 3), got {R.shape}")
    if not np.all(np.isfinite(R)):
        raise ValueError(f"{name}: contains NaN or infinite values")
    return R
