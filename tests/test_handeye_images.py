"""Issue 14 acceptance on rendered images: 15 views (1280x1024, lens distortion, blur, lighting,
noise) of a ChArUco board, detected by robocal.io, 0.3 px Gaussian corner noise added after
detection, 0.05 mm / 0.01 deg robot pose noise. robocal's refined hand-eye against every OpenCV
linear method, and its camera calibration against cv2.calibrateCamera, on the same detections.
The renders depend only on the camera-to-board poses, which the seeded cell draws identically for
both set-ups, so one set of images serves eye-in-hand and eye-to-hand."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from robocal.handeye import refine_hand_eye
from robocal.handeye.camera_calibration import calibrate_camera
from robocal.io.boards import board_image, parse_board
from robocal.io.detection import detect_board
from robocal.sim.cameras.camera_cell import simulate_hand_eye_poses
from robocal.sim.cameras.camera_render import BoardRenderer
from robocal.docs.opencv_reference import opencv_hand_eye_solutions
from robocal.transforms import rotation_angle
from robocal.workflows.cameras.camera_simulate import _texel_mm

BOARD = "charuco:9x7:30mm:22mm:DICT_5X5_100"
SEED = 5
CORNER_NOISE_PX = 0.3


@pytest.fixture(scope="module")
def cells():
    board = parse_board(BOARD)
    X = board.object_points()
    truths = {s: simulate_hand_eye_poses(X, setup=s, n_images=15, front_z=board.front_z, seed=SEED)
              for s in ("eye_in_hand", "eye_to_hand")}
    a, b = truths["eye_in_hand"], truths["eye_to_hand"]
    assert np.allclose(a.T_camera_target, b.T_camera_target)
    texture, affine = board_image(board, _texel_mm(board))
    renderer = BoardRenderer(a.camera, texture, affine)
    rng = np.random.default_rng(SEED)
    uv = np.array([detect_board(renderer.render(T, rng), board).image_points for T in a.T_camera_target])
    exact = np.einsum("nij,pj->npi", a.T_camera_target[:, :3, :3], X) + a.T_camera_target[:, None, :3, 3]
    projected = a.camera.project(exact.reshape(-1, 3)).pixels.reshape(uv.shape)
    detection_error = float(np.sqrt(np.nanmean(np.sum((uv - projected) ** 2, axis=2))))
    noisy = uv + rng.normal(0.0, CORNER_NOISE_PX, uv.shape)
    return board, X, truths, noisy, detection_error


def opencv_solutions(F, uv, X, camera, setup) -> dict:
    """OpenCV end to end on the detections (robocal.docs.opencv_reference, also the docs' producer)."""
    return opencv_hand_eye_solutions(F, uv, X, camera, setup)


def _errors(T, truth):
    return (float(np.degrees(rotation_angle(T[:3, :3].T @ truth[:3, :3]))),
            float(np.linalg.norm(T[:3, 3] - truth[:3, 3])))


@pytest.mark.parametrize("setup", ["eye_in_hand", "eye_to_hand"])
def test_refined_hand_eye_on_rendered_images_beats_every_opencv_method(cells, setup):
    board, X, truths, uv, detection_error = cells
    truth = truths[setup]
    assert detection_error < 0.1  # the detector itself, before the 0.3 px noise is added
    res = refine_hand_eye(truth.T_base_flange, uv, X, truth.camera, setup=setup)
    assert res.converged and res.camera_pose_frame == ("flange" if setup == "eye_in_hand" else "base")
    ours = _errors(res.camera_pose, truth.camera_pose)
    theirs = {k: _errors(T, truth.camera_pose) for k, T in
              opencv_solutions(truth.T_base_flange, uv, X, truth.camera, setup).items()}
    for name, (rot, trans) in theirs.items():
        assert ours[0] < rot and ours[1] < trans, (setup, name, ours, (rot, trans))
    # and the reported uncertainty covers the error (3 sigma per axis)
    d = np.abs(res.camera_pose[:3, 3] - truth.camera_pose[:3, 3])
    assert np.all(d < 3 * res.sigma_translation_mm + 0.02), (d, res.sigma_translation_mm)
    print(setup, "detection RMS", round(detection_error, 4), "robocal", ours, {k: tuple(round(x, 4) for x in v) for k, v in theirs.items()})


def test_intrinsics_match_opencv_calibrate_camera_within_the_reported_uncertainty(cells):
    board, X, truths, uv, _ = cells
    cam = truths["eye_in_hand"].camera
    cal = calibrate_camera(uv, X, cam.image_size, n_distortion=5)
    obj = [X[np.isfinite(p[:, 0])].astype(np.float32) for p in uv]
    img = [p[np.isfinite(p[:, 0])].astype(np.float32) for p in uv]
    rms, K, dist, _, _ = cv2.calibrateCamera(obj, img, cam.image_size, None, None)
    ref = dict(zip(["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"],
                   [K[0, 0], K[1, 1], K[0, 2], K[1, 2], *np.ravel(dist)[:5]]))
    ours = dict(zip(["fx", "fy", "cx", "cy", "k1", "k2", "p1", "p2", "k3"],
                    [cal.camera.fx, cal.camera.fy, cal.camera.cx, cal.camera.cy, *cal.camera.distortion]))
    for name in ref:
        assert abs(ours[name] - ref[name]) < cal.sigma[name], (name, ours[name], ref[name], cal.sigma[name])
    # cv2's RMS is per coordinate pair as ours
    assert abs(cal.rms_px - rms) < 0.01 * rms
    # and both are near the truth: within 3 sigma
    truth = dict(zip(ours, [cam.fx, cam.fy, cam.cx, cam.cy, *cam.distortion]))
    assert all(abs(ours[n] - truth[n]) < 3 * cal.sigma[n] for n in ("fx", "fy", "cx", "cy"))
