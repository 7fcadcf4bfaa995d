"""Initial guesses: rigid (Kabsch/Umeyama, no scale) fits of frames to corresponding points."""

from __future__ import annotations

import numpy as np

__all__ = ["rigid_fit"]


def rigid_fit(points_from, points_to, weights=None) -> np.ndarray:
    """The rigid transform ``T`` (4, 4) minimising ``sum w |T @ from - to|^2``.

    points_from, points_to: (M, 3) corresponding points [mm]; M >= 3 and not all collinear.
    Raises ``ValueError`` when the points cannot fix a rotation.
    """
    A = np.asarray(points_from, dtype=float).reshape(-1, 3)
    B = np.asarray(points_to, dtype=float).reshape(-1, 3)
    if A.shape != B.shape:
        raise ValueError(f"rigid_fit: point sets differ in shape {A.shape} vs {B.shape}")
    ok = np.all(np.isfinite(A), axis=1) & np.all(np.isfinite(B), axis=1)
    A, B = A[ok], B[ok]
    w = np.ones(len(A)) if weights is None else np.asarray(weights, dtype=float).reshape(-1)[ok]
    if len(A) < 3:
        raise ValueError(f"rigid_fit: needs at least 3 finite point pairs, got {len(A)}")
    ca = (w[:, None] * A).sum(0) / w.sum()
    cb = (w[:, None] * B).sum(0) / w.sum()
    H = ((A - ca) * w[:, None]).T @ (B - cb)
    U, s, Vt = np.linalg.svd(H)
    if s[1] <= 1e-9 * max(s[0], 1e-300):
        raise ValueError("rigid_fit: the points are (nearly) collinear; a rotation about their line is undetermined")
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0])
    R = Vt.T @ D @ U.T
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = cb - R @ ca
    return T
