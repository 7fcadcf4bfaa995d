"""Initial guesses: rigid (Kabsch/Umeyama, no scale) fits of frames to corresponding points, and
the 6-D start from measured orientations when the points cannot fix a rotation."""

from __future__ import annotations

import numpy as np

__all__ = ["rigid_fit", "mean_rotation", "frame_from_orientations", "base_and_tool_from_orientations",
           "collinearity"]


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


def collinearity(points) -> float:
    """How far ``points`` (M, 3) [mm] are from a line: the second singular value of the centred
    points over the first (0 for a line or a single point; NaN rows ignored)."""
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    P = P[np.all(np.isfinite(P), axis=1)]
    if len(P) < 3:
        return 0.0
    s = np.linalg.svd(P - P.mean(axis=0), compute_uv=False)
    return float(s[1] / s[0]) if s[0] > 0 else 0.0


def _pair_indices(n: int):
    """Index pairs (i, j) of the relative rotations: every pair for a few poses, else neighbours and
    poses half the set apart (O(n) pairs)."""
    if n <= 40:
        i, j = np.triu_indices(n, 1)
        return i, j
    i = np.concatenate([np.arange(n - 1), np.arange(n - n // 2)])
    j = np.concatenate([np.arange(1, n), np.arange(n // 2, n)])
    return i, j


def base_and_tool_from_orientations(R_base_ee, R_measured, points_from=None, points_to=None,
                                    min_ratio: float = 1e-3) -> tuple:
    """The base rotation ``R_b`` and the tool rotation ``R_t`` of ``R_measured_i = R_b R_base_ee_i
    R_t`` from the data alone (no tool rotation assumed), and the base translation.

    R_base_ee: (N, 3, 3) predicted end-effector orientations in the base frame (nominal model);
    R_measured: (N, 3, 3) measured tool orientations in the instrument frame; points_from /
    points_to: optional (M, 3) corresponding points [mm] (predicted in the base frame, measured)
    whose spread adds its directions. The relative rotations ``R_m_i R_m_j^T = R_b (R_e_i R_e_j^T)
    R_b^T`` turn the same axes, rotated by ``R_b``: a Kabsch fit of those axes (and of the centred
    points, each set scaled to unit weight) gives ``R_b``, then ``R_t`` is the chordal mean of
    ``R_b^T``-rotated residual rotations. Returns ``(T_base (4, 4), R_tool (3, 3))``; raises
    ``ValueError`` when the axes and points span fewer than two directions (``min_ratio`` of the
    fit's singular values): the data then cannot separate base and tool rotation.
    """
    Re = np.asarray(R_base_ee, dtype=float).reshape(-1, 3, 3)
    Rm = np.asarray(R_measured, dtype=float).reshape(-1, 3, 3)
    if Re.shape != Rm.shape or len(Re) < 2:
        raise ValueError(f"base_and_tool_from_orientations: needs two or more matching orientations, got {Re.shape} "
                         f"and {Rm.shape}")
    from ..transforms import so3_log

    i, j = _pair_indices(len(Re))
    b = so3_log(Re[i] @ np.swapaxes(Re[j], 1, 2))  # axes * angles in the base frame
    a = so3_log(Rm[i] @ np.swapaxes(Rm[j], 1, 2))  # the same in the instrument frame
    H = b.T @ a
    H = H / max(np.linalg.svd(H, compute_uv=False)[0], 1e-300)
    if points_from is not None and points_to is not None:
        A = np.asarray(points_from, dtype=float).reshape(-1, 3)
        B = np.asarray(points_to, dtype=float).reshape(-1, 3)
        ok = np.all(np.isfinite(A), axis=1) & np.all(np.isfinite(B), axis=1)
        if ok.sum() >= 2:
            Hp = (A[ok] - A[ok].mean(0)).T @ (B[ok] - B[ok].mean(0))
            sp = np.linalg.svd(Hp, compute_uv=False)[0]
            if sp > 0:
                H = H + Hp / sp
    U, s, Vt = np.linalg.svd(H)
    if s[1] <= min_ratio * max(s[0], 1e-300):
        raise ValueError("base_and_tool_from_orientations: the orientations turn about one axis and the points lie "
                         "on a line: base and tool rotation cannot be told apart")
    D = np.diag([1.0, 1.0, np.sign(np.linalg.det(Vt.T @ U.T)) or 1.0])
    R_b = Vt.T @ D @ U.T
    R_t = mean_rotation(np.swapaxes(Re, 1, 2) @ R_b.T @ Rm)
    T = np.eye(4)
    T[:3, :3] = R_b
    if points_from is not None and points_to is not None:
        A = np.asarray(points_from, dtype=float).reshape(-1, 3)
        B = np.asarray(points_to, dtype=float).reshape(-1, 3)
        ok = np.all(np.isfinite(A), axis=1) & np.all(np.isfinite(B), axis=1)
        if ok.any():
            T[:3, 3] = np.mean(B[ok] - A[ok] @ R_b.T, axis=0)
    return T, R_t
