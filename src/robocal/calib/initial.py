"""Initial guesses: rigid (Kabsch/Umeyama, no scale) fits of frames to corresponding points, and
the 6-D start from measured orientations when the points cannot fix a rotation."""

from __future__ import annotations

import numpy as np

__all__ = ["rigid_fit", "mean_rotation", "frame_from_orientations"]


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
        raise ValueError("rigid_fit: the points are (nearly) collinear; a rotation about their line is undetermined "
                         "(with measured orientations, frame_from_orientations gives a 6-D start)")
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0])
    R = Vt.T @ D @ U.T
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = cb - R @ ca
    return T


def mean_rotation(R) -> np.ndarray:
    """The rotation (3, 3) closest (chordal L2) to rotations ``R`` (N, 3, 3): the projection of
    their sum onto SO(3)."""
    U, _, Vt = np.linalg.svd(np.sum(np.asarray(R, dtype=float), axis=0))
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(U @ Vt)) or 1.0])
    return U @ D @ Vt


def frame_from_orientations(R_from, R_to, points_from, points_to) -> np.ndarray:
    """A rigid transform ``T`` (4, 4) with ``T R_from ~ R_to`` and ``T @ from ~ to``: the 6-D start
    that needs no spread of the points (a line of points, even one point).

    R_from, R_to: (N, 3, 3) corresponding orientations (e.g. the nominal model's predicted tool
    orientations in the base frame and the measured ones in the instrument frame);
    points_from, points_to: (M, 3) corresponding points [mm] (NaN rows ignored), M >= 1.
    The rotation is the chordal mean of ``R_to R_from^T``; the translation the mean point offset.
    """
    Ra = np.asarray(R_from, dtype=float).reshape(-1, 3, 3)
    Rb = np.asarray(R_to, dtype=float).reshape(-1, 3, 3)
    if Ra.shape != Rb.shape or not len(Ra):
        raise ValueError(f"frame_from_orientations: orientation sets differ or are empty {Ra.shape} vs {Rb.shape}")
    R = mean_rotation(Rb @ np.swapaxes(Ra, 1, 2))
    A = np.asarray(points_from, dtype=float).reshape(-1, 3)
    B = np.asarray(points_to, dtype=float).reshape(-1, 3)
    ok = np.all(np.isfinite(A), axis=1) & np.all(np.isfinite(B), axis=1)
    if not ok.any():
        raise ValueError("frame_from_orientations: needs at least one finite point pair")
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = np.mean(B[ok] - A[ok] @ R.T, axis=0)
    return T
