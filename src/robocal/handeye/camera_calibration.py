"""Camera calibration from images of a known target (issue 14 item 4; METHODS.md section 3).

1. Closed-form start (Zhang, 2000): a plane-to-pixel homography per image; with zero skew the
   two constraints per image ``h1^T B h2 = 0``, ``h1^T B h1 = h2^T B h2`` on ``B = K^-T K^-1``
   give the intrinsics (at least 2 images). When that start is not physical (too few or too
   similar views) the principal point is put at the image centre and ``fx, fy`` solved from the
   same constraints by least squares (OpenCV's start). Distortion starts at zero.
2. Per-image target poses from the homographies (:mod:`.pnp`).
3. The calibration core's Levenberg–Marquardt over the intrinsics, the distortion and every
   image's target pose, the poses eliminated per image by a Schur complement
   (:func:`robocal.calib.schur.solve_schur`: same steps and stop rules as :func:`robocal.calib.solve`,
   time linear in the image count) (:class:`~robocal.calib.residuals.ReprojectionResidual`
   with the camera frame fixed at the identity); 1-sigma from the covariance, scaled by the
   residual spread; unidentifiable parameters held and named (``identifiability``).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass

import numpy as np

from ..calib import Problem, solve
from ..calib.blocks import CameraIntrinsics, FramesBlock
from ..calib.residuals import BoardShapeReprojectionResidual, ReprojectionResidual
from ..calib.residuals.board_shape import board_shape_block, sag_bases
from ..calib.schur import StructureError, solve_schur
from ..calib.solve import NotConvergedWarning
from ..camera import BROWN_SIZES, Camera
from .backprojection import rms_px
from .motions import HandEyeError
from .pnp import homographies, plane_frame, solve_pnp, spread_ratio

__all__ = ["CameraCalibration", "calibrate_camera", "initial_intrinsics"]


@dataclass(frozen=True)
class CameraCalibration:
    """The result of :func:`calibrate_camera`.

    camera: the refined :class:`~robocal.camera.Camera`; T_camera_target (N, 4, 4) [mm] per image
    (NaN for images not used); residuals_px (N, P, 2) detected minus projected [px], NaN where not
    detected; rms_px: RMS over all detected corners of the residual norm [px]; per_image_rms_px (N,);
    sigma: 1-sigma of every free intrinsic / distortion parameter by short name (``fx`` [px],
    ``k1`` [1]) from the covariance; converged; identifiability: the core's
    :class:`~robocal.calib.identifiability.IdentifiabilityReport` (``dropped`` names what the
    images cannot determine); message: one line on the outcome; skipped: {image index: reason};
    board_sag_mm: ``(sag_x, sag_y)`` [mm] of the board when its shape was estimated
    (``board_shape=True``; their 1-sigma in ``sigma`` as ``sag_x``, ``sag_y``), else None.
    """

    camera: Camera
    T_camera_target: np.ndarray
    residuals_px: np.ndarray
    rms_px: float
    per_image_rms_px: np.ndarray
    sigma: dict
    converged: bool
    identifiability: object
    message: str
    skipped: dict | None = None
    board_sag_mm: tuple | None = None


def _check_points(image_points, target_points):
    uv = np.asarray(image_points, dtype=float)
    X = np.asarray(target_points, dtype=float)
    if uv.ndim != 3 or uv.shape[2] != 2:
        raise HandEyeError(f"image_points: expected (N images, P points, 2) pixels, got shape {uv.shape}")
    if X.shape != (uv.shape[1], 3):
        raise HandEyeError(f"target_points: expected ({uv.shape[1]}, 3) millimetres (one per image point), "
                           f"got shape {X.shape}")
    if not np.all(np.isfinite(X)):
        raise HandEyeError("target_points contain NaN or infinite coordinates")
    return uv, X


def _zhang(H) -> np.ndarray | None:
    """(fx, fy, cx, cy) from pixel homographies H (N, 3, 3) with zero skew, or None."""
    def v(i, j):
        hi, hj = H[:, :, i], H[:, :, j]
        return np.stack([hi[:, 0] * hj[:, 0], hi[:, 1] * hj[:, 1],
                         hi[:, 2] * hj[:, 0] + hi[:, 0] * hj[:, 2], hi[:, 2] * hj[:, 1] + hi[:, 1] * hj[:, 2],
                         hi[:, 2] * hj[:, 2]], axis=1)  # b = (B11, B22, B13, B23, B33), B12 = 0

    V = np.concatenate([v(0, 1), v(0, 0) - v(1, 1)])
    V /= np.linalg.norm(V, axis=1, keepdims=True)
    b = np.linalg.svd(V)[2][-1]
    B11, B22, B13, B23, B33 = b if b[0] > 0 else -b
    if B11 <= 0 or B22 <= 0:
        return None
    cx, cy = -B13 / B11, -B23 / B22
    lam = B33 - B13**2 / B11 - B23**2 / B22
    if lam <= 0:
        return None
    return np.array([np.sqrt(lam / B11), np.sqrt(lam / B22), cx, cy])


def _centred(H, image_size) -> np.ndarray | None:
    """(fx, fy, cx, cy) with the principal point at the image centre, fx and fy by least squares."""
    c = (np.asarray(image_size, dtype=float) - 1.0) / 2.0
    S = np.array([[1.0, 0.0, -c[0]], [0.0, 1.0, -c[1]], [0.0, 0.0, 1.0]])
    Hc = S @ H
    h1, h2 = Hc[:, :, 0], Hc[:, :, 1]
    A = np.concatenate([np.stack([h1[:, 0] * h2[:, 0], h1[:, 1] * h2[:, 1]], 1),
                        np.stack([h1[:, 0]**2 - h2[:, 0]**2, h1[:, 1]**2 - h2[:, 1]**2], 1)])
    rhs = -np.concatenate([h1[:, 2] * h2[:, 2], h1[:, 2]**2 - h2[:, 2]**2])
    a, b = np.linalg.lstsq(A, rhs, rcond=None)[0]  # 1/fx^2, 1/fy^2
    if a <= 0 or b <= 0:
        return None
    return np.array([1.0 / np.sqrt(a), 1.0 / np.sqrt(b), c[0], c[1]])


def initial_intrinsics(image_points, target_points, image_size, *, min_points: int = 4) -> np.ndarray:
    """Closed-form (fx, fy, cx, cy) [px] from plane-to-pixel homographies (see the module docstring).

    Raises :class:`HandEyeError` when no physical start exists (e.g. every view fronto-parallel)."""
    uv, X = _check_points(image_points, target_points)
    mask = np.all(np.isfinite(uv), axis=2)
    T_tp = plane_frame(X)
    xy = ((X - T_tp[:3, 3]) @ T_tp[:3, :3])[:, :2]
    use = (mask.sum(1) >= min_points) & (spread_ratio(xy, mask) > 0.02)
    H = homographies(xy, np.where(mask[use, :, None], uv[use], 0.0), mask[use])
    H = H[np.all(np.isfinite(H), axis=(1, 2))]
    H /= np.linalg.norm(H, axis=(1, 2), keepdims=True)
    w, h = image_size
    for K in (_zhang(H) if len(H) >= 3 else None, _centred(H, image_size)):
        if K is not None and -0.25 * w < K[2] < 1.25 * w and -0.25 * h < K[3] < 1.25 * h \
                and 0.5 < K[0] / K[1] < 2.0 and K[0] > 0.05 * w:
            return K
    raise HandEyeError("no closed-form start for the intrinsics: the views do not constrain the focal length "
                       "(tilt the target by 20 to 45 degrees in some images, or pass an initial camera)")


def _short(name: str) -> str:
    return name.split(".", 1)[1] if name.startswith("cam.") else name


def calibrate_camera(image_points, target_points, image_size, *, model: str = "brown", n_distortion: int = 5,
                     camera: Camera | None = None, fix=(), min_points: int = 6,
                     loss: str = "linear", board_shape: bool = False) -> CameraCalibration:
    """Intrinsics and distortion of one camera from N images of a known target.

    image_points (N, P, 2) [px], NaN where a corner was not detected; target_points (P, 3) [mm] in
    the target frame; image_size (width, height) [px]; model ``"brown"`` (``n_distortion`` = 4, 5
    or 8 OpenCV coefficients) or ``"division"`` (one kappa); camera: a starting
    :class:`~robocal.camera.Camera` (its model and coefficient count win) or None for the
    closed-form start; fix: parameter names held at their start (``"k3"``, ``"cx"`` ...); images
    with fewer than ``min_points`` detected corners are skipped (``skipped`` says why); loss:
    ``"linear"`` or ``"huber"`` (per image, the core's robust option); board_shape: also estimate
    the board's sag along its x and y axes [mm] (a low-order surface,
    :class:`~robocal.calib.residuals.BoardShapeReprojectionResidual`; the points stay those of a
    flat board otherwise).

    Raises :class:`HandEyeError` for fewer than 3 usable images or no closed-form start.
    """
    uv, X = _check_points(image_points, target_points)
    N, P = uv.shape[:2]
    if len(image_size) != 2 or min(image_size) <= 0:
        raise HandEyeError(f"image_size: expected (width, height) in pixels, got {image_size!r}")
    mask = np.all(np.isfinite(uv), axis=2)
    use = mask.sum(1) >= min_points
    skipped = {int(i): f"{int(mask[i].sum())} target points detected, at least {min_points} needed"
               for i in np.flatnonzero(~use)}
    if use.sum() < 3:
        raise HandEyeError(f"camera calibration needs at least 3 images with {min_points} or more detected target "
                           f"points, got {int(use.sum())} of {N}")
    if camera is None:
        if model == "brown" and n_distortion not in BROWN_SIZES:
            raise HandEyeError(f"n_distortion: Brown-Conrady takes 4, 5 or 8 coefficients, got {n_distortion}")
        dist = np.zeros(n_distortion if model == "brown" else 1)
        camera = Camera(*initial_intrinsics(uv[use], X, image_size), tuple(dist), model, tuple(image_size))
    # per-image start: homography in normalised coordinates of the starting camera, then LM
    T0, _, reasons = solve_pnp(camera, X, np.where(use[:, None, None], uv, np.nan), min_points=min_points,
                             iterations=1)  # a start: the joint solve refines the poses
    good = use & np.all(np.isfinite(T0), axis=(1, 2))
    for i in np.flatnonzero(use & ~good):
        skipped[int(i)] = reasons[i] or "no pose of the target found in this image"
    cam = CameraIntrinsics(camera.intrinsics, camera.distortion, model=camera.model, name="cam")
    fixed = {f"cam.{_short(f)}" for f in fix}
    unknown = fixed - set(cam.names)
    if unknown:
        raise HandEyeError(f"fix: unknown parameter(s) {', '.join(sorted(unknown))}; expected some of "
                           f"{', '.join(_short(n) for n in cam.names)}")
    cam = cam.with_free([n not in fixed for n in cam.names])
    identity = FramesBlock("camera", np.eye(4), free=False)
    poses = FramesBlock("target", T0[good], labels=[f"image{i}" for i in np.flatnonzero(good)], group="targets")
    blocks = [cam, identity, poses]
    if board_shape:
        shape = board_shape_block()
        blocks.append(shape)

    def residual(compact):
        if board_shape:
            return BoardShapeReprojectionResidual(cam, identity, poses, uv[good], X, shape, compact_targets=compact)
        return ReprojectionResidual(cam, identity, poses, uv[good], X, compact_targets=compact)

    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NotConvergedWarning)
        try:  # the per-image poses eliminated (Schur complement): linear in the image count
            result = solve_schur(Problem(blocks, [residual(True)]), poses, loss=loss)
        except StructureError:  # a pose its image does not determine: the dense solve names it
            result = solve(Problem(blocks, [residual(False)]), loss=loss)
    value = result.state[0]
    refined = Camera(*value[:4], tuple(value[4:]), camera.model, tuple(image_size))
    T = np.full((N, 4, 4), np.nan)
    T[good] = result.state[2]
    sigma = {_short(n): float(s) for n, s in zip(result.names, result.std) if n.startswith("cam.")}
    sag = None
    if board_shape:
        sag = tuple(float(v) for v in np.ravel(result.state[3]))
        X = X.copy()
        X[:, 2] += sag_bases(X) @ np.asarray(sag)
        for n, s_ in zip(result.names, result.std):
            if n.startswith("board."):
                sigma[n.split(".", 1)[1]] = float(s_)
    # the solver's final residuals (weight 1: detected minus projected, sag included) per image
    used = np.full(uv[good].shape, np.nan)
    used[np.all(np.isfinite(uv[good]), axis=2)] = np.asarray(result.residuals_after).reshape(-1, 2)
    residuals = np.full(uv.shape, np.nan)
    residuals[good] = used
    rms, per_image = rms_px(residuals)
    dropped = result.identifiability.dropped_names
    msg = (f"{'converged' if result.converged else 'NOT CONVERGED (' + result.reason + ')'} after "
           f"{result.iterations} iterations; {int(good.sum())} of {N} images, RMS {rms:.3f} px")
    if dropped:
        msg += f"; not identifiable from these images (held at their start): {', '.join(map(_short, dropped))}"
    if sag is not None:
        msg += f"; board sag {sag[0]:+.3f} mm along x, {sag[1]:+.3f} mm along y"
    return CameraCalibration(refined, T, residuals, rms, per_image, sigma, bool(result.converged),
                             result.identifiability, msg, skipped, sag)

