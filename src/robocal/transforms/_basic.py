"""Batched SO(3)/SE(3) primitives on arrays shaped ``(..., 3, 3)`` and ``(..., 4, 4)``.

Naming rule (see ``docs/conventions.md``): ``T_a_b`` is the pose of frame ``b`` written in frame
``a``; its columns are b's axes and origin in a-coordinates, so ``p_a = T_a_b @ p_b`` and poses
compose as ``T_a_c = T_a_b @ T_b_c``. Lengths are millimetres and angles radians unless a name
says otherwise.
"""

from __future__ import annotations

import math

import numpy as np

from ._quaternion import rotvec_from_matrix

__all__ = [
    "rodrigues_coefficients",
    "rot_x",
    "rot_y",
    "rot_z",
    "rot_axis",
    "transforms_from",
    "translations",
    "invert_transforms",
    "compose",
    "transform_points",
    "skew",
    "so3_exp",
    "so3_log",
    "rotation_angle",
    "se3_exp",
    "se3_log",
]


def _rot(angle, i: int, j: int) -> np.ndarray:
    angle = np.asarray(angle, dtype=float)
    c, s = np.cos(angle), np.sin(angle)
    R = np.zeros(angle.shape + (3, 3))
    k = 3 - i - j
    R[..., k, k] = 1.0
    R[..., i, i] = c
    R[..., j, j] = c
    R[..., i, j] = -s
    R[..., j, i] = s
    return R


def rot_x(angle) -> np.ndarray:
    """Rotation about x by ``angle`` [rad], shape ``angle.shape + (3, 3)``."""
    return _rot(angle, 1, 2)


def rot_y(angle) -> np.ndarray:
    """Rotation about y by ``angle`` [rad], shape ``angle.shape + (3, 3)``."""
    return _rot(angle, 2, 0)


def rot_z(angle) -> np.ndarray:
    """Rotation about z by ``angle`` [rad], shape ``angle.shape + (3, 3)``."""
    return _rot(angle, 0, 1)


def rot_axis(axis, angle) -> np.ndarray:
    """Rotation by ``angle`` [rad] about unit-normalized ``axis`` (3,), Rodrigues formula."""
    axis = np.asarray(axis, dtype=float)
    n = np.linalg.norm(axis, axis=-1, keepdims=True)
    if np.any(n == 0):
        raise ValueError("rot_axis: axis has zero length")
    return so3_exp(axis / n * np.asarray(angle, dtype=float)[..., None])


def transforms_from(R=None, p=None) -> np.ndarray:
    """Homogeneous transforms ``(..., 4, 4)`` from rotations ``(..., 3, 3)`` and translations ``(..., 3)``."""
    if R is None and p is None:
        return np.eye(4)
    R = np.broadcast_to(np.eye(3), np.shape(p)[:-1] + (3, 3)) if R is None else np.asarray(R, float)
    p = np.zeros(R.shape[:-1]) if p is None else np.asarray(p, float)
    shape = np.broadcast_shapes(R.shape[:-2], p.shape[:-1])
    T = np.zeros(shape + (4, 4))
    T[..., :3, :3] = R
    T[..., :3, 3] = p
    T[..., 3, 3] = 1.0
    return T


def translations(p) -> np.ndarray:
    """Pure translations ``(..., 4, 4)`` from ``(..., 3)`` vectors."""
    return transforms_from(None, p)


def invert_transforms(T) -> np.ndarray:
    """Inverse of rigid transforms ``(..., 4, 4)`` using ``R^T`` (no general matrix inverse)."""
    T = np.asarray(T, dtype=float)
    Rt = np.swapaxes(T[..., :3, :3], -1, -2)
    out = np.zeros(T.shape)
    out[..., :3, :3] = Rt
    out[..., :3, 3] = -(Rt @ T[..., :3, 3:4])[..., 0]
    out[..., 3, 3] = 1.0
    return out


def compose(*Ts) -> np.ndarray:
    """Product ``T_0 @ T_1 @ ...`` of broadcastable transform stacks."""
    out = np.asarray(Ts[0], dtype=float)
    for T in Ts[1:]:
        out = out @ np.asarray(T, dtype=float)
    return out


def transform_points(T, p) -> np.ndarray:
    """Apply ``T (..., 4, 4)`` to points ``p (..., 3)``: ``R p + t``."""
    T = np.asarray(T, dtype=float)
    p = np.asarray(p, dtype=float)
    return (T[..., :3, :3] @ p[..., None])[..., 0] + T[..., :3, 3]


def skew(v) -> np.ndarray:
    """Cross-product matrices ``(..., 3, 3)`` with ``skew(v) @ w == cross(v, w)``."""
    v = np.asarray(v, dtype=float)
    S = np.zeros(v.shape + (3,))
    S[..., 0, 1], S[..., 0, 2] = -v[..., 2], v[..., 1]
    S[..., 1, 0], S[..., 1, 2] = v[..., 2], -v[..., 0]
    S[..., 2, 0], S[..., 2, 1] = -v[..., 1], v[..., 0]
    return S


def so3_exp(rotvec) -> np.ndarray:
    """Rotation matrices ``(..., 3, 3)`` from rotation vectors ``(..., 3)`` [rad] (axis * angle)."""
    w = np.asarray(rotvec, dtype=float)
    if w.size == 3 and w.ndim >= 1 and w.shape[-1] == 3:
        return _so3_exp_one(w)
    th = np.linalg.norm(w, axis=-1)[..., None, None]
    small = th < 1e-6
    th_safe = np.where(small, 1.0, th)
    a = np.where(small, 1.0 - th**2 / 6.0, np.sin(th_safe) / th_safe)
    b = np.where(small, 0.5 - th**2 / 24.0, (1.0 - np.cos(th_safe)) / th_safe**2)
    K = skew(w)
    return np.eye(3) + a * K + b * (K @ K)


def rodrigues_coefficients(x: float, y: float, z: float) -> tuple[float, float]:
    """``(sin t / t, (1 - cos t) / t^2)`` for the rotation vector (x, y, z) [rad] of angle t (their
    series below t = 1e-6): ``exp(skew(w)) = I + a skew(w) + b skew(w)^2``."""
    th2 = x * x + y * y + z * z
    th = math.sqrt(th2)
    if th < 1e-6:
        return 1.0 - th2 / 6.0, 0.5 - th2 / 24.0
    return math.sin(th) / th, (1.0 - math.cos(th)) / th2


def _so3_exp_one(w) -> np.ndarray:
    """:func:`so3_exp` of one rotation vector (shape (3,) or (1, 3)) with scalar math: the same
    formula, ~6x faster than the batched code for one frame (the solvers' frame updates)."""
    x, y, z = (float(v) for v in w.reshape(3))
    a, b = rodrigues_coefficients(x, y, z)
    K = np.array([[0.0, -z, y], [z, 0.0, -x], [-y, x, 0.0]])
    return (np.eye(3) + a * K + b * (K @ K)).reshape(w.shape[:-1] + (3, 3))


def so3_log(R) -> np.ndarray:
    """Rotation vectors ``(..., 3)`` [rad], angle in [0, pi], from rotations ``(..., 3, 3)``.

    Same as :func:`robocal.transforms.rotvec_from_matrix` (through the quaternion, accurate
    to rounding up to pi).
    """
    return rotvec_from_matrix(R)


def rotation_angle(R) -> np.ndarray:
    """Rotation angle [rad] in [0, pi] of rotations ``(..., 3, 3)``."""
    R = np.asarray(R, dtype=float)
    return np.arccos(np.clip((np.trace(R, axis1=-2, axis2=-1) - 1.0) / 2.0, -1.0, 1.0))


def se3_exp(twist) -> np.ndarray:
    """Transforms from the 6-vector ``(rx, ry, rz, x, y, z)``: rotation vector [rad] and translation [mm].

    This is the minimal, always-valid frame parametrization used by calibration: rotation by
    ``so3_exp`` and a plain translation (not the screw exponential), so the translation part is
    directly the frame origin.
    """
    twist = np.asarray(twist, dtype=float)
    return transforms_from(so3_exp(twist[..., :3]), twist[..., 3:])


def se3_log(T) -> np.ndarray:
    """Inverse of :func:`se3_exp`: ``(..., 6)`` = (rotation vector [rad], origin [mm])."""
    T = np.asarray(T, dtype=float)
    return np.concatenate([so3_log(T[..., :3, :3]), T[..., :3, 3]], axis=-1)
