"""An independent screw-axis fit of a two-axis positioner (tests/test_positioner_real_data.py and
docs/datasets.md's positioner figures), written from scratch with numpy and scipy only: it uses no
robocal code, so it can check robocal's own fit of the same records.

Two revolute axes (unit directions u1, u2 through points c1, c2) carry target points; the fitted
angle between the axes and their common normal are exactly the DH model's alpha1 and a1 (gauge
free), from another parameterisation."""

from __future__ import annotations

import numpy as np

__all__ = ["TARGET_POINTS_MM", "reference_axes"]

TARGET_POINTS_MM = np.array([[0.0, 0.0, 0.0], [100.0, 0.0, 0.0], [0.0, 100.0, 0.0]])  # the protocol's three points


def _about(u, t):
    """(N, 3, 3) rotations by angles t (N,) [rad] about the unit axis u (3,) (Rodrigues)."""
    K = np.array([[0.0, -u[2], u[1]], [u[2], 0.0, -u[0]], [-u[1], u[0], 0.0]])
    return np.eye(3) + np.sin(t)[:, None, None] * K + (1.0 - np.cos(t))[:, None, None] * (K @ K)


def _unit(polar, azimuth):
    return np.array([np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), np.cos(polar)])


def _screw_points(x, q, n_points):
    """Target points (N, n_points, 3) [mm] at joints q (N, 2) [rad]; x = (u1 polar, azimuth, u2 polar,
    azimuth, c1 (3), c2 (3), X (n_points, 3)) [rad, mm]."""
    u1, u2, c1, c2 = _unit(*x[0:2]), _unit(*x[2:4]), x[4:7], x[7:10]
    X = x[10:10 + 3 * n_points].reshape(n_points, 3)
    p = np.einsum("nij,kj->nki", _about(u2, q[:, 1]), X - c2) + c2
    return np.einsum("nij,nkj->nki", _about(u1, q[:, 0]), p - c1) + c1


def _axes_of(x):
    """(angle between the axes [deg], common normal [mm]) of a screw-model vector x."""
    u1, u2, c1, c2 = _unit(*x[0:2]), _unit(*x[2:4]), x[4:7], x[7:10]
    n = np.cross(u1, u2)
    return np.array([np.degrees(np.arccos(abs(u1 @ u2))), abs((c2 - c1) @ n) / np.linalg.norm(n)])


def _rotation_axis(R):
    w = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    return w / np.linalg.norm(w)


def reference_axes(T_camera_target, q, n_points=3):
    """Least-squares screw-model fit of the first ``n_points`` of :data:`TARGET_POINTS_MM` on the
    measured target poses (N, 4, 4) [mm] at joints q (N, 2) [rad], started from the data alone
    (axis directions from the relative rotations of records that differ in one joint, the points
    at the centroid and at the record nearest joints 0). Returns ``(angle [deg], common normal
    [mm]), their standard deviations (covariance s^2 (J^T J)^+ of the fit, s^2 the residual
    variance, propagated by finite differences), residual RMS [mm]``."""
    from scipy.optimize import least_squares

    P = np.einsum("nij,kj->nki", T_camera_target[:, :3, :3], TARGET_POINTS_MM[:n_points]) + T_camera_target[:, None, :3, 3]
    w1, w2 = [], []
    for a in range(len(q)):
        d = q - q[a]
        for b in np.flatnonzero((np.abs(d[:, 1]) < 1e-3) & (d[:, 0] > 0.05)):
            w1.append(_rotation_axis(T_camera_target[b, :3, :3] @ T_camera_target[a, :3, :3].T))
        for b in np.flatnonzero((np.abs(d[:, 0]) < 1e-3) & (d[:, 1] > 0.3) & (d[:, 1] < 2.5)):
            w2.append((_rotation_axis(T_camera_target[b, :3, :3] @ T_camera_target[a, :3, :3].T), q[a, 0]))
    u1 = np.mean(w1, axis=0)
    u1 /= np.linalg.norm(u1)
    u2 = np.mean([_about(u1, np.array([-q1]))[0] @ w for w, q1 in w2], axis=0)  # axis 2 back at joint 1 = 0
    u2 /= np.linalg.norm(u2)
    centre = P[:, 0].mean(axis=0)
    x0 = np.concatenate([[np.arccos(u1[2]), np.arctan2(u1[1], u1[0]), np.arccos(u2[2]), np.arctan2(u2[1], u2[0])],
                         centre, centre, P[np.argmin(np.abs(q).sum(axis=1))].ravel()])

    def residuals(x):  # the points, and the gauge: each axis point may not slide along its axis
        gauge = [(x[4:7] - x0[4:7]) @ _unit(*x[0:2]), (x[7:10] - x0[7:10]) @ _unit(*x[2:4])]
        return np.concatenate([(_screw_points(x, q, n_points) - P).ravel(), gauge])

    sol = least_squares(residuals, x0, method="lm", xtol=1e-15, ftol=1e-15, gtol=1e-15, max_nfev=5000)
    r = sol.fun[:-2]
    s2 = r @ r / (len(r) - (len(x0) - 2))
    cov = s2 * np.linalg.pinv(sol.jac.T @ sol.jac)
    h = 1e-7
    g = np.array([(_axes_of(sol.x + h * e) - _axes_of(sol.x)) / h for e in np.eye(len(x0))])
    return _axes_of(sol.x), np.sqrt(np.einsum("pi,pq,qi->i", g, cov, g)), float(np.sqrt(np.mean(r**2)))
