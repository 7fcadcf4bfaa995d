"""The target's pose in the camera from one image of it (perspective-n-point), batched over images
(METHODS.md section 3, "Hand-eye": every image gives ``T_camera_target`` for the linear solvers).

Steps, all images at once:

1. the target points (P, 3) [mm] are written in their best-fit plane (a planar board: its own
   frame; a slightly non-planar one: the plane of least squares);
2. the detected pixels are undistorted to normalised image coordinates with the camera
   (:meth:`robocal.camera.Camera.rays`) and a plane-to-image homography is fitted per image
   (normalised DLT, Hartley's conditioning);
3. the homography gives the pose in closed form (``[r1 r2 t] ~ H``, rotation orthonormalised);
4. Levenberg–Marquardt on the pixel residuals of the full camera model (distortion included),
   every image's 6 x 6 normal equations solved together, with the analytic projection Jacobian.

NaN pixels are corners that were not detected; images with fewer than ``min_points`` detected
corners get a NaN pose and a reason.
"""

from __future__ import annotations

import numpy as np

from ..calib.residuals.reprojection import cross_rows
from ..camera.projection import project_points
from ..transforms import so3_exp

__all__ = ["plane_frame", "spread_ratio", "homographies", "poses_from_homographies", "refine_poses", "solve_pnp"]


def plane_frame(target_points) -> np.ndarray:
    """T_target_plane (4, 4): a frame whose xy-plane is the least-squares plane of the points
    (P, 3) [mm]; the identity when they already lie in z = 0."""
    X = np.asarray(target_points, dtype=float)
    if np.all(X[:, 2] == 0.0):
        return np.eye(4)
    c = X.mean(0)
    _, _, Vt = np.linalg.svd(X - c)
    R = Vt.T.copy()
    if np.linalg.det(R) < 0:
        R[:, 2] *= -1
    T = np.eye(4)
    T[:3, :3], T[:3, 3] = R, c
    return T


def _conditioning(pts, mask):
    """(N, 3, 3) similarity per image moving its masked points to zero mean, mean distance sqrt(2)."""
    w = mask[..., None].astype(float)
    n = np.maximum(w.sum(1), 1.0)
    c = np.nansum(np.where(mask[..., None], pts, 0.0), 1) / n
    d = np.where(mask, np.linalg.norm(np.where(mask[..., None], pts, 0.0) - c[:, None], axis=2), 0.0)
    s = np.sqrt(2.0) / np.maximum(d.sum(1) / n[:, 0], 1e-300)
    T = np.zeros((len(pts), 3, 3))
    T[:, 0, 0] = T[:, 1, 1] = s
    T[:, :2, 2] = -s[:, None] * c
    T[:, 2, 2] = 1.0
    return T


def _apply(T, pts):
    """The similarities T (N, 3, 3) of :func:`_conditioning` (``s I`` and a shift) on pts (N, P, 2)."""
    return pts * T[:, None, 0, 0, None] + T[:, None, :2, 2]


def spread_ratio(plane_xy, mask) -> np.ndarray:
    """(N,) the ratio of the smaller to the larger principal spread of each image's detected
    points on the target plane: 0 for collinear points (no pose from them)."""
    xy = np.broadcast_to(np.asarray(plane_xy, dtype=float), mask.shape + (2,))
    w = mask[..., None].astype(float)
    n = np.maximum(w.sum(1), 1.0)
    c = (xy * w).sum(1) / n
    d = (xy - c[:, None]) * w
    ev = np.linalg.eigvalsh(np.einsum("npi,npj->nij", d, d))
    return np.sqrt(np.maximum(ev[:, 0], 0.0) / np.maximum(ev[:, 1], 1e-300))


def homographies(plane_xy, image_xy, mask) -> np.ndarray:
    """Homographies H (N, 3, 3) with ``image ~ H [x, y, 1]`` by the normalised DLT.

    plane_xy (P, 2) or (N, P, 2); image_xy (N, P, 2); mask (N, P) bool: the points used (at least
    4 per image). Rows of undetected points are zero, so all images are solved in one batched
    eigen-decomposition.
    """
    img = np.asarray(image_xy, dtype=float)
    N, P = img.shape[:2]
    src = np.broadcast_to(np.asarray(plane_xy, dtype=float), (N, P, 2))
    Ts, Td = _conditioning(src, mask), _conditioning(img, mask)
    s, d = _apply(Ts, src), _apply(Td, np.where(mask[..., None], img, 0.0))
    A = np.zeros((N, P, 2, 9))
    one = np.ones((N, P))
    sh = np.stack([s[..., 0], s[..., 1], one], -1)
    A[:, :, 0, 0:3] = sh
    A[:, :, 0, 6:9] = -d[..., 0:1] * sh
    A[:, :, 1, 3:6] = sh
    A[:, :, 1, 6:9] = -d[..., 1:2] * sh
    A *= mask[:, :, None, None]
    # the null vector from the 9 x 9 normal matrix (its smallest eigenvector): on conditioned
    # coordinates its precision suffices for a start and it costs a fraction of an SVD of A
    A = A.reshape(N, 2 * P, 9)
    h = np.linalg.eigh(np.swapaxes(A, 1, 2) @ A)[1][:, :, 0]
    H = np.linalg.solve(Td, h.reshape(N, 3, 3) @ Ts)
    return H / H[:, 2:3, 2:3]


def poses_from_homographies(H) -> np.ndarray:
    """T_camera_plane (N, 4, 4) [mm] from homographies H (N, 3, 3) between the plane (mm) and
    *normalised* image coordinates: ``[r1 r2 t] = lambda H``, the plane in front of the camera."""
    H = np.asarray(H, dtype=float)
    lam = 2.0 / (np.linalg.norm(H[:, :, 0], axis=1) + np.linalg.norm(H[:, :, 1], axis=1))
    lam = lam * np.sign(H[:, 2, 2])  # t_z > 0: the plane is in front of the camera
    r1, r2, t = (H[:, :, k] * lam[:, None] for k in range(3))
    R = np.stack([r1, r2, np.cross(r1, r2)], axis=2)
    U, _, Vt = np.linalg.svd(R)
    D = np.ones((len(H), 3))
    D[:, 2] = np.linalg.det(U @ Vt)
    T = np.tile(np.eye(4), (len(H), 1, 1))
    T[:, :3, :3] = (U * D[:, None]) @ Vt
    T[:, :3, 3] = t
    return T


def _residuals(camera, X, uv, mask, T, jacobian):
    """Pixel residuals (N, P, 2) (0 where masked) and, with ``jacobian``, d(prediction)/d(left step)
    (N, P, 2, 6)."""
    N, P = uv.shape[:2]
    # every image in one matrix product: Y[p, 3n + i] = sum_j X[p, j] R_n[i, j]
    p = (X @ T[:, :3, :3].transpose(2, 0, 1).reshape(3, 3 * N)).reshape(P, N, 3).transpose(1, 0, 2) \
        + T[:, None, :3, 3]
    proj = project_points(p.reshape(-1, 3), camera.intrinsics, camera.distortion, camera.model, jacobian,
                          point_only=True)
    r = np.where(mask[..., None], uv - proj.pixels.reshape(N, P, 2), 0.0)
    finite = bool(np.isfinite(r).all())
    if not finite:
        r = np.nan_to_num(r, nan=1e6)  # a point behind the camera: a huge residual, the step is rejected
    if not jacobian:
        return r, None
    J = cross_rows(p.reshape(-1, 3), proj.d_point, 1.0).reshape(N, P, 2, 6)  # d_point @ [-[p]x, I]
    J[~mask] = 0.0
    if not finite:
        J = np.nan_to_num(J)
    return r, J


def refine_poses(camera, target_points, image_points, T0, *, mask=None, iterations: int = 30,
                 tol: float = 1e-10) -> tuple:
    """Levenberg–Marquardt per image on the pixel residuals, all images together.

    camera: :class:`robocal.camera.Camera`; target_points (P, 3) [mm]; image_points (N, P, 2) [px];
    T0 (N, 4, 4) starting ``T_camera_target`` [mm]; mask (N, P) the points used (default: the
    finite ones). Returns ``(T (N, 4, 4), rms (N,) [px])``.
    """
    X = np.asarray(target_points, dtype=float)
    uv = np.asarray(image_points, dtype=float)
    mask = np.all(np.isfinite(uv), axis=2) if mask is None else mask
    T = np.array(T0, dtype=float)
    N = len(T)
    lam = np.full(N, 1e-3)
    r, J = _residuals(camera, X, uv, mask, T, True)
    cost = np.einsum("npk,npk->n", r, r)
    active = np.ones(N, bool)
    for _ in range(iterations):
        idx = np.flatnonzero(active)  # only the images still iterating are evaluated
        every = len(idx) == N  # all of them: no copies by index
        Jr = (J if every else J[idx]).reshape(len(idx), -1, 6)
        JrT = np.swapaxes(Jr, 1, 2)
        H = JrT @ Jr
        g = (JrT @ (r if every else r[idx]).reshape(len(idx), -1, 1))[..., 0]
        damping = np.einsum("nii->ni", H)[:, :, None] * np.eye(6) + 1e-12 * np.eye(6)
        d = np.linalg.solve(H + lam[idx, None, None] * damping, g[..., None])[..., 0]
        Tn = T[idx]  # a copy (index array)
        R = so3_exp(d[:, :3])
        Tn[:, :3, :3] = R @ Tn[:, :3, :3]
        Tn[:, :3, 3] = (R @ Tn[:, :3, 3, None])[..., 0] + d[:, 3:]
        rn, Jn = _residuals(camera, X, uv if every else uv[idx], mask if every else mask[idx], Tn, True)
        cn = np.einsum("npk,npk->n", rn, rn)
        c0 = cost[idx]
        better = cn <= c0
        up = idx[better]
        if every and better.all():
            T, r, J, cost = Tn, rn, Jn, cn
        else:
            T[up], r[up], J[up], cost[up] = Tn[better], rn[better], Jn[better], cn[better]
        small = better & (c0 - cn <= tol * np.maximum(c0, 1e-30)) | (np.abs(d).max(1) < 1e-12)
        # a refused step whose predicted reduction is at the rounding level: a stationary point
        small |= ~better & (np.einsum("ni,ni->n", g, d) <= tol * np.maximum(c0, 1e-30))
        lam[idx] = np.where(better, lam[idx] * 0.3, lam[idx] * 10.0)
        active[idx] = ~small & (lam[idx] < 1e8)
        if not active.any():
            break
    n = np.maximum(mask.sum(1), 1)
    return T, np.sqrt(cost / n)


def solve_pnp(camera, target_points, image_points, *, min_points: int = 4, iterations: int = 30) -> tuple:
    """The target's pose in the camera per image: homography start, then :func:`refine_poses`.

    camera: :class:`robocal.camera.Camera`; target_points (P, 3) [mm, target frame]; image_points
    (N, P, 2) [px], NaN where not detected. Returns ``(T_camera_target (N, 4, 4) [mm], rms (N,)
    [px], reasons)``; iterations: at most this many refinement steps (a start for a joint
    solve needs few); ``reasons`` a list of N strings, empty for a solved image, else why not (its
    pose and rms are NaN).
    """
    X = np.asarray(target_points, dtype=float)
    uv = np.asarray(image_points, dtype=float)
    if uv.ndim != 3 or uv.shape[2] != 2 or X.shape != (uv.shape[1], 3):
        raise ValueError(f"PnP: image points (N, P, 2) and target points (P, 3) expected, got {uv.shape} and {X.shape}")
    N, P = uv.shape[:2]
    mask = np.all(np.isfinite(uv), axis=2)
    rays = camera.rays(np.where(mask[..., None], uv, 0.0).reshape(-1, 2)).reshape(N, P, 2)
    mask &= np.all(np.isfinite(rays), axis=2)
    count = mask.sum(1)
    T_tp = plane_frame(X)
    xy = (X - T_tp[:3, 3]) @ T_tp[:3, :3]  # plane coordinates (P, 3), z ~ 0
    spread = spread_ratio(xy[:, :2], mask)
    ok = (count >= min_points) & (spread > 0.02)
    reasons = ["" if k else f"{c} target points detected, at least {min_points} needed" if c < min_points
               else f"the {c} detected target points lie on one line" for k, c in zip(ok, count)]
    T = np.full((N, 4, 4), np.nan)
    rms = np.full(N, np.nan)
    if not ok.any():
        return T, rms, reasons
    H = homographies(xy[:, :2], rays[ok], mask[ok])
    T0 = poses_from_homographies(H) @ np.linalg.inv(T_tp)
    bad = ~np.all(np.isfinite(T0), axis=(1, 2))
    T0[bad] = np.eye(4)
    T[ok], rms[ok] = refine_poses(camera, X, uv[ok], T0, mask=mask[ok], iterations=iterations)
    return T, rms, reasons
