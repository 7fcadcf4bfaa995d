"""Batched projection of camera-frame points to pixels with analytic Jacobians, and undistortion.

``u = fx xd + cx``, ``v = fy yd + cy`` with ``xd`` the distorted normalised coordinates of
``(X / Z, Y / Z)`` (:mod:`.distortion`). Intrinsics are ``(fx, fy, cx, cy)`` [px] (no skew, as
OpenCV's ``projectPoints``); ``model`` is ``"brown"`` (OpenCV order ``k1, k2, p1, p2[, k3[, k4,
k5, k6]]``) or ``"division"`` (``kappa``). Points are in millimetres in the camera frame (x right,
y down, z along the optical axis); a point with ``Z <= 0`` is behind the camera and projects to NaN.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .distortion import brown_distort, division_distort, division_undistort

__all__ = ["MODELS", "Projection", "project_points", "distort", "undistort_normalized", "undistort_pixels"]

#: the distortion models by name
MODELS = ("brown", "division")


@dataclass(frozen=True)
class Projection:
    """Pixels (N, 2) and, when asked, their Jacobians: ``d_point`` (N, 2, 3) [px/mm],
    ``d_intrinsics`` (N, 2, 4) w.r.t. ``(fx, fy, cx, cy)`` and ``d_distortion`` (N, 2, K)."""

    pixels: np.ndarray
    d_point: np.ndarray | None = None
    d_intrinsics: np.ndarray | None = None
    d_distortion: np.ndarray | None = None


def distort(x, distortion, model: str = "brown", jacobian: bool = False):
    """Distorted normalised coordinates of x (N, 2) under ``model`` (see :mod:`.distortion`)."""
    if model == "brown":
        return brown_distort(x, distortion, jacobian)
    if model == "division":
        return division_distort(x, distortion, jacobian)
    raise ValueError(f"unknown distortion model {model!r}; expected one of {', '.join(MODELS)}")


def project_points(points, intrinsics, distortion=(0.0, 0.0, 0.0, 0.0), model: str = "brown",
                   jacobian: bool = False, point_only: bool = False) -> Projection:
    """Project points (N, 3) [mm, camera frame] to pixels (N, 2); see the module docstring.
    ``point_only``: with ``jacobian``, only ``d_point`` (a pose solve needs no intrinsics' derivatives)."""
    P = np.asarray(points, dtype=float).reshape(-1, 3)
    fx, fy, cx, cy = np.asarray(intrinsics, dtype=float).ravel()
    Z = np.where(P[:, 2] > 0, P[:, 2], np.nan)
    x = P[:, :2] / Z[:, None]
    if jacobian and point_only and model == "brown":
        out = brown_distort(x, distortion, True, coefficients=False)
    else:
        out = distort(x, distortion, model, jacobian)
    xd = out[0] if jacobian else out
    f = np.array([fx, fy])
    pixels = xd * f + np.array([cx, cy])
    if not jacobian:
        return Projection(pixels)
    _, Jx, Jc = out
    # Jx @ d(X/Z, Y/Z)/d(X, Y, Z) written out: d(X/Z, Y/Z)/dP = [[1, 0, -x], [0, 1, -y]] / Z
    fz = f[None, :] / Z[:, None]  # (N, 2): row k scaled by f_k / Z
    d_point = np.empty((len(P), 2, 3))
    d_point[:, :, 0] = Jx[:, :, 0] * fz
    d_point[:, :, 1] = Jx[:, :, 1] * fz
    d_point[:, :, 2] = -(Jx[:, :, 0] * x[:, :1] + Jx[:, :, 1] * x[:, 1:]) * fz
    if point_only:
        return Projection(pixels, d_point)
    d_intr = np.zeros((len(P), 2, 4))
    d_intr[:, 0, 0], d_intr[:, 1, 1] = xd[:, 0], xd[:, 1]
    d_intr[:, 0, 2] = d_intr[:, 1, 3] = 1.0
    return Projection(pixels, d_point, d_intr, f[None, :, None] * Jc)


def undistort_normalized(xd, distortion, model: str = "brown", *, iterations: int = 20,
                         tol: float = 1e-14) -> np.ndarray:
    """Undistorted normalised coordinates (N, 2) of distorted ones xd (N, 2).

    Division model: closed form. Brown–Conrady: Gauss–Newton on ``distort(x) = xd`` with the
    analytic 2x2 Jacobian, started at ``x = xd``; stops when every step is below ``tol``. Points
    that do not converge (far outside the calibrated field) are NaN.
    """
    xd = np.asarray(xd, dtype=float).reshape(-1, 2)
    if model == "division":
        return division_undistort(xd, distortion)
    x = xd.copy()
    step = np.full(len(x), np.inf)
    for _ in range(iterations):
        f, J, _ = brown_distort(x, distortion, True, coefficients=False)  # the division model returned above
        e = xd - f  # the 2 x 2 systems J d = e by Cramer's rule (one batched LAPACK call per point is slower)
        det = J[:, 0, 0] * J[:, 1, 1] - J[:, 0, 1] * J[:, 1, 0]
        d = np.empty_like(e)
        d[:, 0] = (J[:, 1, 1] * e[:, 0] - J[:, 0, 1] * e[:, 1]) / det
        d[:, 1] = (J[:, 0, 0] * e[:, 1] - J[:, 1, 0] * e[:, 0]) / det
        x += d
        step = np.max(np.abs(d), axis=1)
        if np.all(step < tol):
            break
    x[~(step < 1e-9)] = np.nan
    return x


def undistort_pixels(pixels, intrinsics, distortion, model: str = "brown", **kwargs) -> np.ndarray:
    """Undistorted normalised coordinates (N, 2) (the ray ``(x, y, 1)``) of pixels (N, 2)."""
    fx, fy, cx, cy = np.asarray(intrinsics, dtype=float).ravel()
    uv = np.asarray(pixels, dtype=float).reshape(-1, 2)
    xd = (uv - np.array([cx, cy])) / np.array([fx, fy])
    return undistort_normalized(xd, distortion, model, **kwargs)
