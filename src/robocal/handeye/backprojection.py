"""Back-projection of detections onto the target (issue 14 item 5, METHODS.md section 3 "Hand-eye":
the HALCON paper shows the hand-eye error by projecting the target with the solution).

Residuals are *detected minus predicted*, per image and per corner:

* in pixels: the detected corner minus the target point projected with the solution;
* in millimetres on the target: the detected corner's ray (undistorted with the camera) meets the
  target's plane through that corner (``z = X_k.z`` in the target frame, as posed by the solution)
  at a point whose (x, y) minus the corner's (x, y) is the residual. A residual of 0.1 mm says the
  solution places that corner 0.1 mm away from where the camera saw it, independent of the range.
"""

from __future__ import annotations

import numpy as np

__all__ = ["rms_px", "target_plane_residuals"]


def rms_px(residuals) -> tuple:
    """``(RMS over all finite points, RMS per image (N,))`` of the residual norms of (N, P, 2)
    [px or mm]; NaN for an image without points."""
    sq = np.sum(np.asarray(residuals, dtype=float) ** 2, axis=2)
    ok = np.isfinite(sq)
    count = ok.sum(1)
    total = np.where(ok, sq, 0.0).sum(1)
    per_image = np.sqrt(total / np.where(count > 0, count, 1))
    per_image[count == 0] = np.nan
    return float(np.sqrt(total.sum() / max(count.sum(), 1))), per_image


def target_plane_residuals(camera, T_camera_target, image_points, target_points) -> np.ndarray:
    """(N, P, 2) [mm]: where each detected corner's ray meets the target, minus the corner, in the
    target frame (x, y). camera: :class:`robocal.camera.Camera`; T_camera_target (N, 4, 4) [mm];
    image_points (N, P, 2) [px] (NaN: not detected); target_points (P, 3) [mm]. NaN where not
    detected or the ray runs parallel to the target."""
    uv = np.asarray(image_points, dtype=float)
    X = np.asarray(target_points, dtype=float)
    T = np.asarray(T_camera_target, dtype=float)
    N, P = uv.shape[:2]
    rays = camera.rays(uv.reshape(-1, 2)).reshape(N, P, 2)
    d_cam = np.concatenate([rays, np.ones((N, P, 1))], axis=2)
    Rt = np.swapaxes(T[:, :3, :3], 1, 2)
    origin = -(Rt @ T[:, :3, 3, None])[..., 0]  # the camera centre in the target frame (N, 3)
    d = np.einsum("nij,npj->npi", Rt, d_cam)
    with np.errstate(divide="ignore", invalid="ignore"):
        s = (X[None, :, 2] - origin[:, None, 2]) / d[..., 2]
    hit = origin[:, None, :2] + s[..., None] * d[..., :2]
    out = hit - X[None, :, :2]
    out[~np.isfinite(out).all(axis=2) | ~(s > 0)] = np.nan
    return out
