"""Unit quaternions (w, x, y, z) and the rotation-vector logarithm computed through them.

Batched over leading ``...`` dimensions; rotations are ``(..., 3, 3)``, quaternions ``(..., 4)``
with the scalar first, rotation vectors ``(..., 3)`` = axis * angle [rad]. This module depends
on nothing else in :mod:`robocal.transforms` but the input checks, so :func:`so3_log` (in
``_basic``) and the pose conventions (in ``_orientation``) both build on it.
"""

from __future__ import annotations

import math

import numpy as np

from ._checks import as_matrices, as_vectors

__all__ = ["quaternion_from_matrix", "matrix_from_quaternion", "rotvec_from_matrix"]


def quaternion_from_matrix(R) -> np.ndarray:
    """Unit quaternions ``(..., 4)`` as (w, x, y, z) from rotations ``(..., 3, 3)``.

    Shepperd's method, vectorized: of the four algebraically equivalent formulas, each item uses
    the one whose pivot (4w^2, 4x^2, 4y^2 or 4z^2) is largest, so no division by a small number.
    The sign is chosen so that ``w >= 0`` (q and -q are the same rotation); for a 180 degree
    rotation (w = 0) the sign of the vector part is whatever the pivot formula gives.
    """
    R = as_matrices(R, "R")
    r00, r11, r22 = R[..., 0, 0], R[..., 1, 1], R[..., 2, 2]
    tr = r00 + r11 + r22
    d21, d02, d10 = R[..., 2, 1] - R[..., 1, 2], R[..., 0, 2] - R[..., 2, 0], R[..., 1, 0] - R[..., 0, 1]
    s01, s02, s12 = R[..., 0, 1] + R[..., 1, 0], R[..., 0, 2] + R[..., 2, 0], R[..., 1, 2] + R[..., 2, 1]
    cand = np.stack(
        [
            np.stack([1.0 + tr, d21, d02, d10], axis=-1),  # 4w * q
            np.stack([d21, 1.0 + 2.0 * r00 - tr, s01, s02], axis=-1),  # 4x * q
            np.stack([d02, s01, 1.0 + 2.0 * r11 - tr, s12], axis=-1),  # 4y * q
            np.stack([d10, s02, s12, 1.0 + 2.0 * r22 - tr], axis=-1),  # 4z * q
        ],
        axis=-2,
    )
    pivot = np.argmax(np.stack([tr, r00, r11, r22], axis=-1), axis=-1)
    q = np.take_along_axis(cand, pivot[..., None, None], axis=-2)[..., 0, :]
    q = q / np.linalg.norm(q, axis=-1, keepdims=True)
    return np.where(q[..., :1] < 0.0, -q, q)


def matrix_from_quaternion(q, tol: float | None = 1e-3) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` from quaternions ``(..., 4)`` ordered (w, x, y, z).

    The quaternion is always normalized. ``ValueError`` (naming ``q``) if its norm is ~0, or, when
    ``tol`` is not None, if the norm differs from 1 by more than ``tol``: a norm far from 1 usually
    means the components are in the wrong order, scaled, or not a quaternion at all. Pass
    ``tol=None`` to accept any non-zero norm.
    """
    return matrix_from_quaternion_named(q, tol, "q")


def matrix_from_quaternion_named(q, tol, name: str) -> np.ndarray:
    """:func:`matrix_from_quaternion` whose errors name the argument ``name``."""
    q = as_vectors(q, 4, name)
    norm = np.linalg.norm(q, axis=-1)
    if np.any(norm < 1e-12):
        raise ValueError(f"{name}: quaternion (w, x, y, z) with zero norm is not a rotation")
    if tol is not None:
        dev = np.abs(norm - 1.0).max(initial=0.0)
        if dev > tol:
            raise ValueError(
                f"{name}: quaternion (w, x, y, z) norm deviates from 1 by {dev:.3g} > tol={tol:g}; "
                "check the component order (w first) or pass tol=None to normalize anyway"
            )
    w, x, y, z = np.moveaxis(q / norm[..., None], -1, 0)
    R = np.empty(q.shape[:-1] + (3, 3))
    R[..., 0, 0] = 1.0 - 2.0 * (y * y + z * z)
    R[..., 0, 1] = 2.0 * (x * y - w * z)
    R[..., 0, 2] = 2.0 * (x * z + w * y)
    R[..., 1, 0] = 2.0 * (x * y + w * z)
    R[..., 1, 1] = 1.0 - 2.0 * (x * x + z * z)
    R[..., 1, 2] = 2.0 * (y * z - w * x)
    R[..., 2, 0] = 2.0 * (x * z - w * y)
    R[..., 2, 1] = 2.0 * (y * z + w * x)
    R[..., 2, 2] = 1.0 - 2.0 * (x * x + y * y)
    return R


def rotvec_from_matrix(R) -> np.ndarray:
    """Rotation vectors ``(..., 3)`` [rad], angle in [0, pi], from rotations ``(..., 3, 3)``.

    Computed through the Shepperd quaternion, ``angle = 2 atan2(|v|, w)``, which stays accurate to
    rounding right up to pi (an angle taken from the trace with ``arccos`` loses about half the
    digits there). At exactly pi, ``v`` and ``-v`` are the same rotation; either may be returned.
    """
    R = as_matrices(R, "R")
    if R.size == 9:
        return _rotvec_one(R)
    q = quaternion_from_matrix(R)
    w, v = q[..., 0], q[..., 1:]
    n = np.linalg.norm(v, axis=-1)
    small = n < 1e-8
    # 2 atan2(n, w) / n, with its series 2/w (1 - n^2 / (3 w^2)) for tiny n (w ~ 1 there)
    scale = np.where(small, 2.0 / w * (1.0 - n**2 / (3.0 * w**2)), 2.0 * np.arctan2(n, w) / np.where(small, 1.0, n))
    return v * scale[..., None]


def _rotvec_one(R) -> np.ndarray:
    """:func:`rotvec_from_matrix` of one rotation (shape (3, 3) or (1, 3, 3)) with scalar math: the
    same Shepperd quaternion and the same formulas, several times faster than the batched code for
    one frame (the solvers report every frame's rotation vector)."""
    (r00, r01, r02), (r10, r11, r12), (r20, r21, r22) = R.reshape(3, 3).tolist()
    tr = r00 + r11 + r22
    d21, d02, d10 = r21 - r12, r02 - r20, r10 - r01
    s01, s02, s12 = r01 + r10, r02 + r20, r12 + r21
    pivots = (tr, r00, r11, r22)
    k = pivots.index(max(pivots))  # the first largest, as numpy's argmax
    q = ((1.0 + tr, d21, d02, d10), (d21, 1.0 + 2.0 * r00 - tr, s01, s02),
         (d02, s01, 1.0 + 2.0 * r11 - tr, s12), (d10, s02, s12, 1.0 + 2.0 * r22 - tr))[k]
    norm = math.sqrt(q[0] * q[0] + q[1] * q[1] + q[2] * q[2] + q[3] * q[3])
    w, x, y, z = (c / norm for c in q)
    if w < 0.0:
        w, x, y, z = -w, -x, -y, -z
    n = math.sqrt(x * x + y * y + z * z)
    scale = 2.0 / w * (1.0 - n * n / (3.0 * w * w)) if n < 1e-8 else 2.0 * math.atan2(n, w) / n
    return np.array([x * scale, y * scale, z * scale]).reshape(R.shape[:-2] + (3,))
