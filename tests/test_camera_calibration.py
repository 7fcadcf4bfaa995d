"""robocal.handeye.calibrate_camera: closed-form start + the core's LM; agrees with
cv2.calibrateCamera on the same points far inside the reported uncertainty; recovers the truth
from a board that sags (an effect the planar model lacks) within the reported uncertainty; the
division model; skipped images and fixed parameters; errors that name the problem."""

import numpy as np
import pytest

from robocal.handeye import HandEyeError, calibrate_camera, initial_intrinsics
from robocal.sim.cameras.handeye_points import CAMERA_MODELS, simulate_hand_eye

cv2 = pytest.importorskip("cv2")

BROWN = ("k1", "k2", "p1", "p2", "k3")


def _values(camera):
    names = ("fx", "fy", "cx", "cy") + (BROWN if camera.model == "brown" else ("kappa",))
    return dict(zip(names, (*camera.intrinsics, *camera.distortion)))


def test_intrinsics_match_opencv_within_the_reported_uncertainty():
    sim = simulate_hand_eye(11, n_images=12, pose_noise_mm=0.0, pose_noise_deg=0.0)
    res = calibrate_camera(sim.image_points, sim.target_points, (1280, 1024))
    assert res.converged and res.rms_px == pytest.approx(0.3 * np.sqrt(2), rel=0.05)
    ok = np.all(np.isfinite(sim.image_points), axis=2)
    rms, K, dist, _, _ = cv2.calibrateCamera(
        [sim.target_points[m].astype(np.float32) for m in ok],
        [u[m].astype(np.float32) for u, m in zip(sim.image_points, ok)],
        (1280, 1024), None, None, criteria=(cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 200, 1e-12))
    theirs = dict(zip(("fx", "fy", "cx", "cy") + BROWN, (K[0, 0], K[1, 1], K[0, 2], K[1, 2], *dist.ravel()[:5])))
    ours, truth = _values(res.camera), _values(sim.camera)
    for k in theirs:
        # the same optimum: differences a hundredth of the reported 1-sigma (measured < 1e-3 sigma)
        assert abs(ours[k] - theirs[k]) < 0.01 * res.sigma[k], k
        # and the sigma is honest; the simulator is the model here on purpose: the claim is the
        # agreement with OpenCV on the same corners, this line only checks the size of sigma
        assert abs(ours[k] - truth[k]) < 3.0 * res.sigma[k], k
    assert rms == pytest.approx(res.rms_px, rel=1e-3)  # OpenCV's RMS is per point norm too


@pytest.mark.parametrize("model", ["brown", "division"])
def test_a_sagging_board_still_gives_the_truth_within_the_uncertainty(model):
    # the true board sags by 0.15 mm in the middle (a printed board on a plate); the model is planar
    sim = simulate_hand_eye(11, n_images=12, camera=CAMERA_MODELS[model], bend_mm=0.15, pose_noise_mm=0.0,
                            pose_noise_deg=0.0)
    res = calibrate_camera(sim.image_points, sim.target_points, (1280, 1024), model=model)
    ours, truth = _values(res.camera), _values(sim.camera)
    z = {k: (ours[k] - truth[k]) / res.sigma[k] for k in truth}
    assert max(abs(v) for v in z.values()) < 3.5, z  # measured max 2.1 (brown), 1.9 (division)
    assert abs(ours["fx"] - truth["fx"]) < 5.0 and abs(ours["cx"] - truth["cx"]) < 5.0  # px
    # a 1 mm sag is no longer covered: the focal length moves by several sigma (flatness matters)
    sim = simulate_hand_eye(11, n_images=12, camera=CAMERA_MODELS[model], bend_mm=1.0, pose_noise_mm=0.0,
                            pose_noise_deg=0.0)
    res = calibrate_camera(sim.image_points, sim.target_points, (1280, 1024), model=model)
    assert abs(res.camera.fx - truth["fx"]) > 4.0 * res.sigma["fx"]  # measured 5.7 (brown), 9.9 (division) sigma


def test_skipped_images_fixed_parameters_and_errors():
    sim = simulate_hand_eye(12, n_images=8, pose_noise_mm=0.0, pose_noise_deg=0.0)
    uv = sim.image_points.copy()
    uv[1, 4:] = np.nan
    res = calibrate_camera(uv, sim.target_points, (1280, 1024), fix=("k3", "p1", "p2"))
    assert res.skipped == {1: "4 target points detected, at least 6 needed"}
    assert np.isnan(res.T_camera_target[1]).all() and np.isnan(res.per_image_rms_px[1])
    assert res.camera.distortion[2:] == (0.0, 0.0, 0.0) and set(res.sigma) == {"fx", "fy", "cx", "cy", "k1", "k2"}
    K = initial_intrinsics(uv, sim.target_points, (1280, 1024))
    assert np.max(np.abs(K[:2] / 1400.0 - 1.0)) < 0.1  # the closed-form start is within 10 % (distortion ignored)
    with pytest.raises(HandEyeError, match="at least 3 images with 6 or more"):
        calibrate_camera(uv[:3], sim.target_points, (1280, 1024))
    with pytest.raises(HandEyeError, match="unknown parameter.*k9"):
        calibrate_camera(uv, sim.target_points, (1280, 1024), fix=("k9",))
    with pytest.raises(HandEyeError, match=r"target_points: expected \(88, 3\)"):
        calibrate_camera(uv, sim.target_points[:10], (1280, 1024))
