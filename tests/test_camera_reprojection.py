"""The reprojection residual on the calibration core: a camera calibration from planar-target
image points recovers the intrinsics and agrees with cv2.calibrateCamera on the same points."""

import numpy as np
import pytest

from robocal.calib import Problem, solve
from robocal.calib.blocks import CameraIntrinsics, FramesBlock
from robocal.calib.residuals import ReprojectionResidual
from robocal.camera import project_points
from robocal.transforms import so3_exp

cv2 = pytest.importorskip("cv2")

TRUE_INTR = np.array([1400.0, 1380.0, 645.0, 508.0])
TRUE_DIST = np.array([-0.12, 0.08, 0.0008, -0.0005, -0.02])


def _views(seed, n=12, noise=0.1):
    rng = np.random.default_rng(seed)
    g = np.stack(np.meshgrid(np.arange(9.0), np.arange(6.0)), -1).reshape(-1, 2) * 25.0
    X = np.column_stack([g - g.mean(0), np.zeros(len(g))])
    T = np.tile(np.eye(4), (n, 1, 1))
    T[:, :3, :3] = so3_exp(rng.normal(0, 0.35, (n, 3)))
    T[:, :3, 3] = np.column_stack([rng.normal(0, 60, (n, 2)), rng.uniform(450, 800, n)])
    P = (T[:, None, :3, :3] @ X[None, :, :, None])[..., 0] + T[:, None, :3, 3]
    uv = project_points(P.reshape(-1, 3), TRUE_INTR, TRUE_DIST).pixels.reshape(n, len(X), 2)
    return X, T, uv + rng.normal(0, noise, uv.shape)


def test_camera_calibration_on_the_core_matches_opencv():
    X, T, uv = _views(0)
    K0 = np.array([1300.0, 1300.0, 640.0, 512.0])
    cam = CameraIntrinsics(K0, np.zeros(5))
    start = T.copy()
    start[:, :3, 3] += 5.0  # a rough start for every board pose
    res = ReprojectionResidual(cam, FramesBlock("camera", np.eye(4), free=False), FramesBlock("board", start),
                               uv, X, sigma=0.1)
    result = solve(Problem([cam, res.camera_poses, res.target_poses], [res]))
    ours = result.value("cam")
    rms, K, dist, _, _ = cv2.calibrateCamera([X.astype(np.float32)] * len(uv), [u.astype(np.float32) for u in uv],
                                             (1280, 1024), None, None, flags=0,
                                             criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12))
    theirs = np.concatenate([[K[0, 0], K[1, 1], K[0, 2], K[1, 2]], dist.ravel()[:5]])
    assert np.max(np.abs(ours[:4] - TRUE_INTR)) < 2.0  # px, 0.1 px corner noise
    # same data, same model: the two least-squares optima agree (OpenCV works in float32 points)
    assert np.max(np.abs(ours[:4] - theirs[:4])) < 1e-3  # measured 1.4e-4 px
    assert np.max(np.abs(ours[4:] - theirs[4:])) < 1e-4  # measured 1.7e-5
