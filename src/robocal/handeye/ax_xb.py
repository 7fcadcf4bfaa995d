"""Linear solvers of ``A X = X B`` (METHODS.md section 3, "Hand-eye": linear first, then refine).

Each takes the motion pairs A, B (M, 4, 4) [mm] of :func:`.motions.motion_pairs` and returns X
(4, 4). Rotation first, then the translation from ``(R_A - I) t_X = R_X t_B - t_A`` by linear
least squares (:func:`translation_least_squares`), except Daniilidis, which solves both at once.

* Tsai–Lenz (1989): modified Rodrigues vectors ``P = 2 sin(theta/2) n``;
  ``[P_A + P_B]x P' = P_B - P_A`` in least squares, ``P_X = 2 P' / sqrt(1 + |P'|^2)``.
* Park–Martin (1994): rotation vectors ``a = log R_A``, ``b = log R_B`` satisfy ``a = R_X b``;
  ``R_X = (M^T M)^(-1/2) M^T`` with ``M = sum b a^T`` (the orthogonal Procrustes solution).
* Daniilidis (1999): unit dual quaternions ``a q = q b``; each motion gives 6 linear equations
  in the 8 numbers of ``q``; the null space of the stack is two-dimensional and the unit and
  orthogonality constraints fix the combination.
"""

from __future__ import annotations

import numpy as np

from ..transforms import matrix_from_quaternion, quaternion_from_matrix, skew, so3_log

__all__ = ["tsai_lenz", "park_martin", "daniilidis", "translation_least_squares"]


def _transform(R, t) -> np.ndarray:
    X = np.eye(4)
    X[:3, :3], X[:3, 3] = R, t
    return X


def translation_least_squares(A, B, R_X) -> np.ndarray:
    """t_X (3,) [mm] from ``(R_A - I) t_X = R_X t_B - t_A`` stacked over all motions."""
    lhs = (A[:, :3, :3] - np.eye(3)).reshape(-1, 3)
    rhs = (R_X @ B[:, :3, 3, None])[..., 0] - A[:, :3, 3]
    return np.linalg.lstsq(lhs, rhs.ravel(), rcond=None)[0]


def _orthonormal(M) -> np.ndarray:
    U, _, Vt = np.linalg.svd(M)
    return U @ np.diag([1.0, 1.0, np.linalg.det(U @ Vt)]) @ Vt


def tsai_lenz(A, B) -> np.ndarray:
    """X (4, 4) by Tsai and Lenz's modified Rodrigues formulation."""
    def rodrigues(R):
        w = so3_log(R)
        th = np.linalg.norm(w, axis=1, keepdims=True)
        return 2.0 * np.sin(th / 2) * w / np.where(th > 0, th, 1.0)

    Pa, Pb = rodrigues(A[:, :3, :3]), rodrigues(B[:, :3, :3])
    Pp = np.linalg.lstsq(skew(Pa + Pb).reshape(-1, 3), (Pb - Pa).ravel(), rcond=None)[0]
    P = 2.0 * Pp / np.sqrt(1.0 + Pp @ Pp)
    R = (1.0 - P @ P / 2.0) * np.eye(3) + 0.5 * (np.outer(P, P) + np.sqrt(4.0 - P @ P) * skew(P))
    R = _orthonormal(R)
    return _transform(R, translation_least_squares(A, B, R))


def park_martin(A, B) -> np.ndarray:
    """X (4, 4) by Park and Martin's closed form on the rotation logarithms."""
    a, b = so3_log(A[:, :3, :3]), so3_log(B[:, :3, :3])
    M = b.T @ a  # sum_i b_i a_i^T
    w, V = np.linalg.eigh(M.T @ M)
    R = V @ np.diag(1.0 / np.sqrt(w)) @ V.T @ M.T
    R = _orthonormal(R)
    return _transform(R, translation_least_squares(A, B, R))


def _dual_quaternions(T) -> tuple:
    """(real (M, 4), dual (M, 4)) with w >= 0: ``q_d = 0.5 (0, t) q_r``."""
    qr = quaternion_from_matrix(T[:, :3, :3])
    t = np.concatenate([np.zeros((len(T), 1)), T[:, :3, 3]], axis=1)
    return qr, 0.5 * _qmul(t, qr)


def _qmul(p, q) -> np.ndarray:
    pw, pv, qw, qv = p[..., :1], p[..., 1:], q[..., :1], q[..., 1:]
    return np.concatenate([pw * qw - np.sum(pv * qv, -1, keepdims=True), pw * qv + qw * pv + np.cross(pv, qv)], -1)


def daniilidis(A, B) -> np.ndarray:
    """X (4, 4) by Daniilidis's dual-quaternion SVD."""
    ar, ad = _dual_quaternions(A)
    br, bd = _dual_quaternions(B)
    M = len(A)
    S = np.zeros((M, 6, 8))
    S[:, :3, 0], S[:, :3, 1:4] = ar[:, 1:] - br[:, 1:], skew(ar[:, 1:] + br[:, 1:])
    S[:, 3:, 0], S[:, 3:, 1:4] = ad[:, 1:] - bd[:, 1:], skew(ad[:, 1:] + bd[:, 1:])
    S[:, 3:, 4], S[:, 3:, 5:8] = S[:, :3, 0], S[:, :3, 1:4]
    v = np.linalg.svd(S.reshape(-1, 8), full_matrices=False)[2][-2:]  # the two-dimensional null space
    u1, v1, u2, v2 = v[0, :4], v[0, 4:], v[1, :4], v[1, 4:]
    # q = l1 (u1, v1) + l2 (u2, v2): |q_r| = 1 and q_r . q_d = 0; with s = l1 / l2 the second is quadratic
    a, b, c = u1 @ v1, u1 @ v2 + u2 @ v1, u2 @ v2
    roots = np.roots([a, b, c]) if abs(a) > 1e-15 else np.array([-c / b])
    real = np.abs(np.imag(roots)) < 1e-9
    # noisy motions can push the discriminant below zero: the nearest real choice is the real part
    roots = np.real(roots[real]) if real.any() else np.real(roots[:1])
    norms = roots**2 * (u1 @ u1) + 2 * roots * (u1 @ u2) + u2 @ u2
    s = roots[np.argmax(norms)]
    l2 = 1.0 / np.sqrt(norms.max())
    qr, qd = s * l2 * u1 + l2 * u2, s * l2 * v1 + l2 * v2
    t = 2.0 * _qmul(qd, qr * np.array([1.0, -1.0, -1.0, -1.0]))[1:]
    return _transform(matrix_from_quaternion(qr), t)
