"""Lens distortion of normalised image coordinates, with analytic Jacobians (METHODS.md section 3,
"Hand-eye": the camera-model study of the HALCON paper needs both models).

Both models map *undistorted* normalised coordinates ``x = (X / Z, Y / Z)`` (N, 2) [dimensionless]
to *distorted* normalised coordinates ``xd`` (N, 2); pixels follow by ``u = fx xd + cx``,
``v = fy yd + cy`` (:mod:`.projection`).

* **Brown–Conrady**, OpenCV's convention and coefficient order ``k1, k2, p1, p2[, k3[, k4, k5,
  k6]]`` (4, 5 or 8 numbers), so coefficients from OpenCV or a ROS ``camera_info`` load unchanged::

      r2 = x^2 + y^2
      radial = (1 + k1 r2 + k2 r2^2 + k3 r2^3) / (1 + k4 r2 + k5 r2^2 + k6 r2^3)
      xd = x radial + 2 p1 x y + p2 (r2 + 2 x^2)
      yd = y radial + p1 (r2 + 2 y^2) + 2 p2 x y

  OpenCV's thin-prism (s1..s4) and tilt (tauX, tauY) terms (12 or 14 numbers) are not supported.

* **Division model** (HALCON's ``area_scan_division``), one coefficient ``kappa``: the undistorted
  point is ``x = xd / (1 + kappa |xd|^2)``; its inverse, used for projection, is
  ``xd = 2 x / (1 + sqrt(1 - 4 kappa |x|^2))``. Here ``kappa`` acts on *normalised* coordinates
  (dimensionless); HALCON's kappa [1/m^2] acts on image-plane coordinates in metres, so
  ``kappa_here = kappa_halcon * f^2`` with the focal length f [m]. Points with
  ``4 kappa |x|^2 > 1`` have no image (NaN).
"""

from __future__ import annotations

import numpy as np

__all__ = ["BROWN_SIZES", "brown_distort", "division_distort", "division_undistort"]

#: the numbers of Brown–Conrady coefficients accepted (OpenCV's 4, 5 and 8)
BROWN_SIZES = (4, 5, 8)


def _brown_coefficients(coeffs) -> np.ndarray:
    c = np.asarray(coeffs, dtype=float).ravel()
    if c.size not in BROWN_SIZES:
        raise ValueError(f"Brown-Conrady distortion takes 4, 5 or 8 coefficients (k1, k2, p1, p2[, k3[, k4, k5, k6]]), "
                         f"got {c.size}" + (": thin-prism and tilt terms are not supported" if c.size in (12, 14) else ""))
    return np.concatenate([c, np.zeros(8 - c.size)])


def brown_distort(x, coeffs, jacobian: bool = False, coefficients: bool = True):
    """Brown–Conrady distortion (OpenCV order) of normalised points x (N, 2).

    Returns xd (N, 2), and with ``jacobian`` also ``dxd/dx`` (N, 2, 2) and ``dxd/dcoeffs``
    (N, 2, K) with K = len(coeffs) (None when not ``coefficients``).
    """
    x = np.asarray(x, dtype=float)
    K = np.asarray(coeffs, dtype=float).size
    k1, k2, p1, p2, k3, k4, k5, k6 = _brown_coefficients(coeffs)
    X, Y = x[:, 0], x[:, 1]
    r2 = X * X + Y * Y
    num = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3))
    rational = K == 8  # without k4..k6 the denominator is 1: not computed
    den = 1.0 + r2 * (k4 + r2 * (k5 + r2 * k6)) if rational else 1.0
    rad = num / den if rational else num
    xd = np.stack([X * rad + 2 * p1 * X * Y + p2 * (r2 + 2 * X * X),
                   Y * rad + p1 * (r2 + 2 * Y * Y) + 2 * p2 * X * Y], axis=1)
    if not jacobian:
        return xd
    dnum = k1 + r2 * (2 * k2 + 3 * k3 * r2)  # d num / d r2
    if rational:
        dden = k4 + r2 * (2 * k5 + 3 * k6 * r2)
        drad = (dnum * den - num * dden) / den**2  # d rad / d r2
    else:
        drad = dnum
    J = np.empty((len(x), 2, 2))
    J[:, 0, 0] = rad + 2 * X * X * drad + 2 * p1 * Y + 6 * p2 * X
    J[:, 0, 1] = 2 * X * Y * drad + 2 * p1 * X + 2 * p2 * Y
    J[:, 1, 0] = 2 * X * Y * drad + 2 * p1 * X + 2 * p2 * Y
    J[:, 1, 1] = rad + 2 * Y * Y * drad + 6 * p1 * Y + 2 * p2 * X
    if not coefficients:
        return xd, J, None
    Jc = np.empty((len(x), 2, K))
    xy = np.stack([X, Y], axis=1)  # radial terms scale x and y alike
    r4 = r2 * r2
    for col, term in ((0, r2), (1, r4), (4, r4 * r2)):
        if col < K:
            Jc[:, :, col] = xy * (term / den if rational else term)[:, None]
    if rational:
        for col, term in ((5, -num * r2 / den**2), (6, -num * r4 / den**2), (7, -num * r4 * r2 / den**2)):
            Jc[:, :, col] = xy * term[:, None]
    Jc[:, 0, 2], Jc[:, 1, 2] = 2 * X * Y, r2 + 2 * Y * Y
    Jc[:, 0, 3], Jc[:, 1, 3] = r2 + 2 * X * X, 2 * X * Y
    return xd, J, Jc


def division_distort(x, kappa, jacobian: bool = False):
    """Division-model distortion of normalised points x (N, 2): ``xd = s x``,
    ``s = 2 / (1 + sqrt(1 - 4 kappa r2))``. NaN where ``4 kappa r2 > 1``.

    Returns xd (N, 2), and with ``jacobian`` also ``dxd/dx`` (N, 2, 2) and ``dxd/dkappa`` (N, 2, 1).
    """
    x = np.asarray(x, dtype=float)
    kappa = float(np.asarray(kappa, dtype=float).ravel()[0])
    r2 = np.sum(x * x, axis=1)
    disc = 1.0 - 4.0 * kappa * r2
    w = np.sqrt(np.where(disc > 0, disc, np.nan))
    s = 2.0 / (1.0 + w)
    xd = x * s[:, None]
    if not jacobian:
        return xd
    common = 4.0 / (w * (1.0 + w) ** 2)  # ds/dr2 = kappa * common, ds/dkappa = r2 * common
    ds_dr2 = kappa * common
    J = s[:, None, None] * np.eye(2) + 2.0 * ds_dr2[:, None, None] * x[:, :, None] * x[:, None, :]
    Jk = (x * (r2 * common)[:, None])[:, :, None]
    return xd, J, Jk


def division_undistort(xd, kappa) -> np.ndarray:
    """The division model's closed-form inverse: ``x = xd / (1 + kappa |xd|^2)``, (N, 2)."""
    xd = np.asarray(xd, dtype=float)
    kappa = float(np.asarray(kappa, dtype=float).ravel()[0])
    return xd / (1.0 + kappa * np.sum(xd * xd, axis=1))[:, None]
