"""Robot-world and hand-eye together: ``A_i X = Z B_i`` (METHODS.md section 3, "Hand-eye").

Per image (no motion pairs): with ``F_i = T_base_flange`` and ``C_i = T_camera_target``,

* eye-in-hand: ``F_i X = Z C_i^-1`` with ``X = T_flange_camera``, ``Z = T_base_target``;
* eye-to-hand: ``F_i X = Z C_i`` with ``X = T_flange_target``, ``Z = T_base_camera``.

Rotation by Shah's closed form (2013): ``R_A R_X R_B^T = R_Z`` gives ``vec(R_Z) = (R_B (x) R_A)
vec(R_X)`` (column-major vec, Kronecker product), so ``K = sum (R_B (x) R_A)`` has rank one,
``K = N vec(R_Z) vec(R_X)^T``; its leading singular vectors give both rotations. Translations from
``R_A t_X - t_Z = R_Z t_B - t_A`` by linear least squares.
"""

from __future__ import annotations

import numpy as np

from .ax_xb import _orthonormal, _transform

__all__ = ["shah"]


def _rotation_from(v) -> np.ndarray:
    R = v.reshape(3, 3, order="F")
    R = R * np.cbrt(1.0 / np.linalg.det(R))  # scale and sign: det = 1
    return _orthonormal(R)


def shah(A, B) -> tuple:
    """``(X, Z)`` (4, 4) each from A, B (N, 4, 4) with ``A_i X = Z B_i`` (Shah's closed form)."""
    RA, RB = A[:, :3, :3], B[:, :3, :3]
    K = np.einsum("nij,nkl->ikjl", RB, RA).reshape(9, 9)  # sum of kron(R_B, R_A)
    U, _, Vt = np.linalg.svd(K)
    R_X, R_Z = _rotation_from(Vt[0]), _rotation_from(U[:, 0])
    n = len(A)
    lhs = np.zeros((n, 3, 6))
    lhs[:, :, :3], lhs[:, :, 3:] = RA, -np.eye(3)
    rhs = (R_Z @ B[:, :3, 3, None])[..., 0] - A[:, :3, 3]
    t = np.linalg.lstsq(lhs.reshape(-1, 6), rhs.ravel(), rcond=None)[0]
    return _transform(R_X, t[:3]), _transform(R_Z, t[3:])
