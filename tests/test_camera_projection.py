"""robocal.camera: projection equals OpenCV's projectPoints, analytic Jacobians equal central
differences, undistortion inverts distortion (issue 14 item 1)."""

import numpy as np
import pytest

from robocal.camera import Camera, project_points, undistort_pixels

cv2 = pytest.importorskip("cv2")


def _scene(seed, n_dist):
    rng = np.random.default_rng(seed)
    P = np.column_stack([rng.uniform(-300, 300, (200, 2)), rng.uniform(400, 1500, 200)])  # mm
    intr = np.array([rng.uniform(800, 2500), rng.uniform(800, 2500), rng.uniform(500, 700), rng.uniform(400, 600)])
    dist = rng.normal(0, [0.1, 0.05, 0.002, 0.002, 0.02, 0.01, 0.005, 0.002][:n_dist])
    return P, intr, dist


@pytest.mark.parametrize("n_dist", [4, 5, 8])
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_projection_equals_opencv_project_points(seed, n_dist):
    P, intr, dist = _scene(seed, n_dist)
    K = Camera(*intr, distortion=tuple(dist)).matrix
    ref, _ = cv2.projectPoints(P, np.zeros(3), np.zeros(3), K, dist)
    ours = project_points(P, intr, dist).pixels
    assert np.max(np.abs(ours - ref[:, 0])) < 1e-9  # measured ~1e-12 px


def _central(f, x, h):
    x = np.asarray(x, dtype=float)
    cols = []
    for i in range(x.size):
        d = np.zeros_like(x)
        d.flat[i] = h
        cols.append((f(x + d) - f(x - d)) / (2 * h))
    return np.stack(cols, axis=-1)


@pytest.mark.parametrize("model,dist", [("brown", [0.1, -0.05, 0.002, -0.001, 0.02, 0.01, -0.005, 0.002]),
                                        ("brown", [-0.2, 0.05, 0.001, 0.001]), ("division", [-0.15])])
def test_jacobians_equal_central_differences(model, dist):
    P, intr, _ = _scene(3, 5)
    P = P[:20]
    out = project_points(P, intr, dist, model, jacobian=True)
    for i in range(len(P)):
        fd = _central(lambda p: project_points(p[None], intr, dist, model).pixels[0], P[i], 1e-4)
        assert np.allclose(out.d_point[i], fd, rtol=0, atol=1e-6)
    fd_i = _central(lambda k: project_points(P, k, dist, model).pixels, intr, 1e-4)
    fd_d = _central(lambda d: project_points(P, intr, d, model).pixels, np.asarray(dist, float), 1e-7)
    assert np.max(np.abs(out.d_intrinsics - fd_i)) < 1e-6
    assert np.max(np.abs(out.d_distortion - fd_d)) < 1e-4 * np.max(np.abs(fd_d))


@pytest.mark.parametrize("model,dist", [("brown", [0.1, -0.05, 0.002, -0.001, 0.02]), ("division", [-0.15]),
                                        ("brown", [-0.3, 0.1, 0.001, 0.002, -0.02, 0.01, 0.0, 0.001])])
def test_undistortion_inverts_projection(model, dist):
    P, intr, _ = _scene(4, 5)
    uv = project_points(P, intr, dist, model).pixels
    rays = undistort_pixels(uv, intr, dist, model)
    assert np.max(np.abs(rays - P[:, :2] / P[:, 2:])) < 1e-12


def test_undistortion_agrees_with_opencv():
    P, intr, dist = _scene(5, 5)
    cam = Camera(*intr, distortion=tuple(dist))
    uv = cam.project(P).pixels
    crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-15)
    ref = cv2.undistortPointsIter(uv[:, None], cam.matrix, dist, None, None, crit)[:, 0]
    assert np.max(np.abs(cam.rays(uv) - ref)) < 1e-8  # OpenCV's fixed-point iteration, float64


def test_points_behind_the_camera_and_bad_coefficients():
    out = project_points([[0.0, 0.0, -10.0], [1.0, 2.0, 100.0]], [1000, 1000, 640, 512])
    assert np.all(np.isnan(out.pixels[0])) and np.all(np.isfinite(out.pixels[1]))
    with pytest.raises(ValueError, match="thin-prism"):
        project_points([[0.0, 0.0, 10.0]], [1000, 1000, 640, 512], np.zeros(12))
    with pytest.raises(ValueError, match="division"):
        Camera(1000, 1000, 640, 512, distortion=(0.1, 0.2), model="division")
